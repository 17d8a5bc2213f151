// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/mesh/mesh_io.h"
#include "ext/mesh/meshing.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <sstream>

namespace bayon {

int RunMesh(int argc, char** argv) {
  std::string input_path, output_path, report_path, log_path, sparse_path;
  std::string visibility_path;
  std::string method_name = "cylinder", metric_name = "profile";
  std::string orientation_name = "mst";
  std::string axis_direction = "0,0,1", axis_point;
  bool overwrite = false;
  MeshOptions options;
  CommandLine command(
      "mesh",
      "Triangulate a dense point cloud: the paper's 2.5D Delaunay "
      "triangulation in cylinder coordinates (CGAL), PCL's greedy projection "
      "or Poisson reconstruction, or CGAL's advancing front; then cleanup on "
      "OpenMesh (duplicates, non-manifold and degenerate faces, small "
      "components, optional hole filling). Output format by extension: "
      ".ply, .obj, .off.");
  CLI::App& app = command.app();
  app.add_option("--input_path", input_path, "Point cloud (PLY)")->required();
  app.add_option("--output_path", output_path, "Mesh (.ply, .obj or .off)")
      ->required();
  app.add_option("--method",
                 method_name,
                 "cylinder, greedy_projection, poisson, advancing_front, "
                 "delaunay_graph_cut; colmap_poisson (stock COLMAP, for "
                 "comparison)")
      ->transform(CLI::IsMember({"cylinder",
                                 "greedy_projection",
                                 "poisson",
                                 "advancing_front",
                                 "colmap_poisson",
                                 "delaunay_graph_cut"}));
  app.add_option("--sparse_path",
                 sparse_path,
                 "delaunay_graph_cut: the oriented model whose images saw "
                 "the points (their projection centres: the rays)");
  app.add_option("--visibility_path",
                 visibility_path,
                 "delaunay_graph_cut: which images saw each point, as "
                 "COLMAP's fused.ply.vis (default: --input_path + .vis "
                 "where it exists, else each point's master_id)");
  app.add_option("--min_distance_factor",
                 options.delaunay_graph_cut.min_distance_factor,
                 "delaunay_graph_cut: points closer than this many spacings "
                 "are one vertex");
  app.add_option("--dgc_max_edge_factor",
                 options.delaunay_graph_cut.max_edge_factor,
                 "delaunay_graph_cut: leave out faces with an edge longer "
                 "than this many spacings (0 = none)");
  app.add_option("--inside_depth_factor",
                 options.delaunay_graph_cut.inside_depth_factor,
                 "delaunay_graph_cut: rays end this many spacings behind "
                 "their points, inside");
  app.add_option("--axis_direction",
                 axis_direction,
                 "cylinder: the object's vertical axis, x,y,z (datum z)");
  app.add_option("--axis_point",
                 axis_point,
                 "cylinder: a point on the axis, x,y,z (default centroid)");
  app.add_option("--cylinder_metric", metric_name, "profile or mean_radius")
      ->transform(CLI::IsMember({"profile", "mean_radius"}));
  app.add_option("--cone_angle_deg",
                 options.cylinder.cone_angle_deg,
                 "cylinder: tilt of the projection above the horizontal (0 = "
                 "the paper's cylinder; 45 unfolds flat ledge tops)");
  app.add_option("--seam_band_deg",
                 options.cylinder.seam_band_deg,
                 "cylinder: band copied across the +-180 degree seam");
  app.add_option("--max_edge_factor",
                 options.cylinder.max_edge_factor,
                 "cylinder: drop triangles with an edge longer than this "
                 "many local spacings");
  app.add_option("--min_angle_deg",
                 options.cylinder.min_angle_deg,
                 "cylinder: drop triangles with a smaller angle");
  app.add_option("--search_radius_factor",
                 options.greedy_projection.search_radius_factor,
                 "greedy_projection: search radius in point spacings");
  app.add_option("--mu",
                 options.greedy_projection.mu,
                 "greedy_projection: longest edge in local spacings");
  app.add_option("--depth", options.poisson.depth, "poisson: octree depth");
  app.add_option("--samples_per_node",
                 options.poisson.samples_per_node,
                 "poisson: points per octree leaf");
  app.add_option("--point_weight",
                 options.poisson.point_weight,
                 "poisson: interpolation weight");
  app.add_option("--trim_distance_factor",
                 options.poisson.trim_distance_factor,
                 "poisson: drop faces this many spacings from the points "
                 "(0 = keep)");
  app.add_option("--radius_ratio_bound",
                 options.advancing_front.radius_ratio_bound,
                 "advancing_front: CGAL's radius ratio bound");
  app.add_option("--beta",
                 options.advancing_front.beta,
                 "advancing_front: CGAL's beta (dihedral angle / pi)");
  app.add_option("--colmap_depth",
                 options.colmap_poisson.depth,
                 "colmap_poisson: PoissonMeshing.depth");
  app.add_option("--colmap_trim",
                 options.colmap_poisson.trim,
                 "colmap_poisson: PoissonMeshing.trim");
  app.add_option("--colmap_work_path",
                 options.colmap_poisson.work_path,
                 "colmap_poisson: keep fused.ply, COLMAP's mesh and log here");
  app.add_option("--estimate_normals",
                 options.estimate_normals,
                 "1: estimate missing normals (PCL); 0: refuse such clouds");
  app.add_option("--normal_neighbors",
                 options.normals.num_neighbors,
                 "Neighbours for normal estimation");
  app.add_option("--normal_orientation", orientation_name, "mst or outward")
      ->transform(CLI::IsMember({"mst", "outward"}));
  app.add_option("--merge_distance_m",
                 options.cleanup.merge_distance_m,
                 "Merge vertices closer than this (0 = identical only)");
  app.add_option("--min_component_faces",
                 options.cleanup.min_component_faces,
                 "Drop components with fewer faces ...");
  app.add_option("--min_component_fraction",
                 options.cleanup.min_component_fraction,
                 "... or fewer than this share of the largest");
  app.add_option("--max_hole_edges",
                 options.cleanup.max_hole_edges,
                 "Fill holes with at most this many boundary edges (0 = no)");
  app.add_option("--num_threads", options.num_threads, "-1 = all cores");
  app.add_option(
      "--report_path", report_path, "Write the statistics as JSON here");
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/mesh.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.method = ParseMeshMethod(method_name);
  options.cylinder.metric = ParseCylinderMetric(metric_name);
  options.normals.orientation = ParseNormalOrientation(orientation_name);
  options.cylinder.axis_direction =
      ParseVector(axis_direction, "--axis_direction");
  if (!axis_point.empty()) {
    options.cylinder.axis_point = ParseVector(axis_point, "--axis_point");
  }
  options.Check();
  CheckFileExists(input_path, "--input_path");
  // delaunay_graph_cut's rays: the model and, where there is one, the .vis.
  std::optional<Scene> model;
  std::vector<std::vector<uint32_t>> visibility;
  if (options.method == MeshMethod::kDelaunayGraphCut) {
    if (sparse_path.empty()) {
      ThrowInputError(
          "--method delaunay_graph_cut needs --sparse_path, the oriented "
          "model whose images saw the points");
    }
    model = ReadModel(sparse_path);
    if (visibility_path.empty() &&
        std::filesystem::exists(input_path + ".vis")) {
      visibility_path = input_path + ".vis";
    }
    if (!visibility_path.empty()) {
      visibility = ReadColmapVisibility(visibility_path);
    }
  }
  if (!IsMeshFormatSupported(output_path)) {
    ThrowInputError("--output_path ",
                    output_path,
                    ": unknown mesh format (use .ply, .obj or .off)");
  }
  CheckOutputPath(output_path, overwrite);
  if (!report_path.empty()) CheckOutputPath(report_path, overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(output_path), "mesh");
  }
  command.StartLog(log_path);

  const PointCloud cloud = ReadPointCloudPly(input_path);
  if (model) SetGraphCutRays(*model, cloud, visibility, input_path, &options);
  MeshReport report;
  const TriangleMesh mesh = MeshPointCloud(cloud, options, &report, input_path);
  std::filesystem::create_directories(
      std::filesystem::absolute(output_path).parent_path());
  WriteMesh(mesh, output_path);
  if (!report_path.empty()) {
    WriteFileAtomically(
        report_path,
        MeshReportJson(report, input_path, output_path).dump(2) + "\n");
  }
  command.PrintSummary(report.Summary() + "\n  -> " + output_path);
  return 0;
}

}  // namespace bayon
