// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon match`: conjugate points for the selected image pairs of a COLMAP
// database (pair_selection.h), from the keypoints already in the database
// (`bayon features`, or any other detector's):
// - keypoints with a Moravec interest value (bayon_keypoint_interest), and
//   every keypoint of an image without descriptors, by correlation and
//   relaxation on the images themselves (correlation_matcher.h);
// - the others, which have descriptors (SIFT: `bayon features --detector
//   sift|both`, or COLMAP's feature_extractor), by descriptor
//   (descriptor_matcher.h).
// Written to COLMAP's `matches` table and, with the sub-pixel conjugate
// points and the pair's rotation, to bayon_matches
// (ext/colmap/table_matches.h).
#pragma once

#include "ext/core/types.h"
#include "ext/matching/conjugate_refinement.h"
#include "ext/matching/correlation_matcher.h"
#include "ext/matching/descriptor_matcher.h"
#include "ext/matching/image_retrieval.h"
#include "ext/matching/pair_selection.h"

#include <string>
#include <vector>

namespace bayon {

struct MatchingOptions {
  PairingOptions pairing;
  RetrievalOptions retrieval;  // where the pairing chooses by similarity
  PatchOptions patches;
  CorrelationMatchingOptions correlation;
  DescriptorMatchingOptions descriptors;
  // Least-squares refinement and propagation of the conjugate points
  // (conjugate_refinement.h); off: the correlation peaks, as the paper's
  // matching gives them. Off by default: on the rendered tower it makes the
  // adjacent pairs' relative orientations 4 times more accurate, but weak
  // pairs lose matches (the temple ring's chain through tie points and
  // strip then ends less accurate; see issue 4's note).
  bool lsm_refinement = false;
  ConjugateRefinementOptions refinement;
  // Pairs with fewer conjugate points are reported and not written: the
  // relative orientation needs 8.
  int min_num_matches = 8;
  // Replace the matches of pairs that have some (and what was derived from
  // them: two-view geometry, bayon pair rows). Without it they are skipped.
  bool overwrite = false;
  int num_threads = -1;  // images, then pairs, in parallel; -1 = all cores
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct PairMatchReport {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  std::string name1, name2;
  bool written = false;
  bool skipped = false;  // had matches and no --overwrite
  std::string reason;    // why not written
  int num_points1 = 0;
  int num_points2 = 0;
  int rotation_deg = 0;
  bool mapping_found = false;
  int mapping_inliers = 0;
  int num_candidates = 0;
  int num_relaxed = 0;
  int num_descriptor_matches = 0;  // of num_matches
  int num_target_matches = 0;      // of num_matches: coded targets, by name
  int num_matches = 0;
  // Least-squares refinement: matches it rejected (kept at their
  // correlation peaks, or dropped) by reason, the median move from the
  // peaks, and the matches propagation added.
  ConjugateRefinementReport refinement;
  double seconds = 0;
};

struct MatchingSummary {
  std::vector<PairMatchReport> pairs;
  int num_written = 0;
  int num_failed = 0;
  int num_skipped = 0;
  int64_t num_matches = 0;
  double seconds = 0;
};

// Matches the pairs and writes them (in transactions of a few pairs each,
// so an interrupted run keeps what it finished). Bad input throws
// InputError before anything is written: no images, no keypoints at all,
// images missing on disk or of another size than their camera, a bad pair
// list. A pair that cannot be matched is reported with its reason; the
// other pairs are still done.
MatchingSummary MatchImages(const std::string& database_path,
                            const std::string& image_path,
                            const MatchingOptions& options);

}  // namespace bayon
