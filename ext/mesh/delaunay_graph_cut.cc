// SPDX-License-Identifier: BSD-3-Clause
//
// The visibility-based Delaunay mesher behind meshing.h (Labatut, Pons,
// Keriven 2007; the idea of OpenMVS's ReconstructMesh and COLMAP's
// delaunay_mesher): the space is cut into the tetrahedra of the points'
// 3D Delaunay triangulation, each labelled outside or inside the object by
// a minimum s-t cut of a graph whose nodes are the tetrahedra:
//  - every ray from a projection centre to a point it saw crosses free
//    space: each facet it crosses costs one ray if the surface were put
//    there (an edge from the camera's side to the point's side);
//  - the tetrahedron just behind the point, seen along the ray, is inside
//    (a link to the sink);
//  - the tetrahedra outside the convex hull are outside (the source).
// The surface is the facets between inside and outside tetrahedra: it
// closes wherever the rays leave space uncarved behind the points, and its
// vertices are the points themselves (MPGC's precision kept).
#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/mesh/meshing.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <glog/logging.h>

#include <algorithm>
#include <array>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#include <cmath>
#include <mutex>
#include <unordered_map>

namespace bayon {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<int, Kernel>;
using CellBase = CGAL::Triangulation_cell_base_with_info_3<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_3<VertexBase, CellBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;
using Point = Kernel::Point_3;

Point ToPoint(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

// The points that become vertices: one per cell of a grid of
// min_distance on a side (the first point in each), and for each the
// stations of every point merged into it (at most kMaxRays, distinct).
constexpr int kMaxRays = 6;
struct Vertices {
  std::vector<int> point_index;  // into the cloud
  std::vector<std::vector<int>> stations;
};

Vertices SelectVertices(const std::vector<Eigen::Vector3d>& positions,
                        const std::vector<std::vector<int>>& point_stations,
                        double min_distance) {
  Vertices vertices;
  std::unordered_map<uint64_t, int> cell_vertex;
  cell_vertex.reserve(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector3d cell = (positions[i] / min_distance).array().floor();
    // 21 bits per axis (2 million cells across) is far beyond any cloud.
    const auto key = [](double c) {
      return static_cast<uint64_t>(static_cast<int64_t>(c) & 0x1FFFFF);
    };
    const uint64_t hash =
        key(cell.x()) | (key(cell.y()) << 21) | (key(cell.z()) << 42);
    const auto [it, inserted] = cell_vertex.emplace(
        hash, static_cast<int>(vertices.point_index.size()));
    if (inserted) {
      vertices.point_index.push_back(static_cast<int>(i));
      vertices.stations.emplace_back();
    }
    std::vector<int>& stations = vertices.stations[it->second];
    for (int station : point_stations[i]) {
      if (static_cast<int>(stations.size()) < kMaxRays &&
          std::find(stations.begin(), stations.end(), station) ==
              stations.end()) {
        stations.push_back(station);
      }
    }
  }
  return vertices;
}

// The s-t graph over the tetrahedra: per finite cell its links to the
// terminals and the capacities towards its four neighbours, in rays
// (integers: the sums of the threads' shares do not depend on their order,
// so neither does the cut).
struct CellGraph {
  explicit CellGraph(int num_cells)
      : source(num_cells, 0),
        sink(num_cells, 0),
        capacity(4 * static_cast<size_t>(num_cells), 0) {}
  void Add(const CellGraph& other) {
    for (size_t c = 0; c < source.size(); ++c) {
      source[c] += other.source[c];
      sink[c] += other.sink[c];
    }
    for (size_t k = 0; k < capacity.size(); ++k) {
      capacity[k] += other.capacity[k];
    }
  }
  std::vector<int32_t> source;    // outside
  std::vector<int32_t> sink;      // inside
  std::vector<int32_t> capacity;  // 4 per cell: towards neighbour(k)
};

// Adds one ray's weights: from the station to the vertex, the facets it
// crosses (towards the vertex), then the cell behind the vertex.
void AddRay(const Delaunay& dt,
            Delaunay::Vertex_handle vertex,
            const Eigen::Vector3d& station,
            double behind,
            CellGraph* graph) {
  const Point& p = vertex->point();
  const Eigen::Vector3d target(p.x(), p.y(), p.z());
  const Eigen::Vector3d direction = (target - station).normalized();
  // From the vertex towards the station, until the ray leaves the convex
  // hull (beyond it everything is outside already). It starts a hair in
  // front of the vertex: from the vertex itself the traverser may report
  // a cell behind it first, and the ray would carve into the object.
  const Point start = ToPoint(target - 1e-3 * behind * direction);
  Delaunay::Cell_handle previous;
  for (auto it = dt.segment_traverser_cells_begin(
           start, ToPoint(station), vertex->cell());
       it != dt.segment_traverser_cells_end();
       ++it) {
    const Delaunay::Cell_handle cell = it;
    if (dt.is_infinite(cell)) {
      // Entering the hull from outside: the facet costs a ray, from the
      // source (outside the hull everything is outside).
      if (previous != Delaunay::Cell_handle()) {
        graph->source[previous->info()] += 1;
      }
      break;
    }
    if (previous != Delaunay::Cell_handle()) {
      // The ray enters `previous` from `cell` (towards the vertex).
      for (int k = 0; k < 4; ++k) {
        if (cell->neighbor(k) == previous) {
          graph->capacity[4 * cell->info() + k] += 1;
          break;
        }
      }
    }
    previous = cell;
  }
  // Behind the vertex: inside.
  const Eigen::Vector3d inner = target + behind * direction;
  const Delaunay::Cell_handle cell = dt.locate(ToPoint(inner), vertex->cell());
  if (!dt.is_infinite(cell)) graph->sink[cell->info()] += 1;
}

// Every vertex's rays, in parallel over batches of vertices, each batch
// into its own weights, summed after.
CellGraph CastRays(const Delaunay& dt,
                   const std::vector<Delaunay::Vertex_handle>& handles,
                   const std::vector<std::vector<int>>& vertex_stations,
                   const std::vector<Eigen::Vector3d>& stations,
                   double behind,
                   int num_cells,
                   int num_threads) {
  const int num_batches = std::max(1, EffectiveNumThreads(num_threads));
  const int num_vertices = static_cast<int>(handles.size());
  CellGraph graph(num_cells);
  std::mutex merge;
  ParallelFor(num_batches, num_threads, [&](int batch) {
    CellGraph local(num_cells);
    for (int v = batch; v < num_vertices; v += num_batches) {
      if (handles[v] == Delaunay::Vertex_handle()) continue;  // a duplicate
      for (int station : vertex_stations[v]) {
        AddRay(dt, handles[v], stations[station], behind, &local);
      }
    }
    const std::lock_guard<std::mutex> lock(merge);
    graph.Add(local);
  });
  return graph;
}

// The minimum cut: true for the cells on the sink's side (inside).
std::vector<bool> CutGraph(const Delaunay& dt, const CellGraph& cells) {
  using Traits =
      boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
  using Graph = boost::adjacency_list<
      boost::vecS,
      boost::vecS,
      boost::directedS,
      boost::property<
          boost::vertex_color_t,
          boost::default_color_type,
          boost::property<boost::vertex_distance_t,
                          int64_t,
                          boost::property<boost::vertex_predecessor_t,
                                          Traits::edge_descriptor>>>,
      boost::property<
          boost::edge_capacity_t,
          float,
          boost::property<boost::edge_residual_capacity_t,
                          float,
                          boost::property<boost::edge_reverse_t,
                                          Traits::edge_descriptor>>>>;
  const int num_cells = static_cast<int>(cells.source.size());
  Graph graph(num_cells + 2);
  const int source = num_cells, sink = num_cells + 1;
  auto capacity = boost::get(boost::edge_capacity, graph);
  auto reverse = boost::get(boost::edge_reverse, graph);
  const auto add = [&](int from, int to, float forward, float backward) {
    const auto there = boost::add_edge(from, to, graph).first;
    const auto back = boost::add_edge(to, from, graph).first;
    capacity[there] = forward;
    capacity[back] = backward;
    reverse[there] = back;
    reverse[back] = there;
  };
  for (auto cell = dt.finite_cells_begin(); cell != dt.finite_cells_end();
       ++cell) {
    const int c = cell->info();
    if (cells.source[c] > 0)
      add(source, c, static_cast<float>(cells.source[c]), 0);
    if (cells.sink[c] > 0) add(c, sink, static_cast<float>(cells.sink[c]), 0);
    for (int k = 0; k < 4; ++k) {
      const Delaunay::Cell_handle other = cell->neighbor(k);
      const float out = static_cast<float>(cells.capacity[4 * c + k]);
      // The outside of the hull is the source (AddRay).
      if (dt.is_infinite(other)) continue;
      const int o = other->info();
      if (o < c) continue;  // each facet once
      const int back = other->index(cell);
      const float into = static_cast<float>(cells.capacity[4 * o + back]);
      if (out > 0 || into > 0) add(c, o, out, into);
    }
  }
  boost::boykov_kolmogorov_max_flow(graph, source, sink);
  auto color = boost::get(boost::vertex_color, graph);
  const auto source_color = boost::get(color, source);
  std::vector<bool> inside(num_cells);
  for (int c = 0; c < num_cells; ++c) {
    inside[c] = boost::get(color, c) != source_color;
  }
  return inside;
}

}  // namespace

void DelaunayGraphCutOptions::Register(OptionRegistry* r) {
  r->Add("min_distance_factor",
         &min_distance_factor,
         "Points closer than this many spacings are one vertex");
  r->Add("max_edge_factor",
         &max_edge_factor,
         "Leave out faces with an edge longer than this many spacings (0 = "
         "none)");
  r->Add("inside_depth_factor",
         &inside_depth_factor,
         "Rays end this many spacings behind their points, inside");
}

void DelaunayGraphCutOptions::Check() const {
  CheckOption(min_distance_factor >= 0,
              "min_distance_factor",
              ">= 0",
              min_distance_factor);
  CheckOption(max_edge_factor >= 0, "max_edge_factor", ">= 0", max_edge_factor);
  CheckOption(inside_depth_factor > 0,
              "inside_depth_factor",
              "> 0",
              inside_depth_factor);
}

TriangleMesh DelaunayGraphCutMesh(
    const PointCloud& cloud,
    const std::vector<Eigen::Vector3d>& stations,
    const std::vector<std::vector<int>>& point_stations,
    const DelaunayGraphCutOptions& options,
    double median_spacing,
    int num_threads) {
  options.Check();
  CheckEnoughPointsToClose(cloud, "delaunay_graph_cut");
  if (point_stations.size() != cloud.size()) {
    ThrowInputError("delaunay_graph_cut: the images that saw ",
                    point_stations.size(),
                    " points, but the cloud has ",
                    cloud.size());
  }
  for (const std::vector<int>& seen : point_stations) {
    for (int station : seen) {
      if (station < 0 || station >= static_cast<int>(stations.size())) {
        ThrowInputError("delaunay_graph_cut: a point seen from image ",
                        station,
                        " of ",
                        stations.size());
      }
    }
  }
  // Shifted to the centroid, as the other methods, for the same numerics.
  const Eigen::Vector3d center = Centroid(cloud.positions);
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(cloud.size());
  for (const Eigen::Vector3d& p : cloud.positions) {
    positions.push_back(p - center);
  }
  std::vector<Eigen::Vector3d> centred_stations;
  for (const Eigen::Vector3d& s : stations) {
    centred_stations.push_back(s - center);
  }
  const Vertices vertices = SelectVertices(
      positions,
      point_stations,
      std::max(1e-12, options.min_distance_factor * median_spacing));

  std::vector<std::pair<Point, int>> points;
  points.reserve(vertices.point_index.size());
  for (size_t v = 0; v < vertices.point_index.size(); ++v) {
    points.emplace_back(ToPoint(positions[vertices.point_index[v]]),
                        static_cast<int>(v));
  }
  const Delaunay dt(points.begin(), points.end());
  int num_cells = 0;
  for (auto cell = dt.all_cells_begin(); cell != dt.all_cells_end(); ++cell) {
    cell->info() = dt.is_infinite(cell) ? -1 : num_cells++;
  }
  std::vector<Delaunay::Vertex_handle> handles(vertices.point_index.size());
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end();
       ++v) {
    handles[v->info()] = v;
  }

  const CellGraph graph = CastRays(dt,
                                   handles,
                                   vertices.stations,
                                   centred_stations,
                                   options.inside_depth_factor * median_spacing,
                                   num_cells,
                                   num_threads);
  const std::vector<bool> inside = CutGraph(dt, graph);

  // The facets between inside and outside cells, facing outside.
  TriangleMesh mesh;
  for (int v : vertices.point_index) {
    mesh.vertices.positions.push_back(cloud.positions[v]);
  }
  if (cloud.HasNormals()) {
    for (int v : vertices.point_index) {
      mesh.vertices.normals.push_back(cloud.normals[v]);
    }
  }
  if (cloud.HasColors()) {
    for (int v : vertices.point_index) {
      mesh.vertices.colors.push_back(cloud.colors[v]);
    }
  }
  const double max_edge = options.max_edge_factor * median_spacing;
  size_t num_long = 0, num_unseen = 0;
  for (auto cell = dt.finite_cells_begin(); cell != dt.finite_cells_end();
       ++cell) {
    if (!inside[cell->info()]) continue;
    for (int k = 0; k < 4; ++k) {
      const Delaunay::Cell_handle other = cell->neighbor(k);
      // Between inside and outside, or on the convex hull (the outside
      // beyond it is the source's).
      if (!dt.is_infinite(other) && inside[other->info()]) continue;
      std::array<int, 3> corner;
      for (int j = 0; j < 3; ++j) {
        corner[j] = cell->vertex(Delaunay::vertex_triple_index(k, j))->info();
      }
      // Counter-clockwise seen from outside: the cell's own fourth vertex
      // (inside) behind the face.
      const Eigen::Vector3d& a = positions[vertices.point_index[corner[0]]];
      const Eigen::Vector3d& b = positions[vertices.point_index[corner[1]]];
      const Eigen::Vector3d& c = positions[vertices.point_index[corner[2]]];
      const double longest =
          std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      if (max_edge > 0 && longest > max_edge) {
        ++num_long;
        continue;
      }
      const Point& q = cell->vertex(k)->point();
      const Eigen::Vector3d opposite(q.x(), q.y(), q.z());
      Eigen::Vector3d normal = (b - a).cross(c - a);
      if (normal.dot(opposite - a) > 0) {
        std::swap(corner[1], corner[2]);
        normal = -normal;
      }
      // A face no station of its corners sees from the front closes what
      // no photograph showed from that side (under a ground, behind a
      // wall): left out.
      const Eigen::Vector3d centroid = (a + b + c) / 3;
      const auto in_front = [&](int station) {
        return normal.dot(centred_stations[station] - centroid) > 0;
      };
      const bool seen = std::any_of(corner.begin(), corner.end(), [&](int v) {
        return std::any_of(
            vertices.stations[v].begin(), vertices.stations[v].end(), in_front);
      });
      if (!seen) {
        ++num_unseen;
        continue;
      }
      mesh.faces.emplace_back(corner[0], corner[1], corner[2]);
    }
  }
  LOG(INFO) << "delaunay_graph_cut: " << cloud.size() << " points, "
            << vertices.point_index.size() << " vertices, " << num_cells
            << " tetrahedra, " << std::count(inside.begin(), inside.end(), true)
            << " inside; " << mesh.faces.size() << " faces, " << num_long
            << " with an edge over " << max_edge << " and " << num_unseen
            << " seen from behind left out";
  return mesh;
}

}  // namespace bayon
