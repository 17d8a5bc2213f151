// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/mesh_distance.h"

#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/core/parallel.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

namespace bayon {
namespace {

using Vec3 = Eigen::Vector3d;

// The closest point to p on triangle abc: the Voronoi regions of the
// vertices, then of the edges, else the interior (Ericson 2005, 5.1.5).
Vec3 ClosestPointOnTriangle(const Vec3& p,
                            const Vec3& a,
                            const Vec3& b,
                            const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle
  return a + ab * (vb / denom) + ac * (vc / denom);
}

struct Box {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void Extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void Extend(const Box& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  double SquaredDistance(const Vec3& p) const {
    const Vec3 d = (min - p).cwiseMax(p - max).cwiseMax(Vec3::Zero());
    return d.squaredNorm();
  }
};

struct Node {
  Box box;
  int left = -1;  // children (inner node) or -1
  int right = -1;
  int begin = 0;  // triangle range in `order` (leaf)
  int end = 0;
};

constexpr int kLeafSize = 4;

}  // namespace

struct MeshDistance::Impl {
  std::vector<Vec3> positions;
  std::vector<Eigen::Vector3i> faces;
  std::vector<int> order;  // faces, grouped by leaf
  std::vector<Node> nodes;

  // Median split along the longest axis of the centroids' box.
  int Build(std::vector<Vec3>& centroids, int begin, int end) {
    Node node;
    Box centroid_box;
    for (int i = begin; i < end; ++i) {
      const Eigen::Vector3i& f = faces[order[i]];
      for (int k = 0; k < 3; ++k) node.box.Extend(positions[f(k)]);
      centroid_box.Extend(centroids[order[i]]);
    }
    const int index = static_cast<int>(nodes.size());
    nodes.push_back(node);
    if (end - begin <= kLeafSize) {
      nodes[index].begin = begin;
      nodes[index].end = end;
      return index;
    }
    int axis = 0;
    (centroid_box.max - centroid_box.min).maxCoeff(&axis);
    const int middle = begin + (end - begin) / 2;
    std::nth_element(
        order.begin() + begin,
        order.begin() + middle,
        order.begin() + end,
        [&](int a, int b) { return centroids[a](axis) < centroids[b](axis); });
    const int left = Build(centroids, begin, middle);
    const int right = Build(centroids, middle, end);
    nodes[index].left = left;
    nodes[index].right = right;
    return index;
  }
};

MeshDistance::MeshDistance(const TriangleMesh& mesh)
    : impl_(std::make_unique<Impl>()) {
  if (mesh.faces.empty()) ThrowInputError("mesh has no faces to measure to");
  impl_->positions = mesh.vertices.positions;
  impl_->faces = mesh.faces;
  std::vector<Vec3> centroids(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    centroids[f] = (impl_->positions[face(0)] + impl_->positions[face(1)] +
                    impl_->positions[face(2)]) /
                   3.0;
  }
  impl_->order.resize(mesh.faces.size());
  std::iota(impl_->order.begin(), impl_->order.end(), 0);
  impl_->nodes.reserve(2 * mesh.faces.size() / kLeafSize + 2);
  impl_->Build(centroids, 0, static_cast<int>(mesh.faces.size()));
}

MeshDistance::~MeshDistance() = default;

MeshDistance::Hit MeshDistance::Closest(const Eigen::Vector3d& point) const {
  const Impl& m = *impl_;
  double best = std::numeric_limits<double>::infinity();
  Hit hit;
  int stack[128];
  int size = 0;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = m.nodes[stack[--size]];
    if (node.box.SquaredDistance(point) >= best) continue;
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const Eigen::Vector3i& f = m.faces[m.order[i]];
        const Vec3 q = ClosestPointOnTriangle(
            point, m.positions[f(0)], m.positions[f(1)], m.positions[f(2)]);
        const double d2 = (q - point).squaredNorm();
        if (d2 < best) {
          best = d2;
          hit.closest_point = q;
          hit.face = m.order[i];
        }
      }
      continue;
    }
    // Nearer child last, so it is searched first.
    const double dl = m.nodes[node.left].box.SquaredDistance(point);
    const double dr = m.nodes[node.right].box.SquaredDistance(point);
    if (dl < dr) {
      stack[size++] = node.right;
      stack[size++] = node.left;
    } else {
      stack[size++] = node.left;
      stack[size++] = node.right;
    }
  }
  hit.distance = std::sqrt(best);
  return hit;
}

std::vector<double> MeshDistance::Distances(
    const std::vector<Eigen::Vector3d>& points, int num_threads) const {
  std::vector<double> distances(points.size());
  // Blocks of points, not single points: ParallelFor schedules one task per
  // index.
  constexpr int kBlock = 1024;
  const int num_blocks =
      static_cast<int>((points.size() + kBlock - 1) / kBlock);
  ParallelFor(num_blocks, num_threads, [&](int block) {
    const size_t end = std::min(points.size(), size_t{kBlock} * (block + 1));
    for (size_t i = size_t{kBlock} * block; i < end; ++i) {
      distances[i] = Closest(points[i]).distance;
    }
  });
  return distances;
}

DistanceStatistics ComputeDistanceStatistics(std::vector<double> distances) {
  DistanceStatistics stats;
  stats.count = distances.size();
  if (distances.empty()) return stats;
  double sum = 0, sum2 = 0;
  for (double d : distances) {
    sum += d;
    sum2 += d * d;
    stats.max = std::max(stats.max, d);
  }
  stats.mean = sum / distances.size();
  stats.rms = std::sqrt(sum2 / distances.size());
  auto quantile = [&](double q) {
    const size_t k = std::min(distances.size() - 1,
                              static_cast<size_t>(q * (distances.size() - 1)));
    std::nth_element(distances.begin(), distances.begin() + k, distances.end());
    return distances[k];
  };
  stats.median = quantile(0.5);
  stats.p95 = quantile(0.95);
  return stats;
}

std::vector<double> PointToMeshDistances(const PointCloud& cloud,
                                         const TriangleMesh& mesh,
                                         int num_threads) {
  return MeshDistance(mesh).Distances(cloud.positions, num_threads);
}

namespace {

// Which samples lie within `radius` of some reference point: a hash grid of
// cell size `radius`, each sample checking its 27 cells.
std::vector<bool> CoveredByPoints(const std::vector<Vec3>& samples,
                                  const std::vector<Vec3>& points,
                                  double radius) {
  auto cell_of = [radius](const Vec3& p) {
    return Eigen::Vector3i((p / radius).array().floor().cast<int>());
  };
  auto key_of = [](const Eigen::Vector3i& c) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(c.x())) * 73856093u) ^
           (static_cast<uint64_t>(static_cast<uint32_t>(c.y())) * 19349663u) ^
           (static_cast<uint64_t>(static_cast<uint32_t>(c.z())) * 83492791u);
  };
  std::unordered_multimap<uint64_t, int> grid;
  grid.reserve(points.size());
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    grid.emplace(key_of(cell_of(points[i])), i);
  }
  std::vector<bool> covered(samples.size(), false);
  const double r2 = radius * radius;
  for (size_t s = 0; s < samples.size(); ++s) {
    const Eigen::Vector3i c = cell_of(samples[s]);
    for (int dx = -1; dx <= 1 && !covered[s]; ++dx) {
      for (int dy = -1; dy <= 1 && !covered[s]; ++dy) {
        for (int dz = -1; dz <= 1 && !covered[s]; ++dz) {
          auto range =
              grid.equal_range(key_of(c + Eigen::Vector3i(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) {
            if ((points[it->second] - samples[s]).squaredNorm() <= r2) {
              covered[s] = true;
              break;
            }
          }
        }
      }
    }
  }
  return covered;
}

std::vector<Vec3> SamplePositions(const TriangleMesh& mesh,
                                  size_t num_samples,
                                  uint64_t seed) {
  std::vector<Vec3> positions;
  for (const SurfaceSample& s : SampleMeshSurface(mesh, num_samples, seed)) {
    positions.push_back(s.position);
  }
  return positions;
}

}  // namespace

MeshComparison CompareMeshes(const TriangleMesh& mesh,
                             const TriangleMesh& truth,
                             const MeshComparisonOptions& options) {
  MeshComparison comparison;
  const MeshDistance to_truth(truth);
  const MeshDistance to_mesh(mesh);
  comparison.mesh_to_truth = ComputeDistanceStatistics(to_truth.Distances(
      SamplePositions(mesh, options.num_samples, options.seed),
      options.num_threads));
  std::vector<Vec3> truth_samples =
      SamplePositions(truth, options.num_samples, options.seed + 1);
  if (options.coverage_radius > 0 && !options.coverage_points.empty()) {
    const std::vector<bool> covered = CoveredByPoints(
        truth_samples, options.coverage_points, options.coverage_radius);
    std::vector<Vec3> kept;
    for (size_t i = 0; i < truth_samples.size(); ++i) {
      if (covered[i]) kept.push_back(truth_samples[i]);
    }
    comparison.truth_fraction_covered =
        truth_samples.empty()
            ? 0.0
            : static_cast<double>(kept.size()) / truth_samples.size();
    truth_samples = std::move(kept);
  }
  comparison.truth_to_mesh = ComputeDistanceStatistics(
      to_mesh.Distances(truth_samples, options.num_threads));
  return comparison;
}

nlohmann::ordered_json DistanceStatisticsJson(const DistanceStatistics& s) {
  return {{"count", s.count},
          {"mean", s.mean},
          {"rms", s.rms},
          {"median", s.median},
          {"p95", s.p95},
          {"max", s.max}};
}

}  // namespace bayon
