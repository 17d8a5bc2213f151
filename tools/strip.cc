// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/strip.h"

#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

int RunStripCommand(int argc, char** argv) {
  std::string database_path, output_path, control_path, log_path;
  bool overwrite = false;
  StripOptions options;
  CommandLine command(
      "strip",
      "Approximations without any other tool: the relative orientations of "
      "successive image pairs chained into a strip or closed ring with scale "
      "transfer through common tie points, the tie points intersected, a "
      "strip adjustment in model coordinates, then the 7-parameter "
      "similarity to the control points. Writes a COLMAP model.");
  CLI::App& app = command.app();
  app.add_option("--database_path",
                 database_path,
                 "COLMAP database with keypoints and two-view geometries "
                 "(read only)")
      ->required();
  app.add_option("--output_path",
                 output_path,
                 "Output model folder (e.g. sparse/initial)")
      ->required();
  app.add_option("--control_path",
                 control_path,
                 "control/ folder (points.txt, observations.txt, "
                 "distances.txt); without it the model stays in model "
                 "coordinates");
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  command.AddOptions(&options);
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/strip.log)");
  if (!command.Parse(argc, argv)) return 0;

  options.Check();
  CheckOutputPath(output_path, overwrite);
  if (log_path.empty()) {
    const fs::path workspace =
        fs::path(output_path).parent_path().parent_path();
    log_path =
        WorkspaceLogPath(workspace.empty() ? "." : workspace.string(), "strip");
  }
  command.StartLog(log_path);
  const StripResult result = RunStrip(database_path, control_path, options);

  OutputDirectory output(output_path, overwrite);
  WriteModel(result.model, output.temp_path(), ModelFormat::kBinary);
  WriteFileAtomically(output.File("strip.json"), StripReportJson(result));
  output.Commit();

  int connected = 0;
  for (const StripModel& model : result.models) connected += model.connected;
  command.PrintSummary(StrCat(
      result.model.images.size(),
      " images oriented (",
      result.unoriented_images.size(),
      " not), ",
      result.dropped_pairs.empty() ? std::string()
                                   : StrCat(result.dropped_pairs.size(),
                                            " pairs dropped for their loops, "),
      connected,
      " models, ",
      result.model.points3D.size(),
      " tie points",
      result.resected_images.empty()
          ? std::string()
          : StrCat(" (", result.resected_images.size(), " images resected)"),
      result.num_alsm_tie_points > 0
          ? StrCat(", ", result.num_alsm_tie_points, " from bayon tiepoints")
          : std::string(),
      result.closed_ring ? StrCat("; ring closure ",
                                  result.closure_rotation_deg,
                                  " deg, ",
                                  100 * result.closure_position_relative,
                                  " % of the path")
                         : std::string("; open strip"),
      "; strip adjustment sigma0 ",
      result.sigma0_px,
      " px",
      result.has_control ? StrCat("; similarity to ",
                                  DatumTypeName(result.datum.type),
                                  ": RMS ",
                                  1000 * result.datum.similarity_rms_m,
                                  " mm")
                         : std::string("; model coordinates (no control)"),
      "; ",
      result.time_s,
      " s -> ",
      output_path));
  return result.model.images.size() >= 2 ? 0 : 1;
}

}  // namespace bayon
