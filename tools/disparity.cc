// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/disparity.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <algorithm>
#include <vector>

namespace bayon {

int RunDisparity(int argc, char** argv) {
  std::string database_path, log_path;
  DisparityOptions options;
  DisparitySurfaceOptions& surface = options.surface;
  CommandLine command(
      "disparity",
      "Disparity surfaces of every oriented pair, both directions: inverse "
      "depth over the first image on a grid of bilinear cells with a "
      "thin-plate smoothness chosen by cross-validation, fitted robustly to "
      "the inlier conjugate points; the search band along the epipolar line "
      "from the cross-validated prediction errors, the nearest points' "
      "inverse depths and a depth tolerance for unsampled relief. Writes "
      "bayon_disparity_surfaces.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--use_subpixel_points",
                 options.use_subpixel_points,
                 "1: use bayon_matches' sub-pixel conjugate points");
  app.add_option("--points_per_cell",
                 surface.points_per_cell,
                 "Grid cell size: conjugate points per cell");
  app.add_option("--cell_size_factors",
                 surface.cell_size_factors,
                 "Cell sizes tried by cross-validation (times the above)");
  app.add_option("--max_cells",
                 surface.max_cells,
                 "Most cells along the longer image side");
  app.add_option("--smoothness_candidates",
                 surface.smoothness_candidates,
                 "Smoothness weights tried by cross-validation");
  app.add_option("--num_folds", surface.num_folds, "Cross-validation folds");
  app.add_option("--blunder_threshold",
                 surface.blunder_threshold,
                 "Tukey constant / blunder limit, local robust sigmas");
  app.add_option("--band_quantile",
                 surface.band_quantile,
                 "Share of cross-validated predictions the band holds");
  app.add_option("--min_band_k",
                 surface.min_band_k,
                 "Smallest band half width, local sigmas");
  app.add_option(
      "--min_sigma_px", surface.min_sigma_px, "Smallest local sigma, pixels");
  app.add_option("--depth_tolerance",
                 surface.depth_tolerance,
                 "Unsampled relief the band holds, share of the depth");
  app.add_option("--range_neighbors",
                 surface.range_neighbors,
                 "Nearest points whose inverse depths the band holds");
  app.add_option("--gradient_factor",
                 surface.gradient_factor,
                 "Band growth with disparity gradient times data distance");
  app.add_option("--support_radius_spacings",
                 surface.support_radius_spacings,
                 "Supported within this many point spacings of the data");
  app.add_option("--growth_px_per_px",
                 surface.growth_px_per_px,
                 "Band growth off the supported region, px per px");
  app.add_option("--min_num_points",
                 surface.min_num_points,
                 "Pairs with fewer usable points get no surface");
  app.add_option("--seed", surface.seed, "Seed of the cross-validation folds");
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: fit pairs that have a current surface again");
  app.add_option(
      "--num_threads", options.num_threads, "Threads (-1 = all cores)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/disparity.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "disparity"));

  const DisparitySummary summary = FitDisparitySurfaces(database_path, options);
  std::vector<double> bands, shares;
  int64_t num_used = 0, num_blunders = 0;
  for (const DisparityReport& report : summary.surfaces) {
    if (!report.fitted) continue;
    num_used += report.num_used;
    num_blunders += report.num_blunders;
    bands.push_back(report.median_band_px);
    if (report.median_range_px > 0) {
      shares.push_back(100 * report.median_band_px / report.median_range_px);
    }
  }
  const auto median = [](std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::nth_element(
        values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  command.PrintSummary(StrCat(summary.num_fitted,
                              " surfaces fitted for ",
                              summary.num_pairs,
                              " oriented pairs (",
                              num_used,
                              " points used, ",
                              num_blunders,
                              " blunders; median band ",
                              median(bands),
                              " px, ",
                              median(shares),
                              " % of the epipolar line), ",
                              summary.num_failed,
                              " not fitted, ",
                              summary.num_skipped,
                              " skipped, ",
                              summary.seconds,
                              " s -> ",
                              database_path));
  return summary.num_fitted + summary.num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
