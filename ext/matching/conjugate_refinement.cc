// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/conjugate_refinement.h"

#include "ext/core/errors.h"
#include "ext/core/statistics.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace bayon {

void ConjugateRefinementOptions::Register(OptionRegistry* r) {
  lsm.RegisterMatchChecks(r);
  r->Add("keep_unrefined",
         &keep_unrefined,
         "1: matches LSM rejects stay at their correlation peaks");
  r->Add("refined_sigma_px",
         &refined_sigma_px,
         "Standard deviation given to a refined point, px");
  r->Add("num_neighbors",
         &num_neighbors,
         "Neighbouring matches for the local affinity");
  r->Add("neighbor_fraction",
         &neighbor_fraction,
         "... within this share of the larger image side");
  r->Add("propagation_rounds",
         &propagation_rounds,
         "Rounds of least-squares propagation (0: none)");
  r->Add("propagation_max_shift_px",
         &propagation_max_shift_px,
         "Propagation: largest move from the predicted position, px");
  r->Add("max_keypoint_distance_px",
         &max_keypoint_distance_px,
         "A propagated point must lie this near an image-2 keypoint");
}

void ConjugateRefinementOptions::Check() const {
  lsm.Check();
  CheckOption(num_neighbors >= 6, "num_neighbors", ">= 6", num_neighbors);
  CheckOption(neighbor_fraction > 0 && neighbor_fraction <= 1,
              "neighbor_fraction",
              "in (0, 1]",
              neighbor_fraction);
  CheckOption(
      refined_sigma_px > 0, "refined_sigma_px", "> 0", refined_sigma_px);
  CheckOption(propagation_rounds >= 0,
              "propagation_rounds",
              ">= 0",
              propagation_rounds);
  CheckOption(propagation_max_shift_px > 0,
              "propagation_max_shift_px",
              "> 0",
              propagation_max_shift_px);
  CheckOption(max_keypoint_distance_px > 0,
              "max_keypoint_distance_px",
              "> 0",
              max_keypoint_distance_px);
}

int ConjugateRefinementReport::NumRejected() const {
  return std::accumulate(num_rejected.begin(), num_rejected.end(), 0);
}

namespace {

// Least-squares affinity xy2 ~ A xy1 + t over `rows`; false where the
// points cannot determine it.
bool FitAffinity(const std::vector<Eigen::Vector2d>& xy1,
                 const std::vector<Eigen::Vector2d>& xy2,
                 const std::vector<int>& rows,
                 Eigen::Matrix<double, 2, 3>* affinity) {
  if (rows.size() < 6) return false;
  Eigen::MatrixXd A(rows.size(), 3);
  Eigen::MatrixXd B(rows.size(), 2);
  // Centred on the first point: better conditioned than raw pixels.
  const Eigen::Vector2d origin = xy1[rows[0]];
  for (size_t k = 0; k < rows.size(); ++k) {
    A.row(k) << (xy1[rows[k]] - origin).transpose(), 1.0;
    B.row(k) = xy2[rows[k]].transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(
      A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (svd.singularValues()(2) < 1e-6 * svd.singularValues()(0) ||
      svd.singularValues()(1) < 1e-2 * svd.singularValues()(0)) {
    return false;  // (nearly) collinear neighbours
  }
  const Eigen::Matrix<double, 3, 2> X = svd.solve(B);
  affinity->leftCols<2>() = X.topRows<2>().transpose();
  affinity->col(2) = X.row(2).transpose() - affinity->leftCols<2>() * origin;
  return true;
}

}  // namespace

std::vector<std::optional<Affinity2d>> LocalAffinities(
    const std::vector<Eigen::Vector2d>& xy1,
    const std::vector<Eigen::Vector2d>& xy2,
    const std::vector<Eigen::Vector2d>& queries,
    const Eigen::Matrix2d& reference,
    double max_distance,
    int num_neighbors) {
  const int n = static_cast<int>(xy1.size());
  std::vector<std::optional<Affinity2d>> affinities(queries.size());
  const double reference_det = reference.determinant();
  std::vector<std::pair<double, int>> near;
  std::vector<int> rows, kept;
  std::vector<double> residuals;
  for (size_t q = 0; q < queries.size(); ++q) {
    near.clear();
    for (int j = 0; j < n; ++j) {
      const double d2 = (xy1[j] - queries[q]).squaredNorm();
      if (d2 <= max_distance * max_distance) near.emplace_back(d2, j);
    }
    const size_t keep = std::min<size_t>(near.size(), num_neighbors);
    std::partial_sort(near.begin(), near.begin() + keep, near.end());
    rows.clear();
    for (size_t k = 0; k < keep; ++k) rows.push_back(near[k].second);
    Affinity2d affinity;
    if (!FitAffinity(xy1, xy2, rows, &affinity)) continue;
    // Once more without the neighbours it fits worst: blunders among them
    // would tilt it.
    residuals.clear();
    for (int row : rows) {
      residuals.push_back(
          (affinity.leftCols<2>() * xy1[row] + affinity.col(2) - xy2[row])
              .norm());
    }
    const double bound = std::max(1.0, 3.0 * Median(residuals));
    kept.clear();
    for (size_t k = 0; k < rows.size(); ++k) {
      if (residuals[k] <= bound) kept.push_back(rows[k]);
    }
    if (kept.size() < rows.size() && !FitAffinity(xy1, xy2, kept, &affinity)) {
      continue;
    }
    const double det = affinity.leftCols<2>().determinant();
    if (det * reference_det <= 0 ||
        std::abs(det) < 0.1 * std::abs(reference_det) ||
        std::abs(det) > 10 * std::abs(reference_det)) {
      continue;
    }
    affinities[q] = affinity;
  }
  return affinities;
}

namespace {

// One propagation round (header); returns the number of points added.
int Propagate(const cv::Mat& gray1,
              const cv::Mat& gray2,
              const std::vector<Eigen::Vector2d>& keypoints1,
              const std::vector<Eigen::Vector2d>& keypoints2,
              const ConjugateRefinementOptions& options,
              PairMatches* matches) {
  const int num_matches = static_cast<int>(matches->matches.rows());
  std::vector<uint8_t> used1(keypoints1.size(), 0), used2(keypoints2.size(), 0);
  for (int k = 0; k < num_matches; ++k) {
    used1[matches->matches(k, 0)] = 1;
    used2[matches->matches(k, 1)] = 1;
  }
  std::vector<int> todo;
  std::vector<Eigen::Vector2d> queries;
  for (size_t i = 0; i < keypoints1.size(); ++i) {
    if (used1[i]) continue;
    todo.push_back(static_cast<int>(i));
    queries.push_back(PixelCentreOf(keypoints1[i]));
  }
  const std::vector<std::optional<Affinity2d>> local = LocalAffinities(
      matches->reference_xy1,
      matches->refined_xy2,
      queries,
      matches->mapping.affine.leftCols<2>(),
      options.neighbor_fraction * std::max(gray1.cols, gray1.rows),
      options.num_neighbors);
  // The unused image-2 keypoints on a grid of cells as wide as the largest
  // distance, so that the nearest one lies in the 3 x 3 cells around a point.
  const double cell = std::max(1.0, options.max_keypoint_distance_px);
  const auto key = [](long long cx, long long cy) {
    return cx * 1000003LL + cy;
  };
  std::unordered_map<long long, std::vector<int>> grid;
  for (size_t j = 0; j < keypoints2.size(); ++j) {
    if (used2[j]) continue;
    grid[key(std::floor(keypoints2[j].x() / cell),
             std::floor(keypoints2[j].y() / cell))]
        .push_back(static_cast<int>(j));
  }
  // The nearest unused image-2 keypoint within the largest distance, or -1.
  const auto nearest_keypoint = [&](const Eigen::Vector2d& xy,
                                    double* distance) {
    const long long cx = std::floor(xy.x() / cell);
    const long long cy = std::floor(xy.y() / cell);
    int nearest = -1;
    *distance = options.max_keypoint_distance_px;
    for (long long dy = -1; dy <= 1; ++dy) {
      for (long long dx = -1; dx <= 1; ++dx) {
        const auto it = grid.find(key(cx + dx, cy + dy));
        if (it == grid.end()) continue;
        for (int j : it->second) {
          const double d = (keypoints2[j] - xy).norm();
          if (d <= *distance) {
            *distance = d;
            nearest = j;
          }
        }
      }
    }
    return nearest;
  };
  KeypointRefinementOptions lsm = options.lsm;
  lsm.max_shift_px = options.propagation_max_shift_px;
  struct Claim {
    int idx1, idx2;
    double distance;
    Eigen::Vector2d xy2;
    float correlation;
  };
  std::vector<Claim> claims;
  for (size_t q = 0; q < todo.size(); ++q) {
    if (!local[q]) continue;
    const Affinity2d& affinity = *local[q];
    const Eigen::Vector2d start =
        affinity.leftCols<2>() * queries[q] + affinity.col(2);
    if (!(start.x() >= 0 && start.y() >= 0 && start.x() < gray2.cols &&
          start.y() < gray2.rows)) {
      continue;
    }
    const ObservationRefinement refined = RefineObservation(
        gray1, queries[q], gray2, start, affinity.leftCols<2>(), lsm);
    if (refined.outcome != ObservationOutcome::kRefined) continue;
    double best = 0;
    const int nearest = nearest_keypoint(refined.refined_xy, &best);
    if (nearest < 0) continue;
    claims.push_back({todo[q],
                      nearest,
                      best,
                      refined.refined_xy,
                      static_cast<float>(refined.correlation)});
  }
  std::sort(claims.begin(), claims.end(), [](const Claim& a, const Claim& b) {
    return a.distance < b.distance;
  });
  std::vector<Claim> accepted;
  for (const Claim& claim : claims) {
    if (used2[claim.idx2]) continue;
    used2[claim.idx2] = 1;
    accepted.push_back(claim);
  }
  FeatureMatches rows(num_matches + accepted.size(), 2);
  rows.topRows(num_matches) = matches->matches;
  for (size_t k = 0; k < accepted.size(); ++k) {
    rows(num_matches + k, 0) = static_cast<uint32_t>(accepted[k].idx1);
    rows(num_matches + k, 1) = static_cast<uint32_t>(accepted[k].idx2);
    matches->reference_xy1.push_back(
        PixelCentreOf(keypoints1[accepted[k].idx1]));
    matches->refined_xy2.push_back(accepted[k].xy2);
    matches->ncc.push_back(accepted[k].correlation);
    matches->sigma_px.push_back(static_cast<float>(options.refined_sigma_px));
  }
  matches->matches = std::move(rows);
  return static_cast<int>(accepted.size());
}

}  // namespace

ConjugateRefinementReport RefineConjugatePoints(
    const cv::Mat& gray1,
    const cv::Mat& gray2,
    const std::vector<Eigen::Vector2d>& keypoints1,
    const std::vector<Eigen::Vector2d>& keypoints2,
    const ConjugateRefinementOptions& options,
    PairMatches* matches) {
  options.Check();
  ConjugateRefinementReport report;
  const int n = static_cast<int>(matches->refined_xy2.size());
  if (n == 0) return report;
  const Eigen::Matrix2d global = matches->mapping.affine.leftCols<2>();
  const std::vector<std::optional<Affinity2d>> local = LocalAffinities(
      matches->reference_xy1,
      matches->refined_xy2,
      matches->reference_xy1,
      global,
      options.neighbor_fraction * std::max(gray1.cols, gray1.rows),
      options.num_neighbors);
  std::vector<int> kept;
  std::vector<double> shifts;
  for (int k = 0; k < n; ++k) {
    const ObservationRefinement refined =
        RefineObservation(gray1,
                          matches->reference_xy1[k],
                          gray2,
                          matches->refined_xy2[k],
                          local[k] ? local[k]->leftCols<2>() : global,
                          options.lsm);
    if (refined.outcome != ObservationOutcome::kRefined) {
      ++report.num_rejected[static_cast<int>(refined.outcome)];
      if (options.keep_unrefined) kept.push_back(k);
      continue;
    }
    shifts.push_back((refined.refined_xy - matches->refined_xy2[k]).norm());
    matches->refined_xy2[k] = refined.refined_xy;
    matches->ncc[k] = static_cast<float>(refined.correlation);
    matches->sigma_px[k] = static_cast<float>(options.refined_sigma_px);
    kept.push_back(k);
  }
  report.num_refined = static_cast<int>(shifts.size());
  if (!shifts.empty()) report.median_shift_px = Median(shifts);
  FeatureMatches rows(kept.size(), 2);
  for (size_t k = 0; k < kept.size(); ++k) {
    rows.row(k) = matches->matches.row(kept[k]);
    matches->reference_xy1[k] = matches->reference_xy1[kept[k]];
    matches->refined_xy2[k] = matches->refined_xy2[kept[k]];
    matches->ncc[k] = matches->ncc[kept[k]];
    matches->sigma_px[k] = matches->sigma_px[kept[k]];
  }
  matches->matches = std::move(rows);
  matches->reference_xy1.resize(kept.size());
  matches->refined_xy2.resize(kept.size());
  matches->ncc.resize(kept.size());
  matches->sigma_px.resize(kept.size());
  for (int round = 0; round < options.propagation_rounds; ++round) {
    const int added =
        Propagate(gray1, gray2, keypoints1, keypoints2, options, matches);
    report.num_propagated += added;
    if (added == 0) break;
  }
  return report;
}

}  // namespace bayon
