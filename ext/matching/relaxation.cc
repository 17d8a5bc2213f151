// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/relaxation.h"

#include "ext/core/errors.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace bayon {

void RelaxationOptions::Register(OptionRegistry* r) {
  r->Add("neighborhood_fraction",
         &neighborhood_fraction,
         "Neighbourhood radius / image size");
  r->Add("min_support", &min_support, "Consistent neighbours a match needs");
}

void RelaxationOptions::Check() const {
  CheckOption(neighborhood_fraction > 0 && neighborhood_fraction <= 1,
              "neighborhood_fraction",
              "in (0, 1]",
              neighborhood_fraction);
  CheckOption(max_neighbors >= 1, "max_neighbors", ">= 1", max_neighbors);
  CheckOption(max_relative_distance_difference > 0,
              "max_relative_distance_difference",
              "> 0",
              max_relative_distance_difference);
  CheckOption(max_angle_deg > 0 && max_angle_deg <= 180,
              "max_angle_deg",
              "in (0, 180]",
              max_angle_deg);
  CheckOption(min_support >= 0, "min_support", ">= 0", min_support);
  CheckOption(min_support_fraction >= 0 && min_support_fraction <= 1,
              "min_support_fraction",
              "in [0, 1]",
              min_support_fraction);
  CheckOption(max_iterations >= 1, "max_iterations", ">= 1", max_iterations);
}

namespace {

// For each image-1 point with candidates, its nearest neighbours (other
// points with candidates) within `radius`, nearest first; indexed by point.
std::vector<std::vector<int>> NeighborLists(
    const std::vector<Eigen::Vector2d>& xy1,
    const std::vector<int>& points,
    double radius,
    int max_neighbors) {
  std::unordered_map<long long, std::vector<int>> grid;
  const auto cell = [&](const Eigen::Vector2d& p) {
    return std::make_pair(static_cast<long long>(std::floor(p.x() / radius)),
                          static_cast<long long>(std::floor(p.y() / radius)));
  };
  const auto key = [](long long cx, long long cy) {
    return cx * 1000003LL + cy;
  };
  for (int point : points) {
    const auto [cx, cy] = cell(xy1[point]);
    grid[key(cx, cy)].push_back(point);
  }
  std::vector<std::vector<int>> neighbors(xy1.size());
  std::vector<std::pair<double, int>> near;
  const double radius2 = radius * radius;
  for (int point : points) {
    near.clear();
    const auto [cx, cy] = cell(xy1[point]);
    for (long long dy = -1; dy <= 1; ++dy) {
      for (long long dx = -1; dx <= 1; ++dx) {
        const auto it = grid.find(key(cx + dx, cy + dy));
        if (it == grid.end()) continue;
        for (int other : it->second) {
          if (other == point) continue;
          const double d2 = (xy1[other] - xy1[point]).squaredNorm();
          if (d2 <= radius2) near.emplace_back(d2, other);
        }
      }
    }
    const size_t keep = std::min<size_t>(near.size(), max_neighbors);
    std::partial_sort(near.begin(), near.begin() + keep, near.end());
    std::vector<int>& list = neighbors[point];
    for (size_t k = 0; k < keep; ++k) list.push_back(near[k].second);
  }
  return neighbors;
}

}  // namespace

RelaxationResult RelaxMatches(const std::vector<Eigen::Vector2d>& xy1,
                              const std::vector<Eigen::Vector2d>& xy2,
                              const std::vector<MatchCandidate>& candidates,
                              const Eigen::Matrix2d& image2_from_image1,
                              double image_size1,
                              const RelaxationOptions& options) {
  options.Check();
  RelaxationResult result;
  const int num = static_cast<int>(candidates.size());
  if (num == 0) return result;
  const Eigen::Matrix2d& L = image2_from_image1;
  const double scale = std::sqrt(std::abs(L.determinant()));
  const double radius1 = options.neighborhood_fraction * image_size1;
  const double radius2 = radius1 * std::max(scale, 1e-6);
  const double radius2_sq = radius2 * radius2;
  const double eps_r = options.max_relative_distance_difference;
  const double cos_max = std::cos(options.max_angle_deg * M_PI / 180.0);

  // Candidates by image-1 point and by image-2 point (indexed by point).
  std::vector<std::vector<int>> by_point1(xy1.size()), by_point2(xy2.size());
  for (int c = 0; c < num; ++c) {
    by_point1[candidates[c].idx1].push_back(c);
    by_point2[candidates[c].idx2].push_back(c);
  }
  std::vector<int> points1;
  for (int i = 0; i < static_cast<int>(xy1.size()); ++i) {
    if (!by_point1[i].empty()) points1.push_back(i);
  }
  const std::vector<std::vector<int>> neighbors =
      NeighborLists(xy1, points1, radius1, options.max_neighbors);
  // Image-1 positions mapped by L, so that neighbour offsets compare
  // directly with image-2 offsets.
  std::vector<Eigen::Vector2d> mapped1(xy1.size());
  for (int i : points1) mapped1[i] = L * xy1[i];

  // The support each candidate needs.
  std::vector<int> needed(num);
  for (int c = 0; c < num; ++c) {
    const double neighbors_with_candidates =
        neighbors[candidates[c].idx1].size();
    needed[c] =
        std::max(options.min_support,
                 static_cast<int>(std::ceil(options.min_support_fraction *
                                            neighbors_with_candidates)));
  }
  std::vector<uint8_t> alive(num, 1);
  std::vector<float> strength(num, 0.f);
  std::vector<int> support(num, 0);
  const auto compute_strength = [&](int c) {
    const MatchCandidate& m = candidates[c];
    const Eigen::Vector2d& m1 = mapped1[m.idx1];
    const Eigen::Vector2d& m2 = xy2[m.idx2];
    double sum = 0;
    int consistent = 0;
    for (int k : neighbors[m.idx1]) {
      const Eigen::Vector2d d1 = mapped1[k] - m1;
      const double len1 = d1.norm();
      if (len1 <= 0) continue;
      double best = 0;
      for (int other : by_point1[k]) {
        if (!alive[other]) continue;
        const MatchCandidate& n = candidates[other];
        if (n.idx2 == m.idx2) continue;
        const Eigen::Vector2d d2 = xy2[n.idx2] - m2;
        const double len2_sq = d2.squaredNorm();
        if (len2_sq > radius2_sq || len2_sq <= 0) continue;
        const double len2 = std::sqrt(len2_sq);
        if (d1.dot(d2) < cos_max * len1 * len2) continue;
        const double dist = 0.5 * (len1 + len2);
        const double r = (d1 - d2).norm() / dist;
        if (r >= eps_r) continue;
        const double value =
            n.ncc * std::exp(-r / eps_r) / (1.0 + dist / radius2);
        best = std::max(best, value);
      }
      if (best > 0) {
        sum += best;
        ++consistent;
      }
    }
    strength[c] = static_cast<float>(m.ncc * sum);
    support[c] = consistent;
  };

  // Loser-takes-nothing: each round removes, at every ambiguous point, its
  // weakest candidate, and every candidate without enough support.
  // Strengths change only where a neighbour lost a candidate: after the
  // first round, only the candidates of those points are recomputed.
  std::vector<std::vector<int>> supported(xy1.size());  // k -> points using k
  for (int i : points1) {
    for (int k : neighbors[i]) supported[k].push_back(i);
  }
  std::vector<uint8_t> dirty(xy1.size(), 0);
  for (int i : points1) dirty[i] = 1;
  std::vector<int> losers;
  int iteration = 0;
  for (; iteration < options.max_iterations; ++iteration) {
    for (int i : points1) {
      if (!dirty[i]) continue;
      dirty[i] = 0;
      for (int c : by_point1[i]) {
        if (alive[c]) compute_strength(c);
      }
    }
    losers.clear();
    for (int c = 0; c < num; ++c) {
      if (alive[c] && support[c] < needed[c]) losers.push_back(c);
    }
    for (const auto* groups : {&by_point1, &by_point2}) {
      for (const std::vector<int>& list : *groups) {
        int weakest = -1, num_alive = 0;
        for (int c : list) {
          if (!alive[c]) continue;
          ++num_alive;
          if (weakest < 0 || strength[c] < strength[weakest]) weakest = c;
        }
        if (num_alive > 1) losers.push_back(weakest);
      }
    }
    if (losers.empty()) break;
    for (int c : losers) {
      alive[c] = 0;
      for (int i : supported[candidates[c].idx1]) dirty[i] = 1;
    }
  }
  result.num_iterations = iteration + 1;

  // Ambiguities left after the last round are settled by strength.
  std::vector<int> order;
  for (int c = 0; c < num; ++c) {
    if (alive[c] && support[c] >= needed[c]) order.push_back(c);
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return strength[a] > strength[b];
  });
  std::vector<uint8_t> used1(xy1.size(), 0), used2(xy2.size(), 0);
  for (int c : order) {
    const MatchCandidate& m = candidates[c];
    if (used1[m.idx1] || used2[m.idx2]) continue;
    used1[m.idx1] = used2[m.idx2] = 1;
    result.matches.push_back(m);
    result.strength.push_back(strength[c]);
    result.support.push_back(support[c]);
  }
  return result;
}

}  // namespace bayon
