// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/view_graph.h"

#include "ext/core/errors.h"
#include "ext/core/rigid3.h"
#include "ext/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace bayon {

void ViewGraphOptions::Register(OptionRegistry* r) {
  r->Add("max_loop_error_deg",
         &max_loop_error_deg,
         "A pair most of whose triangles of relative rotations fail to close "
         "within this is left out, deg");
  r->Add("max_loop_error_sigmas",
         &max_loop_error_sigmas,
         "... and within this many of the triangle's standard deviations");
}

void ViewGraphOptions::Check() const {
  CheckOption(
      max_loop_error_deg > 0, "max_loop_error_deg", "> 0", max_loop_error_deg);
  CheckOption(max_loop_error_sigmas > 0,
              "max_loop_error_sigmas",
              "> 0",
              max_loop_error_sigmas);
}

double RotationAngleDeg(const Eigen::Matrix3d& rotation) {
  return RotationAngleBetween(Eigen::Quaterniond(rotation),
                              Eigen::Quaterniond::Identity()) *
         180.0 / M_PI;
}

namespace {

struct Triangle {
  double error_deg = 0;
  bool failing = false;
};

// Each active pair's triangles, over the active pairs only.
std::vector<std::vector<Triangle>> Triangles(
    const std::vector<ViewGraphPair>& pairs,
    const std::vector<bool>& active,
    const ViewGraphOptions& options) {
  // b from a for every ordered pair of images with an active pair.
  std::map<std::pair<int, int>, Eigen::Matrix3d> b_from_a;
  std::map<std::pair<int, int>, int> pair_of;
  std::map<int, std::vector<int>> neighbours;
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (!active[p]) continue;
    const ViewGraphPair& pair = pairs[p];
    b_from_a[{pair.image1, pair.image2}] = pair.rotation;
    b_from_a[{pair.image2, pair.image1}] = pair.rotation.transpose();
    pair_of[{std::min(pair.image1, pair.image2),
             std::max(pair.image1, pair.image2)}] = static_cast<int>(p);
    neighbours[pair.image1].push_back(pair.image2);
    neighbours[pair.image2].push_back(pair.image1);
  }
  std::vector<std::vector<Triangle>> triangles(pairs.size());
  for (const auto& [images, p] : pair_of) {
    const auto [i, j] = images;  // i < j
    for (int k : neighbours[i]) {
      // Each triangle once, from its two smallest images.
      if (k <= j || !b_from_a.count({j, k})) continue;
      const std::pair<int, int> edges[3] = {{i, j}, {i, k}, {j, k}};
      Triangle triangle;
      triangle.error_deg = RotationAngleDeg(
          b_from_a.at({k, i}) * b_from_a.at({j, k}) * b_from_a.at({i, j}));
      double variance = 0;
      for (const auto& edge : edges) {
        const double sigma = pairs[pair_of.at(edge)].sigma_deg;
        variance += sigma * sigma;
      }
      triangle.failing = triangle.error_deg > options.max_loop_error_deg &&
                         triangle.error_deg > options.max_loop_error_sigmas *
                                                  std::sqrt(variance);
      for (const auto& edge : edges) {
        triangles[pair_of.at(edge)].push_back(triangle);
      }
    }
  }
  return triangles;
}

}  // namespace

std::vector<DroppedPair> FindInconsistentPairs(
    const std::vector<ViewGraphPair>& pairs, const ViewGraphOptions& options) {
  options.Check();
  std::vector<bool> active(pairs.size(), true);
  std::vector<DroppedPair> dropped;
  while (true) {
    const std::vector<std::vector<Triangle>> triangles =
        Triangles(pairs, active, options);
    DroppedPair worst;
    for (size_t p = 0; p < pairs.size(); ++p) {
      if (!active[p] || triangles[p].empty()) continue;
      DroppedPair candidate;
      candidate.pair_idx = static_cast<int>(p);
      candidate.num_triangles = static_cast<int>(triangles[p].size());
      std::vector<double> errors;
      for (const Triangle& triangle : triangles[p]) {
        candidate.num_failing += triangle.failing;
        errors.push_back(triangle.error_deg);
      }
      if (2 * candidate.num_failing <= candidate.num_triangles) continue;
      candidate.median_loop_error_deg = Median(errors);
      if (worst.pair_idx < 0 ||
          std::make_tuple(candidate.num_failing,
                          candidate.median_loop_error_deg) >
              std::make_tuple(worst.num_failing, worst.median_loop_error_deg)) {
        worst = candidate;
      }
    }
    if (worst.pair_idx < 0) return dropped;
    active[worst.pair_idx] = false;
    dropped.push_back(worst);
  }
}

}  // namespace bayon
