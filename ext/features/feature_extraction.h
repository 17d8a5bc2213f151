// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon features`: Moravec interest points (moravec.h) for every image of a
// COLMAP database, written to COLMAP's `keypoints` table (N x 6 rows, the
// form COLMAP writes, with an identity affine shape) and the interest values
// to bayon_keypoint_interest. No descriptors are written: bayon matches by
// correlation on the images themselves (ext/matching).
#pragma once

#include "ext/core/types.h"
#include "ext/features/moravec.h"

#include <string>
#include <vector>

namespace bayon {

struct FeatureExtractionOptions {
  MoravecOptions moravec;
  // Replace the keypoints of images that have some. Replacing keypoints
  // invalidates everything indexed by them, so the image's descriptors and
  // the matches, two-view geometries and bayon pair rows of its pairs are
  // deleted with them. Without it such images are skipped.
  bool overwrite = false;
  int num_threads = -1;  // images in parallel; -1 = all cores
  void Check() const;
};

struct ImageFeatureResult {
  image_t image_id = kInvalidImageId;
  std::string name;
  int width = 0;
  int height = 0;
  int patch_size = 0;  // the thinning patch side used
  int num_features = 0;
  double seconds = 0;
  bool skipped = false;
  std::string reason;  // why it was skipped
};

struct FeatureExtractionSummary {
  std::vector<ImageFeatureResult> images;  // in image_id order
  int num_extracted = 0;
  int num_skipped = 0;
  int64_t num_features = 0;
  int num_pairs_invalidated = 0;  // pairs whose matches were removed
  double seconds = 0;
};

// Interest points of one image file (any size, depth and channel count that
// OpenCV reads; colour is reduced to luminance). Throws InputError for an
// unreadable file.
std::vector<InterestPoint> DetectImageFeatures(const std::string& image_file,
                                               const MoravecOptions& options);

// Runs the operator on every image of the database. Everything is checked
// before anything is written (InputError, database unchanged): the database
// has images, every image exists under `image_path` with its camera's size.
// All rows are written in one transaction at the end.
FeatureExtractionSummary ExtractFeatures(
    const std::string& database_path,
    const std::string& image_path,
    const FeatureExtractionOptions& options);

}  // namespace bayon
