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
  app.add_option("--manual_path",
                 options.manual_path,
                 "Manual image measurements: NAME IMAGE_NAME X Y [SIGMA]");
  app.add_option("--manual_sigma_px",
                 options.manual_sigma_px,
                 "Sigma of manual measurements without one, pixels");
  app.add_option("--targets_path",
                 options.targets_path,
                 "Coded targets' measurements (bayon targets --output_path): "
                 "named tie points beside the manual ones");
  app.add_option("--grid_cols", options.grid_cols, "Candidate grid columns");
  app.add_option("--grid_rows", options.grid_rows, "Candidate grid rows");
  app.add_option("--candidates_per_cell",
                 options.candidates_per_cell,
                 "Best-textured keypoints per grid cell");
  app.add_option("--min_texture_score",
                 options.min_texture_score,
                 "Weakest patch texture followed (grey^2 / px^2)");
  app.add_option("--correlation_radius",
                 options.correlation_radius,
                 "Half side of the correlation window, pixels");
  app.add_option(
      "--min_ncc", options.min_ncc, "Smallest correlation peak accepted");
  app.add_option("--min_ncc_margin",
                 options.min_ncc_margin,
                 "Margin of the best peak over any other");
  app.add_option("--max_peaks",
                 options.max_peaks,
                 "Correlation peaks tried by least-squares matching");
  app.add_option("--across_px",
                 options.across_px,
                 "Search +- this many pixels across the epipolar line");
  app.add_option(
      "--max_band_px", options.max_band_px, "Longer bands are not searched");
  app.add_option("--max_epipolar_px",
                 options.max_epipolar_px,
                 "Largest distance from another observation's epipolar line");
  app.add_option("--max_chain_px",
                 options.max_chain_px,
                 "Largest disagreement of the previous link's patch, pixels");
  app.add_option("--min_images", options.min_images, "Fewest images a point");
  app.add_option("--max_images", options.max_images, "Most images a point");
  app.add_option("--min_distance_px",
                 options.min_distance_px,
                 "Points closer than this in an image are one");
  command.AddOptions("matching",
                     &options.matching,
                     {{"patch_radius", "matching.lsm.patch_radius"},
                      {"max_sigma0", "matching.max_sigma0"},
                      {"min_correlation", "matching.min_correlation"},
                      {"max_sigma_px", "matching.max_sigma_px"},
                      {"max_shift_px", "matching.max_shift_px"},
                      {"max_backmatch_px", "matching.max_backmatch_px"}});
  app.add_option(
      "--num_threads", options.num_threads, "Threads (-1 = all cores)");
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
  int num_three = 0;
  for (size_t n = 3; n < summary.points_by_images.size(); ++n) {
    num_three += summary.points_by_images[n];
  }
  command.PrintSummary(
      StrCat(summary.num_points,
             " tie points (",
             num_three,
             " in 3 or more images, ",
             summary.mean_images_per_point,
             " images on average, median sigma ",
             summary.median_sigma_px,
             " px) from ",
             summary.num_followed,
             " candidates over ",
             summary.num_surfaces,
             " surfaces",
             summary.num_manual_points > 0
                 ? StrCat(", ", summary.num_manual_points, " manual points")
                 : std::string(),
             summary.num_target_points > 0
                 ? StrCat(", ", summary.num_target_points, " coded targets")
                 : std::string(),
             colmap_output_path.empty() ? std::string()
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
