// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon relative`: the relative orientation (relative_orientation.h) of
// every matched image pair of a COLMAP database, from COLMAP's matches (and
// the sub-pixel conjugate points of bayon_matches where `bayon match` wrote
// them, each point weighted by its standard deviation there), with each
// image's interior orientation (image_vectors.h).
//
// Written per oriented pair: COLMAP's two_view_geometries row (the inlier
// matches, E and F, config CALIBRATED where both focal lengths are known
// and UNCALIBRATED otherwise, qvec/tvec = cam2_from_cam1 with |t| = 1), so
// that stock `colmap mapper` takes over from here; and the
// bayon_relative_orientation row (ext/colmap/table_relative.h). A pair that
// cannot be oriented gets only its bayon row, with the reason, and no
// two-view geometry: never anything half-done.
//
// A camera whose focal length is unknown (no bayon_calibration, no EXIF or
// given lens: COLMAP's guess of 1.2 x the long side) first gets one from the
// photographs: from its strongest pairs (the most matches) by
// focal_length.h. The estimate replaces the guess in the cameras table, with
// COLMAP's prior_focal_length flag set, and the pairs are then oriented as
// calibrated, so that strip can chain them and adjust refines the focal
// length with everything else. A camera whose focal length the photographs
// do not fix keeps its guess, with the reason in the log; its pairs stay
// uncalibrated.
#pragma once

#include "ext/colmap/database.h"
#include "ext/colmap/table_matches.h"
#include "ext/orientation/focal_length.h"
#include "ext/orientation/image_vectors.h"
#include "ext/orientation/relative_orientation.h"

#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct RelativeOptions {
  RelativeOrientationOptions estimation;
  // The paper's start: camera constant and principal point only, all
  // distortion parameters zero (image_vectors.h).
  bool assume_zero_distortion = false;
  // Use bayon_matches' sub-pixel conjugate points where they exist (else
  // the keypoint positions).
  bool use_subpixel_points = true;
  // Re-orient pairs that have a two-view geometry or a bayon row already.
  bool overwrite = false;
  // Estimate unknown focal lengths (above) from at most this many pairs of
  // the camera.
  bool estimate_focal_length = true;
  int focal_max_num_pairs = 20;
  FocalLengthOptions focal;
  int num_threads = -1;  // pairs in parallel; -1 = all cores
  // Every field but the focal length estimation's; the estimation's
  // without a prefix.
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct PairOrientationReport {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  std::string name1, name2;
  bool oriented = false;
  bool skipped = false;
  std::string reason;
  bool calibrated = false;
  bool subpixel = false;
  int num_matches = 0;
  int num_inliers = 0;
  int num_blunders = 0;
  // Matches of two coded targets; anchored: they oriented the pair first
  // and the other matches joined where they agreed.
  int num_target_points = 0;
  bool anchored_by_targets = false;
  double sigma0_px = 0;
  double convergence_angle_deg = 0;
  double median_intersection_angle_deg = 0;
  Eigen::Vector3d omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d std_omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  Eigen::Vector2d std_base_deg = Eigen::Vector2d::Zero();
  Rigid3d cam2_from_cam1;
  double seconds = 0;
};

// A camera's focal length estimated from the photographs.
struct FocalLengthReport {
  camera_t camera_id = kInvalidCameraId;
  double guess_px = 0;  // COLMAP's
  FocalLengthEstimate estimate;
  double seconds = 0;
};

struct RelativeSummary {
  std::vector<FocalLengthReport> focal_lengths;
  std::vector<PairOrientationReport> pairs;
  int num_oriented = 0;
  int num_failed = 0;
  int num_skipped = 0;
  double seconds = 0;
};

// The conjugate points of one pair as image vectors. `rows` receives, per
// point, its row in `matches` (rows whose pixels the camera model cannot
// invert are left out).
ConjugatePoints PairConjugatePoints(const FeatureKeypoints& keypoints1,
                                    const FeatureKeypoints& keypoints2,
                                    const FeatureMatches& matches,
                                    const std::optional<MatchRecord>& record,
                                    const ImageVectors& vectors1,
                                    const ImageVectors& vectors2,
                                    std::vector<int>* rows);

// Orients the pairs. Bad input throws InputError before anything is
// written (no images, no matched pairs, a camera that cannot be used); a
// pair that cannot be oriented is reported, the others are still done. If
// none can be (photographs that do not overlap), InputError after them,
// naming the pair with the most matches and what stopped it.
// What was oriented, in one line, after the focal lengths estimated.
std::string RelativeSummaryLine(const RelativeSummary& summary);

RelativeSummary OrientImagePairs(const std::string& database_path,
                                 const RelativeOptions& options);

}  // namespace bayon
