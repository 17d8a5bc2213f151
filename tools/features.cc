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
  command.AddOptions(&options,
                     {{"window_size", "moravec.window_size"},
                      {"patch_size", "moravec.patch_size"},
                      {"min_interest", "moravec.min_interest"},
                      {"max_num_features", "moravec.max_num_features"},
                      {"border_px", "moravec.border_px"}});
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
