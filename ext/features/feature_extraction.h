// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon features`: interest points for every image of a COLMAP database,
// written to COLMAP's `keypoints` table (N x 6 rows, the form COLMAP
// writes), by one of three detectors:
// - moravec: the paper's Moravec points (moravec.h), identity affine shape,
//   no descriptors; `bayon match` matches them by correlation on the images
//   themselves (ext/matching);
// - sift: SIFT keypoints and RootSIFT descriptors (sift.h), matched by
//   descriptor; COLMAP's own matchers read them too;
// - both: the Moravec points, then the SIFT keypoints, with descriptors for
//   all (upright ones for the Moravec points), so that COLMAP's matchers can
//   still run on the database.
// bayon_keypoint_interest holds a value per keypoint row: the Moravec
// interest, or NaN for a SIFT keypoint (which `bayon match` then matches by
// its descriptor, not by correlation).
#pragma once

#include "ext/core/types.h"
#include "ext/features/moravec.h"
#include "ext/features/sift.h"

#include <optional>
#include <string>
#include <vector>

namespace bayon {

enum class FeatureDetector { kMoravec, kSift, kBoth };
const char* FeatureDetectorName(FeatureDetector detector);

struct FeatureExtractionOptions {
  FeatureDetector detector = FeatureDetector::kMoravec;
  MoravecOptions moravec;
  SiftOptions sift;
  // Replace the keypoints of images that have some. Replacing keypoints
  // invalidates everything indexed by them, so the image's descriptors and
  // the matches, two-view geometries and bayon pair rows of its pairs are
  // deleted with them. Without it such images are skipped.
  bool overwrite = false;
  // Coded targets measured by `bayon targets` (NAME IMAGE X Y SIGMA lines):
  // appended to each image's keypoints, where `bayon match` pairs them by
  // name (bayon_keypoint_targets). Empty: none.
  std::string targets_path;
  int num_threads = -1;  // images in parallel; -1 = all cores
  // Every field, the detectors' as moravec.* and sift.*.
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct ImageFeatureResult {
  image_t image_id = kInvalidImageId;
  std::string name;
  int width = 0;
  int height = 0;
  int patch_size = 0;  // the thinning patch side used
  int num_features = 0;
  int num_sift = 0;     // of num_features
  int num_targets = 0;  // of num_features
  double seconds = 0;
  bool skipped = false;
  std::string reason;  // why it was skipped
};

struct FeatureExtractionSummary {
  std::vector<ImageFeatureResult> images;  // in image_id order
  int num_extracted = 0;
  int num_skipped = 0;
  int64_t num_features = 0;
  int64_t num_sift = 0;           // of num_features
  int64_t num_targets = 0;        // of num_features
  int num_pairs_invalidated = 0;  // pairs whose matches were removed
  double seconds = 0;
};

// The keypoints of one image as `bayon features` writes them.
struct ImageFeatures {
  FeatureKeypoints keypoints;      // N x 6
  FeatureDescriptors descriptors;  // N x 128, or empty (moravec)
  std::vector<float> interest;     // per row; NaN for SIFT keypoints
  int num_sift = 0;
};

// The features of one image file (any size, depth and channel count that
// OpenCV reads; colour is reduced to luminance). Throws InputError for an
// unreadable file.
ImageFeatures DetectImageFeatures(const std::string& image_file,
                                  const FeatureExtractionOptions& options);

// Runs the operator on every image of the database. Everything is checked
// before anything is written (InputError, database unchanged): the database
// has images, every image exists under `image_path` with its camera's size.
// All rows are written in one transaction at the end.
FeatureExtractionSummary ExtractFeatures(
    const std::string& database_path,
    const std::string& image_path,
    const FeatureExtractionOptions& options);

}  // namespace bayon
