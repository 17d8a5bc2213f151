// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/dense/dense_stage.h"
#include "ext/georef/crs.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The flags of the nested options before they took their dotted names,
// still accepted (configs, scripts): old name -> name.
const std::map<std::string, std::string> kFlagsBefore = {
    {"patch_match_window_radius", "patch_match.window_radius"},
    {"patch_match_window_step", "patch_match.window_step"},
    {"patch_match_iterations", "patch_match.num_iterations"},
    {"patch_match_levels", "patch_match.num_levels"},
    {"patch_match_candidates", "patch_match.num_propagation_candidates"},
    {"patch_match_best_views", "patch_match.best_views"},
    {"edge_margin_px", "fusion.edge_margin_px"},
    {"min_consistent_views", "fusion.min_consistent_views"},
    {"max_depth_error_px", "fusion.max_depth_error_px"},
    {"max_normal_error_deg", "fusion.max_normal_error_deg"},
    {"max_cost", "fusion.max_cost"},
    {"window_radius", "search.window_radius"},
    {"search_step_px", "search.step_px"},
    {"search_stride", "search.stride"},
    {"min_ncc", "search.min_ncc"},
    {"best_views", "search.best_views"},
    {"patch_radius", "mpgc.lsm.patch_radius"},
    {"min_template_stddev", "mpgc.lsm.min_template_stddev"},
    {"min_correlation", "mpgc.min_correlation"},
    {"min_search_views", "mpgc.min_search_views"},
    {"geometric_sigma_px", "mpgc.geometric_sigma_px"},
    {"convergence_px", "mpgc.convergence_px"},
    {"convergence_sigma", "mpgc.convergence_sigma"},
    {"max_iterations", "mpgc.max_iterations"},
    {"max_shift_px", "mpgc.max_shift_px"}};

}  // namespace

int RunDense(int argc, char** argv) {
  OrientedInput in;
  std::string output_path, fused_path, report_path, log_path;
  bool overwrite = false;
  DenseOptions options;
  CommandLine command(
      "dense",
      "Dense surface points by multi-photo geometrically constrained "
      "matching (MPGC, the Bayon paper's sec. 3.3) on the CPU. multiview "
      "(default): every photograph a master, a depth and a normal for every "
      "pixel by propagating plane hypotheses (PatchMatch), the depth maps "
      "fused where they agree, then MPGC of every fused point against the "
      "views that confirmed it. paper: the paper's sampling, a Moravec "
      "point per cell of a few masters, approximations by correlation along "
      "the master rays, then MPGC. Both give X, Y, Z with their standard "
      "deviations. Writes a PLY (normals, colours, sx sy sz, num_images, "
      "master_id) and COLMAP's fused.ply + fused.ply.vis beside it.");
  CLI::App& app = command.app();
  in.AddOptions(app,
                "Workspace: defaults images/, sparse/adjusted, database.db "
                "and dense/points.ply under it");
  app.add_option("--output_path", output_path, "Dense cloud (PLY)");
  app.add_option("--fused_path",
                 fused_path,
                 "COLMAP fused.ply (default: beside --output_path)");
  app.add_option("--report_path",
                 report_path,
                 "Report as JSON (default: --output_path with .json)");
  command.AddOptions(&options, kFlagsBefore);
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/dense.log)");
  if (!command.Parse(argc, argv)) return 0;
  if (in.ApplyWorkspace() && output_path.empty()) {
    output_path = in.workspace_path + "/dense/points.ply";
  }
  if (in.image_path.empty() || in.input_path.empty() || output_path.empty()) {
    ThrowInputError(
        "give --workspace_path, or --image_path, --input_path and "
        "--output_path");
  }
  options.Check();
  in.Check();
  DenseOutputPaths paths{output_path, fused_path, report_path};
  const fs::path output_folder = fs::absolute(output_path).parent_path();
  if (paths.fused.empty()) paths.fused = (output_folder / "fused.ply").string();
  if (paths.report.empty()) {
    paths.report = fs::path(output_path).replace_extension(".json").string();
  }
  for (const std::string& path : {paths.cloud, paths.fused, paths.report}) {
    CheckOutputPath(path, overwrite);
  }
  CheckOutputPath(paths.fused + ".vis", overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(output_path), "dense");
  }
  command.StartLog(log_path);

  const Scene scene = ReadOrientedModel(in.input_path, in.database_path);
  const DenseResult result = RunDense(scene, in.image_path, options);
  WriteDenseOutputs(scene, in.image_path, result, options, paths);
  CopyGeoFrame(in.input_path, output_folder.string());
  std::string left_out;
  for (const auto& [id, error] : result.unreadable) {
    left_out += "\n  left out: " + error;
  }
  command.PrintSummary(result.report.Summary() + left_out + "\n  -> " +
                       paths.cloud + ", " + paths.fused + ", " +
                       paths.RejectsFolder() + "/");
  return 0;
}

}  // namespace bayon
