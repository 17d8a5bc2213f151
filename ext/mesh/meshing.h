// SPDX-License-Identifier: BSD-3-Clause
//
// Surface triangulation of a dense point cloud (the Bayon paper, sec. 3.4 and
// conclusion (d)), four ways:
//
//  kCylinder          the paper's 2.5D Delaunay triangulation in a cylinder
//                     frame (cylinder_mesher.h), for objects that are
//                     star-shaped about a vertical axis, as a tower is;
//  kGreedyProjection  PCL's greedy projection triangulation (Marton, Rusu,
//                     Beetz 2009): interpolating, local, needs normals;
//  kPoisson           PCL's Poisson surface reconstruction (Kazhdan, Bolitho,
//                     Hoppe 2006): approximating, watertight, needs oriented
//                     normals; trimmed back to the points;
//  kAdvancingFront    CGAL's advancing-front surface reconstruction (Cohen-
//                     Steiner, Da 2004): interpolating, from the 3D Delaunay
//                     triangulation, no normals; the "efficient 3D
//                     triangulator" the paper's conclusion asks for;
//  kDelaunayGraphCut  the points' 3D Delaunay tetrahedra labelled inside or
//                     outside by the rays from the projection centres to the
//                     points they saw and a minimum cut (Labatut, Pons,
//                     Keriven 2007; delaunay_graph_cut.cc): interpolating,
//                     closes the seen surface, needs each point's station
//                     (the dense cloud's master_id and the oriented model);
//  kColmapPoisson     for comparison: stock `colmap poisson_mesher` (screened
//                     Poisson, Kazhdan and Hoppe 2013) run through
//                     ext/colmap/colmap_cli on the cloud written as COLMAP's
//                     fused.ply (float x y z, normals).
//
// Then the same cleanup for all (mesh_cleanup.h, on OpenMesh) and the
// statistics of the result. Normals missing where a method needs them are
// estimated with PCL and oriented (normals.h), or refused when
// `estimate_normals` is off. Object units (metres).
#pragma once

#include "ext/core/mesh_geometry.h"
#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"
#include "ext/mesh/cylinder_mesher.h"
#include "ext/mesh/mesh_cleanup.h"
#include "ext/mesh/normals.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

enum class MeshMethod {
  kCylinder,
  kGreedyProjection,
  kPoisson,
  kAdvancingFront,
  kColmapPoisson,
  kDelaunayGraphCut
};
// "cylinder", "greedy_projection", "poisson", "advancing_front",
// "colmap_poisson", "delaunay_graph_cut".
std::string MeshMethodName(MeshMethod method);

struct GreedyProjectionOptions {
  // Neighbourhood radius as a multiple of the median nearest-neighbour
  // distance; larger bridges more gaps and costs more.
  double search_radius_factor = 10.0;
  // Largest edge as a multiple of the local spacing (PCL's mu).
  double mu = 3.5;
  int max_nearest_neighbors = 100;
  double max_surface_angle_deg = 45;
  double min_angle_deg = 10;
  double max_angle_deg = 120;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct PoissonOptions {
  // Octree depth: 2^depth cells across the bounding cube. One more level
  // halves the smallest detail and multiplies time and memory by about 4.
  int depth = 8;
  double samples_per_node = 1.5;
  double point_weight = 4.0;  // interpolation weight (screened Poisson)
  // Vertices farther than this many median point spacings (or octree cells,
  // where those are coarser) from every
  // input point are removed with their faces: the surface Poisson invents
  // over holes and beyond the cloud's border. 0 = keep all.
  double trim_distance_factor = 4.0;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct AdvancingFrontOptions {
  // CGAL's parameters: candidate triangles whose circumradius exceeds this
  // multiple of the local edge length are refused (larger fills more gaps)
  // ...
  double radius_ratio_bound = 5.0;
  // ... and the largest dihedral angle, in radians over pi, between
  // neighbouring triangles (0.52 ~ 94 degrees).
  double beta = 0.52;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct DelaunayGraphCutOptions {
  // Points closer than this many median spacings (a grid cell) are one
  // vertex, whose rays they all give: fewer tetrahedra, the same surface.
  double min_distance_factor = 1.0;
  // Each ray ends this many median spacings behind its point: the
  // tetrahedron there is inside.
  double inside_depth_factor = 2.0;
  // Faces with an edge longer than this many median spacings are left out
  // (0: none): they span what no photograph showed well, the ragged border
  // of a ground, the gap between columns. Rendered tower: 0 gives 90.5 % of
  // the true surface within 5 GSD at an RMS of 8.5 GSD, 50 gives 82.7 % at
  // 2.6, 25 gives 74.8 % at 1.9, 15 gives 64.9 % at 1.7 (the cylinder: 68.3 %
  // at 2.0); temple-ring's silhouettes: IoU 0.56 with all, 0.82 with 25.
  double max_edge_factor = 25;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct ColmapPoissonOptions {
  // COLMAP's PoissonMeshing options. Its default depth 13 takes many
  // minutes on two cores; 9 matches bayon's own Poisson. The trim removes
  // vertices whose sampling-density value (about the octree depth of the
  // samples there, 6.7 to 7.7 on a well-sampled surface at depth 9) is
  // below it: COLMAP's default 10 at depth 13 corresponds to 6 at depth 9
  // (trimming nothing here would be 0).
  int depth = 9;
  double point_weight = 1.0;
  double trim = 6.0;
  // Where fused.ply, meshed-poisson.ply and COLMAP's log go; empty: a
  // temporary folder, removed afterwards.
  std::string work_path;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct MeshOptions {
  MeshMethod method = MeshMethod::kCylinder;
  CylinderMeshOptions cylinder;
  GreedyProjectionOptions greedy_projection;
  PoissonOptions poisson;
  AdvancingFrontOptions advancing_front;
  ColmapPoissonOptions colmap_poisson;
  DelaunayGraphCutOptions delaunay_graph_cut;
  // kDelaunayGraphCut: the projection centres of the images, and per point
  // the indices of those that saw it (from a fused.ply.vis, or the master
  // image of bayon dense's points).
  std::vector<Eigen::Vector3d> stations;
  std::vector<std::vector<int>> point_stations;
  NormalEstimationOptions normals;
  // Estimate normals where the method needs them and the cloud has none;
  // off: refuse such a cloud with InputError.
  bool estimate_normals = true;
  MeshCleanupOptions cleanup;
  int num_threads = -1;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct MeshReport {
  MeshMethod method = MeshMethod::kCylinder;
  size_t num_input_points = 0;
  size_t num_raw_faces = 0;  // from the method, before cleanup
  bool normals_estimated = false;
  CylinderMeshReport cylinder;   // kCylinder only
  size_t num_trimmed_faces = 0;  // kPoisson: removed far from the points
  MeshCleanupReport cleanup;
  MeshTopology topology;      // of the result
  double median_spacing = 0;  // of the input points
  double seconds_normals = 0;
  double seconds_method = 0;
  double seconds_cleanup = 0;
  // A few lines for the summary and the log.
  std::string Summary() const;
};

// The methods that close a surface in 3D (poisson, delaunay_graph_cut) are
// refused fewer than 100 points, which span no surface worth closing (a
// few hundred tetrahedra, or a Poisson blob, around a handful of points):
// InputError naming `method`, and the cylinder, which needs fewer. Never
// falls back to another method silently.
void CheckEnoughPointsToClose(const PointCloud& cloud,
                              const std::string& method);

// The methods one by one, on a checked cloud; `median_spacing` is its median
// nearest-neighbour distance (MedianPointSpacing). The meshes' vertices are
// the cloud's points (greedy projection, advancing front; unreferenced ones
// included) or new ones (Poisson). Greedy projection and Poisson need
// normals.
TriangleMesh GreedyProjectionMesh(const PointCloud& cloud,
                                  const GreedyProjectionOptions& options,
                                  double median_spacing);
TriangleMesh PoissonMesh(const PointCloud& cloud,
                         const PoissonOptions& options,
                         double median_spacing,
                         int num_threads,
                         size_t* num_trimmed_faces);
TriangleMesh AdvancingFrontMesh(const PointCloud& cloud,
                                const AdvancingFrontOptions& options);
// `point_stations`: per point the indices into `stations` of the projection
// centres it was seen from (one or more).
TriangleMesh DelaunayGraphCutMesh(
    const PointCloud& cloud,
    const std::vector<Eigen::Vector3d>& stations,
    const std::vector<std::vector<int>>& point_stations,
    const DelaunayGraphCutOptions& options,
    double median_spacing,
    int num_threads);
// Throws RunFailure when COLMAP fails (its log path in the message).
TriangleMesh ColmapPoissonMesh(const PointCloud& cloud,
                               const ColmapPoissonOptions& options,
                               int num_threads);

// delaunay_graph_cut's rays into `options`: the projection centres of
// `model`'s images (in the order of its images file, as a fused.ply.vis
// indexes them) and per point of `cloud` the images that saw it, from
// `visibility` (a fused.ply.vis; empty: none) or else the points' master_id
// (bayon dense). InputError naming `what` where the cloud has neither, or
// names an image the model lacks.
void SetGraphCutRays(const Scene& model,
                     const PointCloud& cloud,
                     const std::vector<std::vector<uint32_t>>& visibility,
                     const std::string& what,
                     MeshOptions* options);

// Checks the cloud (not empty, finite, at least 10 points, not all on one
// line: InputError naming `what`), meshes it, cleans the mesh and returns
// it. Throws RunFailure when the method produced no faces.
TriangleMesh MeshPointCloud(const PointCloud& cloud,
                            const MeshOptions& options,
                            MeshReport* report,
                            const std::string& what = "point cloud");

// The report `bayon mesh` writes beside the mesh: method, topology,
// cleanup and times.
nlohmann::ordered_json MeshReportJson(const MeshReport& r,
                                      const std::string& input_path,
                                      const std::string& output_path);

}  // namespace bayon
