// SPDX-License-Identifier: BSD-3-Clause
//
// Least-squares refinement of the matched keypoints of a COLMAP database
// (`bayon refine_keypoints`): the keypoints of any detector (SIFT from stock
// `colmap feature_extractor`, say) are accurate to a fraction of their
// detection scale, and each image's keypoint is found independently of the
// others, so the observations of one 3D point disagree by that much. Here
// they are made conjugate by least-squares matching (lsm.h, Gruen 1985):
//
// 1. Tracks. The verified matches (two_view_geometries inlier matches; the
//    raw `matches` where no pair was verified) link keypoints; the connected
//    components of that graph with two or more observations are the tracks,
//    as COLMAP's mapper would build them.
// 2. Reference. In each track the observation whose patch is best textured
//    (the largest smaller eigenvalue of the gradient structure tensor over
//    the patch: the precision its shifts allow in the weakest direction) is
//    the reference; it keeps its position. Where fewer than half of the
//    others match it (a reference on an occluding contour, say), the next
//    best-textured observation is tried (num_reference_candidates).
// 3. Matching. Every other observation is matched to the reference patch,
//    from its own keypoint position, with the patch shape the two keypoints'
//    affine frames predict (A_obs A_ref^-1; COLMAP stores a11 a12 a21 a22
//    for SIFT, 4-column keypoints give scale and orientation; 2-column ones
//    an identity shape): affine + 2 radiometric parameters, adaptive.
// 4. Blunder checks. An observation keeps its original position unless
//    LSM converged, sigma0 and the correlation are acceptable, the shift is
//    determined to max_sigma_px, it moved at most max_shift_px from the
//    keypoint, the shape stayed within bounds (LSM's divergence test), and
//    matching back (the refined patch against the reference image) returns
//    to the reference point within max_backmatch_px.
// 5. Output. A copy of the input database (SQLite's backup, so it is
//    consistent even in WAL mode) under a temporary name, every changed
//    keypoints row replaced in one transaction (x and y only; the shape
//    columns, descriptors, matches and geometries stay as they were, so
//    COLMAP's tools run on it unchanged), then renamed to the output path.
//    The input is opened read-only and never written.
//
// Templates are centred on the pixel centre nearest to the reference point
// (no interpolation of the template, which would smooth it); the conjugate
// of the reference point itself follows from the estimated affinity.
// Pixel coordinates are COLMAP's (pixel centres at +0.5).
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/types.h"
#include "ext/matching/lsm.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

// LSM as refinement uses it: LsmOptions' defaults with step control on
// (real patches with relief and occlusion make plain Gauss-Newton
// oscillate; lsm.h).
LsmOptions DefaultRefinementLsmOptions();

struct KeypointRefinementOptions {
  // The matching itself; patch_radius 7 gives 15 x 15 patches. Its
  // max_shift_px and shape bounds are LSM's divergence tests.
  LsmOptions lsm = DefaultRefinementLsmOptions();
  // Both images are smoothed by a Gaussian of this standard deviation,
  // pixels, before matching (0: not at all): for noisy or aliased images.
  // On clean ones it costs precision and makes weak texture flat.
  double smoothing_sigma_px = 0.0;
  // Use the keypoints' affine frames (scale, orientation, shape) for the
  // approximate patch shape; off: identity (upright, equal scale).
  bool use_keypoint_shape = true;
  // Accepted results: a posteriori sigma0 of the grey values (0..255) at
  // most this, and a correlation of template and resampled patch at least
  // this. Larger sigma0 means occlusion, relief or a wrong conjugate.
  double max_sigma0 = 12.0;
  double min_correlation = 0.75;
  // Largest standard deviation of either shift, pixels: weaker points are
  // not worth moving.
  double max_sigma_px = 0.3;
  // Largest move from the original keypoint, pixels (a keypoint of a good
  // match is rarely off by more than its scale).
  double max_shift_px = 3.0;
  // Match back from the refined position into the reference image; the
  // result must land within this distance of the reference point, pixels.
  bool back_matching = true;
  double max_backmatch_px = 0.2;
  // Where fewer than half of a track's other observations match its
  // best-textured reference, the next best-textured ones are tried, up to
  // this many references in all; the one most observations match wins.
  int num_reference_candidates = 2;
  // Tracks longer than this are not refined (a component that large has
  // merged several points through wrong matches).
  int max_track_length = 50;
  int num_threads = -1;  // -1 = all cores
  void Check() const;    // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h), LSM's as lsm.*.
  void Register(OptionRegistry* registry);
  // Those that judge one match (LSM's as lsm.*), for matchers that refine
  // points found otherwise.
  void RegisterMatchChecks(OptionRegistry* registry);
};

// One keypoint of one image.
struct TrackObservation {
  image_t image_id = kInvalidImageId;
  point2D_t point2D_idx = kInvalidPoint2DIdx;
  bool operator<(const TrackObservation& other) const {
    return std::make_pair(image_id, point2D_idx) <
           std::make_pair(other.image_id, other.point2D_idx);
  }
  bool operator==(const TrackObservation& other) const {
    return image_id == other.image_id && point2D_idx == other.point2D_idx;
  }
};
using KeypointTrack = std::vector<TrackObservation>;

// The connected components (two or more observations) of the match graph,
// each sorted, in the order of their smallest observation. `matches` are
// (pair_id, matches) in COLMAP's canonical order, as the database stores
// them.
std::vector<KeypointTrack> BuildKeypointTracks(
    const std::vector<std::pair<pair_t, FeatureMatches>>& matches);

enum class ObservationOutcome {
  kReference = 0,  // the track's reference, kept
  kRefined,        // moved to its least-squares position
  // Rejected (kept at the original position):
  kOutsideImage,       // a patch leaves its image
  kFlatPatch,          // no contrast
  kNotConverged,       // LSM did not converge
  kDiverged,           // moved too far or shape out of bounds
  kShiftUndetermined,  // texture in one direction only
  kSingular,           // normal equations singular
  kLargeSigma0,        // sigma0 > max_sigma0
  kLowCorrelation,     // correlation < min_correlation
  kImprecise,          // sigma of a shift > max_sigma_px
  kLargeShift,         // moved more than max_shift_px
  kBackMatching,       // back-matching missed the reference point
  kLongTrack,          // track longer than max_track_length
};
constexpr int kNumObservationOutcomes = 14;
const char* ObservationOutcomeName(ObservationOutcome outcome);
inline bool IsRejection(ObservationOutcome outcome) {
  return outcome != ObservationOutcome::kReference &&
         outcome != ObservationOutcome::kRefined;
}

struct ObservationRefinement {
  TrackObservation observation;
  ObservationOutcome outcome = ObservationOutcome::kReference;
  Eigen::Vector2d original_xy = Eigen::Vector2d::Zero();
  // The position written: the refined one, or the original where rejected.
  Eigen::Vector2d refined_xy = Eigen::Vector2d::Zero();
  // What least-squares matching found, whether accepted or not (the
  // original where it found nothing): for judging the blunder checks.
  Eigen::Vector2d matched_xy = Eigen::Vector2d::Zero();
  Eigen::Vector2d sigma_xy = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_xy = Eigen::Matrix2d::Zero();  // pixels^2
  // The estimated patch shape (search pixels per reference pixel).
  Eigen::Matrix2d shape = Eigen::Matrix2d::Identity();
  double sigma0 = 0;
  double correlation = 0;
  double backmatch_px = 0;  // distance of the back-match from the reference
};

// What refinement needs of one image: its grey values (CV_32F, 0..255,
// smoothed with SmoothForMatching) and its keypoints as stored.
struct RefinementImage {
  cv::Mat gray;
  FeatureKeypoints keypoints;
};

// The approximate shape of the patch of keypoint `to` for the template of
// keypoint `from` (2 x 2, search pixels per template pixel): A_to A_from^-1
// from the stored affine frames, identity for 2-column keypoints.
Eigen::Matrix2d KeypointShapeRatio(const FeatureKeypoints& from_keypoints,
                                   int from_idx,
                                   const FeatureKeypoints& to_keypoints,
                                   int to_idx);

// The grey image as refinement matches it: smoothed by
// options.smoothing_sigma_px (a copy; unchanged for 0).
cv::Mat SmoothForMatching(const cv::Mat& gray,
                          const KeypointRefinementOptions& options);

// Texture score of a patch: the smaller eigenvalue of sum(grad grad^T) over
// it, divided by the number of samples (grey values^2 per pixel^2); 0
// where the patch leaves the image.
double PatchTextureScore(const cv::Mat& gray,
                         const Eigen::Vector2d& xy,
                         int radius);

// Refines one track (steps 2 to 4). One result per observation, in track
// order.
std::vector<ObservationRefinement> RefineTrack(
    const KeypointTrack& track,
    const std::map<image_t, RefinementImage>& images,
    const KeypointRefinementOptions& options);

// Matches the reference patch (reference_xy in `reference`) into `search`
// from `start_xy` with the approximate `shape`, then applies the blunder
// checks. The outcome is kRefined or a rejection.
ObservationRefinement RefineObservation(
    const cv::Mat& reference,
    const Eigen::Vector2d& reference_xy,
    const cv::Mat& search,
    const Eigen::Vector2d& start_xy,
    const Eigen::Matrix2d& shape,
    const KeypointRefinementOptions& options);

struct ImageRefinementReport {
  image_t image_id = kInvalidImageId;
  std::string name;
  int num_keypoints = 0;
  int num_observations = 0;  // keypoints in tracks
  int num_reference = 0;
  int num_refined = 0;
  int num_rejected = 0;
  double median_shift_px = 0;  // of the refined observations
};

struct KeypointRefinementSummary {
  // "two_view_geometries" or "matches".
  std::string match_source;
  int num_pairs = 0;
  int num_tracks = 0;
  int64_t num_observations = 0;
  int64_t num_reference = 0;
  int64_t num_refined = 0;
  int64_t num_rejected = 0;
  double median_shift_px = 0;
  double mean_shift_px = 0;
  // Rejections by reason, indexed by ObservationOutcome.
  std::array<int64_t, kNumObservationOutcomes> num_by_outcome{};
  std::vector<ImageRefinementReport> images;  // in image_id order
  double read_seconds = 0;
  double refine_seconds = 0;
  double write_seconds = 0;
  double seconds = 0;
};

// The whole command: reads `database_path` (read-only) and the images under
// `image_path`, refines every track and writes the refined database to
// `output_path` (through a temporary file; an existing file is replaced
// only with `overwrite`). Throws InputError for a missing or non-COLMAP
// database, no matches, match indices beyond the keypoints, missing images
// or images of the wrong size, and an output path that exists (without
// `overwrite`) or is the input.
KeypointRefinementSummary RefineDatabaseKeypoints(
    const std::string& database_path,
    const std::string& image_path,
    const std::string& output_path,
    bool overwrite,
    const KeypointRefinementOptions& options);

// The report `bayon refine_keypoints` writes.
nlohmann::ordered_json KeypointRefinementSummaryJson(
    const KeypointRefinementSummary& summary,
    const std::string& database_path,
    const std::string& output_path);

// Its table per image and the rejections, as the command prints them.
std::string KeypointRefinementTable(const KeypointRefinementSummary& summary);

}  // namespace bayon
