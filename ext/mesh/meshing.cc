// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/meshing.h"

#include "ext/cloud/cloud_edit.h"
#include "ext/core/errors.h"
#include "ext/core/progress.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <iomanip>
#include <map>
#include <sstream>

namespace bayon {

std::string MeshMethodName(MeshMethod method) {
  switch (method) {
    case MeshMethod::kCylinder:
      return "cylinder";
    case MeshMethod::kGreedyProjection:
      return "greedy_projection";
    case MeshMethod::kPoisson:
      return "poisson";
    case MeshMethod::kAdvancingFront:
      return "advancing_front";
    case MeshMethod::kColmapPoisson:
      return "colmap_poisson";
    case MeshMethod::kDelaunayGraphCut:
      return "delaunay_graph_cut";
  }
  return "?";
}

void GreedyProjectionOptions::Register(OptionRegistry* r) {
  r->Add("search_radius_factor",
         &search_radius_factor,
         "Search radius in point spacings");
  r->Add("mu", &mu, "Longest edge in local spacings");
  r->Add("max_nearest_neighbors",
         &max_nearest_neighbors,
         "Neighbours searched per point");
  r->Add("max_surface_angle_deg",
         &max_surface_angle_deg,
         "Neighbours whose normals differ more are left out");
  r->Add("min_angle_deg", &min_angle_deg, "Smallest triangle angle");
  r->Add("max_angle_deg", &max_angle_deg, "Largest triangle angle");
}

void GreedyProjectionOptions::Check() const {
  CheckOption(search_radius_factor > 1,
              "search_radius_factor",
              "> 1",
              search_radius_factor);
  CheckOption(mu > 1, "mu", "> 1", mu);
  CheckOption(max_nearest_neighbors >= 10,
              "max_nearest_neighbors",
              ">= 10",
              max_nearest_neighbors);
  CheckOption(min_angle_deg > 0 && min_angle_deg < 60,
              "min_angle_deg",
              "in (0, 60)",
              min_angle_deg);
  CheckOption(max_angle_deg > 60 && max_angle_deg < 180,
              "max_angle_deg",
              "in (60, 180)",
              max_angle_deg);
  CheckOption(max_surface_angle_deg > 0 && max_surface_angle_deg < 180,
              "max_surface_angle_deg",
              "in (0, 180)",
              max_surface_angle_deg);
}

void CheckEnoughPointsToClose(const PointCloud& cloud,
                              const std::string& method) {
  constexpr size_t kMinPoints = 100;
  if (cloud.size() < kMinPoints) {
    ThrowInputError(method,
                    ": ",
                    cloud.size(),
                    " points are too sparse to close a surface (",
                    kMinPoints,
                    " or more; the cylinder, method cylinder, needs fewer)");
  }
}

void PoissonOptions::Register(OptionRegistry* r) {
  r->Add("depth", &depth, "Octree depth");
  r->Add("samples_per_node", &samples_per_node, "Points per octree leaf");
  r->Add("point_weight", &point_weight, "Interpolation weight");
  r->Add("trim_distance_factor",
         &trim_distance_factor,
         "Drop faces this many spacings from the points (0 = keep)");
}

void PoissonOptions::Check() const {
  CheckOption(depth >= 4 && depth <= 14, "depth", "in [4, 14]", depth);
  CheckOption(
      samples_per_node >= 1, "samples_per_node", ">= 1", samples_per_node);
  CheckOption(point_weight >= 0, "point_weight", ">= 0", point_weight);
  CheckOption(trim_distance_factor >= 0,
              "trim_distance_factor",
              ">= 0 (0 = no trimming)",
              trim_distance_factor);
}

void AdvancingFrontOptions::Register(OptionRegistry* r) {
  r->Add(
      "radius_ratio_bound", &radius_ratio_bound, "CGAL's radius ratio bound");
  r->Add("beta", &beta, "CGAL's beta (dihedral angle / pi)");
}

void AdvancingFrontOptions::Check() const {
  CheckOption(
      radius_ratio_bound > 0, "radius_ratio_bound", "> 0", radius_ratio_bound);
  CheckOption(beta > 0 && beta < 1, "beta", "in (0, 1)", beta);
}

void ColmapPoissonOptions::Register(OptionRegistry* r) {
  r->Add("depth", &depth, "PoissonMeshing.depth");
  r->Add("point_weight", &point_weight, "PoissonMeshing.point_weight");
  r->Add("trim", &trim, "PoissonMeshing.trim");
  r->Add("work_path", &work_path, "Keep fused.ply, COLMAP's mesh and log here");
}

void ColmapPoissonOptions::Check() const {
  CheckOption(depth >= 4 && depth <= 14, "depth", "in [4, 14]", depth);
  CheckOption(point_weight >= 0, "point_weight", ">= 0", point_weight);
  CheckOption(trim >= 0, "trim", ">= 0", trim);
}

void MeshOptions::Register(OptionRegistry* r) {
  r->AddChoice("method",
               &method,
               ChoicesOf<MeshMethod>(MeshMethodName,
                                     {MeshMethod::kCylinder,
                                      MeshMethod::kGreedyProjection,
                                      MeshMethod::kPoisson,
                                      MeshMethod::kAdvancingFront,
                                      MeshMethod::kColmapPoisson,
                                      MeshMethod::kDelaunayGraphCut}),
               "cylinder, greedy_projection, poisson, advancing_front, "
               "delaunay_graph_cut; colmap_poisson (stock COLMAP, for "
               "comparison)");
  r->AddNested("cylinder", &cylinder);
  r->AddNested("greedy_projection", &greedy_projection);
  r->AddNested("poisson", &poisson);
  r->AddNested("advancing_front", &advancing_front);
  r->AddNested("colmap_poisson", &colmap_poisson);
  r->AddNested("delaunay_graph_cut", &delaunay_graph_cut);
  r->Add("estimate_normals",
         &estimate_normals,
         "1: estimate missing normals (PCL); 0: refuse such clouds");
  r->AddNested("normals", &normals);
  r->AddNested("cleanup", &cleanup);
  r->Add("num_threads", &num_threads, "-1 = all cores");
}

void MeshOptions::Check() const {
  CheckNested("colmap_poisson", colmap_poisson);
  CheckNested("cylinder", cylinder);
  CheckNested("greedy_projection", greedy_projection);
  CheckNested("poisson", poisson);
  CheckNested("advancing_front", advancing_front);
  CheckNested("delaunay_graph_cut", delaunay_graph_cut);
  CheckNested("normals", normals);
  CheckNested("cleanup", cleanup);
}

std::string MeshReport::Summary() const {
  std::ostringstream out;
  out << std::setprecision(4);
  out << MeshMethodName(method) << ": " << num_input_points << " points -> "
      << topology.num_vertices << " vertices, " << topology.num_faces
      << " faces; " << topology.num_boundary_loops << " boundary loops, "
      << topology.num_non_manifold_edges << " non-manifold edges, "
      << topology.num_non_manifold_vertices << " non-manifold vertices, "
      << topology.num_components << " components, Euler characteristic "
      << topology.euler_characteristic << "; edges mean " << topology.mean_edge
      << " m, longest " << topology.longest_edge << " m (point spacing "
      << median_spacing << " m)";
  if (normals_estimated) out << "\n  normals estimated with PCL";
  if (method == MeshMethod::kCylinder) {
    out << "\n  cylinder: axis through (" << cylinder.axis_point.transpose()
        << ") along (" << cylinder.axis_direction.transpose()
        << "), mean radius " << cylinder.mean_radius << " m; "
        << cylinder.num_faces_once << " plane triangles, "
        << cylinder.num_seam_faces << " across the seam, "
        << cylinder.num_seam_unsafe << " with circumcircles beyond the seam "
        << "band, " << cylinder.num_long_removed << " too long and "
        << cylinder.num_degenerate_removed << " degenerate removed";
    if (cylinder.num_on_axis > 0) {
      out << ", " << cylinder.num_on_axis << " points on the axis skipped";
    }
  }
  if (method == MeshMethod::kPoisson) {
    out << "\n  poisson: " << num_trimmed_faces
        << " faces trimmed far from the points";
  }
  out << "\n  cleanup: " << num_raw_faces << " raw faces; "
      << cleanup.num_merged_vertices << " vertices merged, "
      << cleanup.num_repeated_vertex_faces + cleanup.num_duplicate_faces
      << " repeated faces, " << cleanup.num_flipped_faces << " flipped, "
      << cleanup.num_non_manifold_faces << " non-manifold, "
      << cleanup.num_degenerate_faces << " degenerate, "
      << cleanup.num_small_component_faces << " in "
      << cleanup.num_small_components << " small components removed, "
      << cleanup.num_holes_filled << " holes filled (" << cleanup.num_fill_faces
      << " faces)";
  out << std::fixed << std::setprecision(2) << "\n  time: normals "
      << seconds_normals << " s, " << MeshMethodName(method) << " "
      << seconds_method << " s, cleanup " << seconds_cleanup << " s";
  return out.str();
}

void SetGraphCutRays(const Scene& model,
                     const PointCloud& cloud,
                     const std::vector<std::vector<uint32_t>>& visibility,
                     const std::string& what,
                     MeshOptions* options) {
  options->stations.clear();
  options->point_stations.clear();
  std::map<image_t, int> index_of;
  for (const auto& [image_id, image] : model.images) {
    index_of[image_id] = static_cast<int>(options->stations.size());
    options->stations.push_back(image.cam_from_world.Center());
  }
  if (!visibility.empty()) {
    for (const std::vector<uint32_t>& seen : visibility) {
      options->point_stations.emplace_back(seen.begin(), seen.end());
    }
    return;
  }
  const PointAttribute* master = cloud.FindAttribute("master_id");
  if (master == nullptr) {
    ThrowInputError(what,
                    ": delaunay_graph_cut needs the images that saw each "
                    "point: a .vis beside it (--visibility_path) or the "
                    "master_id attribute of bayon dense's clouds");
  }
  for (double id : master->values) {
    const auto it = index_of.find(static_cast<image_t>(id));
    if (it == index_of.end()) {
      ThrowInputError(what,
                      ": a point's master_id ",
                      static_cast<int64_t>(id),
                      " is no image of the oriented model");
    }
    options->point_stations.push_back({it->second});
  }
}

TriangleMesh MeshPointCloud(const PointCloud& input,
                            const MeshOptions& options,
                            MeshReport* report,
                            const std::string& what) {
  options.Check();
  CheckCloudSpansSurface(input, 10, what);
  *report = MeshReport();
  report->method = options.method;
  report->num_input_points = input.size();
  report->median_spacing = MedianPointSpacing(input);

  const bool needs_normals = options.method == MeshMethod::kGreedyProjection ||
                             options.method == MeshMethod::kPoisson ||
                             options.method == MeshMethod::kColmapPoisson;
  PointCloud cloud = input;
  if (needs_normals && !cloud.HasNormals()) {
    if (!options.estimate_normals) {
      ThrowInputError(what,
                      ": ",
                      MeshMethodName(options.method),
                      " needs point normals and the cloud has none (let "
                      "bayon estimate them with --estimate_normals 1)");
    }
    const Timer timer;
    NormalEstimationOptions normal_options = options.normals;
    normal_options.num_threads = options.num_threads;
    EstimateNormals(normal_options, &cloud);
    report->normals_estimated = true;
    report->seconds_normals = timer.Seconds();
  }

  const Timer method_timer;
  TriangleMesh raw;
  switch (options.method) {
    case MeshMethod::kCylinder:
      raw = CylinderDelaunayMesh(
          cloud, options.cylinder, options.num_threads, &report->cylinder);
      break;
    case MeshMethod::kGreedyProjection:
      raw = GreedyProjectionMesh(
          cloud, options.greedy_projection, report->median_spacing);
      break;
    case MeshMethod::kPoisson:
      raw = PoissonMesh(cloud,
                        options.poisson,
                        report->median_spacing,
                        options.num_threads,
                        &report->num_trimmed_faces);
      break;
    case MeshMethod::kAdvancingFront:
      raw = AdvancingFrontMesh(cloud, options.advancing_front);
      break;
    case MeshMethod::kColmapPoisson:
      raw =
          ColmapPoissonMesh(cloud, options.colmap_poisson, options.num_threads);
      break;
    case MeshMethod::kDelaunayGraphCut: {
      raw = DelaunayGraphCutMesh(cloud,
                                 options.stations,
                                 options.point_stations,
                                 options.delaunay_graph_cut,
                                 report->median_spacing,
                                 options.num_threads);
      break;
    }
  }
  report->seconds_method = method_timer.Seconds();
  report->num_raw_faces = raw.NumFaces();
  if (raw.faces.empty()) {
    throw RunFailure(StrCat(
        what, ": ", MeshMethodName(options.method), " produced no triangles"));
  }

  const Timer cleanup_timer;
  TriangleMesh mesh = CleanupMesh(raw, options.cleanup, &report->cleanup);
  report->seconds_cleanup = cleanup_timer.Seconds();
  if (mesh.faces.empty()) {
    throw RunFailure(StrCat(what, ": no triangles survived the cleanup"));
  }
  report->topology = ComputeMeshTopology(mesh);
  return mesh;
}

nlohmann::ordered_json MeshReportJson(const MeshReport& r,
                                      const std::string& input_path,
                                      const std::string& output_path) {
  const MeshTopology& t = r.topology;
  nlohmann::ordered_json json;
  json["input_path"] = input_path;
  json["output_path"] = output_path;
  json["method"] = MeshMethodName(r.method);
  json["num_input_points"] = r.num_input_points;
  json["median_spacing"] = r.median_spacing;
  json["normals_estimated"] = r.normals_estimated;
  json["num_raw_faces"] = r.num_raw_faces;
  json["num_vertices"] = t.num_vertices;
  json["num_faces"] = t.num_faces;
  json["num_edges"] = t.num_edges;
  json["num_boundary_edges"] = t.num_boundary_edges;
  json["num_boundary_loops"] = t.num_boundary_loops;
  json["num_non_manifold_edges"] = t.num_non_manifold_edges;
  json["num_non_manifold_vertices"] = t.num_non_manifold_vertices;
  json["num_components"] = t.num_components;
  json["euler_characteristic"] = t.euler_characteristic;
  json["mean_edge"] = t.mean_edge;
  json["longest_edge"] = t.longest_edge;
  json["area"] = t.area;
  if (r.method == MeshMethod::kCylinder) {
    const CylinderMeshReport& c = r.cylinder;
    json["cylinder"] = {
        {"axis_point", {c.axis_point.x(), c.axis_point.y(), c.axis_point.z()}},
        {"axis_direction",
         {c.axis_direction.x(), c.axis_direction.y(), c.axis_direction.z()}},
        {"mean_radius", c.mean_radius},
        {"num_on_axis", c.num_on_axis},
        {"num_duplicates", c.num_duplicates},
        {"num_seam_copies", c.num_seam_copies},
        {"num_plane_faces", c.num_faces_once},
        {"num_seam_faces", c.num_seam_faces},
        {"num_long_removed", c.num_long_removed},
        {"num_degenerate_removed", c.num_degenerate_removed}};
  }
  if (r.method == MeshMethod::kPoisson) {
    json["num_trimmed_faces"] = r.num_trimmed_faces;
  }
  const MeshCleanupReport& c = r.cleanup;
  json["cleanup"] = {{"merged_vertices", c.num_merged_vertices},
                     {"repeated_vertex_faces", c.num_repeated_vertex_faces},
                     {"duplicate_faces", c.num_duplicate_faces},
                     {"flipped_faces", c.num_flipped_faces},
                     {"non_manifold_faces", c.num_non_manifold_faces},
                     {"degenerate_faces", c.num_degenerate_faces},
                     {"small_components", c.num_small_components},
                     {"small_component_faces", c.num_small_component_faces},
                     {"holes_filled", c.num_holes_filled},
                     {"fill_faces", c.num_fill_faces},
                     {"split_vertices", c.num_split_vertices}};
  json["seconds"] = {{"normals", r.seconds_normals},
                     {"method", r.seconds_method},
                     {"cleanup", r.seconds_cleanup}};
  return json;
}

}  // namespace bayon
