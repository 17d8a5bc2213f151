// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/features/feature_extraction.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunFeatures(int argc, char** argv) {
  std::string database_path, image_path, log_path, detector = "moravec";
  FeatureExtractionOptions options;
  MoravecOptions& moravec = options.moravec;
  SiftOptions& sift = options.sift;
  CommandLine command(
      "features",
      "Interest points for every image of a COLMAP database: the paper's "
      "Moravec points (matched by correlation), SIFT keypoints with RootSIFT "
      "descriptors (matched by descriptor), or both; written to its keypoints "
      "and descriptors tables, the interest values to "
      "bayon_keypoint_interest.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
  app.add_option("--detector", detector, "moravec, sift or both")
      ->transform(CLI::IsMember({"moravec", "sift", "both"}));
  app.add_option("--window_size",
                 moravec.window_size,
                 "Operator window side, pixels (odd)");
  app.add_option("--patch_size",
                 moravec.patch_size,
                 "Thinning patch side, pixels; 0 = from max_num_features");
  app.add_option("--min_interest",
                 moravec.min_interest,
                 "Smallest interest value kept (squared grey values, 0..255)");
  app.add_option("--max_num_features",
                 moravec.max_num_features,
                 "At most this many points per image (0 = no limit)");
  app.add_option(
      "--border_px", moravec.border_px, "No points this close to the border");
  app.add_option("--sift.max_num_features",
                 sift.max_num_features,
                 "SIFT: at most this many keypoints per image, the strongest");
  app.add_option("--sift.contrast_threshold",
                 sift.contrast_threshold,
                 "SIFT: smallest DoG contrast kept (OpenCV's units)");
  app.add_option("--sift.edge_threshold",
                 sift.edge_threshold,
                 "SIFT: largest ratio of principal curvatures kept");
  app.add_option("--sift.max_image_size",
                 sift.max_image_size,
                 "SIFT: longer images are reduced to this first (0 = never)");
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: replace existing keypoints (drops their matches)");
  app.add_option("--targets_path",
                 options.targets_path,
                 "Coded targets of `bayon targets`, appended as keypoints "
                 "that match pairs by name");
  app.add_option(
      "--num_threads", options.num_threads, "Images in parallel (-1 = all)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/features.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.detector = *FeatureDetectorFromName(detector);
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "features"));

  const FeatureExtractionSummary summary =
      ExtractFeatures(database_path, image_path, options);
  command.PrintSummary(StrCat(summary.num_extracted,
                              " images, ",
                              summary.num_features,
                              " points (",
                              summary.num_extracted > 0
                                  ? summary.num_features / summary.num_extracted
                                  : 0,
                              " per image, ",
                              summary.num_sift,
                              " SIFT, ",
                              summary.num_targets,
                              " targets), ",
                              summary.num_skipped,
                              " skipped, ",
                              summary.num_pairs_invalidated,
                              " pairs' matches removed, ",
                              summary.seconds,
                              " s -> ",
                              database_path));
  return summary.num_extracted + summary.num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
