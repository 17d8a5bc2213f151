// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/mesh_geometry.h"

#include "ext/core/union_find.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

namespace bayon {
namespace {

// One face side: the undirected edge (lo, hi), the face, and whether the
// face runs lo -> hi.
struct FaceEdge {
  int lo;
  int hi;
  int face;
  int corner;  // 0..2, the corner the edge starts at
  bool forward;
};

std::vector<FaceEdge> SortedFaceEdges(const TriangleMesh& mesh) {
  std::vector<FaceEdge> edges;
  edges.reserve(3 * mesh.faces.size());
  for (int f = 0; f < static_cast<int>(mesh.faces.size()); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[f](k);
      const int b = mesh.faces[f]((k + 1) % 3);
      if (a == b) continue;
      edges.push_back({std::min(a, b), std::max(a, b), f, k, a < b});
    }
  }
  std::sort(
      edges.begin(), edges.end(), [](const FaceEdge& x, const FaceEdge& y) {
        return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi;
      });
  return edges;
}

// Index of the corner of face f that holds vertex v.
int CornerOf(const TriangleMesh& mesh, int f, int v) {
  for (int k = 0; k < 3; ++k) {
    if (mesh.faces[f](k) == v) return 3 * f + k;
  }
  return -1;
}

}  // namespace

Eigen::Vector3d FaceNormal(const TriangleMesh& mesh, int face) {
  const Eigen::Vector3i& f = mesh.faces[face];
  const auto& p = mesh.vertices.positions;
  const Eigen::Vector3d n = (p[f(1)] - p[f(0)]).cross(p[f(2)] - p[f(0)]);
  const double norm = n.norm();
  return norm > 0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
}

Eigen::Vector3d Centroid(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) sum += p;
  return sum / static_cast<double>(std::max<size_t>(points.size(), 1));
}

std::vector<std::vector<int>> FindBoundaryLoops(const TriangleMesh& mesh) {
  const std::vector<FaceEdge> edges = SortedFaceEdges(mesh);
  // Boundary halfedges as their faces run them: a consistently oriented
  // boundary then chains head to tail.
  std::vector<std::pair<int, int>> boundary;
  const int num_sides = static_cast<int>(edges.size());
  for (int i = 0; i < num_sides;) {
    int j = i;
    while (j < num_sides && edges[j].lo == edges[i].lo &&
           edges[j].hi == edges[i].hi) {
      ++j;
    }
    if (j - i == 1) {
      const FaceEdge& e = edges[i];
      boundary.push_back(e.forward ? std::make_pair(e.lo, e.hi)
                                   : std::make_pair(e.hi, e.lo));
    }
    i = j;
  }
  std::unordered_multimap<int, size_t> by_start;
  for (size_t i = 0; i < boundary.size(); ++i) {
    by_start.emplace(boundary[i].first, i);
  }
  std::vector<bool> used(boundary.size(), false);
  std::vector<std::vector<int>> loops;
  for (size_t start = 0; start < boundary.size(); ++start) {
    if (used[start]) continue;
    std::vector<int> loop;
    size_t current = start;
    while (true) {
      used[current] = true;
      loop.push_back(boundary[current].first);
      const int head = boundary[current].second;
      if (head == boundary[start].first) break;
      size_t next = boundary.size();
      auto range = by_start.equal_range(head);
      for (auto it = range.first; it != range.second; ++it) {
        if (!used[it->second]) {
          next = it->second;
          break;
        }
      }
      // An inconsistently oriented boundary ends the walk early: the chain
      // still counts as one loop.
      if (next == boundary.size()) break;
      current = next;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::vector<int> CornerFans(const TriangleMesh& mesh) {
  const int num_faces = static_cast<int>(mesh.faces.size());
  UnionFind corners(3 * mesh.faces.size());
  const std::vector<FaceEdge> edges = SortedFaceEdges(mesh);
  const int num_sides = static_cast<int>(edges.size());
  for (int i = 0; i < num_sides;) {
    int j = i;
    while (j < num_sides && edges[j].lo == edges[i].lo &&
           edges[j].hi == edges[i].hi) {
      ++j;
    }
    if (j - i == 2) {
      // The two faces belong to the same fan around both end points.
      for (int v : {edges[i].lo, edges[i].hi}) {
        corners.Union(CornerOf(mesh, edges[i].face, v),
                      CornerOf(mesh, edges[i + 1].face, v));
      }
    }
    i = j;
  }
  std::vector<int> fans(3 * mesh.faces.size(), -1);
  for (int f = 0; f < num_faces; ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    if (t(0) == t(1) || t(1) == t(2) || t(0) == t(2)) continue;
    for (int k = 0; k < 3; ++k) {
      fans[3 * f + k] = static_cast<int>(corners.Find(3 * f + k));
    }
  }
  return fans;
}

size_t SplitNonManifoldVertices(TriangleMesh* mesh) {
  const std::vector<int> fans = CornerFans(*mesh);
  PointCloud& v = mesh->vertices;
  const size_t n = v.size();
  std::vector<int> first_fan(n, -1);
  // For the second and later fans of a vertex, the copy that takes them.
  std::unordered_map<int, int> copy_of_fan;
  size_t num_copies = 0;
  for (size_t c = 0; c < fans.size(); ++c) {
    if (fans[c] < 0) continue;
    int& vertex = mesh->faces[c / 3](c % 3);
    if (first_fan[vertex] < 0) first_fan[vertex] = fans[c];
    if (first_fan[vertex] == fans[c]) continue;
    auto [it, inserted] = copy_of_fan.emplace(fans[c], -1);
    if (inserted) {
      it->second = static_cast<int>(v.positions.size());
      v.positions.push_back(v.positions[vertex]);
      if (v.HasNormals()) v.normals.push_back(v.normals[vertex]);
      if (v.HasColors()) v.colors.push_back(v.colors[vertex]);
      for (PointAttribute& a : v.attributes) {
        a.values.push_back(a.values[vertex]);
      }
      ++num_copies;
    }
    vertex = it->second;
  }
  return num_copies;
}

MeshTopology ComputeMeshTopology(const TriangleMesh& mesh) {
  MeshTopology topology;
  const auto& positions = mesh.vertices.positions;
  topology.num_vertices = positions.size();
  topology.num_faces = mesh.faces.size();
  const int num_faces = static_cast<int>(mesh.faces.size());

  std::vector<bool> referenced(positions.size(), false);
  for (const Eigen::Vector3i& face : mesh.faces) {
    for (int k = 0; k < 3; ++k) referenced[face(k)] = true;
  }
  const size_t num_referenced =
      std::count(referenced.begin(), referenced.end(), true);
  topology.num_unreferenced_vertices = positions.size() - num_referenced;

  double max_edge = 0;
  for (int f = 0; f < num_faces; ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    const Eigen::Vector3d cross =
        (positions[face(1)] - positions[face(0)])
            .cross(positions[face(2)] - positions[face(0)]);
    const double area = 0.5 * cross.norm();
    topology.area += area;
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
      longest = std::max(
          longest, (positions[face(k)] - positions[face((k + 1) % 3)]).norm());
    }
    max_edge = std::max(max_edge, longest);
    const bool repeated =
        face(0) == face(1) || face(1) == face(2) || face(0) == face(2);
    if (repeated || area <= 1e-12 * longest * longest) {
      ++topology.num_degenerate_faces;
    }
  }

  const std::vector<FaceEdge> edges = SortedFaceEdges(mesh);
  UnionFind components(mesh.faces.size());
  double edge_sum = 0;
  topology.shortest_edge = std::numeric_limits<double>::infinity();
  const int num_sides = static_cast<int>(edges.size());
  for (int i = 0; i < num_sides;) {
    int j = i;
    while (j < num_sides && edges[j].lo == edges[i].lo &&
           edges[j].hi == edges[i].hi) {
      ++j;
    }
    const int count = j - i;
    const FaceEdge& e = edges[i];
    ++topology.num_edges;
    const double length = (positions[e.lo] - positions[e.hi]).norm();
    edge_sum += length;
    topology.shortest_edge = std::min(topology.shortest_edge, length);
    topology.longest_edge = std::max(topology.longest_edge, length);
    if (count == 1) ++topology.num_boundary_edges;
    if (count > 2) ++topology.num_non_manifold_edges;
    for (int k = i; k + 1 < j; ++k) {
      components.Union(edges[k].face, edges[k + 1].face);
    }
    if (count == 2 && e.forward == edges[i + 1].forward) {
      ++topology.num_inconsistent_edges;
    }
    i = j;
  }
  if (topology.num_edges > 0) {
    topology.mean_edge = edge_sum / topology.num_edges;
  } else {
    topology.shortest_edge = 0;
  }

  const std::vector<int> fans = CornerFans(mesh);
  std::vector<int> first_fan(positions.size(), -1);
  std::vector<bool> non_manifold(positions.size(), false);
  for (int c = 0; c < 3 * num_faces; ++c) {
    if (fans[c] < 0) continue;
    const int v = mesh.faces[c / 3](c % 3);
    if (first_fan[v] < 0) {
      first_fan[v] = fans[c];
    } else if (first_fan[v] != fans[c]) {
      non_manifold[v] = true;
    }
  }
  topology.num_non_manifold_vertices =
      std::count(non_manifold.begin(), non_manifold.end(), true);

  std::vector<bool> is_root(mesh.faces.size(), false);
  for (int f = 0; f < num_faces; ++f) is_root[components.Find(f)] = true;
  topology.num_components = std::count(is_root.begin(), is_root.end(), true);
  topology.num_boundary_loops = FindBoundaryLoops(mesh).size();
  topology.euler_characteristic = static_cast<int64_t>(num_referenced) -
                                  static_cast<int64_t>(topology.num_edges) +
                                  static_cast<int64_t>(topology.num_faces);
  return topology;
}

std::vector<SurfaceSample> SampleMeshSurface(const TriangleMesh& mesh,
                                             size_t num_samples,
                                             uint64_t seed) {
  std::vector<SurfaceSample> samples;
  if (mesh.faces.empty() || num_samples == 0) return samples;
  const auto& p = mesh.vertices.positions;
  std::vector<double> cumulative(mesh.faces.size());
  double total = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    total +=
        0.5 * (p[face(1)] - p[face(0)]).cross(p[face(2)] - p[face(0)]).norm();
    cumulative[f] = total;
  }
  if (!(total > 0)) return samples;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  samples.reserve(num_samples);
  for (size_t i = 0; i < num_samples; ++i) {
    const double r = uniform(rng) * total;
    const size_t f = std::min<size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), r) -
            cumulative.begin(),
        mesh.faces.size() - 1);
    // Uniform barycentric coordinates (Osada et al. 2002, eq. 1).
    const double s = std::sqrt(uniform(rng));
    const double t = uniform(rng);
    const Eigen::Vector3i& face = mesh.faces[f];
    samples.push_back(
        {(1 - s) * p[face(0)] + s * (1 - t) * p[face(1)] + s * t * p[face(2)],
         static_cast<int>(f)});
  }
  return samples;
}

}  // namespace bayon
