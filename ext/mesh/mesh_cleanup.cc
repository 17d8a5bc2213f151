// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/mesh_cleanup.h"

#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/mesh/openmesh_types.h"

#include <Eigen/Geometry>
#include <glog/logging.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

namespace bayon {
namespace {

// Step 1: merges vertices closer than `distance` (a hash grid of that cell
// size; 0 = identical positions) and returns the representative of each.
std::vector<int> MergeVertices(const std::vector<Eigen::Vector3d>& positions,
                               double distance,
                               size_t* num_merged) {
  const size_t n = positions.size();
  std::vector<int> representative(n);
  std::iota(representative.begin(), representative.end(), 0);
  *num_merged = 0;
  if (distance <= 0) {
    std::map<std::array<double, 3>, int> first;
    for (size_t i = 0; i < n; ++i) {
      const std::array<double, 3> key = {
          positions[i].x(), positions[i].y(), positions[i].z()};
      const auto [it, inserted] = first.emplace(key, static_cast<int>(i));
      if (!inserted) {
        representative[i] = it->second;
        ++*num_merged;
      }
    }
    return representative;
  }
  auto cell_of = [distance](const Eigen::Vector3d& p) {
    return Eigen::Vector3i((p / distance).array().floor().cast<int>());
  };
  auto key_of = [](const Eigen::Vector3i& c) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(c.x())) * 73856093u) ^
           (static_cast<uint64_t>(static_cast<uint32_t>(c.y())) * 19349663u) ^
           (static_cast<uint64_t>(static_cast<uint32_t>(c.z())) * 83492791u);
  };
  std::unordered_multimap<uint64_t, int> grid;
  const double d2 = distance * distance;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i c = cell_of(positions[i]);
    int found = -1;
    for (int dx = -1; dx <= 1 && found < 0; ++dx) {
      for (int dy = -1; dy <= 1 && found < 0; ++dy) {
        for (int dz = -1; dz <= 1 && found < 0; ++dz) {
          auto range =
              grid.equal_range(key_of(c + Eigen::Vector3i(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) {
            if ((positions[it->second] - positions[i]).squaredNorm() <= d2) {
              found = it->second;
              break;
            }
          }
        }
      }
    }
    if (found >= 0) {
      representative[i] = found;
      ++*num_merged;
    } else {
      grid.emplace(key_of(c), static_cast<int>(i));
    }
  }
  return representative;
}

// Step 2: breadth-first over faces sharing an edge with exactly one other
// face, flipping a neighbour that runs the shared edge the same way. Then
// each component agrees with the vertex normals (or, without them, faces
// away from the centroid of all vertices), by area-weighted majority.
size_t OrientConsistently(const PointCloud& vertices,
                          std::vector<Eigen::Vector3i>* faces) {
  const size_t num_faces = faces->size();
  struct Side {
    int lo, hi, face;
  };
  std::vector<Side> sides;
  sides.reserve(3 * num_faces);
  for (size_t f = 0; f < num_faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = (*faces)[f](k), b = (*faces)[f]((k + 1) % 3);
      sides.push_back({std::min(a, b), std::max(a, b), static_cast<int>(f)});
    }
  }
  std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi;
  });
  // Neighbour across each manifold edge.
  std::vector<std::vector<int>> neighbors(num_faces);
  for (size_t i = 0; i + 1 < sides.size();) {
    size_t j = i;
    while (j < sides.size() && sides[j].lo == sides[i].lo &&
           sides[j].hi == sides[i].hi) {
      ++j;
    }
    if (j - i == 2) {
      neighbors[sides[i].face].push_back(sides[i + 1].face);
      neighbors[sides[i + 1].face].push_back(sides[i].face);
    }
    i = j;
  }
  auto runs = [&](int f, int a, int b) {
    const Eigen::Vector3i& t = (*faces)[f];
    for (int k = 0; k < 3; ++k) {
      if (t(k) == a && t((k + 1) % 3) == b) return true;
    }
    return false;
  };
  const auto& p = vertices.positions;
  const Eigen::Vector3d centroid = Centroid(p);

  size_t flipped = 0;
  std::vector<int> component(num_faces, -1);
  std::vector<bool> was_flipped(num_faces, false);
  for (size_t seed = 0; seed < num_faces; ++seed) {
    if (component[seed] >= 0) continue;
    std::vector<int> members = {static_cast<int>(seed)};
    component[seed] = static_cast<int>(seed);
    std::deque<int> queue = {static_cast<int>(seed)};
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop_front();
      const Eigen::Vector3i t = (*faces)[f];
      for (int g : neighbors[f]) {
        if (component[g] >= 0) continue;
        // The shared edge, as f runs it.
        for (int k = 0; k < 3; ++k) {
          const int a = t(k), b = t((k + 1) % 3);
          const Eigen::Vector3i& u = (*faces)[g];
          if ((u.array() == a).any() && (u.array() == b).any()) {
            if (runs(g, a, b)) {
              std::swap((*faces)[g](0), (*faces)[g](1));
              was_flipped[g] = !was_flipped[g];
            }
            break;
          }
        }
        component[g] = static_cast<int>(seed);
        members.push_back(g);
        queue.push_back(g);
      }
    }
    // Which way the component faces.
    double agree = 0;
    for (int f : members) {
      const Eigen::Vector3i& t = (*faces)[f];
      const Eigen::Vector3d area_normal =
          0.5 * (p[t(1)] - p[t(0)]).cross(p[t(2)] - p[t(0)]);
      Eigen::Vector3d reference;
      if (vertices.HasNormals()) {
        reference = (vertices.normals[t(0)] + vertices.normals[t(1)] +
                     vertices.normals[t(2)])
                        .cast<double>();
      } else {
        reference = (p[t(0)] + p[t(1)] + p[t(2)]) / 3.0 - centroid;
      }
      agree += area_normal.dot(reference.normalized());
    }
    const bool reverse = agree < 0;
    for (int f : members) {
      if (reverse) {
        std::swap((*faces)[f](0), (*faces)[f](1));
        was_flipped[f] = !was_flipped[f];
      }
      flipped += was_flipped[f];
    }
  }
  return flipped;
}

// Step 4: a face with (numerically) zero area.
bool IsDegenerate(const OmMesh& mesh, OmMesh::FaceHandle f) {
  auto it = mesh.cfv_iter(f);
  const OmMesh::Point a = mesh.point(*it++);
  const OmMesh::Point b = mesh.point(*it++);
  const OmMesh::Point c = mesh.point(*it);
  const double longest =
      std::max({(b - a).sqrnorm(), (c - b).sqrnorm(), (a - c).sqrnorm()});
  return ((b - a) % (c - a)).sqrnorm() <= 1e-20 * longest * longest;
}

size_t RemoveDegenerateFaces(OmMesh* mesh) {
  size_t removed = 0;
  for (int pass = 0; pass < 5; ++pass) {
    size_t changed = 0;
    for (OmMesh::FaceHandle f : mesh->faces()) {
      if (mesh->status(f).deleted() || !IsDegenerate(*mesh, f)) continue;
      // Shortest and longest edge of the face.
      OmMesh::HalfedgeHandle shortest, longest;
      double min_length = std::numeric_limits<double>::infinity(),
             max_length = -1;
      for (OmMesh::HalfedgeHandle h : mesh->fh_range(f)) {
        const double length = mesh->calc_edge_length(h);
        if (length < min_length) min_length = length, shortest = h;
        if (length > max_length) max_length = length, longest = h;
      }
      if (min_length <= 1e-6 * max_length && mesh->is_collapse_ok(shortest)) {
        mesh->collapse(shortest);  // a needle: its short edge goes
      } else if (mesh->is_flip_ok(mesh->edge_handle(longest))) {
        mesh->flip(mesh->edge_handle(longest));  // a cap: its long edge turns
      } else {
        mesh->delete_face(f, true);
      }
      ++changed;
    }
    removed += changed;
    if (changed == 0) break;
  }
  return removed;
}

// Step 5.
void RemoveSmallComponents(const MeshCleanupOptions& options,
                           OmMesh* mesh,
                           MeshCleanupReport* report) {
  OpenMesh::FPropHandleT<int> label;
  mesh->add_property(label);
  for (OmMesh::FaceHandle f : mesh->faces()) mesh->property(label, f) = -1;
  std::vector<std::vector<OmMesh::FaceHandle>> components;
  for (OmMesh::FaceHandle seed : mesh->faces()) {
    if (mesh->status(seed).deleted() || mesh->property(label, seed) >= 0) {
      continue;
    }
    const int id = static_cast<int>(components.size());
    components.emplace_back();
    std::vector<OmMesh::FaceHandle> stack = {seed};
    mesh->property(label, seed) = id;
    while (!stack.empty()) {
      const OmMesh::FaceHandle f = stack.back();
      stack.pop_back();
      components[id].push_back(f);
      for (OmMesh::FaceHandle g : mesh->ff_range(f)) {
        if (mesh->property(label, g) < 0) {
          mesh->property(label, g) = id;
          stack.push_back(g);
        }
      }
    }
  }
  mesh->remove_property(label);
  size_t largest = 0;
  for (const auto& c : components) largest = std::max(largest, c.size());
  const double keep = std::max<double>(
      options.min_component_faces, options.min_component_fraction * largest);
  for (const auto& c : components) {
    if (c.size() >= keep || c.size() == largest) continue;
    ++report->num_small_components;
    report->num_small_component_faces += c.size();
    for (OmMesh::FaceHandle f : c) mesh->delete_face(f, true);
  }
}

// Step 6: the minimum-area triangulation of a closed polygon (its corners
// in loop order); triangles as index triples into `loop`.
std::vector<std::array<int, 3>> MinimumAreaTriangulation(
    const std::vector<OmMesh::Point>& loop) {
  const int m = static_cast<int>(loop.size());
  auto area = [&](int i, int j, int k) {
    return 0.5 * ((loop[j] - loop[i]) % (loop[k] - loop[i])).norm();
  };
  std::vector<double> cost(m * m, 0.0);
  std::vector<int> split(m * m, -1);
  for (int length = 2; length < m; ++length) {
    for (int i = 0; i + length < m; ++i) {
      const int k = i + length;
      double best = std::numeric_limits<double>::infinity();
      for (int j = i + 1; j < k; ++j) {
        const double c = cost[i * m + j] + cost[j * m + k] + area(i, j, k);
        if (c < best) {
          best = c;
          split[i * m + k] = j;
        }
      }
      cost[i * m + k] = best;
    }
  }
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::pair<int, int>> stack = {{0, m - 1}};
  while (!stack.empty()) {
    const auto [i, k] = stack.back();
    stack.pop_back();
    if (k - i < 2) continue;
    const int j = split[i * m + k];
    triangles.push_back({i, j, k});
    stack.emplace_back(i, j);
    stack.emplace_back(j, k);
  }
  return triangles;
}

// Whether OpenMesh can add the face (a, b, c) without relinking: each edge
// free or new, and at each corner whose two edges exist already, the two
// following each other around the vertex's boundary. Where they do not,
// add_face must move the faces between them into another gap at the vertex,
// and where that fails ("patch re-linking failed") it has already changed
// part of the mesh, which then fails OpenMesh's assertions (the rendered
// tower's graph-cut mesh with holes of up to 50 edges filled). A hole's
// triangles are added as ears instead: each next to the boundary as it
// stands.
bool CanAddFace(const OmMesh& mesh,
                const std::array<OmMesh::VertexHandle, 3>& v) {
  if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) return false;
  // edge[k]: v[k] -> v[k + 1], where it exists already.
  std::array<OmMesh::HalfedgeHandle, 3> edge;
  for (int k = 0; k < 3; ++k) {
    if (!mesh.is_boundary(v[k])) return false;
    edge[k] = mesh.find_halfedge(v[k], v[(k + 1) % 3]);
    if (edge[k].is_valid() && !mesh.is_boundary(edge[k])) return false;
  }
  for (int k = 0; k < 3; ++k) {
    // The corner at v[k]: from edge[k - 1] into edge[k].
    const OmMesh::HalfedgeHandle in = edge[(k + 2) % 3];
    if (in.is_valid() && edge[k].is_valid() &&
        mesh.next_halfedge_handle(in) != edge[k]) {
      return false;
    }
  }
  return true;
}

void FillHoles(int max_hole_edges, OmMesh* mesh, MeshCleanupReport* report) {
  std::vector<std::vector<OmMesh::VertexHandle>> holes;
  OpenMesh::HPropHandleT<bool> seen;
  mesh->add_property(seen);
  for (OmMesh::HalfedgeHandle h : mesh->halfedges()) {
    mesh->property(seen, h) = false;
  }
  for (OmMesh::HalfedgeHandle start : mesh->halfedges()) {
    if (mesh->status(start).deleted() || !mesh->is_boundary(start) ||
        mesh->property(seen, start)) {
      continue;
    }
    std::vector<OmMesh::VertexHandle> loop;
    OmMesh::HalfedgeHandle h = start;
    do {
      mesh->property(seen, h) = true;
      loop.push_back(mesh->from_vertex_handle(h));
      h = mesh->next_halfedge_handle(h);
    } while (h != start &&
             loop.size() <= static_cast<size_t>(max_hole_edges) + 1);
    // A loop through one vertex twice (two holes that touch there) has no
    // triangulation without that vertex in a face twice: left open.
    std::vector<OmMesh::VertexHandle> sorted = loop;
    std::sort(sorted.begin(), sorted.end());
    const bool simple =
        std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
    if (h == start && simple && loop.size() >= 3 &&
        loop.size() <= static_cast<size_t>(max_hole_edges)) {
      holes.push_back(std::move(loop));
    } else {
      // Mark the rest of a long loop so that it is not walked again.
      while (h != start && !mesh->property(seen, h)) {
        mesh->property(seen, h) = true;
        h = mesh->next_halfedge_handle(h);
      }
    }
  }
  mesh->remove_property(seen);
  for (const auto& hole : holes) {
    std::vector<OmMesh::Point> corners;
    for (OmMesh::VertexHandle v : hole) corners.push_back(mesh->point(v));
    // The boundary halfedges run the loop the way a face filling the hole
    // runs its edges, so triangles in loop order are oriented like their
    // neighbours. They go in as ears of the boundary as it stands
    // (CanAddFace), in passes until none more can be added.
    std::vector<std::array<OmMesh::VertexHandle, 3>> pending;
    for (const auto& t : MinimumAreaTriangulation(corners)) {
      pending.push_back({hole[t[0]], hole[t[1]], hole[t[2]]});
    }
    const auto add = [&](const std::array<OmMesh::VertexHandle, 3>& face) {
      return CanAddFace(*mesh, face) &&
             mesh->add_face(face[0], face[1], face[2]).is_valid();
    };
    const size_t num_triangles = pending.size();
    for (size_t before = 0; before != pending.size();) {
      before = pending.size();
      pending.erase(std::remove_if(pending.begin(), pending.end(), add),
                    pending.end());
    }
    const size_t added = num_triangles - pending.size();
    if (added > 0) {
      ++report->num_holes_filled;
      report->num_fill_faces += added;
    }
  }
}

// The points `indices` of a cloud, with every per-point array.
PointCloud GatherPoints(const PointCloud& cloud,
                        const std::vector<int>& indices) {
  PointCloud out;
  out.positions.reserve(indices.size());
  for (int i : indices) out.positions.push_back(cloud.positions[i]);
  if (cloud.HasNormals()) {
    for (int i : indices) out.normals.push_back(cloud.normals[i]);
  }
  if (cloud.HasColors()) {
    for (int i : indices) out.colors.push_back(cloud.colors[i]);
  }
  for (const PointAttribute& attribute : cloud.attributes) {
    PointAttribute& copy = out.attributes.emplace_back();
    copy.name = attribute.name;
    copy.type = attribute.type;
    for (int i : indices) copy.values.push_back(attribute.values[i]);
  }
  return out;
}

}  // namespace

void MeshCleanupOptions::Register(OptionRegistry* r) {
  r->Add("merge_distance_m",
         &merge_distance_m,
         "Merge vertices closer than this (0 = identical only)");
  r->Add("min_component_faces",
         &min_component_faces,
         "Drop components with fewer faces ...");
  r->Add("min_component_fraction",
         &min_component_fraction,
         "... or fewer than this share of the largest");
  r->Add("max_hole_edges",
         &max_hole_edges,
         "Fill holes with at most this many boundary edges (0 = no)");
}

void MeshCleanupOptions::Check() const {
  CheckOption(
      merge_distance_m >= 0, "merge_distance_m", ">= 0", merge_distance_m);
  CheckOption(min_component_fraction >= 0 && min_component_fraction <= 1,
              "min_component_fraction",
              "in [0, 1]",
              min_component_fraction);
  CheckOption(min_component_faces >= 0,
              "min_component_faces",
              ">= 0",
              min_component_faces);
  CheckOption(max_hole_edges >= 0 && max_hole_edges <= 2000,
              "max_hole_edges",
              "in [0, 2000]",
              max_hole_edges);
}

TriangleMesh CleanupMesh(const TriangleMesh& input,
                         const MeshCleanupOptions& options,
                         MeshCleanupReport* report) {
  options.Check();
  *report = MeshCleanupReport();
  const PointCloud& vertices = input.vertices;

  // 1. Merge, drop repeated-vertex and duplicate faces.
  const std::vector<int> representative =
      MergeVertices(vertices.positions,
                    options.merge_distance_m,
                    &report->num_merged_vertices);
  std::vector<Eigen::Vector3i> faces;
  faces.reserve(input.faces.size());
  std::map<std::array<int, 3>, int> seen_faces;
  for (const Eigen::Vector3i& f : input.faces) {
    const Eigen::Vector3i g(
        representative[f(0)], representative[f(1)], representative[f(2)]);
    if (g(0) == g(1) || g(1) == g(2) || g(0) == g(2)) {
      ++report->num_repeated_vertex_faces;
      continue;
    }
    std::array<int, 3> key = {g(0), g(1), g(2)};
    std::sort(key.begin(), key.end());
    if (!seen_faces.emplace(key, 0).second) {
      ++report->num_duplicate_faces;
      continue;
    }
    faces.push_back(g);
  }

  // 2. Orientation.
  report->num_flipped_faces = OrientConsistently(vertices, &faces);

  // 3. Into OpenMesh: faces it cannot hold are non-manifold.
  OmMesh mesh;
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_halfedge_status();
  mesh.request_face_status();
  OpenMesh::VPropHandleT<int> source;
  mesh.add_property(source);
  std::vector<OmMesh::VertexHandle> handle(vertices.size());
  for (const Eigen::Vector3i& f : faces) {
    for (int k = 0; k < 3; ++k) {
      const int v = f(k);
      if (handle[v].is_valid()) continue;
      const Eigen::Vector3d& q = vertices.positions[v];
      handle[v] = mesh.add_vertex(OmMesh::Point(q.x(), q.y(), q.z()));
      mesh.property(source, handle[v]) = v;
    }
  }
  {
    // OpenMesh reports each refused face on its error stream; the count
    // goes into the report instead.
    const bool was_enabled = omerr().is_enabled();
    omerr().disable();
    for (const Eigen::Vector3i& f : faces) {
      if (!mesh.add_face(handle[f(0)], handle[f(1)], handle[f(2)]).is_valid()) {
        ++report->num_non_manifold_faces;
      }
    }
    if (was_enabled) omerr().enable();
  }

  // 4.-6.
  report->num_degenerate_faces = RemoveDegenerateFaces(&mesh);
  RemoveSmallComponents(options, &mesh, report);
  if (options.max_hole_edges > 0) {
    FillHoles(options.max_hole_edges, &mesh, report);
  }
  for (OmMesh::VertexHandle v : mesh.vertices()) {
    if (!mesh.status(v).deleted() && mesh.is_isolated(v)) mesh.delete_vertex(v);
  }
  mesh.garbage_collection();

  // Back to bayon's mesh, attributes following their source vertex.
  std::vector<int> sources;
  sources.reserve(mesh.n_vertices());
  for (OmMesh::VertexHandle v : mesh.vertices()) {
    sources.push_back(mesh.property(source, v));
  }
  TriangleMesh output;
  output.vertices = GatherPoints(vertices, sources);
  for (OmMesh::VertexHandle v : mesh.vertices()) {
    const OmMesh::Point& q = mesh.point(v);
    output.vertices.positions[v.idx()] = Eigen::Vector3d(q[0], q[1], q[2]);
  }
  output.faces.reserve(mesh.n_faces());
  for (OmMesh::FaceHandle f : mesh.faces()) {
    auto it = mesh.cfv_iter(f);
    const int a = (*it++).idx(), b = (*it++).idx(), c = (*it).idx();
    output.faces.emplace_back(a, b, c);
  }
  // 7. What OpenMesh keeps as two boundary fans at one vertex becomes two
  // vertices.
  report->num_split_vertices = SplitNonManifoldVertices(&output);
  LOG(INFO) << "cleanup: " << report->num_merged_vertices
            << " vertices merged, " << report->num_non_manifold_faces
            << " non-manifold faces, " << report->num_degenerate_faces
            << " degenerate, " << report->num_small_components
            << " small components, " << report->num_holes_filled
            << " holes filled";
  return output;
}

}  // namespace bayon
