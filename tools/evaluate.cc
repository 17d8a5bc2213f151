// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon evaluate`: every product of a run against the truth. The truth is a
// COLMAP model, or a synthetic workspace's gt/ folder (sparse/, surface.ply
// and its texture, heldout/, calibration.json, synth.json), from which the
// other truth files default. Dense clouds, meshes and textured models made
// from the evaluated sparse model are brought into the truth's datum by the
// same similarity as the cameras (with --align 1 and --input_path); without
// a sparse model they are taken to be in the truth's datum already.
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/calibration_eval.h"
#include "ext/eval/cloud_edit_eval.h"
#include "ext/eval/mesh_distance.h"
#include "ext/eval/relative_eval.h"
#include "ext/eval/silhouette_eval.h"
#include "ext/eval/sparse_eval.h"
#include "ext/eval/surface_eval.h"
#include "ext/eval/texture_eval.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

namespace bayon {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Json Statistics(const DistanceStatistics& s) {
  return {{"count", s.count},
          {"mean", s.mean},
          {"rms", s.rms},
          {"median", s.median},
          {"p95", s.p95},
          {"max", s.max}};
}

Json SparseToJson(const SparseEvaluation& e) {
  Json json;
  json["num_truth_images"] = e.num_truth_images;
  json["num_registered"] = e.num_registered;
  json["num_model_points"] = e.num_model_points;
  json["similarity"] = {{"scale", e.truth_from_model.scale},
                        {"qvec",
                         {e.truth_from_model.rotation.w(),
                          e.truth_from_model.rotation.x(),
                          e.truth_from_model.rotation.y(),
                          e.truth_from_model.rotation.z()}},
                        {"tvec",
                         {e.truth_from_model.translation.x(),
                          e.truth_from_model.translation.y(),
                          e.truth_from_model.translation.z()}}};
  json["mean_camera_distance"] = e.mean_camera_distance;
  json["center_rms"] = e.center_rms;
  json["center_max"] = e.center_max;
  json["center_rms_relative"] = e.center_rms_relative;
  json["center_max_relative"] = e.center_max_relative;
  json["rotation_rms_deg"] = e.rotation_rms_deg;
  json["rotation_max_deg"] = e.rotation_max_deg;
  json["images"] = Json::array();
  for (const ImageEvaluation& image : e.images) {
    json["images"].push_back(
        {{"name", image.name},
         {"registered", image.registered},
         {"center_error", image.center_error},
         {"rotation_error_deg", image.rotation_error_deg}});
  }
  return json;
}

Json RelativeToJson(const RelativeEvaluation& e) {
  Json json = {{"num_pairs", e.num_pairs},
               {"num_oriented", e.num_oriented},
               {"median_rotation_error_deg", e.median_rotation_error_deg},
               {"max_rotation_error_deg", e.max_rotation_error_deg},
               {"max_base_error_deg", e.max_base_error_deg},
               {"max_rotation_ratio", e.max_rotation_ratio},
               {"max_base_ratio", e.max_base_ratio},
               {"pairs", Json::array()}};
  for (const PairEvaluation& pair : e.pairs) {
    Json p = {{"image1", pair.name1},
              {"image2", pair.name2},
              {"oriented", pair.oriented}};
    if (pair.oriented) {
      p["num_matches"] = pair.num_matches;
      p["num_inliers"] = pair.num_inliers;
      p["sigma0_px"] = pair.sigma0_px;
      p["rotation_error_deg"] = pair.rotation_error_deg;
      p["std_rotation_deg"] = pair.std_rotation_deg;
      p["base_error_deg"] = pair.base_error_deg;
      p["std_base_deg"] = pair.std_base_deg;
    } else {
      p["reason"] = pair.reason;
    }
    json["pairs"].push_back(p);
  }
  return json;
}

Json CalibrationToJson(const CalibrationEvaluation& e) {
  Json json = {{"camera_id", e.camera_id},
               {"model", e.model},
               {"truth_model", e.truth_model},
               {"max_abs_error_over_sigma", e.max_abs_ratio}};
  json["parameters"] = Json::array();
  for (const ParameterError& p : e.parameters) {
    Json row = {{"name", p.name},
                {"estimate", p.estimate},
                {"truth", p.truth},
                {"error", p.error}};
    if (p.sigma > 0) {
      row["sigma"] = p.sigma;
      row["error_over_sigma"] = p.ratio;
    }
    json["parameters"].push_back(row);
  }
  return json;
}

Json TopologyToJson(const MeshTopology& t) {
  return {{"vertices", t.num_vertices},
          {"faces", t.num_faces},
          {"boundary_loops", t.num_boundary_loops},
          {"non_manifold_edges", t.num_non_manifold_edges},
          {"non_manifold_vertices", t.num_non_manifold_vertices},
          {"components", t.num_components},
          {"manifold", t.IsManifold()},
          {"closed", t.IsClosed()}};
}

Json SurfaceToJson(const SurfaceEvaluation& e) {
  Json json = {{"num_points", e.num_points},
               {"num_points_outside_region", e.num_points_outside_region},
               {"accuracy_m", Statistics(e.accuracy)},
               {"completeness_m", Statistics(e.completeness)},
               {"completeness_fraction", e.completeness_fraction},
               {"completeness_threshold_m", e.completeness_threshold_m},
               {"num_visible_true_samples", e.num_visible_samples}};
  Json by_orientation = Json::object();
  for (int o = 0; o < kNumSurfaceOrientations; ++o) {
    const OrientationCompleteness& c = e.completeness_by_orientation[o];
    by_orientation[SurfaceOrientationName(static_cast<SurfaceOrientation>(o))] =
        {{"num_visible_true_samples", c.num_samples},
         {"completeness_fraction", c.fraction}};
  }
  json["completeness_by_orientation"] = by_orientation;
  if (e.gsd_m > 0) {
    json["gsd_m"] = e.gsd_m;
    json["accuracy_gsd"] = {{"mean", e.accuracy.mean / e.gsd_m},
                            {"rms", e.accuracy.rms / e.gsd_m},
                            {"median", e.accuracy.median / e.gsd_m},
                            {"p95", e.accuracy.p95 / e.gsd_m}};
  }
  if (e.is_mesh) {
    json["topology"] = TopologyToJson(e.topology);
    json["truth_topology"] = TopologyToJson(e.truth_topology);
  }
  return json;
}

void PrintSparseTable(const std::string& label, const SparseEvaluation& e) {
  std::printf("%-28s %10s %12s %12s %12s %12s\n",
              "model",
              "registered",
              "centre RMS",
              "centre max",
              "centre RMS %",
              "rot RMS deg");
  std::printf("%-28s %6d/%-3d %12.6g %12.6g %12.5f %12.5f\n",
              label.c_str(),
              e.num_registered,
              e.num_truth_images,
              e.center_rms,
              e.center_max,
              100.0 * e.center_rms_relative,
              e.rotation_rms_deg);
}

void PrintTopology(const char* label, const MeshTopology& t) {
  std::printf(
      "  %-6s %zu faces, %zu boundary loops, %zu non-manifold edges, "
      "%zu non-manifold vertices: %s\n",
      label,
      t.num_faces,
      t.num_boundary_loops,
      t.num_non_manifold_edges,
      t.num_non_manifold_vertices,
      t.IsClosed() ? "closed"
                   : (t.IsManifold() ? "manifold, open" : "not manifold"));
}

// The truth files: explicit paths win, else the members of a gt/ folder.
struct TruthPaths {
  std::string model, surface, ground, texture, heldout, calibration, synth_json;
};

TruthPaths FindTruth(const std::string& ground_truth_path) {
  TruthPaths truth;
  const fs::path root(ground_truth_path);
  if (!fs::is_directory(root)) {
    ThrowInputError(ground_truth_path, ": the ground truth is not a folder");
  }
  auto member = [&](const char* name) {
    const fs::path path = root / name;
    return fs::exists(path) ? path.string() : std::string();
  };
  truth.model = fs::is_directory(root / "sparse") ? (root / "sparse").string()
                                                  : root.string();
  truth.surface = member("surface.ply");
  truth.ground = member("ground.ply");
  truth.heldout = member("heldout");
  truth.calibration = member("calibration.json");
  truth.synth_json = member("synth.json");
  return truth;
}

// The evaluation region and GSD that `bayon synth` records.
void ReadSynthDescription(const std::string& path,
                          Eigen::AlignedBox3d* region,
                          double* gsd_m) {
  std::ifstream in(path);
  Json json;
  try {
    json = Json::parse(in);
    if (json.contains("evaluation_region")) {
      const Json& r = json["evaluation_region"];
      *region = Eigen::AlignedBox3d(
          Eigen::Vector3d(r["min"][0], r["min"][1], r["min"][2]),
          Eigen::Vector3d(r["max"][0], r["max"][1], r["max"][2]));
    }
    if (json.contains("gsd_m")) *gsd_m = json["gsd_m"].get<double>();
  } catch (const Json::exception& e) {
    ThrowInputError(path, ": not a synth description (", e.what(), ")");
  }
}

Json TextureToJson(const TextureEvaluation& e) {
  Json json = {{"mean_psnr_db", e.mean_psnr_db},
               {"mean_ssim", e.mean_ssim},
               {"mean_normalized_psnr_db", e.mean_normalized_psnr_db},
               {"mean_normalized_ssim", e.mean_normalized_ssim}};
  json["views"] = Json::array();
  for (const ViewComparison& v : e.views) {
    json["views"].push_back({{"name", v.name},
                             {"pixels", v.raw.num_pixels},
                             {"psnr_db", v.raw.psnr_db},
                             {"ssim", v.raw.ssim},
                             {"normalized_psnr_db", v.normalized.psnr_db},
                             {"normalized_ssim", v.normalized.ssim}});
  }
  return json;
}

// The triangles of several meshes in one (positions and faces only).
TriangleMesh MergedGeometry(const std::vector<const TriangleMesh*>& meshes) {
  TriangleMesh merged;
  for (const TriangleMesh* mesh : meshes) {
    const int offset = static_cast<int>(merged.vertices.size());
    merged.vertices.positions.insert(merged.vertices.positions.end(),
                                     mesh->vertices.positions.begin(),
                                     mesh->vertices.positions.end());
    for (const Eigen::Vector3i& face : mesh->faces) {
      merged.faces.push_back(face + Eigen::Vector3i::Constant(offset));
    }
  }
  return merged;
}

void Transform(const Sim3d& b_from_a, PointCloud* cloud) {
  for (Eigen::Vector3d& p : cloud->positions) p = b_from_a * p;
  for (Eigen::Vector3f& n : cloud->normals) {
    n = (b_from_a.rotation.cast<float>() * n).normalized();
  }
}

// A textured model (PLY with texture coordinates and its atlas, or with
// vertex colours); `texture_path` defaults to the PLY's TextureFile.
TriangleMesh ReadTexturedModel(const std::string& path,
                               std::string texture_path,
                               cv::Mat* texture) {
  TriangleMesh model = ReadMeshPly(path);
  if (texture_path.empty()) texture_path = PlyTextureFile(path);
  if (model.HasTexcoords()) {
    if (texture_path.empty()) {
      ThrowInputError(path,
                      ": has texture coordinates but names no TextureFile "
                      "(give --texture_path)");
    }
    *texture = ReadImage(texture_path, ImageReadMode::kColor);
  } else if (!model.vertices.HasColors()) {
    ThrowInputError(path,
                    ": has neither texture coordinates nor vertex colours");
  }
  return model;
}

// Leave one out: the textured model from the stations of photographs it was
// not made from, against those photographs.
int EvaluateAgainstPhotographs(const std::string& textured_mesh_path,
                               const std::string& texture_path,
                               const std::string& input_path,
                               const std::string& image_path,
                               const std::vector<std::string>& image_names,
                               const TextureEvaluationOptions& options,
                               const std::string& output_path) {
  if (textured_mesh_path.empty() || input_path.empty() || image_names.empty()) {
    ThrowInputError(
        "--image_path needs the textured model (--textured_mesh_path), the "
        "model whose cameras took the photographs (--input_path) and the "
        "photographs to compare with (--image_names)");
  }
  CheckFileExists(textured_mesh_path, "--textured_mesh_path");
  const Scene scene = ReadOrientedModel(input_path, "");
  std::vector<std::pair<std::string, cv::Mat>> photographs;
  for (const std::string& name : image_names) {
    photographs.emplace_back(name, ReadImageColor8(image_path + "/" + name));
  }
  cv::Mat texture;
  const TriangleMesh model =
      ReadTexturedModel(textured_mesh_path, texture_path, &texture);
  const TextureEvaluation e = bayon::EvaluateAgainstPhotographs(
      model, texture, scene, photographs, options);
  std::printf("textured model against photographs:\n%s",
              TextureTable(e).c_str());
  Json report;
  report["textured_mesh_path"] = textured_mesh_path;
  report["input_path"] = input_path;
  report["image_path"] = image_path;
  report["photographs"] = TextureToJson(e);
  if (!output_path.empty()) {
    WriteFileAtomically(output_path, report.dump(2) + "\n");
  }
  return 0;
}

}  // namespace

int RunEvaluate(int argc, char** argv) {
  std::string input_path, ground_truth_path, output_path, label;
  std::string calibration_path, surface_path, cloud_path, mesh_path;
  std::string cloud_errors_path, edit_input_path, database_path;
  std::string textured_mesh_path, texture_path, heldout_path, render_path;
  bool align = true, adjacent_pairs = false;
  double gsd_m = 0, threshold_m = 0, threshold_gsd = 2;
  // synth_cloud's smallest blunder offset: an unflagged point as far off is
  // as much a blunder as an injected one.
  double off_surface_m = 0.01;
  int num_samples = 200000, num_threads = -1;
  std::string silhouette_image_path, image_path;
  std::vector<std::string> image_names;
  SilhouetteOptions silhouette;
  CommandLine command(
      "evaluate",
      "Compare results with the ground truth: a sparse model (registered "
      "images, camera centre and rotation errors after a 7-parameter "
      "similarity, calibration per parameter, 3D points against the true "
      "surface), a dense cloud and a mesh (accuracy, completeness over the "
      "visible true surface, topology) and a textured model (PSNR and SSIM "
      "of renders from held-out viewpoints), and a database's pair "
      "orientations (rotation and base direction errors). Prints tables, "
      "writes JSON.");
  CLI::App& app = command.app();
  app.add_option("--ground_truth_path",
                 ground_truth_path,
                 "True model folder, or a synthetic workspace's gt/ folder "
                 "(required but for silhouettes)");
  app.add_option("--input_path", input_path, "Sparse model to evaluate");
  app.add_option("--calibration_path",
                 calibration_path,
                 "calibration.json of the model (default: the one beside it)");
  app.add_option("--database_path",
                 database_path,
                 "Database whose pair orientations (`bayon relative`) to "
                 "evaluate");
  app.add_option("--adjacent_pairs",
                 adjacent_pairs,
                 "With --database_path, 1: only neighbouring images in the "
                 "database's order, the last with the first (a ring)");
  app.add_option("--cloud_path", cloud_path, "Dense cloud (PLY) to evaluate");
  app.add_option("--cloud_errors_path",
                 cloud_errors_path,
                 "Write the cloud, in the truth's frame, with each point's "
                 "distance to the true surface (PLY attribute distance_m)");
  app.add_option("--edit_input_path",
                 edit_input_path,
                 "The cloud before `bayon edit`, with blunders flagged "
                 "(`bayon synth_cloud`); --cloud_path is the edited one: "
                 "blunders and good points removed, and the RMS of the "
                 "kept points against the blunder-free input's");
  app.add_option("--off_surface_m",
                 off_surface_m,
                 "With --edit_input_path: unflagged points farther than this "
                 "from the truth (the input's own blunders) are also counted "
                 "apart");
  app.add_option("--mesh_path", mesh_path, "Mesh (PLY) to evaluate");
  app.add_option("--textured_mesh_path",
                 textured_mesh_path,
                 "Textured model (PLY with texcoord and a TextureFile "
                 "comment, or per-vertex colours)");
  app.add_option("--texture_path",
                 texture_path,
                 "Its texture atlas (default: the PLY's TextureFile)");
  app.add_option("--surface_path",
                 surface_path,
                 "True surface (default: <ground truth>/surface.ply)");
  app.add_option("--heldout_path",
                 heldout_path,
                 "Held-out viewpoints (default: <ground truth>/heldout)");
  app.add_option(
      "--gsd_m", gsd_m, "Ground sampling distance (default: from synth.json)");
  app.add_option("--completeness_threshold_m",
                 threshold_m,
                 "Distance within which the truth counts as reached; 0: "
                 "--completeness_threshold_gsd GSDs");
  app.add_option(
      "--completeness_threshold_gsd", threshold_gsd, "The same in GSDs");
  app.add_option("--num_samples",
                 num_samples,
                 "Samples of the true surface and of meshes");
  app.add_option("--render_path",
                 render_path,
                 "Write the renders of the texture evaluation here");
  app.add_option("--silhouette_image_path",
                 silhouette_image_path,
                 "Photographs of an object on a dark background: --mesh_path "
                 "carried into them through --input_path's cameras, its "
                 "silhouette's IoU with the object (no ground truth needed)");
  app.add_option("--silhouette_threshold",
                 silhouette.grey_threshold,
                 "Silhouettes: grey value above which a pixel is the object's");
  app.add_option("--silhouette_mask_path",
                 silhouette.mask_dir,
                 "Silhouettes: write the masks here (white both, red model "
                 "only, blue photograph only)");
  app.add_option("--image_path",
                 image_path,
                 "Photographs the textured model (--textured_mesh_path) was "
                 "not made from (leave one out): it is rendered through "
                 "their cameras (--input_path) and compared with them");
  app.add_option("--image_names", image_names, "Those photographs' names")
      ->delimiter(',');
  app.add_option("--output_path", output_path, "Write the report as JSON here");
  app.add_option(
      "--align", align, "1: fit a similarity first; 0: both share a datum");
  app.add_option("--label", label, "Name of the model in the tables");
  app.add_option("--num_threads", num_threads, "Threads (-1: all cores)");
  if (!command.Parse(argc, argv)) return 0;

  if (image_path.empty() && !image_names.empty()) {
    ThrowInputError(
        "--image_names needs --image_path, the folder of those photographs");
  }
  if (!image_path.empty()) {
    TextureEvaluationOptions options;
    options.num_threads = num_threads;
    options.render_dir = render_path;
    return EvaluateAgainstPhotographs(textured_mesh_path,
                                      texture_path,
                                      input_path,
                                      image_path,
                                      image_names,
                                      options,
                                      output_path);
  }
  if (!silhouette_image_path.empty()) {
    if (mesh_path.empty() || input_path.empty()) {
      ThrowInputError(
          "--silhouette_image_path needs the mesh (--mesh_path) and the "
          "model whose cameras see it (--input_path)");
    }
    silhouette.num_threads = num_threads;
    silhouette.Check();
    CheckFileExists(mesh_path, "--mesh_path");
    const Scene scene = ReadOrientedModel(input_path, "");
    const SilhouetteEvaluation evaluation = EvaluateSilhouettes(
        ReadMeshPly(mesh_path), scene, silhouette_image_path, silhouette);
    std::printf("%s", SilhouetteTable(evaluation).c_str());
    Json report;
    report["mesh_path"] = mesh_path;
    report["input_path"] = input_path;
    report["silhouettes"] = {{"threshold", silhouette.grey_threshold},
                             {"mean_iou", evaluation.mean_iou},
                             {"min_iou", evaluation.min_iou},
                             {"mean_best_iou", evaluation.mean_best_iou},
                             {"worst", evaluation.worst},
                             {"views", Json::array()}};
    for (const SilhouetteView& v : evaluation.views) {
      report["silhouettes"]["views"].push_back(
          {{"name", v.name},
           {"iou", v.iou},
           {"model_only", v.model_only},
           {"photograph_only", v.photograph_only},
           {"best_iou", v.best_iou}});
    }
    if (!output_path.empty()) {
      WriteFileAtomically(output_path, report.dump(2) + "\n");
    }
    return 0;
  }
  if (ground_truth_path.empty()) {
    ThrowInputError("--ground_truth_path is required");
  }
  if (input_path.empty() && cloud_path.empty() && mesh_path.empty() &&
      textured_mesh_path.empty() && database_path.empty()) {
    ThrowInputError(
        "nothing to evaluate: give --input_path, --cloud_path, "
        "--mesh_path, --textured_mesh_path or --database_path");
  }
  if (!database_path.empty()) {
    CheckFileExists(database_path, "--database_path");
  }
  if (!edit_input_path.empty()) {
    if (cloud_path.empty()) {
      ThrowInputError(
          "--edit_input_path needs the edited cloud as "
          "--cloud_path");
    }
    CheckFileExists(edit_input_path, "--edit_input_path");
  }
  if (!(off_surface_m >= 0)) {
    ThrowInputError("--off_surface_m must be >= 0 (got ", off_surface_m, ")");
  }
  const TruthPaths found = FindTruth(ground_truth_path);
  if (surface_path.empty()) surface_path = found.surface;
  if (heldout_path.empty()) heldout_path = found.heldout;
  Eigen::AlignedBox3d region;
  double synth_gsd_m = 0;
  if (!found.synth_json.empty()) {
    ReadSynthDescription(found.synth_json, &region, &synth_gsd_m);
  }
  if (gsd_m <= 0) gsd_m = synth_gsd_m;
  const Scene truth = ReadModel(found.model);
  const std::string name =
      !label.empty() ? label
                     : (!input_path.empty() ? input_path : database_path);

  Json report;
  report["ground_truth_path"] = ground_truth_path;
  if (!database_path.empty()) {
    report["database_path"] = database_path;
    Database database(database_path, Database::Mode::kReadOnly);
    RelativeEvaluationOptions options;
    options.adjacent_only = adjacent_pairs;
    const RelativeEvaluation relative =
        EvaluateRelativeOrientations(&database, truth, options);
    std::printf("%s", RelativeEvaluationTable(name, relative).c_str());
    report["relative"] = RelativeToJson(relative);
  }
  Sim3d truth_from_model;  // identity unless a sparse model is aligned
  std::optional<Scene> model;
  if (!input_path.empty()) {
    report["input_path"] = input_path;
    model = ReadModel(input_path);
    SparseEvaluationOptions options;
    options.align = align;
    const SparseEvaluation evaluation = EvaluateSparse(*model, truth, options);
    truth_from_model = evaluation.truth_from_model;
    PrintSparseTable(name, evaluation);
    report["sparse"] = SparseToJson(evaluation);

    if (calibration_path.empty() &&
        fs::exists(fs::path(input_path) / "calibration.json")) {
      calibration_path = (fs::path(input_path) / "calibration.json").string();
    }
    if (!calibration_path.empty() && !found.calibration.empty()) {
      report["calibration"] = Json::array();
      for (const CalibrationEvaluation& e :
           EvaluateCalibrations(ReadCalibrationJson(calibration_path),
                                ReadCalibrationJson(found.calibration))) {
        std::printf("\n%s", CalibrationTable(e).c_str());
        report["calibration"].push_back(CalibrationToJson(e));
      }
    }
  }

  const bool surfaces = !cloud_path.empty() || !mesh_path.empty() ||
                        (!input_path.empty() && !surface_path.empty());
  if (surfaces) {
    if (surface_path.empty()) {
      ThrowInputError(ground_truth_path,
                      ": no surface.ply to judge clouds and meshes against "
                      "(give --surface_path)");
    }
    const TriangleMesh surface = ReadMeshPly(surface_path);
    // Accuracy against everything the photographs show: a point on the
    // ground around the object is judged against the ground, not against
    // the object's nearest face. Completeness stays the object's.
    const bool with_ground =
        !found.ground.empty() && surface_path == found.surface;
    const TriangleMesh ground =
        with_ground ? ReadMeshPly(found.ground) : TriangleMesh();
    const MeshDistance truth_distance(
        with_ground ? MergedGeometry({&surface, &ground}) : surface);
    if (with_ground) report["accuracy_includes_ground"] = found.ground;
    SurfaceEvaluationOptions options;
    options.gsd_m = gsd_m;
    options.region = region;
    options.num_mesh_samples = num_samples;
    options.num_threads = num_threads;
    options.completeness_threshold_m =
        threshold_m > 0 ? threshold_m : threshold_gsd * gsd_m;

    if (model) {
      // The tie points against the true surface, in the truth's datum.
      std::vector<double> distances;
      for (const auto& [id, point] : model->points3D) {
        const Eigen::Vector3d p = truth_from_model * point.xyz;
        if (region.isEmpty() || region.contains(p)) {
          distances.push_back(truth_distance.Closest(p).distance);
        }
      }
      if (!distances.empty()) {
        const DistanceStatistics s =
            ComputeDistanceStatistics(std::move(distances));
        std::printf(
            "\n3D points to the true surface: %zu points, mean %.5f, "
            "RMS %.5f, median %.5f, p95 %.5f, max %.5f\n",
            s.count,
            s.mean,
            s.rms,
            s.median,
            s.p95,
            s.max);
        report["points3D_to_surface_m"] = Statistics(s);
      }
    }

    if (!cloud_path.empty() || !mesh_path.empty()) {
      if (!(options.completeness_threshold_m > 0)) {
        ThrowInputError(
            "no ground sampling distance known: give "
            "--completeness_threshold_m or --gsd_m");
      }
      VisibleSurfaceOptions visible_options;
      visible_options.num_samples = num_samples;
      visible_options.region = region;
      visible_options.num_threads = num_threads;
      const VisibleSurface visible =
          FindVisibleSurface(surface, truth, visible_options);
      std::printf(
          "\ntrue surface: %.3f m2, %zu of %zu samples visible in 2 "
          "or more images\n%s\n",
          visible.area,
          visible.samples.size(),
          visible.num_candidates,
          SurfaceTableHeader().c_str());
      if (!cloud_path.empty()) {
        PointCloud cloud = ReadPointCloudPly(cloud_path);
        Transform(truth_from_model, &cloud);
        const SurfaceEvaluation e =
            EvaluateCloud(cloud, truth_distance, visible, options);
        std::printf("%s\n",
                    SurfaceTableRow(
                        "cloud " + fs::path(cloud_path).filename().string(), e)
                        .c_str());
        report["cloud"] = SurfaceToJson(e);
        report["cloud"]["path"] = cloud_path;
        if (!edit_input_path.empty()) {
          PointCloud before = ReadPointCloudPly(edit_input_path);
          Transform(truth_from_model, &before);
          const CloudEditEvaluation edit = EvaluateCloudEdit(
              before, cloud, truth_distance, off_surface_m, num_threads);
          std::printf(
              "\n%s\n%s\n",
              CloudEditEvaluation::TableHeader().c_str(),
              edit.Table(fs::path(cloud_path).filename().string()).c_str());
          report["edit"] = {
              {"input_path", edit_input_path},
              {"num_blunders", edit.num_blunders_before},
              {"blunders_removed", edit.BlundersRemovedFraction()},
              {"num_good", edit.num_good_before},
              {"good_removed", edit.GoodRemovedFraction()},
              {"off_surface_m", edit.off_surface_m},
              {"num_off_surface", edit.num_off_surface_before},
              {"off_surface_removed", edit.OffSurfaceRemovedFraction()},
              {"on_surface_removed", edit.OnSurfaceRemovedFraction()},
              {"rms_good_before_m", edit.good_before.rms},
              {"rms_kept_m", edit.kept_after.rms},
              {"rms_good_kept_m", edit.good_after.rms}};
        }
        if (!cloud_errors_path.empty()) {
          // Every point with its distance to the truth, in the truth's
          // frame: where the errors are, to look at.
          PointAttribute& distance =
              cloud.AddAttribute("distance_m", PlyScalarType::kFloat);
          distance.values =
              truth_distance.Distances(cloud.positions, num_threads);
          PlyWriteOptions write_options;
          write_options.comment = "bayon evaluate: distance_m to the truth";
          WritePointCloudPly(cloud, cloud_errors_path, write_options);
        }
      }
      if (!mesh_path.empty()) {
        TriangleMesh mesh = ReadMeshPly(mesh_path);
        Transform(truth_from_model, &mesh.vertices);
        const SurfaceEvaluation e =
            EvaluateMesh(mesh, surface, truth_distance, visible, options);
        std::printf("%s\n",
                    SurfaceTableRow(
                        "mesh " + fs::path(mesh_path).filename().string(), e)
                        .c_str());
        PrintTopology("mesh", e.topology);
        PrintTopology("truth", e.truth_topology);
        report["mesh"] = SurfaceToJson(e);
        report["mesh"]["path"] = mesh_path;
      }
    }
  }

  if (!textured_mesh_path.empty()) {
    if (heldout_path.empty() || surface_path.empty()) {
      ThrowInputError(ground_truth_path,
                      ": the texture evaluation needs held-out viewpoints and "
                      "a textured true surface (give --heldout_path and "
                      "--surface_path)");
    }
    cv::Mat model_texture;
    TriangleMesh model =
        ReadTexturedModel(textured_mesh_path, texture_path, &model_texture);
    Transform(truth_from_model, &model.vertices);
    const TriangleMesh surface = ReadMeshPly(surface_path);
    const std::string truth_texture_path = PlyTextureFile(surface_path);
    const cv::Mat truth_texture =
        truth_texture_path.empty()
            ? cv::Mat()
            : ReadImage(truth_texture_path, ImageReadMode::kColor);
    TextureEvaluationOptions options;
    options.num_threads = num_threads;
    options.render_dir = render_path;
    const TextureEvaluation e = EvaluateTexturedModel(model,
                                                      model_texture,
                                                      surface,
                                                      truth_texture,
                                                      ReadModel(heldout_path),
                                                      options);
    std::printf("\ntextured model from held-out viewpoints:\n%s",
                TextureTable(e).c_str());
    Json texture = {{"path", textured_mesh_path}};
    texture.update(TextureToJson(e));
    report["texture"] = texture;
  }

  if (!output_path.empty()) {
    WriteFileAtomically(output_path, report.dump(2) + "\n");
  }
  return 0;
}

}  // namespace bayon
