// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/matching/matching.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunMatch(int argc, char** argv) {
  std::string database_path, image_path, log_path, pairing = "auto";
  MatchingOptions options;
  CorrelationMatchingOptions& correlation = options.correlation;
  RelaxationOptions& relaxation = correlation.relaxation;
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
  app.add_option("--pairing",
                 pairing,
                 "auto (every pair up to max_exhaustive_images, else "
                 "retrieval), retrieval (the most similar photographs), "
                 "exhaustive, ring or sequential (in name order), or list")
      ->transform(CLI::IsMember(
          {"auto", "retrieval", "exhaustive", "ring", "sequential", "list"}));
  app.add_option("--max_exhaustive_images",
                 options.pairing.max_exhaustive_images,
                 "auto: every pair up to this many images");
  app.add_option("--retrieval_neighbors",
                 options.pairing.retrieval_neighbors,
                 "retrieval: each image with this many most similar ones");
  app.add_option("--retrieval.vocabulary_size",
                 options.retrieval.vocabulary_size,
                 "retrieval: visual words learnt from the set");
  app.add_option("--num_neighbors",
                 options.pairing.num_neighbors,
                 "ring/sequential: successors paired with each image");
  app.add_option("--pair_list_path",
                 options.pairing.pair_list_path,
                 "list: file of 'name1 name2' lines");
  app.add_option("--window_size",
                 options.patches.window_size,
                 "Correlation window side, pixels (odd)");
  app.add_option("--refine_radius",
                 options.patches.refine_radius,
                 "Sub-pixel search range around a matched keypoint, pixels");
  app.add_option("--min_ncc", correlation.min_ncc, "Correlation threshold r");
  app.add_option("--search_window_fraction",
                 correlation.search_window_fraction,
                 "Search window area as a fraction of the image");
  app.add_option("--max_keypoint_shift_px",
                 correlation.max_keypoint_shift_px,
                 "Image-2 windows also shifted this far from the keypoint");
  app.add_option("--max_candidates_per_point",
                 correlation.max_candidates_per_point,
                 "Candidates kept per point");
  app.add_option("--detect_rotation",
                 correlation.detect_rotation,
                 "1: find in-plane rotations by quarter turns");
  app.add_option("--num_passes",
                 correlation.num_passes,
                 "Matching passes (later ones centred on earlier matches)");
  app.add_option("--neighborhood_fraction",
                 relaxation.neighborhood_fraction,
                 "Relaxation neighbourhood radius / image size");
  app.add_option("--min_support",
                 relaxation.min_support,
                 "Consistent neighbours a match needs");
  app.add_option("--descriptors.max_ratio",
                 options.descriptors.max_ratio,
                 "Descriptor matching: nearest / second-nearest distance "
                 "below this (Lowe's ratio test)");
  app.add_option("--descriptors.max_distance",
                 options.descriptors.max_distance,
                 "Descriptor matching: largest angle between descriptors, "
                 "radians");
  app.add_option("--descriptors.cross_check",
                 options.descriptors.cross_check,
                 "Descriptor matching: 1 = mutual nearest only");
  app.add_option("--lsm_refinement",
                 options.lsm_refinement,
                 "1: conjugate points refined by least-squares matching");
  app.add_option("--lsm_max_sigma_px",
                 options.refinement.lsm.max_sigma_px,
                 "Refined points less precise than this are dropped, px");
  app.add_option("--lsm_keep_unrefined",
                 options.refinement.keep_unrefined,
                 "1: matches LSM rejects stay at their correlation peaks");
  app.add_option("--propagation_rounds",
                 options.refinement.propagation_rounds,
                 "Rounds of least-squares propagation (0: none)");
  app.add_option("--max_keypoint_distance_px",
                 options.refinement.max_keypoint_distance_px,
                 "A propagated point must lie this near an image-2 keypoint");
  app.add_option("--min_num_matches",
                 options.min_num_matches,
                 "Pairs with fewer matches are not written");
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: replace existing matches of a pair");
  app.add_option(
      "--num_threads", options.num_threads, "Threads (-1 = all cores)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/match.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.pairing.mode = *PairingModeFromName(pairing);
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  if (options.pairing.mode == PairingMode::kList) {
    CheckFileExists(options.pairing.pair_list_path, "--pair_list_path");
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
