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
#include <map>
#include <optional>
#include <sstream>

namespace bayon {
namespace {

// The flags of the nested options before they took their dotted names,
// still accepted (configs, scripts): old name -> name.
const std::map<std::string, std::string> kFlagsBefore = {
    {"axis_direction", "cylinder.axis_direction"},
    {"axis_point", "cylinder.axis_point"},
    {"cylinder_metric", "cylinder.metric"},
    {"cone_angle_deg", "cylinder.cone_angle_deg"},
    {"seam_band_deg", "cylinder.seam_band_deg"},
    {"max_edge_factor", "cylinder.max_edge_factor"},
    {"min_angle_deg", "cylinder.min_angle_deg"},
    {"search_radius_factor", "greedy_projection.search_radius_factor"},
    {"mu", "greedy_projection.mu"},
    {"depth", "poisson.depth"},
    {"samples_per_node", "poisson.samples_per_node"},
    {"point_weight", "poisson.point_weight"},
    {"trim_distance_factor", "poisson.trim_distance_factor"},
    {"radius_ratio_bound", "advancing_front.radius_ratio_bound"},
    {"beta", "advancing_front.beta"},
    {"colmap_depth", "colmap_poisson.depth"},
    {"colmap_trim", "colmap_poisson.trim"},
    {"colmap_work_path", "colmap_poisson.work_path"},
    {"min_distance_factor", "delaunay_graph_cut.min_distance_factor"},
    {"dgc_max_edge_factor", "delaunay_graph_cut.max_edge_factor"},
    {"inside_depth_factor", "delaunay_graph_cut.inside_depth_factor"},
    {"normal_neighbors", "normals.num_neighbors"},
    {"normal_orientation", "normals.orientation"},
    {"merge_distance_m", "cleanup.merge_distance_m"},
    {"min_component_faces", "cleanup.min_component_faces"},
    {"min_component_fraction", "cleanup.min_component_fraction"},
    {"max_hole_edges", "cleanup.max_hole_edges"}};

}  // namespace

int RunMesh(int argc, char** argv) {
  std::string input_path, output_path, report_path, log_path, sparse_path;
  std::string visibility_path;
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
  app.add_option("--sparse_path",
                 sparse_path,
                 "delaunay_graph_cut: the oriented model whose images saw "
                 "the points (their projection centres: the rays)");
  app.add_option("--visibility_path",
                 visibility_path,
                 "delaunay_graph_cut: which images saw each point, as "
                 "COLMAP's fused.ply.vis (default: --input_path + .vis "
                 "where it exists, else each point's master_id)");
  command.AddOptions(&options, kFlagsBefore);
  app.add_option(
      "--report_path", report_path, "Write the statistics as JSON here");
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/mesh.log)");
  if (!command.Parse(argc, argv)) return 0;
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
