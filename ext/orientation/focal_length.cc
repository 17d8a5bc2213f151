// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/focal_length.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {

FocalLengthOptions::FocalLengthOptions() {
  // Each hypothesis orients every pair with the full settings (fewer
  // samples let temple-ring's narrow pairs settle on false minima). No pair
  // is refused for its sigma: a wrong hypothesis must score badly, not
  // vanish.
  estimation.max_sigma_px = std::numeric_limits<double>::max();
}

void FocalLengthOptions::Check() const {
  CheckOption(min_focal_ratio > 0,
              "FocalLengthOptions.min_focal_ratio",
              "> 0",
              min_focal_ratio);
  CheckOption(max_focal_ratio > min_focal_ratio,
              "FocalLengthOptions.max_focal_ratio",
              "> min_focal_ratio",
              max_focal_ratio);
  CheckOption(grid_step > 1, "FocalLengthOptions.grid_step", "> 1", grid_step);
  CheckOption(tolerance > 0 && tolerance < 0.1,
              "FocalLengthOptions.tolerance",
              "in (0, 0.1)",
              tolerance);
  CheckOption(inlier_threshold_px > 0,
              "FocalLengthOptions.inlier_threshold_px",
              "> 0",
              inlier_threshold_px);
  CheckOption(min_rise_ratio > 1,
              "FocalLengthOptions.min_rise_ratio",
              "> 1",
              min_rise_ratio);
  CheckOption(min_rise >= 1, "FocalLengthOptions.min_rise", ">= 1", min_rise);
  CheckOption(max_relative_sigma > 0,
              "FocalLengthOptions.max_relative_sigma",
              "> 0",
              max_relative_sigma);
  estimation.Check();
}

namespace {

// The score of one hypothesis (see the header): per pair the calibrated
// orientation at f and its points' truncated squared residuals.
class FocalScore {
 public:
  FocalScore(const std::vector<ConjugatePoints>& pairs,
             const FocalLengthOptions& options)
      : pairs_(pairs), options_(options), use_(pairs.size(), true) {
    options_.estimation.calibrated = true;
  }

  struct Value {
    double score = 0;  // the sum of truncated squares
    // The points within the threshold and their squares' sum, for the
    // variance of unit weight.
    int num_inliers = 0;
    double inlier_sum = 0;
    // The orientation was accepted, with this robust sigma (pixels).
    bool oriented = false;
    double sigma_px = 0;
    Value& operator+=(const Value& other) {
      score += other.score;
      num_inliers += other.num_inliers;
      inlier_sum += other.inlier_sum;
      return *this;
    }
  };

  // Each pair's value at f.
  std::vector<Value> PerPair(double focal_px) const {
    const double t2 =
        options_.inlier_threshold_px * options_.inlier_threshold_px;
    std::vector<Value> values(pairs_.size());
    ParallelFor(
        static_cast<int>(pairs_.size()), options_.num_threads, [&](int k) {
          if (!use_[k]) return;
          const ConjugatePoints points = AtFocal(pairs_[k], focal_px);
          const RelativeOrientation orientation =
              EstimateRelativeOrientation(points, options_.estimation);
          Value& value = values[k];
          value.oriented = orientation.success;
          value.sigma_px = orientation.lmeds_sigma_px;
          if (orientation.M.isZero()) {
            value.score = t2 * points.size();
            return;
          }
          for (double r : DrtResiduals(orientation.M,
                                       points.u1,
                                       points.u2,
                                       DrtResidual::kSampson)) {
            value.score += std::min(r * r, t2);
            if (r * r < t2) {
              ++value.num_inliers;
              value.inlier_sum += r * r;
            }
          }
        });
    return values;
  }

  // The score of the pairs in use at f.
  Value operator()(double focal_px) const {
    Value total;
    for (const Value& value : PerPair(focal_px)) total += value;
    return total;
  }

  // Only these pairs count from now on.
  void Use(const std::vector<bool>& use) { use_ = use; }

 private:
  static ConjugatePoints AtFocal(ConjugatePoints points, double focal_px) {
    for (auto* vectors : {&points.u1, &points.u2}) {
      for (Eigen::Vector3d& u : *vectors) {
        // x and y are pixels whatever the guessed camera constant.
        u.z() = -focal_px;
      }
    }
    return points;
  }

  const std::vector<ConjugatePoints>& pairs_;
  FocalLengthOptions options_;
  std::vector<bool> use_;
};

// The golden-section search for the minimum of score(exp(x)) in [a, b],
// down to a width of `tolerance`.
double GoldenSection(const FocalScore& score,
                     double a,
                     double b,
                     double tolerance) {
  const double golden = (std::sqrt(5.0) - 1) / 2;
  double c = b - golden * (b - a), d = a + golden * (b - a);
  double score_c = score(std::exp(c)).score;
  double score_d = score(std::exp(d)).score;
  while (b - a > tolerance) {
    if (score_c < score_d) {
      b = d;
      d = c;
      score_d = score_c;
      c = b - golden * (b - a);
      score_c = score(std::exp(c)).score;
    } else {
      a = c;
      c = d;
      score_c = score_d;
      d = a + golden * (b - a);
      score_d = score(std::exp(d)).score;
    }
  }
  return (a + b) / 2;
}

// The relative standard deviation of the estimate exp(x) from the score's
// curvature over +-h, h a few per cent: wide enough that the samples' noise
// in the score does not dominate. The variance of unit weight comes from
// the points within the threshold, the blunders being a constant of the
// score.
double RelativeSigma(const FocalScore& score,
                     double x,
                     const FocalScore::Value& at_x,
                     int num_pairs) {
  const double h = 0.03;
  const double curvature = (score(std::exp(x + h)).score - 2 * at_x.score +
                            score(std::exp(x - h)).score) /
                           (h * h);
  const int dof = at_x.num_inliers - 5 * num_pairs - 1;
  if (dof <= 0 || !(curvature > 0)) {
    return std::numeric_limits<double>::infinity();
  }
  return std::sqrt(2 * at_x.inlier_sum / dof / curvature);
}

}  // namespace

FocalLengthEstimate EstimateFocalLength(
    const std::vector<ConjugatePoints>& pairs,
    double long_side_px,
    const FocalLengthOptions& options) {
  options.Check();
  CheckOption(long_side_px > 0, "long_side_px", "> 0", long_side_px);
  FocalLengthEstimate estimate;
  std::vector<ConjugatePoints> usable;
  for (const ConjugatePoints& points : pairs) {
    if (points.size() >= options.estimation.min_num_points) {
      usable.push_back(points);
    }
  }
  if (usable.empty()) {
    estimate.reason = "no image pair with enough conjugate points";
    return estimate;
  }
  FocalScore score(usable, options);

  // The grid, in x = ln f. A pair counts only if some hypothesis orients it
  // with a robust sigma of max_pair_sigma_px or better: identical images
  // (no base), chance matches and other motions say nothing about f.
  const double x_min = std::log(options.min_focal_ratio * long_side_px);
  const double x_max = std::log(options.max_focal_ratio * long_side_px);
  const double step = std::log(options.grid_step);
  std::vector<double> xs;
  std::vector<std::vector<FocalScore::Value>> grid_values;
  for (double x = x_min; x <= x_max + 1e-12; x += step) {
    xs.push_back(x);
    grid_values.push_back(score.PerPair(std::exp(x)));
  }
  std::vector<bool> use(usable.size(), false);
  for (const auto& values : grid_values) {
    for (size_t k = 0; k < values.size(); ++k) {
      use[k] = use[k] || (values[k].oriented &&
                          values[k].sigma_px <= options.max_pair_sigma_px);
    }
  }
  score.Use(use);
  for (size_t k = 0; k < usable.size(); ++k) {
    if (!use[k]) continue;
    ++estimate.num_pairs;
    estimate.num_points += usable[k].size();
  }
  if (estimate.num_pairs == 0) {
    estimate.reason = StrCat("no pair of the ",
                             usable.size(),
                             " tried could be oriented at any focal length");
    return estimate;
  }
  std::vector<double> scores;
  for (size_t i = 0; i < xs.size(); ++i) {
    FocalScore::Value total;
    for (size_t k = 0; k < usable.size(); ++k) {
      if (use[k]) total += grid_values[i][k];
    }
    scores.push_back(total.score);
    estimate.grid.emplace_back(std::exp(xs[i]), total.score);
  }
  const int best = static_cast<int>(
      std::min_element(scores.begin(), scores.end()) - scores.begin());
  if (best == 0 || best + 1 == static_cast<int>(xs.size())) {
    estimate.reason = StrCat(
        "the photographs do not fix the focal length "
        "in the range searched: the best value is at "
        "its end (",
        std::exp(xs[best]) / long_side_px,
        " x the long side)");
    return estimate;
  }

  const double x =
      GoldenSection(score, xs[best - 1], xs[best + 1], options.tolerance);
  estimate.focal_length_px = std::exp(x);
  const FocalScore::Value at_estimate = score(estimate.focal_length_px);
  estimate.score = at_estimate.score;
  estimate.relative_sigma =
      RelativeSigma(score, x, at_estimate, estimate.num_pairs);
  if (!(estimate.relative_sigma <= options.max_relative_sigma)) {
    estimate.reason = StrCat("the photographs do not fix the focal length ",
                             "(relative standard deviation ",
                             estimate.relative_sigma,
                             " > ",
                             options.max_relative_sigma,
                             ")");
    return estimate;
  }
  const double rise =
      std::min(score(estimate.focal_length_px * options.min_rise_ratio).score,
               score(estimate.focal_length_px / options.min_rise_ratio).score) /
      estimate.score;
  if (!(rise >= options.min_rise)) {
    estimate.reason = StrCat(
        "the photographs do not fix the focal length: "
        "its score rises by only ",
        100 * (rise - 1),
        " % at ",
        options.min_rise_ratio,
        " times or 1 / ",
        options.min_rise_ratio,
        " times the best value (",
        estimate.focal_length_px,
        " px); give the focal length (EXIF, "
        "--focal_length_mm or a calibrated camera)");
    return estimate;
  }
  estimate.success = true;
  return estimate;
}

}  // namespace bayon
