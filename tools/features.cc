// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/features/feature_extraction.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunFeatures(int argc, char** argv) {
  std::string database_path, image_path, log_path;
  FeatureExtractionOptions options;
  MoravecOptions& moravec = options.moravec;
  CommandLine command(
      "features",
      "Moravec interest points, thinned to the strongest per patch, for every "
      "image of a COLMAP database: written to its keypoints table, the "
      "interest values to bayon_keypoint_interest.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
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
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: replace existing keypoints (drops their matches)");
  app.add_option(
      "--num_threads", options.num_threads, "Images in parallel (-1 = all)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/features.log)");
  if (!command.Parse(argc, argv)) return 0;
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
                              " per image), ",
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
