// SPDX-License-Identifier: BSD-3-Clause
//
// Relative orientation of an image pair from conjugate points, the paper's
// step 3.2.1(d): the Direct Relative Transform (DRT, Chang 1986) solved
// linearly, LMedS over random 8-point samples against blunders, a weighted
// least-squares solution, and then the rigorous non-linear adjustment of the
// five orientation elements with the coplanarity condition.
//
// Frames and units. Each image has its photogrammetric image frame: x right,
// y up, z towards the viewer, origin at the projection centre. A point's
// image vector is u = (x, y, -c): the image coordinates reduced to the
// principal point and corrected for distortion, and the camera constant,
// all divided by the pixel pitch (for COLMAP cameras, which have no pitch:
// the normalized coordinates times the focal length). Everything below is
// therefore in pixels: residuals, sigma0, thresholds; the paper's
// millimetres are these values times the pitch. The model frame is the
// frame of image 1; image 2 is placed by a rotation R (model from image-2
// frame) and the base b (its projection centre, |b| = 1).
//
// The DRT. Coplanarity of the base and the two rays,
//
//   b . (u1 x R u2) = 0   <=>   u1^T M u2 = 0,   M ~ [b]x R,
//
// is bilinear in the image coordinates. With u = (x, y, -c) and a common c
// it reads, after dividing by -M(2,1) (the coefficient of c y''),
//
//   L1 x''y' + L2 y''y' - L3 y'c + L4 x''c - L5 c^2 + L6 x'x'' + L7 x'y''
//     - L8 x'c + c y'' = 0                                   (paper, eq. 1)
//
// with M = [[L6, L7, L8], [L1, L2, L3], [-L4, -1, -L5]], so the eight L are
// the elements of M. Eight points determine M linearly. We solve the
// homogeneous form (|M| = 1, SVD): for eight points it is the paper's
// solution exactly, and for more points it remains valid when the
// normalising coefficient vanishes (a base along y, the paper's "vertical
// base"); L1..L8 are reported by dividing by -M(2,1) where it does not.
//
// Decomposition (the sign and chirality choice). M is projected onto the
// nearest essential matrix (two equal singular values, one zero; Hartley &
// Zisserman 2003, 9.6), M = U diag(1, 1, 0) V^T, and factored as [b]x R with
// R in {U W V^T, U W^T V^T} (det +1) and b = +-U e3. Of the four, the one
// that puts the most points in front of both cameras (positive scale along
// both rays when intersected) is kept; b is scaled to unit length. In
// COLMAP's frames (x right, y down, z forward; D = diag(1, -1, -1))
// cam2_from_cam1 has rotation D R^T D and translation -(D R^T D)(D b).
//
// Robust estimation (paper, eqs. 2-5). m = 1024 random samples of p = 8
// points each (drawn from eight different cells of an 8 x 8 grid over
// image 1, as Zhang et al. 1995 do) give M_j; M_j's residuals r_i over all n
// points give M_j = med r_i^2; the sample with the smallest median is kept, the
// scale is sigma = 1.48 (1 + 5 / (n - p)) sqrt(min M_j), points with r_i^2 >
// (2.5 sigma)^2 get weight 0 (blunders), and M is solved again by weighted
// least squares from the others. Two additions make this hold for narrow-angle
// pairs (such as the temple ring's 24-degree views), whose 8-point solutions
// are loose enough that a false model with a tiny convergence angle can have
// the smallest median: the few best samples are each polished once by the
// weighted solution of the points they accept (the local optimisation of
// LO-RANSAC, Chum et al. 2003), and each is taken through eqs. (3)-(5) and the
// rigorous adjustment below; the one whose final blunder test has the smallest
// robust sigma wins. The weighted solution divides each misclosure by its
// standard deviation (from the previous M), so points count by geometric fit,
// not by image position. The residual r_i is eq. (1)'s misclosure divided by
// its first-order standard deviation for unit- variance image coordinates (the
// Sampson distance, in pixels), so that one threshold fits the whole image; the
// paper's plain misclosure is available as DrtResidual::kAlgebraic.
//
// Points of different precision. Where the points carry standard
// deviations, each is divided by their median (after raising it to
// min_sigma_px): s_i, the point's precision relative to the typical point.
// Every residual above (eq. 2's median, the blunder test, the weighted
// solution) is then r_i / s_i, and the rigorous refinement gives each
// point's coordinates the cofactor s_i^2. sigma0, the robust sigma and the
// pixel thresholds thus refer to a point of the median precision; without
// standard deviations (s_i = 1) everything is as the paper has it.
//
// Rigorous refinement. The five elements (R: three angles; b: two angles on
// the unit sphere) are adjusted by least squares with the coplanarity
// condition as a condition equation between observations and unknowns
// (Gauss-Helmert model: each point contributes one condition in its four
// image coordinates, all of unit weight), iterated to convergence with the
// observations corrected at each step. sigma0 (pixels) and the covariance of
// the elements follow from it. The blunder test is then repeated with the
// refined model (the same rule, p = 5) and the adjustment rerun until the
// set of blunders stays the same.
//
// omega, phi, kappa: R = Rx(omega) Ry(phi) Rz(kappa) (rotation of image 2
// in the model frame, Kraus' sequence of primary, secondary and tertiary
// rotations).
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

// Conjugate points of one pair as image vectors u = (x, y, -c), pixels.
struct ConjugatePoints {
  std::vector<Eigen::Vector3d> u1;
  std::vector<Eigen::Vector3d> u2;
  // Optional: the pixel positions, to tell identical images apart from a
  // pure rotation in the report.
  std::vector<Eigen::Vector2d> pixel1;
  std::vector<Eigen::Vector2d> pixel2;
  // Optional: each point's standard deviation (pixels, both images alike),
  // e.g. least-squares matching's for refined points and a nominal one for
  // correlation peaks. The points are then weighted by them (see the
  // header comment); empty, or any value <= 0: all equally precise.
  std::vector<double> sigma;
  int size() const { return static_cast<int>(u1.size()); }
};

enum class DrtResidual {
  kSampson,    // misclosure / its standard deviation: pixels
  kAlgebraic,  // the paper's eq. (2) literally (misclosure with M(2,1) = -1)
};

struct RelativeOrientationOptions {
  // m: random 8-point samples for LMedS (paper: 1024).
  int num_samples = 1024;
  // The best samples (by median) that are each polished and taken through
  // the whole adjustment; the one that fits best in the end wins.
  int num_candidates = 32;
  // Blunder threshold in units of the robust sigma (paper: 2.5).
  double blunder_threshold = 2.5;
  DrtResidual residual = DrtResidual::kSampson;
  // The interior orientation is known: M is an essential matrix (two equal
  // singular values). Otherwise only rank 2 is imposed in the linear steps
  // (the rigorous refinement always assumes the given camera constants).
  bool calibrated = true;
  // Refinement: iterations per adjustment, and rounds of re-testing the
  // blunders with the refined model.
  int max_iterations = 50;
  int max_rounds = 5;
  // Failure criteria.
  int min_num_points = 15;   // conjugate points needed at all
  int min_num_inliers = 15;  // after the blunder test (COLMAP's mapper
                             // ignores pairs with fewer)
  // The robust sigma of the final blunder test (refined model) or sigma0
  // above this means the points follow no epipolar geometry (chance
  // matches, another motion, a false minimum), pixels. 1 px suits sub-pixel
  // conjugate points (`bayon match` gives 0.1 - 0.5 px); whole-pixel
  // keypoints or uncorrected lens distortion (assume_zero_distortion on a
  // real lens) need more.
  double max_sigma_px = 1.0;
  // ... and is never taken below this (image measurements are not better),
  // so that exact data are not split into "blunders" by rounding.
  double min_sigma_px = 0.02;
  // A rotation alone explaining the points this well (median residual,
  // pixels), or within min_parallax_sigma0 times the coplanarity model's
  // sigma0, means there is no usable base: pure rotation, identical images,
  // a base too short for the image measurements, or points that move with
  // the camera (a background fixed to the camera rig).
  double min_parallax_px = 1.5;
  double min_parallax_sigma0 = 3.0;
  unsigned int seed = 1;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct RelativeOrientation {
  bool success = false;
  std::string reason;  // why not, one line

  // The result (model frame = image-1 frame, see above).
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();   // u1^T M u2 = 0, |M| = 1
  std::optional<Eigen::Matrix<double, 8, 1>> L;  // the paper's L1..L8
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // R
  Eigen::Vector3d base = Eigen::Vector3d::UnitX();         // b, |b| = 1
  Eigen::Vector3d omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d std_omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  // Standard deviation of the base direction along two perpendicular
  // directions on the unit sphere (e1 = z x b normalised, e2 = b x e1),
  // degrees.
  Eigen::Vector2d std_base_deg = Eigen::Vector2d::Zero();
  // Covariance of the five elements: rotation increments of image 2 about
  // its own axes (rad), base tangent increments along e1, e2 (rad).
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();
  double sigma0_px = 0;          // a posteriori, refinement
  double lmeds_sigma_px = 0;     // eq. (4) of the final blunder test
  std::vector<uint8_t> inliers;  // 1: used; 0: blunder
  int num_inliers = 0;
  int num_blunders = 0;
  int num_iterations = 0;  // of the last adjustment
  int num_rounds = 0;
  // Angle between the optical axes, and median angle between the two rays
  // of the conjugate points, degrees.
  double convergence_angle_deg = 0;
  double median_intersection_angle_deg = 0;
  // Median residual of the best rotation-only model, pixels.
  double rotation_only_residual_px = 0;

  // cam2_from_cam1 in COLMAP's camera frames, |t| = 1.
  Rigid3d Cam2FromCam1() const;
};

RelativeOrientation EstimateRelativeOrientation(
    const ConjugatePoints& points, const RelativeOrientationOptions& options);

// ---------------------------------------------------------------------------
// The steps, for tests and for other stages.

// Weighted linear DRT: M minimising sum w_i (u1_i^T M u2_i)^2 with |M| = 1,
// then projected to an essential matrix (calibrated) or to rank 2. False for
// fewer than 8 points with weight or a degenerate configuration.
bool SolveDrtLinear(const std::vector<Eigen::Vector3d>& u1,
                    const std::vector<Eigen::Vector3d>& u2,
                    const std::vector<double>& weights,
                    bool calibrated,
                    Eigen::Matrix3d* M);

// r_i for every point (see DrtResidual).
std::vector<double> DrtResiduals(const Eigen::Matrix3d& M,
                                 const std::vector<Eigen::Vector3d>& u1,
                                 const std::vector<Eigen::Vector3d>& u2,
                                 DrtResidual type);

// The paper's L1..L8 (M divided by -M(2,1)); nullopt where M(2,1) is too
// small for that division to mean anything.
std::optional<Eigen::Matrix<double, 8, 1>> PaperParameters(
    const Eigen::Matrix3d& M);

// R and b from M by the chirality rule (points with mask 1 vote). Returns
// the number of points in front of both cameras.
int DecomposeDrt(const Eigen::Matrix3d& M,
                 const std::vector<Eigen::Vector3d>& u1,
                 const std::vector<Eigen::Vector3d>& u2,
                 const std::vector<uint8_t>& mask,
                 Eigen::Matrix3d* R,
                 Eigen::Vector3d* b);

// R = Rx(omega) Ry(phi) Rz(kappa), radians.
Eigen::Matrix3d RotationFromOmegaPhiKappa(const Eigen::Vector3d& opk);
Eigen::Vector3d OmegaPhiKappaFromRotation(const Eigen::Matrix3d& R);

// The photogrammetric elements (R, b) from COLMAP's cam2_from_cam1, and
// back.
void ElementsFromCam2FromCam1(const Rigid3d& cam2_from_cam1,
                              Eigen::Matrix3d* R,
                              Eigen::Vector3d* b);
Rigid3d Cam2FromCam1FromElements(const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& b);

}  // namespace bayon
