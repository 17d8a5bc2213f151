// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/matching/matching.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <map>

namespace bayon {

namespace {

// The flags of the nested options before they took their dotted names,
// still accepted (configs, scripts): old name -> name.
const std::map<std::string, std::string> kFlagsBefore = {
    {"pairing", "pairing.mode"},
    {"max_exhaustive_images", "pairing.max_exhaustive_images"},
    {"retrieval_neighbors", "pairing.retrieval_neighbors"},
    {"num_neighbors", "pairing.num_neighbors"},
    {"pair_list_path", "pairing.pair_list_path"},
    {"window_size", "patches.window_size"},
    {"refine_radius", "patches.refine_radius"},
    {"min_ncc", "correlation.min_ncc"},
    {"search_window_fraction", "correlation.search_window_fraction"},
    {"max_keypoint_shift_px", "correlation.max_keypoint_shift_px"},
    {"max_candidates_per_point", "correlation.max_candidates_per_point"},
    {"detect_rotation", "correlation.detect_rotation"},
    {"num_passes", "correlation.num_passes"},
    {"neighborhood_fraction", "correlation.relaxation.neighborhood_fraction"},
    {"min_support", "correlation.relaxation.min_support"},
    {"lsm_max_sigma_px", "refinement.max_sigma_px"},
    {"lsm_keep_unrefined", "refinement.keep_unrefined"},
    {"propagation_rounds", "refinement.propagation_rounds"},
    {"max_keypoint_distance_px", "refinement.max_keypoint_distance_px"}};

}  // namespace

int RunMatch(int argc, char** argv) {
  std::string database_path, image_path, log_path;
  MatchingOptions options;
  CommandLine command(
      "match",
      "Conjugate points for image pairs: Moravec points by correlation (7x7 "
      "windows, r >= 0.75, search window 1/16 of the image) and relaxation "
      "(continuity, uniqueness, loser-takes-nothing), with in-plane "
      "rotations of 90/180 degrees found automatically; keypoints with "
      "descriptors (SIFT) by descriptor (ratio test, mutual best): to "
      "COLMAP's matches table, sub-pixel points to bayon_matches.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
  command.AddOptions(&options, kFlagsBefore);
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/match.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  if (options.pairing.mode == PairingMode::kList) {
    CheckFileExists(options.pairing.pair_list_path, "--pairing.pair_list_path");
  }
  command.StartLog(DatabaseLogPath(log_path, database_path, "match"));

  const MatchingSummary summary =
      MatchImages(database_path, image_path, options);
  command.PrintSummary(StrCat(summary.num_written,
                              " pairs matched (",
                              summary.num_matches,
                              " matches), ",
                              summary.num_failed,
                              " failed, ",
                              summary.num_skipped,
                              " skipped, ",
                              summary.seconds,
                              " s -> ",
                              database_path));
  return summary.num_written + summary.num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
