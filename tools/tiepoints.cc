// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/matching/tie_points.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <cstdio>

namespace bayon {

int RunTiePoints(int argc, char** argv) {
  std::string database_path, image_path, colmap_output_path, report_path,
      log_path;
  bool overwrite = false;
  TiePointOptions options;
  CommandLine command(
      "tiepoints",
      "Automatic multi-image tie points: interest points spread over every "
      "image, followed through the disparity surfaces into as many images "
      "as possible (cross-correlation in the epipolar band, then adaptive "
      "least-squares matching of the reference patch, affine + 2 "
      "radiometric parameters; blunder checks: convergence, sigma0, "
      "precision, shape, back-matching, epipolar lines of the other "
      "observations). Manual measurements are merged. Writes "
      "bayon_tie_points and bayon_tie_observations; with "
      "--colmap_output_path also a COLMAP database of the tie points "
      "(keypoints + matches) for colmap point_triangulator / mapper.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
  app.add_option("--colmap_output_path",
                 colmap_output_path,
                 "Also write the tie points as a new COLMAP database here");
  app.add_option("--overwrite", overwrite, "1: replace an existing export");
  command.AddOptions(&options,
                     {{"patch_radius", "matching.lsm.patch_radius"},
                      {"max_sigma0", "matching.max_sigma0"},
                      {"min_correlation", "matching.min_correlation"},
                      {"max_sigma_px", "matching.max_sigma_px"},
                      {"max_shift_px", "matching.max_shift_px"},
                      {"max_backmatch_px", "matching.max_backmatch_px"}});
  app.add_option("--report_path", report_path, "Write the summary as JSON");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/tiepoints.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  // Not a COLMAP database: one line, before a log appears beside it.
  Database(database_path, Database::Mode::kReadOnly);
  command.StartLog(DatabaseLogPath(log_path, database_path, "tiepoints"));

  const TiePointSummary summary = FindTiePoints(
      database_path, image_path, colmap_output_path, overwrite, options);
  if (!report_path.empty()) {
    WriteFileAtomically(report_path,
                        TiePointSummaryJson(summary).dump(2) + "\n");
  }
  std::printf("%s", TiePointTables(summary).c_str());
  std::fflush(stdout);
  command.PrintSummary(StrCat(TiePointSummaryLine(summary),
                              colmap_output_path.empty()
                                  ? std::string()
                                  : StrCat(", COLMAP export of ",
                                           summary.colmap_pairs,
                                           " pairs -> ",
                                           colmap_output_path),
                              ", ",
                              summary.seconds,
                              " s -> ",
                              database_path));
  const int num_named = summary.num_manual_points + summary.num_target_points;
  return summary.num_points + num_named > 0 ? 0 : 1;
}

}  // namespace bayon
