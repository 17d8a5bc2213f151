// SPDX-License-Identifier: BSD-3-Clause
//
// Adaptive least-squares matching (ALSM; Gruen 1985, "Adaptive least squares
// correlation: a powerful image matching technique", South African Journal
// of Photogrammetry 14(3)): a template patch f of one image is matched to a
// search patch g of another by estimating the geometric and radiometric
// transformation between them.
//
// Model, for each template sample at offset (u, v) from the template centre
// (template pixels; the patch is the (2r + 1)^2 grid u, v in -r..r):
//
//   f(u, v) - e(u, v) = r0 + r1 g(x, y),
//   x = a0 + a1 u + a2 v,   y = b0 + b1 u + b2 v        (search pixels)
//
// (a0, b0) is the conjugate point of the template centre in the search
// image; (a1, a2, b1, b2) reshape the patch (scale, shear, rotation); r0, r1
// are the radiometric shift and scale. Linearised at the current estimate
// with the gradient (gx, gy) of the resampled search patch, each sample
// gives one observation equation (Gruen 1985, eq. 7 ff.):
//
//   l = f - r0 - r1 g  =  r1 gx da0 + r1 gy db0 + r1 gx u da1 + r1 gx v da2
//                         + r1 gy u db1 + r1 gy v db2 + dr0 + g dr1 + e
//
// solved by Gauss-Newton to convergence. sigma0^2 = v'v / (n - u) and the
// covariance of the estimate is sigma0^2 N^-1 (N the normal matrix of the
// parameters estimated in the last iteration).
//
// Resampling the search patch averages neighbouring pixels and so removes
// part of its noise from the residuals (up to 3/4 of the variance midway
// between pixels, bilinear), but not from the shifts, which depend on the
// noise at the texture's own, lower frequencies. Left alone, sigma0 and
// the standard deviations would be too small by up to a third. With
// `correct_resampling_noise`, sigma0 is scaled by
// sqrt((1 + r1^2) / (1 + r1^2 k)), k the mean fraction of noise variance
// the resampling kept, assuming both images carry noise of the same level
// (the same camera); lsm_test.cc checks the result against the empirical
// errors.
//
// "Adaptive": a parameter the patch's texture cannot determine is detected
// from the normal equations and held at its current value (its column is
// removed) instead of letting it drift and drag the shifts with it. With the
// normal matrix scaled to unit diagonal, parameters are taken in the order
// a0, b0, r0, r1, a1, b2, a2, b1 (shifts first, then radiometry, then
// scales, then shears); each one's pivot -- the part of its information not
// explained by the parameters already taken, 1 - R^2 of its multiple
// correlation -- must exceed `min_pivot`, and the second shift's conditional
// information must be at least `min_shift_information_ratio` of the first
// one's (a straight edge determines the shift across it, not along it). A
// shift that is held makes the match "undetermined" in that direction.
//
// Pieces are public so that multi-photo geometrically constrained matching
// (MPGC, Gruen and Baltsavias 1988; ext/dense) can reuse them: the template
// (LsmTemplate, cut out at any pyramid level), the normal equations of one
// template/search pair at given parameters (BuildLsmNormalEquations), and
// the adaptive selection of determinable parameters (SelectLsmParameters).
// MPGC adds its collinearity conditions to the per-patch normal equations;
// MatchLsm below is the unconstrained solution of one pair.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/image/interpolation.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <string>
#include <vector>

namespace bayon {

// Parameter order in vectors and normal equations.
enum LsmParam : int {
  kLsmA0 = 0,  // x shift of the patch centre, search pixels
  kLsmB0 = 1,  // y shift
  kLsmA1 = 2,  // dx/du
  kLsmA2 = 3,  // dx/dv
  kLsmB1 = 4,  // dy/du
  kLsmB2 = 5,  // dy/dv
  kLsmR0 = 6,  // radiometric shift, grey values
  kLsmR1 = 7,  // radiometric scale
};
constexpr int kNumLsmParams = 8;
const char* LsmParamName(int param);

using LsmVector = Eigen::Matrix<double, kNumLsmParams, 1>;
using LsmMatrix = Eigen::Matrix<double, kNumLsmParams, kNumLsmParams>;

// The transformation from the template to one search patch.
struct LsmParameters {
  // (x, y) = affine * (u, v, 1): col(2) is the search position of the
  // template centre, the left 2 x 2 block the patch shape.
  Eigen::Matrix<double, 2, 3> affine =
      (Eigen::Matrix<double, 2, 3>() << 0, 1, 0, 0, 0, 1).finished();
  double r0 = 0;
  double r1 = 1;

  // A pure shift to `xy` (the usual approximation), optionally with a shape.
  static LsmParameters At(
      const Eigen::Vector2d& xy,
      const Eigen::Matrix2d& shape = Eigen::Matrix2d::Identity());
  Eigen::Vector2d Position() const { return affine.col(2); }
  Eigen::Matrix2d Shape() const { return affine.leftCols<2>(); }
  LsmVector AsVector() const;
  // Adds an increment in parameter order.
  void Add(const LsmVector& delta);
};

// The template: grey values (and gradients) on the (2r + 1)^2 grid around a
// point of one image (one pyramid level; coordinates of that level).
struct LsmTemplate {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  int radius = 0;
  std::vector<float> values;  // row-major, v then u, (2r + 1)^2
  std::vector<float> dx;      // gradients in the template image
  std::vector<float> dy;
  double mean = 0;
  double stddev = 0;  // contrast: standard deviation of the values

  int side() const { return 2 * radius + 1; }
  int size() const { return side() * side(); }
};

// Cuts out the template. Returns false where the patch (with the
// interpolation footprint) leaves the image. At a pixel centre the values
// are the pixels themselves (no smoothing by interpolation).
bool ExtractLsmTemplate(const cv::Mat& image,
                        const Eigen::Vector2d& center,
                        int radius,
                        Interpolation interpolation,
                        LsmTemplate* patch);

// The linearised system of one template/search pair at `params`:
// N = A'A, rhs = A'l over the template samples, l'l, and n. The search
// patch is resampled at the transformed grid. Returns false (system
// untouched) where a sample leaves the search image.
struct LsmNormalEquations {
  LsmMatrix N = LsmMatrix::Zero();
  LsmVector rhs = LsmVector::Zero();
  double residual_sq = 0;  // l'l: sum of squared residuals at `params`
  int num_observations = 0;
  // Sum over the samples of InterpolationNoiseGain at the resampled
  // positions (how much search-image noise the resampling kept).
  double noise_gain_sum = 0;
  // Template and resampled search values, for the correlation coefficient.
  double sum_f = 0, sum_g = 0, sum_ff = 0, sum_gg = 0, sum_fg = 0;
  double Correlation() const;
};
bool BuildLsmNormalEquations(const LsmTemplate& patch,
                             const cv::Mat& search,
                             const LsmParameters& params,
                             Interpolation interpolation,
                             LsmNormalEquations* equations);

// Sets the radiometric parameters to their best values for the patch's
// geometry as it stands (the regression of the template's grey values on
// the resampled ones: r1 = cov(f, g) / var(g), at least min_scale) and
// turns the normal equations built at the old values into those at the new
// ones: exact, from the sums they hold, without resampling. MPGC matches
// grey values high-passed about 128, where the columns of r0 and r1 are
// nearly parallel and a joint Gauss-Newton step from a poor start swings
// the contrast back and forth (rendered tower: with the fit a third fewer
// points fail to converge). False where the resampled values do not vary.
bool FitLsmRadiometry(double min_scale,
                      LsmParameters* params,
                      LsmNormalEquations* equations);

// The correlation coefficient of the template and the search patch
// resampled at `params` alone, without the normal equations (the same value
// as BuildLsmNormalEquations' Correlation()): for searches that only rank
// positions. False where a sample leaves the search image.
bool LsmCorrelation(const LsmTemplate& patch,
                    const cv::Mat& search,
                    const LsmParameters& params,
                    Interpolation interpolation,
                    double* correlation);

struct LsmOptions {
  // Half side of the patch, pixels: 7 gives the 15 x 15 patch. Larger
  // patches are more precise on weak texture and less exact on relief.
  int patch_radius = 7;
  Interpolation interpolation = Interpolation::kBilinear;
  // Estimate the four shaping parameters (affine); off: shifts only.
  bool estimate_shape = true;
  // Estimate r0, r1; off: the grey values are compared as they are.
  bool estimate_radiometry = true;
  int max_iterations = 25;
  // Step control: where an iteration ends with a larger sum of squared
  // residuals than it started from, go back and take half the step instead
  // (each halving counts as an iteration). Gauss-Newton ignores the second
  // derivatives of the residuals; where the residuals are large (relief,
  // occlusion, non-affine distortion in real images) the full step can
  // overshoot by about 2x and the iteration then oscillates between two
  // states around the solution without converging. Off: plain Gauss-Newton.
  bool step_control = false;
  // Scale sigma0 for the noise the resampling removed (header comment).
  bool correct_resampling_noise = true;
  // Converged when the shift changes by less than this, and the shape moves
  // the patch corners by less than this, pixels.
  double convergence_px = 0.005;
  // Adaptive parameter selection (header comment).
  double min_pivot = 0.02;
  double min_shift_information_ratio = 0.05;
  // A template whose grey values vary less than this (standard deviation,
  // 0..255) is flat: nothing to match.
  double min_template_stddev = 2.0;
  // Diverged: the centre moved further than this from the approximation
  // (pixels), or the patch shape left these bounds (singular values of the
  // 2 x 2 shape relative to the approximation's).
  double max_shift_px = 5.0;
  double min_shape_scale = 0.5;
  double max_shape_scale = 2.0;
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

enum class LsmStatus {
  kConverged = 0,
  kOutsideImage,       // template or search patch leaves its image
  kFlatPatch,          // template without contrast
  kShiftUndetermined,  // converged, but a shift was not determinable
  kNotConverged,       // max_iterations reached
  kDiverged,           // moved too far or shape out of bounds
  kSingular,           // no determinable parameter at all
};
const char* LsmStatusName(LsmStatus status);

struct LsmMatch {
  LsmStatus status = LsmStatus::kSingular;
  LsmParameters params;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // = params.Position()
  // Covariance of xy (search pixels^2) and its standard deviations; a held
  // shift has no variance of its own (infinite standard deviation).
  Eigen::Matrix2d covariance_xy = Eigen::Matrix2d::Zero();
  Eigen::Vector2d sigma_xy = Eigen::Vector2d::Zero();
  // Standard deviations of all parameters (0 for held ones).
  LsmVector sigma = LsmVector::Zero();
  double sigma0 = 0;       // a posteriori, grey values
  double correlation = 0;  // template vs resampled search at the end
  int iterations = 0;
  int num_observations = 0;
  int redundancy = 0;                      // n - u of the last iteration
  std::array<bool, kNumLsmParams> held{};  // not determinable / not estimated

  bool ok() const { return status == LsmStatus::kConverged; }
};

// Adaptive selection (header comment): which parameters the normal matrix
// can determine, given the ones `enabled`. Returns the held ones (true: not
// estimated), as LsmMatch::held.
std::array<bool, kNumLsmParams> SelectLsmParameters(
    const LsmMatrix& N,
    const std::array<bool, kNumLsmParams>& enabled,
    const LsmOptions& options);

// Matches the template against one search image from the approximation
// (search-image pixel coordinates, same pyramid level as the template).
LsmMatch MatchLsm(const LsmTemplate& patch,
                  const cv::Mat& search,
                  const LsmParameters& approximation,
                  const LsmOptions& options);

// Convenience: cuts the template (options.patch_radius) and matches it.
LsmMatch MatchLsm(const cv::Mat& template_image,
                  const Eigen::Vector2d& template_xy,
                  const cv::Mat& search,
                  const LsmParameters& approximation,
                  const LsmOptions& options);

// One template against several search images (unconstrained: each search
// patch has its own parameters, so the solutions are independent).
struct LsmSearch {
  const cv::Mat* image = nullptr;
  LsmParameters approximation;
};
std::vector<LsmMatch> MatchLsmMulti(const LsmTemplate& patch,
                                    const std::vector<LsmSearch>& searches,
                                    const LsmOptions& options);

}  // namespace bayon
