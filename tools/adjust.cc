// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment.h"
#include "ext/adjustment/adjustment_input.h"
#include "ext/adjustment/adjustment_output.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/georef/crs.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

int RunAdjust(int argc, char** argv) {
  std::string database_path, input_path, output_path, control_path, log_path;
  bool overwrite = false;
  AdjustmentInputOptions input_options;
  AdjustmentOptions options;
  CommandLine command(
      "adjust",
      "Self-calibrating bundle adjustment of a sparse model (bayon strip's or "
      "stock colmap mapper's, hosted in its database) with control points, "
      "the minimum datum or a free network; Brown/Beyer additional "
      "parameters selected by significance, blunders by data snooping, the "
      "precision of every point and orientation. Writes a COLMAP model, "
      "calibration.json, adjustment.json and adjustment.txt.");
  CLI::App& app = command.app();
  app.add_option("--database_path",
                 database_path,
                 "COLMAP database with the model's keypoints (read only)")
      ->required();
  app.add_option("--input_path", input_path, "Input sparse model folder")
      ->required();
  app.add_option("--output_path",
                 output_path,
                 "Output model folder (e.g. sparse/adjusted)")
      ->required();
  app.add_option("--control_path",
                 control_path,
                 "control/ folder: points.txt, observations.txt, "
                 "distances.txt");
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  command.AddOptions(&input_options);
  command.AddOptions(&options);
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <output_path>/../../logs/adjust.log)");
  if (!command.Parse(argc, argv)) return 0;

  options.Check();
  input_options.Check();
  CheckOutputPath(output_path, overwrite);
  // The control's frame (import_control) goes with the model: read before
  // the work, not after it.
  const std::optional<GeoFrame> frame =
      control_path.empty() ? std::nullopt : ReadModelGeoFrame(control_path);
  if (log_path.empty()) {
    // sparse/<name> sits two levels below the workspace.
    const fs::path workspace =
        fs::path(output_path).parent_path().parent_path();
    log_path = WorkspaceLogPath(workspace.empty() ? "." : workspace.string(),
                                "adjust");
  }

  AdjustmentInput input = LoadAdjustmentInput(
      database_path, input_path, control_path, input_options);
  command.StartLog(log_path);
  const AdjustmentResult result = RunAdjustment(options, &input.block);
  AdjustmentRunInfo info;
  info.database_path = database_path;
  info.input_path = input_path;
  info.control_path = control_path;
  if (frame) info.georeference_json = GeoFrameJson(*frame);
  info.self_calibration = options.SelfCalibrationName();
  info.blunder_detection = BlunderDetectionName(options.blunder_detection);
  const AdjustmentOutputs outputs =
      MakeAdjustmentOutputs(input, result, options, info);
  WriteAdjustmentOutputs(outputs, output_path, overwrite);

  const AdjustmentPrecision& p = result.precision;
  // Parameter names once each, however many cameras share them.
  std::string parameters;
  std::set<std::string> seen;
  for (const ParameterEstimate& e : result.final_parameters) {
    if (!seen.insert(e.name).second) continue;
    parameters += (parameters.empty() ? "" : ",") + e.name;
  }
  command.PrintSummary(StrCat(
      DatumTypeName(input.datum.type),
      " datum, ",
      input.block.images.size(),
      " images; n = ",
      p.num_observations,
      ", u = ",
      p.num_unknowns,
      ", r = ",
      p.redundancy,
      ", r/n = ",
      static_cast<double>(p.redundancy) / p.num_observations,
      ", sigma0 = ",
      p.sigma0,
      " px; parameters ",
      parameters.empty() ? "none" : parameters,
      " (",
      input.block.cameras.size(),
      input.block.cameras.size() == 1 ? " camera); " : " cameras); ",
      result.rejected.size(),
      " observations rejected",
      outputs.check_rms_m > 0
          ? StrCat("; check points RMS ", 1000 * outputs.check_rms_m, " mm")
          : std::string(),
      "; ",
      result.total_time_s,
      " s -> ",
      output_path));
  return 0;
}

}  // namespace bayon
