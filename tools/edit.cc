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
  std::string method_name = "surface_fit";
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
  app.add_option("--method", method_name, "surface_fit, statistical, radius")
      ->transform(CLI::IsMember({"surface_fit", "statistical", "radius"}));
  app.add_option("--num_neighbors",
                 options.surface_fit.num_neighbors,
                 "surface_fit: neighbours per second-order patch");
  app.add_option("--num_iterations",
                 options.surface_fit.num_iterations,
                 "surface_fit: passes of fitting and testing (paper: 3-5)");
  app.add_option("--max_deviation_sigma",
                 options.surface_fit.max_deviation_sigma,
                 "surface_fit: delete beyond this many standard deviations");
  app.add_option("--max_deviation_m",
                 options.surface_fit.max_deviation_m,
                 "surface_fit: delete beyond this distance, metres (0 = off)");
  app.add_option("--num_close_neighbors",
                 options.surface_fit.num_close_neighbors,
                 "surface_fit: the close test, against the plane of this "
                 "many nearest points (0 = off)");
  app.add_option("--max_close_deviation_sigma",
                 options.surface_fit.max_close_deviation_sigma,
                 "surface_fit: the close test's threshold, standard "
                 "deviations");
  app.add_option(
      "--use_point_precision",
      options.surface_fit.use_point_precision,
      "surface_fit: 1 = weights and sigma units from s_normal, or sx, sy, sz");
  app.add_option("--added_sigma_m",
                 options.surface_fit.added_sigma_m,
                 "surface_fit: sigma added to every stated one in quadrature, "
                 "metres (-1 = estimated from the cloud, 0 = none)");
  app.add_option("--mean_k",
                 options.statistical.mean_k,
                 "statistical: neighbours for the mean distance");
  app.add_option("--stddev_mul",
                 options.statistical.stddev_mul,
                 "statistical: threshold in standard deviations");
  app.add_option("--radius_m",
                 options.radius.radius_m,
                 "radius: search radius, metres (0 = 5 x median spacing)");
  app.add_option("--min_neighbors",
                 options.radius.min_neighbors,
                 "radius: fewest neighbours within the radius");
  app.add_option("--num_threads", options.num_threads, "-1 = all cores");
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
  options.method = ParseCloudEditMethod(method_name);
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
  write_options.comment = "bayon edit --method " + method_name;
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
