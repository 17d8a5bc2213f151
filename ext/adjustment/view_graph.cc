// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/view_graph.h"

#include "ext/core/errors.h"
#include "ext/core/rigid3.h"
#include "ext/core/statistics.h"
#include "ext/core/string_printf.h"
#include "ext/core/union_find.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

namespace bayon {

void ViewGraphOptions::Register(OptionRegistry* r) {
  r->Add("max_loop_error_deg",
         &max_loop_error_deg,
         "A pair most of whose triangles of relative rotations fail to close "
         "within this is left out (a longer loop: this x sqrt(its pairs / "
         "3)), deg");
  r->Add("max_loop_error_sigmas",
         &max_loop_error_sigmas,
         "... and within this many of the loop's standard deviations");
  r->Add("num_spanning_trees",
         &num_spanning_trees,
         "Spanning trees of the pairs tried for the consensus of the longer "
         "loops");
}

void ViewGraphOptions::Check() const {
  CheckOption(
      max_loop_error_deg > 0, "max_loop_error_deg", "> 0", max_loop_error_deg);
  CheckOption(max_loop_error_sigmas > 0,
              "max_loop_error_sigmas",
              "> 0",
              max_loop_error_sigmas);
  CheckOption(num_spanning_trees >= 1,
              "num_spanning_trees",
              ">= 1",
              num_spanning_trees);
}

std::string WhyDropped(const DroppedPair& dropped,
                       const ViewGraphOptions& options) {
  if (dropped.num_triangles > 0) {
    return StringPrintf(
        "its rotation disagrees with the loops it lies on (%d of %d "
        "triangles fail, median loop error %.1f deg, above %g deg and %g "
        "standard deviations)",
        dropped.num_failing,
        dropped.num_triangles,
        dropped.median_loop_error_deg,
        options.max_loop_error_deg,
        options.max_loop_error_sigmas);
  }
  return StringPrintf(
      "its rotation disagrees with a loop of %d pairs through the pairs that "
      "agree (loop error %.1f deg, allowed %.1f deg), and the loop's other "
      "pairs have more conjugate points",
      dropped.loop_length,
      dropped.loop_error_deg,
      dropped.loop_limit_deg);
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

// The longer loops (see the header): spanning trees of the active pairs,
// the rotations each gives the images, and the loop each other pair closes
// through it.
class LoopConsensus {
 public:
  LoopConsensus(const std::vector<ViewGraphPair>& pairs,
                const std::vector<bool>& active,
                const ViewGraphOptions& options)
      : pairs_(pairs), options_(options), ends_(pairs.size()) {
    std::map<int, int> idx;
    for (size_t p = 0; p < pairs.size(); ++p) {
      if (!active[p]) continue;
      active_.push_back(static_cast<int>(p));
      for (int image : {pairs[p].image1, pairs[p].image2}) {
        idx.emplace(image, static_cast<int>(idx.size()));
      }
    }
    for (int p : active_) {
      ends_[p] = {idx.at(pairs[p].image1), idx.at(pairs[p].image2)};
    }
    num_images_ = static_cast<int>(idx.size());
    heaviest_first_ = active_;
    std::stable_sort(
        heaviest_first_.begin(), heaviest_first_.end(), [&](int a, int b) {
          return pairs_[a].weight > pairs_[b].weight;
        });
  }

  // The pairs whose loop fails through the consensus tree and whose
  // heaviest tree closes less weight.
  std::vector<DroppedPair> Inconsistent() const {
    const Tree best = Consensus();
    std::vector<DroppedPair> dropped;
    for (int p : active_) {
      const Loop& loop = best.loops[p];
      if (loop.closes) continue;
      std::vector<int> order = {p};
      for (int q : heaviest_first_) {
        if (q != p) order.push_back(q);
      }
      if (Grow(order).closed_weight >= best.closed_weight) continue;
      DroppedPair pair;
      pair.pair_idx = p;
      pair.loop_length = loop.length;
      pair.loop_error_deg = loop.error_deg;
      pair.loop_limit_deg = loop.limit_deg;
      dropped.push_back(pair);
    }
    return dropped;
  }

 private:
  struct Loop {
    int length = 0;  // pairs
    double error_deg = 0;
    double limit_deg = 0;
    bool closes = true;
  };
  struct Tree {
    std::vector<Loop> loops;  // by pair (the active ones)
    double closed_weight = 0;
  };

  // Of the heaviest tree and num_spanning_trees - 1 drawn at random, the
  // one whose loops close for the most weight (the first of equals).
  Tree Consensus() const {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> unit(0, 1);
    Tree best = Grow(heaviest_first_);
    for (int t = 1; t < options_.num_spanning_trees; ++t) {
      // A weighted random order: each pair's key is an exponential draw
      // with its weight as rate, so heavier pairs tend to come first.
      std::vector<std::pair<double, int>> keys;
      for (int p : active_) {
        keys.emplace_back(-std::log(1 - unit(rng)) / pairs_[p].weight, p);
      }
      std::sort(keys.begin(), keys.end());
      std::vector<int> order;
      for (const auto& key : keys) order.push_back(key.second);
      Tree tree = Grow(order);
      if (tree.closed_weight > best.closed_weight) best = std::move(tree);
    }
    return best;
  }

  // The spanning forest that takes the pairs in this order where they join
  // two parts (Kruskal), and every active pair's loop through it.
  Tree Grow(const std::vector<int>& order) const {
    UnionFind parts(num_images_);
    std::vector<std::vector<int>> tree_pairs(num_images_);
    for (int p : order) {
      const auto [i, j] = ends_[p];
      if (parts.Find(i) == parts.Find(j)) continue;
      parts.Union(i, j);
      tree_pairs[i].push_back(p);
      tree_pairs[j].push_back(p);
    }
    // Each image's rotation (camera from the root's frame), depth, parent
    // and the variance accumulated from the root.
    std::vector<Eigen::Matrix3d> rotation(num_images_);
    std::vector<int> parent(num_images_, -1), depth(num_images_, -1);
    std::vector<double> variance(num_images_, 0);
    for (int root = 0; root < num_images_; ++root) {
      if (depth[root] >= 0) continue;
      rotation[root].setIdentity();
      depth[root] = 0;
      std::vector<int> stack = {root};
      while (!stack.empty()) {
        const int u = stack.back();
        stack.pop_back();
        for (int p : tree_pairs[u]) {
          const auto [i, j] = ends_[p];
          const int v = i == u ? j : i;
          if (depth[v] >= 0) continue;
          const Eigen::Matrix3d& v_from_u = pairs_[p].rotation;  // j from i
          rotation[v] =
              (i == u ? v_from_u : Eigen::Matrix3d(v_from_u.transpose())) *
              rotation[u];
          parent[v] = u;
          depth[v] = depth[u] + 1;
          variance[v] = variance[u] + Square(pairs_[p].sigma_deg);
          stack.push_back(v);
        }
      }
    }
    Tree tree;
    tree.loops.resize(pairs_.size());
    for (int p : active_) {
      const auto [i, j] = ends_[p];
      int a = i, b = j;
      while (depth[a] > depth[b]) a = parent[a];
      while (depth[b] > depth[a]) b = parent[b];
      while (a != b) {
        a = parent[a];
        b = parent[b];
      }
      Loop loop;
      loop.length = depth[i] + depth[j] - 2 * depth[a] + 1;
      loop.error_deg = RotationAngleDeg(pairs_[p].rotation * rotation[i] *
                                        rotation[j].transpose());
      // The variances along the loop: from the root to i and to j, less
      // the common part, and the pair's own.
      const double sigma =
          std::sqrt(std::max(0.0, variance[i] + variance[j] - 2 * variance[a]) +
                    Square(pairs_[p].sigma_deg));
      loop.limit_deg =
          std::max(options_.max_loop_error_deg * std::sqrt(loop.length / 3.0),
                   options_.max_loop_error_sigmas * sigma);
      loop.closes = loop.error_deg <= loop.limit_deg;
      if (loop.closes) tree.closed_weight += pairs_[p].weight;
      tree.loops[p] = loop;
    }
    return tree;
  }

  static double Square(double x) { return x * x; }

  const std::vector<ViewGraphPair>& pairs_;
  const ViewGraphOptions& options_;
  std::vector<int> active_;
  std::vector<int> heaviest_first_;
  std::vector<std::pair<int, int>> ends_;  // by pair: its images' indices
  int num_images_ = 0;
};

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
    if (worst.pair_idx < 0) break;
    active[worst.pair_idx] = false;
    dropped.push_back(worst);
  }
  for (const DroppedPair& pair :
       LoopConsensus(pairs, active, options).Inconsistent()) {
    dropped.push_back(pair);
  }
  return dropped;
}

}  // namespace bayon
