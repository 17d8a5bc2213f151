// SPDX-License-Identifier: BSD-3-Clause
//
// Least-squares refinement and propagation of the conjugate points of one
// matched pair
// (after correlation_matcher.h's step 4). The correlation peak of an
// upright window is biased wherever the surface is slanted between the
// views: the window of image 2 is sheared and scaled, the peak follows the
// stronger texture inside it, and the bias changes with the surface's
// orientation, so it does not average out in a relative orientation (on
// the rendered tower it turned adjacent pairs by 0.1 - 0.5 degrees, several
// times their reported standard deviations). Adaptive least-squares
// matching (lsm.h; keypoint_refinement.h's RefineObservation: affine + 2
// radiometric parameters, back-matching) models that shape.
//
// The image-1 keypoint's pixel centre is the reference and keeps its
// position; the conjugate in image 2 starts at the correlation peak with
// the patch shape of the local affinity between the images: the least
// squares affinity of the nearest other matches (pixel1 -> pixel2), fitted
// twice with the matches whose residuals exceed 3 times the median removed
// in between (matches before the relative orientation include blunders), or
// the pair's global mapping where too few neighbours are near.
//
// Propagation. Correlation of 7 x 7 windows and relaxation keep only the
// unambiguous few (about 1 image-1 keypoint in 10 on the tower), and a
// relative orientation from a few dozen points clustered on the object is
// weak. Each image-1 keypoint not yet matched is therefore predicted by the
// local affinity of the refined conjugate points around it and matched by
// least-squares matching from there, with the same checks; a result within
// max_keypoint_distance_px of an image-2 keypoint that no other match uses
// becomes a match of those keypoints (the nearest claim wins). The new
// points take part in the next round's affinities. Wrong predictions (at
// depth edges, say) fail the checks; the few blunders that pass are left to
// the relative orientation's LMedS, as the paper leaves those of
// relaxation.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/matching/correlation_matcher.h"
#include "ext/matching/keypoint_refinement.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <vector>

namespace bayon {

struct ConjugateRefinementOptions {
  // Least-squares matching and its blunder checks. The defaults differ from
  // refine_keypoints' in two places: the start is the correlation peak, not
  // a keypoint, so it should not move far, and needs to be precise.
  KeypointRefinementOptions lsm = [] {
    KeypointRefinementOptions options;
    options.max_shift_px = 1.5;
    options.max_sigma_px = 0.25;
    return options;
  }();
  // Keep a match that least-squares matching rejects at its correlation
  // peak (the paper's conjugate point; the relative orientation's blunder
  // test judges it) instead of dropping it. Weak pairs (wide angles, little
  // texture) keep their few matches, but the peaks' bias comes back: on the
  // tower the median rotation error of the adjacent pairs is 0.19 degrees
  // with them and 0.045 without (0.22 with correlation alone).
  bool keep_unrefined = false;
  // Standard deviation given to a refined point, pixels, as the relative
  // orientation weighs it against correlation peaks
  // (CorrelationMatchingOptions::peak_sigma_px): the sigma0 of relative
  // orientations from refined points alone, 0.05 - 0.2 px on the tower and
  // the temple ring. Each point's own LSM standard deviation is not used:
  // it follows the texture, not the relief and light that make the errors
  // here (weighting by it: median tower error 0.074 deg against 0.045).
  double refined_sigma_px = 0.1;
  // Neighbours for the local affinity, and the largest distance at which a
  // match counts as a neighbour (fraction of the larger image side).
  int num_neighbors = 12;
  double neighbor_fraction = 0.15;
  // Propagation rounds (0: none), how far least-squares matching may move
  // from the predicted position, and how near an image-2 keypoint the
  // result must lie to become a match (COLMAP matches keypoints).
  int propagation_rounds = 2;
  double propagation_max_shift_px = 3.0;
  double max_keypoint_distance_px = 2.0;
  void Register(OptionRegistry* registry);
  void Check() const;
};

// pixel2 ~= affinity * (pixel1, 1).
using Affinity2d = Eigen::Matrix<double, 2, 3>;

// The local affinity of the matches `xy1` -> `xy2` at each of `queries`
// (image-1 pixels), from up to `num_neighbors` matches within
// `max_distance`; nullopt where fewer than six are near, they are
// (nearly) collinear, or the fit flips the image or scales it by more than
// 10 against `reference` (the pair's global mapping).
std::vector<std::optional<Affinity2d>> LocalAffinities(
    const std::vector<Eigen::Vector2d>& xy1,
    const std::vector<Eigen::Vector2d>& xy2,
    const std::vector<Eigen::Vector2d>& queries,
    const Eigen::Matrix2d& reference,
    double max_distance,
    int num_neighbors);

struct ConjugateRefinementReport {
  int num_refined = 0;
  // Rejected, by RefineObservation's outcome (kRefined counts nothing).
  std::array<int, kNumObservationOutcomes> num_rejected{};
  int NumRejected() const;
  double median_shift_px = 0;  // of the refined points from the peaks
  int num_propagated = 0;      // conjugate points added by propagation
};

// Refines `matches` (reference_xy1 / refined_xy2) in place on the grey
// images (CV_32F, 0..255); rejected matches stay at their correlation
// peaks (keep_unrefined) or are removed from all of its arrays. Then propagates
// them (header) from the keypoints of both images (pixel coordinates, the
// keypoint indices of `matches`).
ConjugateRefinementReport RefineConjugatePoints(
    const cv::Mat& gray1,
    const cv::Mat& gray2,
    const std::vector<Eigen::Vector2d>& keypoints1,
    const std::vector<Eigen::Vector2d>& keypoints2,
    const ConjugateRefinementOptions& options,
    PairMatches* matches);

}  // namespace bayon
