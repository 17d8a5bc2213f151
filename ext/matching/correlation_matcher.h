// SPDX-License-Identifier: BSD-3-Clause
//
// Matching one image pair by correlation and relaxation, the paper's steps
// 3.2.1(b) and (c), with what a ring of hand-held or gantry photographs
// adds to them:
//
// 1. Global mapping. A spread subset of image-1 points is correlated (on
//    the wider coarse windows) with every point of image 2, in each of the
//    four in-plane rotations by quarter turns; the mutually best pairs vote
//    for a similarity transformation (RANSAC on two-point samples). The
//    rotation with the most consistent votes wins, and an affine mapping
//    fitted to its votes predicts where each point should be found. This is
//    what makes cameras turned by 90 or 180 degrees (temple-ring) and large
//    shifts between the images harmless. The paper's search (centred on
//    the same position, upright) is always tried too, and used when it
//    gives clearly more (5 %) conjugate points. Where the votes find no
//    mapping, each quarter turn about the image centres is tried, and the
//    one that leaves the most conjugate points after relaxation wins (the
//    upright one unless another has 5 % more).
// 2. Candidates. Every image-1 point is correlated (w x w windows, 7 x 7 by
//    default) with the image-2 points inside a search window of 1/16 of the
//    image (sqrt(1/16) of its width and height) around its predicted
//    position; those with r >= 0.75 are candidates. The Moravec operator
//    marks one feature in two photographs only to about a pixel (noise, a
//    different sun and the change of view move its maximum), so the
//    image-2 window is also taken shifted by up to max_keypoint_shift_px
//    around the keypoint and the best correlation counts; the match is
//    still keypoint to keypoint, step 4 finds the exact position.
// 3. Relaxation (relaxation.h): continuity and uniqueness, loser-takes-
//    nothing. Then a second pass of 2 and 3 with each search window centred
//    where the conjugate points of the first pass say the point should be
//    (the mapping plus the median offset of the nearest matches): the
//    displacements between two views of a 3D object vary more than one
//    affine mapping and a window of 1/16 of the image can follow.
// 4. Sub-pixel conjugate points. The image-1 keypoint is the reference; the
//    correlation peak of its window is searched within +-refine_radius
//    pixels of the matched image-2 keypoint and located to sub-pixel
//    precision by a parabola through the peak and its neighbours in x and
//    y. Matches whose peak lies on the edge of that range (the keypoints
//    are not the same feature) or below refine_min_ncc are dropped. The
//    refined positions feed the relative orientation; COLMAP gets the
//    keypoint indices.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/option_registry.h"
#include "ext/matching/correlation_patches.h"
#include "ext/matching/relaxation.h"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace bayon {

struct CorrelationMatchingOptions {
  // Correlation threshold r for candidates and conjugate points (paper).
  double min_ncc = 0.75;
  // Area of the search window as a fraction of the image (paper: 1/16).
  double search_window_fraction = 1.0 / 16.0;
  // Candidates kept per image-1 point (the best ones).
  int max_candidates_per_point = 8;
  // The image-2 window of a candidate is also taken shifted by up to this
  // many pixels from its keypoint, and the best correlation counts (step 2
  // above): more true pairs pass r, at the price of some more chance ones.
  // 0: the keypoint's own window only. Must stay below the refinement's
  // search radius (PatchOptions::refine_radius).
  int max_keypoint_shift_px = 1;
  // Shifted windows are only tried where the keypoint's own window reaches
  // this correlation (most points of a search window are hopeless).
  double shift_min_ncc = 0.5;
  // The sub-pixel peak on the wider refinement window must reach this (the
  // match itself was accepted on the 7 x 7 window with min_ncc; the wider
  // window is less similar between convergent views).
  double refine_min_ncc = 0.5;
  // Standard deviation of a correlation peak's position, pixels, as the
  // relative orientation weighs it against least-squares points
  // (conjugate_refinement.h): the sigma0 of relative orientations from peaks
  // alone is 0.2 - 0.35 px on the rendered tower and the temple ring.
  double peak_sigma_px = 0.3;

  // Global mapping: try all four quarter turns (else upright only).
  bool detect_rotation = true;
  // Image-1 points used for it, spread over a grid.
  int global_num_points = 200;
  // Coarse correlation a vote needs, and how much better than the
  // runner-up it must be: (1 - r_best) <= ratio * (1 - r_second).
  double global_min_ncc = 0.7;
  double global_max_ratio = 0.8;
  // RANSAC inlier distance as a fraction of the image diagonal: loose,
  // because a similarity only approximates two views of a 3D object.
  double global_inlier_fraction = 0.05;
  int global_min_inliers = 8;
  // Largest chance that the winning model's inliers are a coincidence of
  // random votes (a Poisson tail, times the number of trials).
  double global_max_false_alarm = 1e-3;
  int global_num_trials = 500;
  unsigned int seed = 1;

  // Matching passes: each pass after the first centres the search windows
  // on the positions the previous pass's conjugate points predict.
  int num_passes = 2;

  RelaxationOptions relaxation;
  void Register(OptionRegistry* registry);
  void Check() const;
};

// The approximate mapping from image 1 to image 2.
struct GlobalMapping {
  bool found = false;
  int quarter_turns = 0;  // image 2 is turned by 90 * quarter_turns degrees
  // pixel2 ~= affine * (pixel1, 1).
  Eigen::Matrix<double, 2, 3> affine =
      (Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 1, 0).finished();
  int num_votes = 0;    // tentative pairs for the winning rotation
  int num_inliers = 0;  // consistent with its similarity
  std::array<int, 4> inliers_per_rotation = {0, 0, 0, 0};
  int RotationDeg() const { return 90 * quarter_turns; }
};

struct PairMatches {
  GlobalMapping mapping;   // the mapping the matches were found with
  int num_candidates = 0;  // candidate pairs with r >= min_ncc
  int num_relaxed = 0;     // one-to-one after relaxation
  int num_iterations = 0;  // relaxation rounds (of the last pass)
  int num_passes = 1;      // passes that improved the result
  // Conjugate points: keypoint indices; the reference point in image 1 (the
  // centre of the keypoint's pixel) and the sub-pixel position of its
  // conjugate in image 2, with their correlation and its standard deviation.
  FeatureMatches matches;
  std::vector<Eigen::Vector2d> reference_xy1;
  std::vector<Eigen::Vector2d> refined_xy2;
  std::vector<float> ncc;
  std::vector<float> sigma_px;  // of refined_xy2
};

GlobalMapping EstimateGlobalMapping(const ImagePatches& image1,
                                    const ImagePatches& image2,
                                    const CorrelationMatchingOptions& options);

// Candidate pairs for every valid image-1 point, around the predicted
// position of `mapping`.
std::vector<MatchCandidate> FindCandidates(
    const ImagePatches& image1,
    const ImagePatches& image2,
    const GlobalMapping& mapping,
    const CorrelationMatchingOptions& options);

// The same around given positions in image 2 (one per image-1 point; NaN:
// not searched), with image 2 turned by `quarter_turns`.
std::vector<MatchCandidate> FindCandidatesAround(
    const ImagePatches& image1,
    const ImagePatches& image2,
    int quarter_turns,
    const std::vector<Eigen::Vector2d>& centers,
    const CorrelationMatchingOptions& options);

// The sub-pixel conjugate in image 2 of keypoint idx1 of image 1 near
// keypoint idx2 (step 4 above). False if the peak is on the edge of the
// search range or below min_ncc.
bool RefineConjugatePoint(const ImagePatches& image1,
                          int idx1,
                          const ImagePatches& image2,
                          int idx2,
                          int quarter_turns,
                          double min_ncc,
                          Eigen::Vector2d* xy2,
                          float* ncc);

// Steps 1-4 for one pair.
PairMatches MatchImagePatches(const ImagePatches& image1,
                              const ImagePatches& image2,
                              const CorrelationMatchingOptions& options);

}  // namespace bayon
