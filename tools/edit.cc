// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/cloud_edit.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace bayon {

int RunEdit(int argc, char** argv) {
  std::string input_path, output_path, removed_path, report_path, log_path;
  bool overwrite = false;
  CloudEditOptions options;
  CommandLine command(
      "edit",
      "Remove blunders from a dense point cloud without smoothing it: "
      "iterative local second-order surface fitting (Fua and Sander 1992, as "
      "adapted in the Bayon paper, sec. 3.4), weighted by the points' own "
      "precision (s_normal, or sx, sy, sz); or PCL's statistical / radius "
      "outlier removal "
      "for comparison. Kept points are written unchanged.");
  CLI::App& app = command.app();
  app.add_option("--input_path", input_path, "Point cloud (PLY)")->required();
  app.add_option("--output_path", output_path, "Edited cloud (PLY)")
      ->required();
  command.AddOptions(
      &options,
      {{"num_neighbors", "surface_fit.num_neighbors"},
       {"num_iterations", "surface_fit.num_iterations"},
       {"max_deviation_sigma", "surface_fit.max_deviation_sigma"},
       {"max_deviation_m", "surface_fit.max_deviation_m"},
       {"num_close_neighbors", "surface_fit.num_close_neighbors"},
       {"max_close_deviation_sigma", "surface_fit.max_close_deviation_sigma"},
       {"use_point_precision", "surface_fit.use_point_precision"},
       {"added_sigma_m", "surface_fit.added_sigma_m"},
       {"mean_k", "statistical.mean_k"},
       {"stddev_mul", "statistical.stddev_mul"},
       {"radius_m", "radius.radius_m"},
       {"min_neighbors", "radius.min_neighbors"}});
  app.add_option("--removed_path",
                 removed_path,
                 "Also write the removed points here (PLY, attribute "
                 "edit_reason: 1 sigma, 2 absolute, 3 statistical, 4 radius, "
                 "5 close)");
  app.add_option(
      "--report_path", report_path, "Write the report (per pass) as JSON");
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/edit.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(input_path, "--input_path");
  CheckOutputPath(output_path, overwrite);
  if (!removed_path.empty()) CheckOutputPath(removed_path, overwrite);
  if (!report_path.empty()) CheckOutputPath(report_path, overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(output_path), "edit");
  }
  command.StartLog(log_path);

  const PointCloud cloud = ReadPointCloudPly(input_path);
  CloudEditReport report;
  const PointCloud edited = EditPointCloud(cloud, options, &report, input_path);
  if (edited.empty()) {
    throw RunFailure(StrCat(input_path, ": the edit removed every point"));
  }
  PlyWriteOptions write_options;
  write_options.comment =
      "bayon edit --method " + CloudEditMethodName(options.method);
  std::filesystem::create_directories(
      std::filesystem::absolute(output_path).parent_path());
  WritePointCloudPly(edited, output_path, write_options);
  if (!removed_path.empty()) {
    PointCloud removed = cloud;
    PointAttribute& reason =
        removed.AddAttribute("edit_reason", PlyScalarType::kUChar);
    std::vector<bool> is_removed(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      reason.values[i] = static_cast<double>(report.reasons[i]);
      is_removed[i] = report.reasons[i] != EditReason::kKept;
    }
    removed.Filter(is_removed);
    WritePointCloudPly(removed, removed_path, write_options);
  }
  if (!report_path.empty()) {
    WriteFileAtomically(report_path,
                        CloudEditReportJson(report, input_path).dump(2) + "\n");
  }
  command.PrintSummary(report.Summary() + "\n  -> " + output_path);
  return 0;
}

}  // namespace bayon
