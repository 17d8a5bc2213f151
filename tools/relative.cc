// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/relative.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunRelative(int argc, char** argv) {
  std::string database_path, log_path, residual = "sampson";
  RelativeOptions options;
  RelativeOrientationOptions& estimation = options.estimation;
  CommandLine command(
      "relative",
      "Relative orientation of every matched pair: the DRT (Chang 1986) "
      "solved linearly, LMedS over 1024 random 8-point samples, 2.5-sigma "
      "blunder weights, weighted least squares, then the rigorous "
      "coplanarity adjustment of the five elements. Writes COLMAP's "
      "two_view_geometries and bayon_relative_orientation.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--assume_zero_distortion",
                 options.assume_zero_distortion,
                 "1: camera constant and principal point only (the paper's "
                 "start)");
  app.add_option("--use_subpixel_points",
                 options.use_subpixel_points,
                 "1: use bayon_matches' sub-pixel conjugate points");
  app.add_option("--num_samples",
                 estimation.num_samples,
                 "LMedS random 8-point samples (m)");
  app.add_option("--blunder_threshold",
                 estimation.blunder_threshold,
                 "Blunder threshold, robust sigmas");
  app.add_option("--residual", residual, "sampson or algebraic (eq. 2)")
      ->transform(CLI::IsMember({"sampson", "algebraic"}));
  app.add_option("--min_num_inliers",
                 estimation.min_num_inliers,
                 "Pairs with fewer inliers are not oriented");
  app.add_option("--max_sigma_px",
                 estimation.max_sigma_px,
                 "Robust sigma above this: no epipolar geometry, pixels");
  app.add_option("--min_parallax_px",
                 estimation.min_parallax_px,
                 "A rotation alone fitting this well: no base, pixels");
  app.add_option("--seed", estimation.seed, "Random seed of the samples");
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: orient pairs that were oriented before again");
  app.add_option("--estimate_focal_length",
                 options.estimate_focal_length,
                 "1: a camera without calibration or EXIF focal length gets "
                 "one from its strongest pairs before they are oriented");
  app.add_option("--focal_max_num_pairs",
                 options.focal_max_num_pairs,
                 "Pairs that estimate an unknown focal length");
  app.add_option(
      "--num_threads", options.num_threads, "Threads (-1 = all cores)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/relative.log)");
  if (!command.Parse(argc, argv)) return 0;
  estimation.residual =
      residual == "algebraic" ? DrtResidual::kAlgebraic : DrtResidual::kSampson;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "relative"));

  const RelativeSummary summary = OrientImagePairs(database_path, options);
  int64_t num_inliers = 0, num_blunders = 0;
  double sum_sigma0 = 0;
  for (const PairOrientationReport& pair : summary.pairs) {
    if (!pair.oriented) continue;
    num_inliers += pair.num_inliers;
    num_blunders += pair.num_blunders;
    sum_sigma0 += pair.sigma0_px;
  }
  std::string focal_lengths;
  for (const FocalLengthReport& focal : summary.focal_lengths) {
    focal_lengths += StrCat(
        "camera ",
        focal.camera_id,
        focal.estimate.success
            ? StrCat(": focal length ",
                     focal.estimate.focal_length_px,
                     " px +- ",
                     100 * focal.estimate.relative_sigma,
                     " % from the photographs; ")
            : StrCat(": focal length unknown, ", focal.estimate.reason, "; "));
  }
  command.PrintSummary(
      StrCat(focal_lengths,
             summary.num_oriented,
             " pairs oriented (",
             num_inliers,
             " inliers, ",
             num_blunders,
             " blunders, mean sigma0 ",
             summary.num_oriented > 0 ? sum_sigma0 / summary.num_oriented : 0.0,
             " px), ",
             summary.num_failed,
             " not oriented, ",
             summary.num_skipped,
             " skipped, ",
             summary.seconds,
             " s -> ",
             database_path));
  return 0;
}

}  // namespace bayon
