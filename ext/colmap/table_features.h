// SPDX-License-Identifier: BSD-3-Clause
//
// bayon_keypoint_interest: what the interest operator said about each
// keypoint of an image (written by `bayon features`). The keypoints
// themselves are in COLMAP's `keypoints` table, row for row in the same
// order; a record whose row count differs from the keypoints row is stale
// (the keypoints were replaced by another tool) and is ignored by readers.
#pragma once

#include "ext/colmap/bayon_tables.h"

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace bayon {

struct KeypointInterestRecord {
  std::string detector = "moravec";
  int window_size = 0;  // operator window, pixels
  int patch_size = 0;   // thinning patch side, pixels
  // One value per keypoint row (squared grey values, 0..255 scale).
  std::vector<float> interest;
};

extern const BayonTable kKeypointInterestTable;

void WriteKeypointInterest(Database* database,
                           image_t image_id,
                           const KeypointInterestRecord& record);
std::optional<KeypointInterestRecord> ReadKeypointInterest(Database* database,
                                                           image_t image_id);
void DeleteKeypointInterest(Database* database, image_t image_id);

// bayon_keypoint_targets: which keypoints of an image are coded targets
// (`bayon targets`, appended by `bayon features --targets_path`), by row,
// with their names and standard deviations. `bayon match` pairs them by
// name, not by correlation or descriptor. A record written for another
// number of keypoints is stale (the keypoints were replaced since) and is
// read as none.
struct KeypointTarget {
  uint32_t point2D_idx = 0;
  std::string name;
  float sigma_px = 0;
};

extern const BayonTable kKeypointTargetsTable;

void WriteKeypointTargets(Database* database,
                          image_t image_id,
                          int num_keypoints,
                          const std::vector<KeypointTarget>& targets);
std::vector<KeypointTarget> ReadKeypointTargets(Database* database,
                                                image_t image_id,
                                                int num_keypoints);
// Just the rows of an image's targets (none where the record is stale), for
// the stages that keep them out of their own use of the keypoints.
std::set<uint32_t> KeypointTargetRows(Database* database,
                                      image_t image_id,
                                      int num_keypoints);
void DeleteKeypointTargets(Database* database, image_t image_id);

}  // namespace bayon

namespace bayon {

// Removes everything that refers to an image's keypoints by index, before
// its keypoints are replaced: COLMAP's descriptors row, the matches and
// two-view geometries of every pair with this image, and the rows of every
// bayon_* table keyed by an image pair (columns image_id1, image_id2).
// Returns the number of image pairs whose matches were removed.
int DeleteKeypointDependents(Database* database, image_t image_id);

}  // namespace bayon
