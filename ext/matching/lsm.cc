// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/lsm.h"

#include "ext/core/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {

const char* LsmParamName(int param) {
  static const char* const kNames[kNumLsmParams] = {
      "a0", "b0", "a1", "a2", "b1", "b2", "r0", "r1"};
  return param >= 0 && param < kNumLsmParams ? kNames[param] : "?";
}

const char* LsmStatusName(LsmStatus status) {
  switch (status) {
    case LsmStatus::kConverged:
      return "converged";
    case LsmStatus::kOutsideImage:
      return "outside_image";
    case LsmStatus::kFlatPatch:
      return "flat_patch";
    case LsmStatus::kShiftUndetermined:
      return "shift_undetermined";
    case LsmStatus::kNotConverged:
      return "not_converged";
    case LsmStatus::kDiverged:
      return "diverged";
    case LsmStatus::kSingular:
      return "singular";
  }
  return "?";
}

LsmParameters LsmParameters::At(const Eigen::Vector2d& xy,
                                const Eigen::Matrix2d& shape) {
  LsmParameters params;
  params.affine.leftCols<2>() = shape;
  params.affine.col(2) = xy;
  return params;
}

LsmVector LsmParameters::AsVector() const {
  LsmVector v;
  v[kLsmA0] = affine(0, 2);
  v[kLsmB0] = affine(1, 2);
  v[kLsmA1] = affine(0, 0);
  v[kLsmA2] = affine(0, 1);
  v[kLsmB1] = affine(1, 0);
  v[kLsmB2] = affine(1, 1);
  v[kLsmR0] = r0;
  v[kLsmR1] = r1;
  return v;
}

void LsmParameters::Add(const LsmVector& delta) {
  affine(0, 2) += delta[kLsmA0];
  affine(1, 2) += delta[kLsmB0];
  affine(0, 0) += delta[kLsmA1];
  affine(0, 1) += delta[kLsmA2];
  affine(1, 0) += delta[kLsmB1];
  affine(1, 1) += delta[kLsmB2];
  r0 += delta[kLsmR0];
  r1 += delta[kLsmR1];
}

bool ExtractLsmTemplate(const cv::Mat& image,
                        const Eigen::Vector2d& center,
                        int radius,
                        Interpolation interpolation,
                        LsmTemplate* patch) {
  CHECK_EQ(image.type(), CV_32F);
  const int side = 2 * radius + 1;
  patch->center = center;
  patch->radius = radius;
  patch->values.resize(side * side);
  patch->dx.resize(side * side);
  patch->dy.resize(side * side);
  double sum = 0, sum_sq = 0;
  int k = 0;
  for (int v = -radius; v <= radius; ++v) {
    for (int u = -radius; u <= radius; ++u, ++k) {
      ImageSample sample;
      if (!SampleImage(
              image, center.x() + u, center.y() + v, interpolation, &sample)) {
        return false;
      }
      patch->values[k] = sample.value;
      patch->dx[k] = sample.dx;
      patch->dy[k] = sample.dy;
      sum += sample.value;
      sum_sq += static_cast<double>(sample.value) * sample.value;
    }
  }
  const double n = side * side;
  patch->mean = sum / n;
  patch->stddev =
      std::sqrt(std::max(0.0, sum_sq / n - patch->mean * patch->mean));
  return true;
}

namespace {

// The correlation coefficient from the sums over n sample pairs (f, g).
double CorrelationFromSums(double n,
                           double sum_f,
                           double sum_g,
                           double sum_ff,
                           double sum_gg,
                           double sum_fg) {
  if (n < 2) return 0;
  const double cov = sum_fg - sum_f * sum_g / n;
  const double var_f = sum_ff - sum_f * sum_f / n;
  const double var_g = sum_gg - sum_g * sum_g / n;
  if (var_f <= 0 || var_g <= 0) return 0;
  return cov / std::sqrt(var_f * var_g);
}

// Whether every sample of a patch of radius r under `affine` has its
// bilinear footprint (InsideSampleFootprint) in the image: its four corner
// samples have, with a margin against rounding (the region is convex and
// holds the samples' convex hull). False also sends a patch near the border
// to the per-sample test.
bool BilinearPatchInside(const cv::Mat& image,
                         const Eigen::Matrix<double, 2, 3>& affine,
                         int r) {
  constexpr double kMargin = 1e-6;
  for (int v : {-r, r}) {
    for (int u : {-r, r}) {
      const double x = affine(0, 2) + affine(0, 0) * u + affine(0, 1) * v;
      const double y = affine(1, 2) + affine(1, 0) * u + affine(1, 1) * v;
      if (!InsideSampleFootprint(image, x - kMargin, y - kMargin) ||
          !InsideSampleFootprint(image, x + kMargin, y + kMargin)) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace

double LsmNormalEquations::Correlation() const {
  return CorrelationFromSums(
      num_observations, sum_f, sum_g, sum_ff, sum_gg, sum_fg);
}

bool LsmCorrelation(const LsmTemplate& patch,
                    const cv::Mat& search,
                    const LsmParameters& params,
                    Interpolation interpolation,
                    double* correlation) {
  const int r = patch.radius;
  const auto& a = params.affine;
  if (interpolation == Interpolation::kBilinear &&
      BilinearPatchInside(search, a, r)) {
    // The search along a ray calls this for every sample and view: values
    // only, no test per sample, the template's sums known (its mean and
    // contrast).
    double sum_g = 0, sum_gg = 0, sum_fg = 0;
    int k = 0;
    for (int v = -r; v <= r; ++v) {
      for (int u = -r; u <= r; ++u, ++k) {
        const float g =
            BilinearValueInside(search,
                                a(0, 2) + a(0, 0) * u + a(0, 1) * v - 0.5,
                                a(1, 2) + a(1, 0) * u + a(1, 1) * v - 0.5);
        sum_g += g;
        sum_gg += static_cast<double>(g) * g;
        sum_fg += (patch.values[k] - patch.mean) * g;
      }
    }
    const double n = patch.size();
    const double var_f = n * patch.stddev * patch.stddev;
    const double var_g = sum_gg - sum_g * sum_g / n;
    *correlation =
        var_f > 0 && var_g > 0 ? sum_fg / std::sqrt(var_f * var_g) : 0;
    return true;
  }
  double sum_f = 0, sum_g = 0, sum_ff = 0, sum_gg = 0, sum_fg = 0;
  int k = 0;
  for (int v = -r; v <= r; ++v) {
    for (int u = -r; u <= r; ++u, ++k) {
      const double x = a(0, 2) + a(0, 0) * u + a(0, 1) * v;
      const double y = a(1, 2) + a(1, 0) * u + a(1, 1) * v;
      // Values only: no gradients to interpolate.
      float value = 0;
      if (interpolation == Interpolation::kBilinear) {
        if (!SampleBilinear(search, x, y, &value)) return false;
      } else {
        ImageSample sample;
        if (!SampleImage(search, x, y, interpolation, &sample)) return false;
        value = sample.value;
      }
      const double f = patch.values[k];
      const double g = value;
      sum_f += f;
      sum_g += g;
      sum_ff += f * f;
      sum_gg += g * g;
      sum_fg += f * g;
    }
  }
  *correlation =
      CorrelationFromSums(patch.size(), sum_f, sum_g, sum_ff, sum_gg, sum_fg);
  return true;
}

bool BuildLsmNormalEquations(const LsmTemplate& patch,
                             const cv::Mat& search,
                             const LsmParameters& params,
                             Interpolation interpolation,
                             LsmNormalEquations* equations) {
  const int r = patch.radius;
  const auto& a = params.affine;
  // A sample's row of the design matrix is (gx, gy, gx u, gx v, gy u, gy v,
  // 1, g). Along a patch row v is constant, so the row is c_i q_m(i) for the
  // six values q = (gx, gy, gx u, gy u, 1, g), with c_i = v for the two
  // entries in v and 1 otherwise: per sample the 21 products of q are
  // summed (instead of 36 of the full row), and per patch row they are
  // spread into A'A (upper triangle, plain arrays, mirrored at the end).
  constexpr int kQ = 6;
  constexpr int kFrom[kNumLsmParams] = {0, 1, 2, 0, 3, 1, 4, 5};
  double n_upper[kNumLsmParams][kNumLsmParams] = {};
  double rhs[kNumLsmParams] = {};
  double residual_sq = 0;
  double sum_f = 0, sum_g = 0, sum_ff = 0, sum_gg = 0, sum_fg = 0;
  double noise_gain_sum = 0;
  // Bilinear patches away from the border: no test per sample.
  const bool inside = interpolation == Interpolation::kBilinear &&
                      BilinearPatchInside(search, a, r);
  int k = 0;
  for (int v = -r; v <= r; ++v) {
    double q_upper[kQ][kQ] = {};
    double q_rhs[kQ] = {};
    for (int u = -r; u <= r; ++u, ++k) {
      const double x = a(0, 2) + a(0, 0) * u + a(0, 1) * v;
      const double y = a(1, 2) + a(1, 0) * u + a(1, 1) * v;
      ImageSample sample;
      float noise_gain;
      if (inside) {
        SampleBilinearInside(search, x, y, &sample, &noise_gain);
      } else {
        if (!SampleImage(search, x, y, interpolation, &sample)) return false;
        noise_gain = InterpolationNoiseGain(interpolation, x, y);
      }
      const double f = patch.values[k];
      const double g = sample.value;
      const double gx = params.r1 * sample.dx;
      const double gy = params.r1 * sample.dy;
      const double q[kQ] = {gx, gy, gx * u, gy * u, 1.0, g};
      const double l = f - params.r0 - params.r1 * g;
      for (int i = 0; i < kQ; ++i) {
        for (int j = i; j < kQ; ++j) q_upper[i][j] += q[i] * q[j];
        q_rhs[i] += q[i] * l;
      }
      residual_sq += l * l;
      sum_f += f;
      sum_g += g;
      sum_ff += f * f;
      sum_gg += g * g;
      sum_fg += f * g;
      noise_gain_sum += noise_gain;
    }
    const double c[kNumLsmParams] = {1, 1, 1, double(v), 1, double(v), 1, 1};
    for (int i = 0; i < kNumLsmParams; ++i) {
      for (int j = i; j < kNumLsmParams; ++j) {
        const int qi = std::min(kFrom[i], kFrom[j]);
        const int qj = std::max(kFrom[i], kFrom[j]);
        n_upper[i][j] += c[i] * c[j] * q_upper[qi][qj];
      }
      rhs[i] += c[i] * q_rhs[kFrom[i]];
    }
  }
  for (int i = 0; i < kNumLsmParams; ++i) {
    for (int j = i; j < kNumLsmParams; ++j) {
      equations->N(i, j) = equations->N(j, i) = n_upper[i][j];
    }
    equations->rhs[i] = rhs[i];
  }
  equations->residual_sq = residual_sq;
  equations->num_observations = patch.size();
  equations->sum_f = sum_f;
  equations->sum_g = sum_g;
  equations->sum_ff = sum_ff;
  equations->sum_gg = sum_gg;
  equations->sum_fg = sum_fg;
  equations->noise_gain_sum = noise_gain_sum;
  return true;
}

bool FitLsmRadiometry(double min_scale,
                      LsmParameters* params,
                      LsmNormalEquations* equations) {
  const LsmNormalEquations& e = *equations;
  const double n = e.num_observations;
  const double var_g = e.sum_gg - e.sum_g * e.sum_g / n;
  if (!(n > 0) || !(var_g > 0) || params->r1 == 0) return false;
  const double r1 =
      std::max(min_scale, (e.sum_fg - e.sum_f * e.sum_g / n) / var_g);
  const double r0 = (e.sum_f - r1 * e.sum_g) / n;
  // Residuals l' = l + a + b g; the geometric columns carry r1 (scaled by
  // s), the radiometric ones (1 and g) do not.
  const double a = params->r0 - r0;
  const double b = params->r1 - r1;
  const double s = r1 / params->r1;
  LsmMatrix& N = equations->N;
  LsmVector& rhs = equations->rhs;
  equations->residual_sq +=
      2 * a * rhs[kLsmR0] + 2 * b * rhs[kLsmR1] + a * a * N(kLsmR0, kLsmR0) +
      2 * a * b * N(kLsmR0, kLsmR1) + b * b * N(kLsmR1, kLsmR1);
  for (int i = 0; i < kNumLsmParams; ++i) {
    rhs[i] += a * N(i, kLsmR0) + b * N(i, kLsmR1);
  }
  LsmVector scale = LsmVector::Constant(s);
  scale[kLsmR0] = scale[kLsmR1] = 1;
  rhs = rhs.cwiseProduct(scale);
  N = scale.asDiagonal() * N * scale.asDiagonal();
  equations->residual_sq = std::max(0.0, equations->residual_sq);
  params->r0 = r0;
  params->r1 = r1;
  return true;
}

void LsmOptions::Check() const {
  CheckOption(patch_radius >= 2 && patch_radius <= 50,
              "patch_radius",
              "in [2, 50]",
              patch_radius);
  CheckOption(max_iterations >= 1, "max_iterations", ">= 1", max_iterations);
  CheckOption(convergence_px > 0, "convergence_px", "> 0", convergence_px);
  CheckOption(
      min_pivot > 0 && min_pivot < 1, "min_pivot", "in (0, 1)", min_pivot);
  CheckOption(
      min_shift_information_ratio > 0 && min_shift_information_ratio < 1,
      "min_shift_information_ratio",
      "in (0, 1)",
      min_shift_information_ratio);
  CheckOption(min_template_stddev >= 0,
              "min_template_stddev",
              ">= 0",
              min_template_stddev);
  CheckOption(max_shift_px > 0, "max_shift_px", "> 0", max_shift_px);
  CheckOption(min_shape_scale > 0 && min_shape_scale < 1,
              "min_shape_scale",
              "in (0, 1)",
              min_shape_scale);
  CheckOption(max_shape_scale > 1, "max_shape_scale", "> 1", max_shape_scale);
}

void LsmOptions::Register(OptionRegistry* r) {
  r->Add("patch_radius",
         &patch_radius,
         "Half side of the patches, px (7: 15 x 15)");
  r->AddChoice("interpolation",
               &interpolation,
               ChoicesOf<Interpolation>(
                   InterpolationName,
                   {Interpolation::kBilinear, Interpolation::kBicubic}),
               "Resampling of the search patches");
  r->Add("estimate_shape",
         &estimate_shape,
         "1: affine patch shape; 0: shifts only");
  r->Add("estimate_radiometry",
         &estimate_radiometry,
         "1: estimate brightness and contrast; 0: grey values as they are");
  r->Add("max_iterations", &max_iterations, "Most iterations per match");
  r->Add("step_control",
         &step_control,
         "1: halve a step that raises the sum of squares");
  r->Add("correct_resampling_noise",
         &correct_resampling_noise,
         "1: scale sigma0 for the noise the resampling removed");
  r->Add("convergence_px",
         &convergence_px,
         "Converged when shift and patch corners move less, px");
  r->Add("min_pivot",
         &min_pivot,
         "Adaptive parameters: smallest pivot of a parameter taken");
  r->Add("min_shift_information_ratio",
         &min_shift_information_ratio,
         "Adaptive parameters: smallest share of a shift's information kept");
  r->Add("min_template_stddev",
         &min_template_stddev,
         "Templates with less contrast are flat (standard deviation of the "
         "grey values)");
  r->Add("max_shift_px",
         &max_shift_px,
         "Diverged: the centre moved further from its approximation, px");
  r->Add("min_shape_scale",
         &min_shape_scale,
         "Diverged: the patch shape shrank below this scale");
  r->Add("max_shape_scale",
         &max_shape_scale,
         "Diverged: the patch shape grew beyond this scale");
}

namespace {

// The parameters taken so far as the Cholesky factor L of their normal
// matrix N_SS (taken one at a time, so L grows by a row per parameter): the
// conditional information of another parameter j, the Schur complement
// N_jj - N_jS N_SS^-1 N_Sj, is N_jj - |y|^2 with L y = N_Sj, one forward
// substitution instead of a factorisation per question. Every parameter is
// taken with a positive conditional information, so L stays regular.
class TakenParameters {
 public:
  explicit TakenParameters(const LsmMatrix& N) : N_(N) {}

  // What parameter j would add: its conditional information s and the row
  // y that would extend L (L y = N_Sj).
  struct Candidate {
    int j = -1;
    double information = 0;
    LsmVector y;
  };
  Candidate Consider(int j) const {
    Candidate c;
    c.j = j;
    c.information = N_(j, j);
    for (int a = 0; a < size_; ++a) {
      double v = N_(index_[a], j);
      for (int b = 0; b < a; ++b) v -= L_(a, b) * c.y[b];
      c.y[a] = v / L_(a, a);
      c.information -= c.y[a] * c.y[a];
    }
    return c;
  }

  // Takes a considered parameter; its information must be positive (the
  // selection's thresholds are), or L would not stay regular.
  void Take(const Candidate& c) {
    for (int b = 0; b < size_; ++b) L_(size_, b) = c.y[b];
    L_(size_, size_) = std::sqrt(c.information);
    index_[size_++] = c.j;
  }

 private:
  const LsmMatrix& N_;
  LsmMatrix L_ = LsmMatrix::Zero();
  std::array<int, kNumLsmParams> index_{};
  int size_ = 0;
};

std::vector<int> FreeIndices(const std::array<bool, kNumLsmParams>& held) {
  std::vector<int> free;
  for (int i = 0; i < kNumLsmParams; ++i) {
    if (!held[i]) free.push_back(i);
  }
  return free;
}

}  // namespace

std::array<bool, kNumLsmParams> SelectLsmParameters(
    const LsmMatrix& N_in,
    const std::array<bool, kNumLsmParams>& enabled,
    const LsmOptions& options) {
  // Radiometry in centred form, r1 against g - mean(g): whether the scale is
  // determinable must not depend on how bright the patch is. The column of
  // r0 is all ones, so N(r0, r0) = n and N(r0, r1) = sum g.
  // That is N = T' N T with T the identity but T(r0, r1) = -mean(g): the
  // column of r1, then its row, less mean(g) times r0's.
  LsmMatrix N = N_in;
  if (N(kLsmR0, kLsmR0) > 0) {
    const double mean_g = N(kLsmR0, kLsmR1) / N(kLsmR0, kLsmR0);
    N.col(kLsmR1) -= mean_g * N.col(kLsmR0);
    N.row(kLsmR1) -= mean_g * N.row(kLsmR0);
  }
  std::array<bool, kNumLsmParams> held;
  held.fill(true);
  TakenParameters taken(N);
  auto accept = [&](const TakenParameters::Candidate& c) {
    taken.Take(c);
    held[c.j] = false;
  };
  // Shifts: the better determined first, the other one only if it carries
  // enough information of its own.
  int first = kLsmA0, second = kLsmB0;
  if (N(kLsmB0, kLsmB0) > N(kLsmA0, kLsmA0)) std::swap(first, second);
  if (enabled[first] && N(first, first) > 0) {
    accept(taken.Consider(first));
    if (enabled[second]) {
      const TakenParameters::Candidate c = taken.Consider(second);
      if (c.information > 0 &&
          c.information >=
              options.min_shift_information_ratio * N(first, first)) {
        accept(c);
      }
    }
  } else if (enabled[second] && N(second, second) > 0) {
    accept(taken.Consider(second));
  }
  for (int j : {kLsmR0, kLsmR1, kLsmA1, kLsmB2, kLsmA2, kLsmB1}) {
    if (!enabled[j] || !(N(j, j) > 0)) continue;
    const TakenParameters::Candidate c = taken.Consider(j);
    if (c.information > options.min_pivot * N(j, j)) accept(c);
  }
  return held;
}

namespace {

bool ShapeWithinBounds(const Eigen::Matrix2d& shape,
                       const Eigen::Matrix2d& approximation,
                       const LsmOptions& options) {
  const double det = approximation.determinant();
  if (!(std::abs(det) > 1e-12)) return false;
  const Eigen::Matrix2d relative = shape * approximation.inverse();
  if (relative.determinant() <= 0) return false;  // patch turned inside out
  const Eigen::Vector2d singular =
      Eigen::JacobiSVD<Eigen::Matrix2d>(relative).singularValues();
  return singular[1] >= options.min_shape_scale &&
         singular[0] <= options.max_shape_scale;
}

}  // namespace

LsmMatch MatchLsm(const LsmTemplate& patch,
                  const cv::Mat& search,
                  const LsmParameters& approximation,
                  const LsmOptions& options) {
  LsmMatch match;
  match.params = approximation;
  match.xy = approximation.Position();
  if (patch.stddev < options.min_template_stddev) {
    match.status = LsmStatus::kFlatPatch;
    return match;
  }
  std::array<bool, kNumLsmParams> enabled;
  enabled.fill(true);
  for (int j : {kLsmA1, kLsmA2, kLsmB1, kLsmB2}) {
    enabled[j] = options.estimate_shape;
  }
  enabled[kLsmR0] = enabled[kLsmR1] = options.estimate_radiometry;

  LsmParameters params = approximation;
  LsmNormalEquations equations;
  std::array<bool, kNumLsmParams> held{};
  bool converged = false;
  const double r = patch.radius;
  // The step control's memory: where the last step started, its residuals
  // there, and the step.
  LsmParameters step_start;
  double step_start_residual_sq = std::numeric_limits<double>::infinity();
  LsmVector last_delta = LsmVector::Zero();
  const auto small_step = [r, &options](const LsmVector& delta) {
    const double shift_change = std::hypot(delta[kLsmA0], delta[kLsmB0]);
    const double corner_change =
        r * (std::abs(delta[kLsmA1]) + std::abs(delta[kLsmA2]) +
             std::abs(delta[kLsmB1]) + std::abs(delta[kLsmB2]));
    return shift_change < options.convergence_px &&
           corner_change < options.convergence_px;
  };
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    match.iterations = iteration;
    if (!BuildLsmNormalEquations(
            patch, search, params, options.interpolation, &equations)) {
      match.status = LsmStatus::kOutsideImage;
      match.params = params;
      match.xy = params.Position();
      return match;
    }
    if (options.step_control &&
        equations.residual_sq > step_start_residual_sq) {
      // The last step went too far: half of it from where it started.
      last_delta *= 0.5;
      params = step_start;
      params.Add(last_delta);
      if (small_step(last_delta)) {
        converged = true;
        break;
      }
      continue;
    }
    step_start = params;
    step_start_residual_sq = equations.residual_sq;
    held = SelectLsmParameters(equations.N, enabled, options);
    const std::vector<int> free = FreeIndices(held);
    if (free.empty()) {
      match.status = LsmStatus::kSingular;
      return match;
    }
    const int m = static_cast<int>(free.size());
    Eigen::MatrixXd nr(m, m);
    Eigen::VectorXd br(m);
    for (int a = 0; a < m; ++a) {
      for (int b = 0; b < m; ++b) nr(a, b) = equations.N(free[a], free[b]);
      br[a] = equations.rhs[free[a]];
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(nr);
    if (ldlt.info() != Eigen::Success) {
      match.status = LsmStatus::kSingular;
      return match;
    }
    const Eigen::VectorXd dr = ldlt.solve(br);
    LsmVector delta = LsmVector::Zero();
    for (int a = 0; a < m; ++a) delta[free[a]] = dr[a];
    if (!delta.allFinite()) {
      match.status = LsmStatus::kSingular;
      return match;
    }
    last_delta = delta;
    params.Add(delta);
    if ((params.Position() - approximation.Position()).norm() >
            options.max_shift_px ||
        !ShapeWithinBounds(params.Shape(), approximation.Shape(), options) ||
        !(params.r1 > 0)) {
      match.status = LsmStatus::kDiverged;
      match.params = params;
      match.xy = params.Position();
      return match;
    }
    if (small_step(delta)) {
      converged = true;
      break;
    }
  }
  match.params = params;
  match.xy = params.Position();
  match.held = held;

  // Statistics at the final estimate: residuals, sigma0 and the covariance
  // of the parameters estimated in the last iteration.
  if (!BuildLsmNormalEquations(
          patch, search, params, options.interpolation, &equations)) {
    match.status = LsmStatus::kOutsideImage;
    return match;
  }
  const std::vector<int> free = FreeIndices(held);
  const int m = static_cast<int>(free.size());
  Eigen::MatrixXd nr(m, m);
  Eigen::VectorXd br(m);
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) nr(a, b) = equations.N(free[a], free[b]);
    br[a] = equations.rhs[free[a]];
  }
  const Eigen::MatrixXd q = nr.inverse();
  const double vtv = std::max(0.0, equations.residual_sq - br.dot(q * br));
  match.num_observations = equations.num_observations;
  match.redundancy = equations.num_observations - m;
  match.sigma0 = match.redundancy > 0 ? std::sqrt(vtv / match.redundancy) : 0.0;
  if (options.correct_resampling_noise && equations.num_observations > 0) {
    const double kept = equations.noise_gain_sum / equations.num_observations;
    const double r1_sq = params.r1 * params.r1;
    match.sigma0 *= std::sqrt((1 + r1_sq) / (1 + r1_sq * kept));
  }
  match.correlation = equations.Correlation();
  const double inf = std::numeric_limits<double>::infinity();
  for (int a = 0; a < m; ++a) {
    match.sigma[free[a]] = match.sigma0 * std::sqrt(std::max(0.0, q(a, a)));
  }
  int index_of[kNumLsmParams];
  std::fill(index_of, index_of + kNumLsmParams, -1);
  for (int a = 0; a < m; ++a) index_of[free[a]] = a;
  const int ia = index_of[kLsmA0], ib = index_of[kLsmB0];
  match.covariance_xy.setZero();
  match.covariance_xy(0, 0) =
      ia >= 0 ? match.sigma0 * match.sigma0 * q(ia, ia) : inf;
  match.covariance_xy(1, 1) =
      ib >= 0 ? match.sigma0 * match.sigma0 * q(ib, ib) : inf;
  if (ia >= 0 && ib >= 0) {
    match.covariance_xy(0, 1) = match.covariance_xy(1, 0) =
        match.sigma0 * match.sigma0 * q(ia, ib);
  }
  match.sigma_xy = Eigen::Vector2d(std::sqrt(match.covariance_xy(0, 0)),
                                   std::sqrt(match.covariance_xy(1, 1)));
  if (!converged) {
    match.status = LsmStatus::kNotConverged;
  } else if (held[kLsmA0] || held[kLsmB0]) {
    match.status = LsmStatus::kShiftUndetermined;
  } else {
    match.status = LsmStatus::kConverged;
  }
  return match;
}

LsmMatch MatchLsm(const cv::Mat& template_image,
                  const Eigen::Vector2d& template_xy,
                  const cv::Mat& search,
                  const LsmParameters& approximation,
                  const LsmOptions& options) {
  LsmTemplate patch;
  if (!ExtractLsmTemplate(template_image,
                          template_xy,
                          options.patch_radius,
                          options.interpolation,
                          &patch)) {
    LsmMatch match;
    match.status = LsmStatus::kOutsideImage;
    match.params = approximation;
    match.xy = approximation.Position();
    return match;
  }
  return MatchLsm(patch, search, approximation, options);
}

std::vector<LsmMatch> MatchLsmMulti(const LsmTemplate& patch,
                                    const std::vector<LsmSearch>& searches,
                                    const LsmOptions& options) {
  std::vector<LsmMatch> matches;
  matches.reserve(searches.size());
  for (const LsmSearch& search : searches) {
    CHECK(search.image != nullptr);
    matches.push_back(
        MatchLsm(patch, *search.image, search.approximation, options));
  }
  return matches;
}

}  // namespace bayon
