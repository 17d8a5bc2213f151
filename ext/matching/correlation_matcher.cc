// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/correlation_matcher.h"

#include "ext/core/errors.h"
#include "ext/core/robust_estimator.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <complex>
#include <unordered_map>
#include <utility>

namespace bayon {

void CorrelationMatchingOptions::Register(OptionRegistry* r) {
  r->Add("min_ncc", &min_ncc, "Correlation threshold r");
  r->Add("search_window_fraction",
         &search_window_fraction,
         "Search window area as a fraction of the image");
  r->Add("max_keypoint_shift_px",
         &max_keypoint_shift_px,
         "Image-2 windows also shifted this far from the keypoint");
  r->Add("max_candidates_per_point",
         &max_candidates_per_point,
         "Candidates kept per point");
  r->Add("detect_rotation",
         &detect_rotation,
         "1: find in-plane rotations by quarter turns");
  r->Add("num_passes",
         &num_passes,
         "Matching passes (later ones centred on earlier matches)");
  r->AddNested("relaxation", &relaxation);
}

void CorrelationMatchingOptions::Check() const {
  CheckOption(min_ncc > -1 && min_ncc < 1, "min_ncc", "in (-1, 1)", min_ncc);
  CheckOption(search_window_fraction > 0 && search_window_fraction <= 4,
              "search_window_fraction",
              "in (0, 4]",
              search_window_fraction);
  CheckOption(max_candidates_per_point >= 1,
              "max_candidates_per_point",
              ">= 1",
              max_candidates_per_point);
  CheckOption(max_keypoint_shift_px >= 0 && max_keypoint_shift_px <= 3,
              "max_keypoint_shift_px",
              "in [0, 3]",
              max_keypoint_shift_px);
  CheckOption(shift_min_ncc > -1 && shift_min_ncc < 1,
              "shift_min_ncc",
              "in (-1, 1)",
              shift_min_ncc);
  CheckOption(refine_min_ncc > -1 && refine_min_ncc < 1,
              "refine_min_ncc",
              "in (-1, 1)",
              refine_min_ncc);
  CheckOption(
      global_num_points >= 4, "global_num_points", ">= 4", global_num_points);
  CheckOption(global_inlier_fraction > 0 && global_inlier_fraction < 1,
              "global_inlier_fraction",
              "in (0, 1)",
              global_inlier_fraction);
  CheckOption(global_min_inliers >= 2,
              "global_min_inliers",
              ">= 2",
              global_min_inliers);
  CheckOption(
      global_num_trials >= 1, "global_num_trials", ">= 1", global_num_trials);
  CheckOption(num_passes >= 1, "num_passes", ">= 1", num_passes);
  CheckOption(peak_sigma_px > 0, "peak_sigma_px", "> 0", peak_sigma_px);
  CheckNested("relaxation", relaxation);
}

namespace {

using Complex = std::complex<double>;

inline float Dot(const float* a, const float* b, int n) {
  return Eigen::Map<const Eigen::VectorXf>(a, n).dot(
      Eigen::Map<const Eigen::VectorXf>(b, n));
}

Complex ToComplex(const Eigen::Vector2d& p) { return Complex(p.x(), p.y()); }

// P(X >= k) for X ~ Poisson(lambda).
double PoissonTail(double lambda, int k) {
  if (k <= 0) return 1.0;
  double term = std::exp(-lambda), below = 0;
  for (int i = 0; i < k; ++i) {
    below += term;
    term *= lambda / (i + 1);
  }
  return std::max(0.0, 1.0 - below);
}

// Up to `count` valid points spread over a grid, the first valid point of
// each cell in index order (Moravec writes the strongest first).
std::vector<int> SpreadPoints(const ImagePatches& image, int count) {
  const int grid = std::max(1, static_cast<int>(std::ceil(std::sqrt(count))));
  std::vector<int> chosen(grid * grid, -1);
  for (int i = 0; i < image.size(); ++i) {
    if (!image.valid[i]) continue;
    const int cx = std::clamp(
        static_cast<int>(image.xy[i].x() * grid / image.width), 0, grid - 1);
    const int cy = std::clamp(
        static_cast<int>(image.xy[i].y() * grid / image.height), 0, grid - 1);
    int& cell = chosen[cy * grid + cx];
    if (cell < 0) cell = i;
  }
  std::vector<int> points;
  for (int idx : chosen) {
    if (idx >= 0) points.push_back(idx);
  }
  return points;
}

struct Vote {
  Complex z1, z2;
};

// The similarity z2 = a z1 + b of two votes (the model is (a, b)), and
// every vote's distance from it in image 2.
class SimilarityEstimator {
 public:
  using Model = std::pair<Complex, Complex>;
  static constexpr int kMinNumSamples = 2;

  explicit SimilarityEstimator(const std::vector<Vote>& votes)
      : votes_(votes) {}

  bool Estimate(const std::vector<int>& sample, Model* model) const {
    const Vote& v = votes_[sample[0]];
    const Complex dz1 = v.z1 - votes_[sample[1]].z1;
    if (std::abs(dz1) < 1e-6) return false;
    const Complex a = (v.z2 - votes_[sample[1]].z2) / dz1;
    *model = {a, v.z2 - a * v.z1};
    return true;
  }

  void Residuals(const Model& model, std::vector<double>* residuals) const {
    residuals->resize(votes_.size());
    for (size_t k = 0; k < votes_.size(); ++k) {
      (*residuals)[k] =
          std::abs(model.first * votes_[k].z1 + model.second - votes_[k].z2);
    }
  }

 private:
  const std::vector<Vote>& votes_;
};

// RANSAC for z2 = a z1 + b on two-point samples; returns the inliers of
// the best model.
std::vector<int> BestSimilarity(const std::vector<Vote>& votes,
                                double threshold,
                                int num_trials,
                                unsigned int seed,
                                Complex* a_best,
                                Complex* b_best) {
  if (votes.size() < 2) return {};
  UniformSampler sampler(static_cast<int>(votes.size()), seed);
  const RansacReport<SimilarityEstimator::Model> report =
      Ransac(SimilarityEstimator(votes), num_trials, threshold, &sampler);
  if (!report.success) return {};
  *a_best = report.model.first;
  *b_best = report.model.second;
  return report.inliers;
}

// Image 2 turned by r quarter turns about its centre, image centre on image
// centre.
GlobalMapping CentredTurn(const ImagePatches& image1,
                          const ImagePatches& image2,
                          int quarter_turns) {
  GlobalMapping mapping;
  mapping.quarter_turns = quarter_turns;
  const Eigen::Matrix2d R = QuarterRotation(quarter_turns);
  const Eigen::Vector2d c1(0.5 * image1.width, 0.5 * image1.height);
  const Eigen::Vector2d c2(0.5 * image2.width, 0.5 * image2.height);
  mapping.affine.leftCols<2>() = R;
  mapping.affine.col(2) = c2 - R * c1;
  return mapping;
}

// For every image-1 point: the mapping's prediction corrected by the median
// offset (observed minus predicted) of the nearest matched points.
std::vector<Eigen::Vector2d> PredictFromMatches(
    const ImagePatches& image1,
    const ImagePatches& image2,
    const GlobalMapping& mapping,
    const std::vector<MatchCandidate>& matches) {
  constexpr size_t kNeighbors = 8;
  const auto predict = [&](const Eigen::Vector2d& xy) {
    return Eigen::Vector2d(mapping.affine.leftCols<2>() * xy +
                           mapping.affine.col(2));
  };
  std::vector<Eigen::Vector2d> offsets;
  for (const MatchCandidate& m : matches) {
    offsets.push_back(image2.xy[m.idx2] - predict(image1.xy[m.idx1]));
  }
  std::vector<Eigen::Vector2d> centers(image1.size(),
                                       Eigen::Vector2d::Constant(std::nan("")));
  std::vector<std::pair<double, int>> near(matches.size());
  std::vector<double> dx, dy;
  for (int i = 0; i < image1.size(); ++i) {
    if (!image1.valid[i]) continue;
    for (size_t k = 0; k < matches.size(); ++k) {
      near[k] = {(image1.xy[matches[k].idx1] - image1.xy[i]).squaredNorm(),
                 static_cast<int>(k)};
    }
    const size_t count = std::min(kNeighbors, near.size());
    std::partial_sort(near.begin(), near.begin() + count, near.end());
    dx.clear();
    dy.clear();
    for (size_t k = 0; k < count; ++k) {
      dx.push_back(offsets[near[k].second].x());
      dy.push_back(offsets[near[k].second].y());
    }
    std::nth_element(dx.begin(), dx.begin() + count / 2, dx.end());
    std::nth_element(dy.begin(), dy.begin() + count / 2, dy.end());
    centers[i] =
        predict(image1.xy[i]) + Eigen::Vector2d(dx[count / 2], dy[count / 2]);
  }
  return centers;
}

}  // namespace

GlobalMapping EstimateGlobalMapping(const ImagePatches& image1,
                                    const ImagePatches& image2,
                                    const CorrelationMatchingOptions& options) {
  options.Check();
  GlobalMapping mapping;
  const std::vector<int> points1 =
      SpreadPoints(image1, options.global_num_points);
  std::vector<int> points2;
  for (int j = 0; j < image2.size(); ++j) {
    if (image2.valid[j]) points2.push_back(j);
  }
  if (points1.size() < 2 || points2.size() < 2) return mapping;
  const int side = image1.options.CoarseSide();
  const int dim = image1.options.CoarseDim();
  const double diagonal = std::hypot(image2.width, image2.height);
  std::vector<float> rotated(points1.size() * dim);
  std::vector<float> best_ncc1(points1.size()), second_ncc1(points1.size());
  std::vector<float> best_ncc2(points2.size());
  std::vector<int> best_of1(points1.size()), best_of2(points2.size());

  struct Hypothesis {
    std::vector<Vote> votes;
    std::vector<int> inliers;
    Complex a, b;
  };
  std::array<Hypothesis, 4> hypotheses;
  const int num_rotations = options.detect_rotation ? 4 : 1;
  for (int r = 0; r < num_rotations; ++r) {
    for (size_t i = 0; i < points1.size(); ++i) {
      RotateWindow(image1.Coarse(points1[i]), side, r, &rotated[i * dim]);
    }
    std::fill(best_ncc1.begin(), best_ncc1.end(), -2.f);
    std::fill(second_ncc1.begin(), second_ncc1.end(), -2.f);
    std::fill(best_ncc2.begin(), best_ncc2.end(), -2.f);
    for (size_t i = 0; i < points1.size(); ++i) {
      const float* window = &rotated[i * dim];
      for (size_t j = 0; j < points2.size(); ++j) {
        const float ncc = Dot(window, image2.Coarse(points2[j]), dim);
        if (ncc > best_ncc1[i]) {
          second_ncc1[i] = best_ncc1[i];
          best_ncc1[i] = ncc;
          best_of1[i] = static_cast<int>(j);
        } else if (ncc > second_ncc1[i]) {
          second_ncc1[i] = ncc;
        }
        if (ncc > best_ncc2[j]) {
          best_ncc2[j] = ncc;
          best_of2[j] = static_cast<int>(i);
        }
      }
    }
    Hypothesis& hypothesis = hypotheses[r];
    for (size_t i = 0; i < points1.size(); ++i) {
      const int j = best_of1[i];
      if (best_ncc1[i] < options.global_min_ncc) continue;
      // Distinct: clearly better than the runner-up (ratio of the
      // dissimilarities 1 - r, in the spirit of Lowe's ratio test).
      if (1 - best_ncc1[i] > options.global_max_ratio * (1 - second_ncc1[i])) {
        continue;
      }
      if (best_of2[j] != static_cast<int>(i)) continue;  // mutual best only
      hypothesis.votes.push_back(
          {ToComplex(image1.xy[points1[i]]), ToComplex(image2.xy[points2[j]])});
    }
    hypothesis.inliers =
        BestSimilarity(hypothesis.votes,
                       options.global_inlier_fraction * diagonal,
                       options.global_num_trials,
                       options.seed + r,
                       &hypothesis.a,
                       &hypothesis.b);
    // The windows were compared turned by r quarter turns; a similarity
    // turned otherwise is a coincidence of the texture, not this rotation.
    if (!hypothesis.inliers.empty()) {
      const double turn = std::arg(hypothesis.a) - r * M_PI / 2;
      if (std::cos(turn) < std::cos(M_PI / 4)) hypothesis.inliers.clear();
    }
    mapping.inliers_per_rotation[r] =
        static_cast<int>(hypothesis.inliers.size());
  }

  int best = 0;
  for (int r = 1; r < num_rotations; ++r) {
    if (hypotheses[r].inliers.size() > hypotheses[best].inliers.size()) {
      best = r;
    }
  }
  const Hypothesis& winner = hypotheses[best];
  mapping.num_votes = static_cast<int>(winner.votes.size());
  mapping.num_inliers = static_cast<int>(winner.inliers.size());
  if (mapping.num_inliers < options.global_min_inliers) return mapping;
  // Not a coincidence: random votes fall within the inlier distance of a
  // model with probability p (the disc over the image area); the best of
  // all trials must be far beyond what Poisson chance gives.
  const double radius = options.global_inlier_fraction * diagonal;
  const double p = std::min(
      1.0, M_PI * radius * radius / (1.0 * image2.width * image2.height));
  const double tail =
      PoissonTail(p * (mapping.num_votes - 2), mapping.num_inliers - 2);
  if (tail * options.global_num_trials > options.global_max_false_alarm) {
    return mapping;
  }
  mapping.found = true;
  mapping.quarter_turns = best;
  // Affine least squares on the consistent votes; the similarity where they
  // cannot determine it.
  mapping.affine << winner.a.real(), -winner.a.imag(), winner.b.real(),
      winner.a.imag(), winner.a.real(), winner.b.imag();
  if (mapping.num_inliers >= 6) {
    Eigen::MatrixXd A(mapping.num_inliers, 3);
    Eigen::MatrixXd B(mapping.num_inliers, 2);
    for (int k = 0; k < mapping.num_inliers; ++k) {
      const Vote& vote = winner.votes[winner.inliers[k]];
      A.row(k) << vote.z1.real(), vote.z1.imag(), 1.0;
      B.row(k) << vote.z2.real(), vote.z2.imag();
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(
        A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    if (sv(2) > 1e-3 * sv(0)) {
      const Eigen::MatrixXd X = svd.solve(B);  // 3 x 2
      const Eigen::Matrix<double, 2, 3> affine = X.transpose();
      // Keep it only if it does not flip or collapse the image.
      const double det = affine.leftCols<2>().determinant();
      if (det > 0.1 * std::norm(winner.a) && det < 10 * std::norm(winner.a)) {
        mapping.affine = affine;
      }
    }
  }
  return mapping;
}

std::vector<MatchCandidate> FindCandidates(
    const ImagePatches& image1,
    const ImagePatches& image2,
    const GlobalMapping& mapping,
    const CorrelationMatchingOptions& options) {
  std::vector<Eigen::Vector2d> centers(image1.size());
  for (int i = 0; i < image1.size(); ++i) {
    centers[i] =
        mapping.affine.leftCols<2>() * image1.xy[i] + mapping.affine.col(2);
  }
  return FindCandidatesAround(
      image1, image2, mapping.quarter_turns, centers, options);
}

std::vector<MatchCandidate> FindCandidatesAround(
    const ImagePatches& image1,
    const ImagePatches& image2,
    int quarter_turns,
    const std::vector<Eigen::Vector2d>& centers,
    const CorrelationMatchingOptions& options) {
  const double side = std::sqrt(options.search_window_fraction);
  const double half_w = 0.5 * side * image2.width;
  const double half_h = 0.5 * side * image2.height;
  const double cell = std::max(8.0, 0.5 * std::min(half_w, half_h));
  const int grid_w = static_cast<int>(std::ceil(image2.width / cell)) + 1;
  const int grid_h = static_cast<int>(std::ceil(image2.height / cell)) + 1;
  std::vector<std::vector<int>> grid(grid_w * grid_h);
  for (int j = 0; j < image2.size(); ++j) {
    if (!image2.valid[j]) continue;
    const int cx =
        std::clamp(static_cast<int>(image2.xy[j].x() / cell), 0, grid_w - 1);
    const int cy =
        std::clamp(static_cast<int>(image2.xy[j].y() / cell), 0, grid_h - 1);
    grid[cy * grid_w + cx].push_back(j);
  }
  const int window = image1.options.window_size;
  const int dim = image1.options.FineDim();
  std::vector<float> rotated(dim);
  // Image-2 windows shifted around their keypoints (step 2 of the header),
  // cut from the raw windows when a candidate first needs them.
  const int shift = std::min(options.max_keypoint_shift_px,
                             (image2.options.RawSide() - window) / 2);
  const int num_shifts = (2 * shift + 1) * (2 * shift + 1);
  std::vector<float> shifted;
  std::vector<uint8_t> has_shifted;
  if (shift > 0) has_shifted.assign(image2.size(), 0);
  const auto shifted_windows = [&](int j) -> const float* {
    if (shifted.empty()) shifted.resize(image2.size() * num_shifts * dim);
    float* windows = shifted.data() + static_cast<size_t>(j) * num_shifts * dim;
    if (!has_shifted[j]) {
      ShiftedWindows(image2, j, shift, windows);
      has_shifted[j] = 1;
    }
    return windows;
  };
  std::vector<MatchCandidate> candidates, local;
  for (int i = 0; i < image1.size(); ++i) {
    if (!image1.valid[i]) continue;
    const Eigen::Vector2d& center = centers[i];
    if (!center.allFinite()) continue;
    RotateWindow(image1.Fine(i), window, quarter_turns, rotated.data());
    const int x0 = std::max(0, static_cast<int>((center.x() - half_w) / cell));
    const int x1 =
        std::min(grid_w - 1, static_cast<int>((center.x() + half_w) / cell));
    const int y0 = std::max(0, static_cast<int>((center.y() - half_h) / cell));
    const int y1 =
        std::min(grid_h - 1, static_cast<int>((center.y() + half_h) / cell));
    local.clear();
    for (int cy = y0; cy <= y1; ++cy) {
      for (int cx = x0; cx <= x1; ++cx) {
        for (int j : grid[cy * grid_w + cx]) {
          const Eigen::Vector2d d = image2.xy[j] - center;
          if (std::abs(d.x()) > half_w || std::abs(d.y()) > half_h) continue;
          float ncc = Dot(rotated.data(), image2.Fine(j), dim);
          if (shift > 0 && ncc >= options.shift_min_ncc) {
            const float* windows = shifted_windows(j);
            for (int k = 0; k < num_shifts; ++k) {
              ncc = std::max(ncc, Dot(rotated.data(), windows + k * dim, dim));
            }
          }
          if (ncc >= options.min_ncc) local.push_back({i, j, ncc});
        }
      }
    }
    const size_t keep =
        std::min<size_t>(local.size(), options.max_candidates_per_point);
    std::partial_sort(local.begin(),
                      local.begin() + keep,
                      local.end(),
                      [](const MatchCandidate& a, const MatchCandidate& b) {
                        return a.ncc > b.ncc ||
                               (a.ncc == b.ncc && a.idx2 < b.idx2);
                      });
    candidates.insert(candidates.end(), local.begin(), local.begin() + keep);
  }
  return candidates;
}

bool RefineConjugatePoint(const ImagePatches& image1,
                          int idx1,
                          const ImagePatches& image2,
                          int idx2,
                          int quarter_turns,
                          double min_ncc,
                          Eigen::Vector2d* xy2,
                          float* ncc) {
  const PatchOptions& po = image1.options;
  const int w = po.refine_window_size, h = w / 2, m = po.refine_radius;
  const int raw_side = po.RawSide();
  const int margin = (raw_side - w) / 2;  // = m when the raw side is w + 2m
  const int dim = w * w;
  // The reference window, as it appears in image 2.
  std::vector<float> upright(dim), reference(dim), window(dim);
  const float* raw1 = image1.Raw(idx1);
  for (int v = 0; v < w; ++v) {
    for (int u = 0; u < w; ++u) {
      upright[v * w + u] = raw1[(v + margin) * raw_side + (u + margin)];
    }
  }
  RotateWindow(upright.data(), w, quarter_turns, reference.data());
  if (!NormalizeWindow(reference.data(), dim, po.min_std)) return false;
  const float* raw2 = image2.Raw(idx2);
  const int center = raw_side / 2;
  const int n = 2 * m + 1;
  std::vector<float> scores(n * n, -2.f);
  int best = -1;
  for (int b = -m; b <= m; ++b) {
    for (int a = -m; a <= m; ++a) {
      for (int v = -h; v <= h; ++v) {
        for (int u = -h; u <= h; ++u) {
          window[(v + h) * w + (u + h)] =
              raw2[(center + v + b) * raw_side + (center + u + a)];
        }
      }
      if (!NormalizeWindow(window.data(), dim, po.min_std)) continue;
      const int k = (b + m) * n + (a + m);
      scores[k] = Dot(reference.data(), window.data(), dim);
      if (best < 0 || scores[k] > scores[best]) best = k;
    }
  }
  if (best < 0) return false;
  const int a = best % n - m, b = best / n - m;
  if (std::abs(a) == m || std::abs(b) == m) return false;
  if (scores[best] < min_ncc) return false;
  // A quadratic surface fitted to the 3 x 3 scores around the peak; its
  // maximum is the sub-pixel position (the cross term follows correlation
  // peaks that are elongated obliquely, which separate x and y parabolas
  // would pull towards the pixel centre).
  Eigen::Matrix<double, 9, 6> design;
  Eigen::Matrix<double, 9, 1> values;
  int row = 0;
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) {
      design.row(row) << 1, du, dv, du * du, du * dv, dv * dv;
      values(row) = scores[best + dv * n + du];
      ++row;
    }
  }
  const Eigen::Matrix<double, 6, 1> q =
      (design.transpose() * design).ldlt().solve(design.transpose() * values);
  // Gradient zero: [2 q3, q4; q4, 2 q5] (du, dv) = -(q1, q2).
  Eigen::Matrix2d hessian;
  hessian << 2 * q(3), q(4), q(4), 2 * q(5);
  double da = 0, db = 0;
  if (hessian.determinant() > 0 && hessian.trace() < 0) {
    const Eigen::Vector2d step =
        -hessian.inverse() * Eigen::Vector2d(q(1), q(2));
    if (step.cwiseAbs().maxCoeff() <= 0.75) {
      da = step.x();
      db = step.y();
    }
  }
  const Eigen::Vector2i pixel = PixelOf(image2.xy[idx2]);
  *xy2 = Eigen::Vector2d(pixel.x() + 0.5 + a + da, pixel.y() + 0.5 + b + db);
  *ncc = scores[best];
  return true;
}

PairMatches MatchImagePatches(const ImagePatches& image1,
                              const ImagePatches& image2,
                              const CorrelationMatchingOptions& options) {
  options.Check();
  PairMatches result;
  // The global mapping is a guess from a few votes; the upright, unshifted
  // search of the paper is tried as well, and the hypothesis that leaves
  // more conjugate points after relaxation wins.
  std::vector<GlobalMapping> hypotheses = {
      EstimateGlobalMapping(image1, image2, options)};
  if (hypotheses[0].found) {
    hypotheses.push_back(GlobalMapping());
  } else if (options.detect_rotation) {
    // Without votes the quarter turn is unknown: each one is tried, turning
    // about the image centres.
    for (int r = 1; r < 4; ++r)
      hypotheses.push_back(CentredTurn(image1, image2, r));
  }
  RelaxationResult relaxed;
  for (const GlobalMapping& mapping : hypotheses) {
    const std::vector<MatchCandidate> candidates =
        FindCandidates(image1, image2, mapping, options);
    RelaxationResult attempt =
        RelaxMatches(image1.xy,
                     image2.xy,
                     candidates,
                     mapping.affine.leftCols<2>(),
                     std::max(image1.width, image1.height),
                     options.relaxation);
    // A later hypothesis needs clearly more (5 %) conjugate points: where
    // both find the same ones, a few chance matches must not decide.
    if (&mapping == &hypotheses[0] ||
        attempt.matches.size() >
            relaxed.matches.size() + relaxed.matches.size() / 20) {
      relaxed = std::move(attempt);
      result.mapping = mapping;
      result.num_candidates = static_cast<int>(candidates.size());
    }
  }
  // Further passes: the search windows centred where the conjugate points
  // found so far say each point should be (the mapping plus the median
  // offset of the nearest matches), which follows a displacement field no
  // single affine mapping describes (a 3D object seen from two stations).
  for (int pass = 1; pass < options.num_passes; ++pass) {
    if (relaxed.matches.size() < 8) break;
    const std::vector<Eigen::Vector2d> centers =
        PredictFromMatches(image1, image2, result.mapping, relaxed.matches);
    const std::vector<MatchCandidate> candidates = FindCandidatesAround(
        image1, image2, result.mapping.quarter_turns, centers, options);
    RelaxationResult attempt =
        RelaxMatches(image1.xy,
                     image2.xy,
                     candidates,
                     result.mapping.affine.leftCols<2>(),
                     std::max(image1.width, image1.height),
                     options.relaxation);
    if (attempt.matches.size() <= relaxed.matches.size()) break;
    relaxed = std::move(attempt);
    result.num_candidates = static_cast<int>(candidates.size());
    result.num_passes = pass + 1;
  }
  result.num_relaxed = static_cast<int>(relaxed.matches.size());
  result.num_iterations = relaxed.num_iterations;
  std::vector<std::pair<int, int>> kept;
  for (const MatchCandidate& match : relaxed.matches) {
    Eigen::Vector2d xy2;
    float ncc = 0;
    if (!RefineConjugatePoint(image1,
                              match.idx1,
                              image2,
                              match.idx2,
                              result.mapping.quarter_turns,
                              options.refine_min_ncc,
                              &xy2,
                              &ncc)) {
      continue;
    }
    kept.emplace_back(match.idx1, match.idx2);
    result.reference_xy1.push_back(PixelCentreOf(image1.xy[match.idx1]));
    result.refined_xy2.push_back(xy2);
    result.ncc.push_back(ncc);
    result.sigma_px.push_back(static_cast<float>(options.peak_sigma_px));
  }
  result.matches.resize(kept.size(), 2);
  for (size_t k = 0; k < kept.size(); ++k) {
    result.matches(k, 0) = static_cast<uint32_t>(kept[k].first);
    result.matches(k, 1) = static_cast<uint32_t>(kept[k].second);
  }
  return result;
}

}  // namespace bayon
