// SPDX-License-Identifier: BSD-3-Clause
//
// Multi-photo geometrically constrained matching (MPGC; Gruen 1985, Gruen
// and Baltsavias 1988, Baltsavias 1991) of one point: the template patch
// of a master image is matched by least squares against the patches of
// several search images at once, and the geometry of the oriented images
// ties the matches together through the object point X they all show.
//
// Unknowns: X (3, object coordinates) and, per search image j, the eight
// parameters of adaptive least-squares matching (ext/matching/lsm.h: the
// patch centre a0, b0, its shape a1 a2 b1 b2, radiometry r0 r1).
// Observations:
//   - the grey values of every search patch against the template (lsm.h's
//     observation equations, unit weight, grey values);
//   - the collinearity conditions, as observations of weight
//     (grey_sigma / geometric_sigma_px)^2: the projection of X into each
//     search image equals that patch's centre, (a0, b0)_j - P_j(X) = 0, and
//     the projection into the master equals the template centre,
//     P_m(X) - x_m = 0.
// The projections P use the full camera model (distortion, the image's
// interior orientation), so X comes out of the adjustment directly, with
// its covariance sigma0^2 (N^-1)_XX, inflated where the grey residuals are
// correlated (smooth residual fields carry fewer independent observations). The
// shifts are always estimated (the geometry determines what the texture leaves
// open: the point of MPGC); shape and radiometry follow lsm.h's adaptive
// selection per patch.
//
// Blunders and occlusions: a search image whose patch leaves the image,
// moves more than max_shift_px from its approximation, or whose correlation
// with the template stays below min_correlation after convergence is
// dropped (the worst one first) and the point solved again from the rest;
// where the joint solution does not converge, the worst-correlating patch
// is dropped likewise. The point fails when fewer than min_search_views
// remain.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/rigid3.h"
#include "ext/matching/lsm.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace bayon {

// One oriented image: grey values (CV_32F, 0..255) and its camera.
struct MpgcView {
  const cv::Mat* image = nullptr;
  const Camera* camera = nullptr;
  Rigid3d cam_from_world;
  const ImageFrame* frame = nullptr;  // nullptr: the camera's default
};

struct MpgcOptions {
  // Patch radius, interpolation and the adaptive selection of shape and
  // radiometry (lsm.h); step_control is not used here (MPGC halves its own
  // steps where the total sum of squares grows).
  LsmOptions lsm;
  // A priori precision of a grey value and of the collinearity conditions
  // (the orientation's precision in pixels); their ratio weighs the two
  // kinds of observation.
  double grey_sigma = 2.0;
  double geometric_sigma_px = 0.1;
  int max_iterations = 30;
  // Converged when no patch centre moves by more than this, pixels.
  double convergence_px = 0.005;
  // Converged also when a step lowers the sum of squares by less than
  // (convergence_sigma * sigma0)^2, that is moves the solution by less than
  // that many of its standard deviations; 0: by convergence_px alone.
  double convergence_sigma = 0.3;
  // A search patch whose centre moves further from its approximation is
  // dropped (pixels).
  double max_shift_px = 5.0;
  // Search patches that correlate less with the template are dropped.
  double min_correlation = 0.7;
  int min_search_views = 1;
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

enum class MpgcStatus {
  kConverged = 0,
  kOutsideImage,  // the template leaves the master, X projects outside
  kFlatPatch,     // the template has no contrast
  kBehindCamera,  // X behind the master or a search camera
  kTooFewViews,   // fewer than min_search_views search patches fit
  kNotConverged,  // max_iterations reached
  kSingular,      // the normal equations could not be solved
};
const char* MpgcStatusName(MpgcStatus status);

struct MpgcResult {
  MpgcStatus status = MpgcStatus::kSingular;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // object units^2
  double sigma0 = 0;  // a posteriori, grey values
  // Lag-one autocorrelations of the grey residuals along the patch rows and
  // columns; the covariance is inflated by them (mpgc.cc).
  double residual_rho_u = 0, residual_rho_v = 0;
  int iterations = 0;
  int redundancy = 0;
  // The search views (indices into the `search` argument) in the final
  // solution, their patches' correlation with the template and centres.
  std::vector<int> views;
  std::vector<double> correlation;
  std::vector<Eigen::Vector2d> xy;
  std::vector<int> dropped;  // search views removed as blunders/occlusions
  bool ok() const { return status == MpgcStatus::kConverged; }
  Eigen::Vector3d StdDev() const {
    return covariance.diagonal().cwiseMax(0).cwiseSqrt();
  }
};

// Approximations for MPGC (the paper's step 3 of section 3.3): the object
// point on the master pixel's ray whose projections into the search views
// correlate best with the master window, the mean correlation coefficient
// over the views where it projects inside, each search window shaped as a
// plane facing the master through that point would show it. The ray is
// sampled between two distances from the master's projection centre, evenly
// in inverse distance, so that the largest epipolar step is step_px, and the
// best sample refined by a parabola through its neighbours.
struct EpipolarSearchOptions {
  int window_radius = 3;  // 7 x 7 windows, the paper's
  double step_px = 0.5;
  // The best mean correlation must reach this, over at least min_views.
  double min_ncc = 0.6;
  int min_views = 1;
  // The score of a sample is the mean over its best_views best-correlating
  // views (0: all views where it projects inside), so that a view in which
  // the point is hidden or lit otherwise does not drown the others.
  int best_views = 0;
  // Coarse to fine: where this is above 1, every stride-th sample is
  // scored first, then every sample within a stride of the best num_peaks
  // local maxima among those (1: every sample).
  int stride = 1;
  int num_peaks = 3;
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

struct EpipolarSearchResult {
  bool found = false;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  double distance = 0;  // from the master's projection centre, object units
  double ncc = -1;      // mean over the views
  // The best score elsewhere along the ray (a local maximum more than a
  // window radius of epipolar travel away): near `ncc` where the texture
  // repeats along the epipolar lines and the match is ambiguous. -2: none.
  double second_ncc = -2;
  int num_views = 0;
  int num_samples = 0;  // along the ray
  int num_scored = 0;   // of them, correlated (fewer with a stride)
};

EpipolarSearchResult SearchMasterRay(const MpgcView& master,
                                     const Eigen::Vector2d& master_xy,
                                     const std::vector<MpgcView>& search,
                                     double min_distance,
                                     double max_distance,
                                     const EpipolarSearchOptions& options);

// Per view, the correlation of the master window (2 window_radius + 1
// square) at `master_xy` with that view's window around the projection of
// `xyz`, shaped as in SearchMasterRay or, with a `normal`, by the plane
// with that normal; -2 where it projects outside: which views show the
// point at all.
std::vector<double> ViewCorrelations(
    const MpgcView& master,
    const Eigen::Vector2d& master_xy,
    const std::vector<MpgcView>& views,
    const Eigen::Vector3d& xyz,
    int window_radius,
    const std::optional<Eigen::Vector3d>& normal = std::nullopt);

// Matches the master pixel `master_xy` into the search views, starting from
// the object point `approximation` (e.g. from correlation along the
// epipolar line) with each search patch shaped by the local affinity that a
// plane through it induces: the plane with `normal` (object system; e.g.
// from the surface found around the point), or one facing the master.
MpgcResult MatchMpgc(
    const MpgcView& master,
    const Eigen::Vector2d& master_xy,
    const std::vector<MpgcView>& search,
    const Eigen::Vector3d& approximation,
    const MpgcOptions& options,
    const std::optional<Eigen::Vector3d>& normal = std::nullopt);

}  // namespace bayon
