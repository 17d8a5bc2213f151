// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/evaluation.h"

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
#include "ext/eval/sparse_eval.h"
#include "ext/eval/surface_eval.h"
#include "ext/eval/texture_eval.h"
#include "ext/image/image_io.h"

#include <filesystem>
#include <fstream>
#include <optional>

namespace bayon {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// The truth's files, explicit paths winning over the members of a gt/
// folder, and the evaluation region and GSD that `bayon synth` records.
struct Truth {
  std::string model_path;
  std::string surface_path;
  // The ground around the object, where the surface is the folder's own:
  // accuracy is judged against everything the photographs show.
  std::string ground_path;
  std::string heldout_path;
  std::string calibration_path;
  Eigen::AlignedBox3d region;  // empty: everywhere
  double gsd_m = 0;
};

void ReadSynthDescription(const std::string& path, Truth* truth) {
  std::ifstream in(path);
  try {
    const Json json = Json::parse(in);
    if (json.contains("evaluation_region")) {
      const Json& r = json["evaluation_region"];
      truth->region = Eigen::AlignedBox3d(
          Eigen::Vector3d(r["min"][0], r["min"][1], r["min"][2]),
          Eigen::Vector3d(r["max"][0], r["max"][1], r["max"][2]));
    }
    if (json.contains("gsd_m")) truth->gsd_m = json["gsd_m"].get<double>();
  } catch (const Json::exception& e) {
    ThrowInputError(path, ": not a synth description (", e.what(), ")");
  }
}

Truth FindTruth(const EvaluationOptions& options) {
  const fs::path root(options.ground_truth_path);
  if (!fs::is_directory(root)) {
    ThrowInputError(options.ground_truth_path,
                    ": the ground truth is not a folder");
  }
  auto member = [&](const char* name) {
    const fs::path path = root / name;
    return fs::exists(path) ? path.string() : std::string();
  };
  Truth truth;
  truth.model_path = fs::is_directory(root / "sparse")
                         ? (root / "sparse").string()
                         : root.string();
  const std::string folder_surface = member("surface.ply");
  truth.surface_path =
      !options.surface_path.empty() ? options.surface_path : folder_surface;
  if (truth.surface_path == folder_surface) {
    truth.ground_path = member("ground.ply");
  }
  truth.heldout_path =
      !options.heldout_path.empty() ? options.heldout_path : member("heldout");
  truth.calibration_path = member("calibration.json");
  const std::string synth_json = member("synth.json");
  if (!synth_json.empty()) ReadSynthDescription(synth_json, &truth);
  if (options.gsd_m > 0) truth.gsd_m = options.gsd_m;
  return truth;
}

double CompletenessThreshold(const EvaluationOptions& options,
                             const Truth& truth) {
  return options.completeness_threshold_m > 0
             ? options.completeness_threshold_m
             : options.completeness_threshold_gsd * truth.gsd_m;
}

// What the truth must hold for the products asked about, checked before any
// of them is evaluated.
void CheckTruthCovers(const EvaluationOptions& options, const Truth& truth) {
  const bool dense = !options.cloud_path.empty() || !options.mesh_path.empty();
  if (dense && truth.surface_path.empty()) {
    ThrowInputError(options.ground_truth_path,
                    ": no surface.ply to judge clouds and meshes against "
                    "(give surface_path)");
  }
  if (dense && !(CompletenessThreshold(options, truth) > 0)) {
    ThrowInputError(
        "no ground sampling distance known: give "
        "completeness_threshold_m or gsd_m");
  }
  if (!options.textured_mesh_path.empty() &&
      (truth.heldout_path.empty() || truth.surface_path.empty())) {
    ThrowInputError(options.ground_truth_path,
                    ": the texture evaluation needs held-out viewpoints and "
                    "a textured true surface (give heldout_path and "
                    "surface_path)");
  }
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
                      "(give texture_path)");
    }
    *texture = ReadImage(texture_path, ImageReadMode::kColor);
  } else if (!model.vertices.HasColors()) {
    ThrowInputError(path,
                    ": has neither texture coordinates nor vertex colours");
  }
  return model;
}

TextureEvaluationOptions TextureOptions(const EvaluationOptions& options) {
  TextureEvaluationOptions texture;
  texture.num_threads = options.num_threads;
  texture.render_dir = options.render_path;
  return texture;
}

// Leave one out: the textured model from the stations of photographs it was
// not made from, against those photographs.
Json EvaluateLeaveOneOut(const EvaluationOptions& options, std::FILE* tables) {
  const Scene scene = ReadOrientedModel(options.input_path, "");
  std::vector<std::pair<std::string, cv::Mat>> photographs;
  for (const std::string& name : options.image_names) {
    photographs.emplace_back(name,
                             ReadImageColor8(options.image_path + "/" + name));
  }
  cv::Mat texture;
  const TriangleMesh model = ReadTexturedModel(
      options.textured_mesh_path, options.texture_path, &texture);
  const TextureEvaluation e = EvaluateAgainstPhotographs(
      model, texture, scene, photographs, TextureOptions(options));
  std::fprintf(tables,
               "textured model against photographs:\n%s",
               TextureTable(e).c_str());
  Json report;
  report["textured_mesh_path"] = options.textured_mesh_path;
  report["input_path"] = options.input_path;
  report["image_path"] = options.image_path;
  report["photographs"] = TextureEvaluationJson(e);
  return report;
}

SilhouetteOptions SilhouetteOptionsOf(const EvaluationOptions& options) {
  SilhouetteOptions silhouette = options.silhouette;
  silhouette.num_threads = options.num_threads;
  return silhouette;
}

// The mesh carried into photographs of the object through the model's
// cameras: its silhouettes against the object's.
Json EvaluateMeshSilhouettes(const EvaluationOptions& options,
                             std::FILE* tables) {
  const SilhouetteOptions silhouette = SilhouetteOptionsOf(options);
  const Scene scene = ReadOrientedModel(options.input_path, "");
  const SilhouetteEvaluation evaluation =
      EvaluateSilhouettes(ReadMeshPly(options.mesh_path),
                          scene,
                          options.silhouette_image_path,
                          silhouette);
  std::fprintf(tables, "%s", SilhouetteTable(evaluation).c_str());
  Json report;
  report["mesh_path"] = options.mesh_path;
  report["input_path"] = options.input_path;
  report["silhouettes"] = SilhouetteEvaluationJson(evaluation, silhouette);
  return report;
}

// The database's pair orientations against the truth's.
Json EvaluatePairs(const EvaluationOptions& options,
                   const Scene& truth,
                   const std::string& name,
                   std::FILE* tables) {
  Database database(options.database_path, Database::Mode::kReadOnly);
  RelativeEvaluationOptions relative_options;
  relative_options.adjacent_only = options.adjacent_pairs;
  const RelativeEvaluation relative =
      EvaluateRelativeOrientations(&database, truth, relative_options);
  std::fprintf(tables, "%s", RelativeEvaluationTable(name, relative).c_str());
  return RelativeEvaluationJson(relative);
}

// The sparse model's cameras against the truth's, and its calibration where
// both have one; returns the similarity from the model into the truth.
Sim3d EvaluateSparseModel(const EvaluationOptions& options,
                          const Truth& truth,
                          const Scene& truth_model,
                          const Scene& model,
                          const std::string& name,
                          std::FILE* tables,
                          Json* report) {
  SparseEvaluationOptions sparse_options;
  sparse_options.align = options.align;
  const SparseEvaluation evaluation =
      EvaluateSparse(model, truth_model, sparse_options);
  std::fprintf(tables, "%s", SparseEvaluationTable(name, evaluation).c_str());
  (*report)["sparse"] = SparseEvaluationJson(evaluation);

  std::string calibration_path = options.calibration_path;
  const fs::path beside = fs::path(options.input_path) / "calibration.json";
  if (calibration_path.empty() && fs::exists(beside)) {
    calibration_path = beside.string();
  }
  if (!calibration_path.empty() && !truth.calibration_path.empty()) {
    (*report)["calibration"] = Json::array();
    for (const CalibrationEvaluation& e :
         EvaluateCalibrations(ReadCalibrationJson(calibration_path),
                              ReadCalibrationJson(truth.calibration_path))) {
      std::fprintf(tables, "\n%s", CalibrationTable(e).c_str());
      (*report)["calibration"].push_back(CalibrationEvaluationJson(e));
    }
  }
  return evaluation.truth_from_model;
}

// The model's tie points against the true surface, in the truth's datum;
// null where none lies in the evaluation region.
Json EvaluateTiePoints(const Scene& model,
                       const Sim3d& truth_from_model,
                       const Truth& truth,
                       const MeshDistance& truth_distance,
                       std::FILE* tables) {
  std::vector<double> distances;
  for (const auto& [id, point] : model.points3D) {
    const Eigen::Vector3d p = truth_from_model * point.xyz;
    if (truth.region.isEmpty() || truth.region.contains(p)) {
      distances.push_back(truth_distance.Closest(p).distance);
    }
  }
  if (distances.empty()) return nullptr;
  const DistanceStatistics s = ComputeDistanceStatistics(std::move(distances));
  std::fprintf(tables,
               "\n3D points to the true surface: %zu points, mean %.5f, "
               "RMS %.5f, median %.5f, p95 %.5f, max %.5f\n",
               s.count,
               s.mean,
               s.rms,
               s.median,
               s.p95,
               s.max);
  return DistanceStatisticsJson(s);
}

// What `bayon edit` removed of the flagged blunders and of the good points.
Json EvaluateEdit(const EvaluationOptions& options,
                  const PointCloud& edited,
                  const Sim3d& truth_from_model,
                  const MeshDistance& truth_distance,
                  std::FILE* tables) {
  PointCloud before = ReadPointCloudPly(options.edit_input_path);
  Transform(truth_from_model, &before);
  const CloudEditEvaluation edit = EvaluateCloudEdit(before,
                                                     edited,
                                                     truth_distance,
                                                     options.off_surface_m,
                                                     options.num_threads);
  std::fprintf(
      tables,
      "\n%s\n%s\n",
      CloudEditEvaluation::TableHeader().c_str(),
      edit.Table(fs::path(options.cloud_path).filename().string()).c_str());
  Json json = {{"input_path", options.edit_input_path}};
  json.update(CloudEditEvaluationJson(edit));
  return json;
}

// Every point with its distance to the truth, in the truth's frame: where
// the errors are, to look at.
void WriteCloudErrors(PointCloud cloud,
                      const MeshDistance& truth_distance,
                      const EvaluationOptions& options) {
  PointAttribute& distance =
      cloud.AddAttribute("distance_m", PlyScalarType::kFloat);
  distance.values =
      truth_distance.Distances(cloud.positions, options.num_threads);
  PlyWriteOptions write_options;
  write_options.comment = "bayon evaluate: distance_m to the truth";
  WritePointCloudPly(cloud, options.cloud_errors_path, write_options);
}

// The true surface a dense product is judged against, and the part of it
// that two or more true cameras see.
struct TrueSurface {
  const TriangleMesh& surface;
  const MeshDistance& distance;
  const VisibleSurface& visible;
  SurfaceEvaluationOptions options;
};

void EvaluateDenseCloud(const EvaluationOptions& options,
                        const TrueSurface& truth,
                        const Sim3d& truth_from_model,
                        std::FILE* tables,
                        Json* report) {
  PointCloud cloud = ReadPointCloudPly(options.cloud_path);
  Transform(truth_from_model, &cloud);
  const SurfaceEvaluation e =
      EvaluateCloud(cloud, truth.distance, truth.visible, truth.options);
  const std::string file = fs::path(options.cloud_path).filename().string();
  std::fprintf(tables, "%s\n", SurfaceTableRow("cloud " + file, e).c_str());
  (*report)["cloud"] = SurfaceEvaluationJson(e);
  (*report)["cloud"]["path"] = options.cloud_path;
  if (!options.edit_input_path.empty()) {
    (*report)["edit"] =
        EvaluateEdit(options, cloud, truth_from_model, truth.distance, tables);
  }
  if (!options.cloud_errors_path.empty()) {
    WriteCloudErrors(std::move(cloud), truth.distance, options);
  }
}

void EvaluateDenseMesh(const EvaluationOptions& options,
                       const TrueSurface& truth,
                       const Sim3d& truth_from_model,
                       std::FILE* tables,
                       Json* report) {
  TriangleMesh mesh = ReadMeshPly(options.mesh_path);
  Transform(truth_from_model, &mesh.vertices);
  const SurfaceEvaluation e = EvaluateMesh(
      mesh, truth.surface, truth.distance, truth.visible, truth.options);
  const std::string file = fs::path(options.mesh_path).filename().string();
  std::fprintf(tables, "%s\n", SurfaceTableRow("mesh " + file, e).c_str());
  std::fprintf(tables, "%s", MeshTopologyLine("mesh", e.topology).c_str());
  std::fprintf(
      tables, "%s", MeshTopologyLine("truth", e.truth_topology).c_str());
  (*report)["mesh"] = SurfaceEvaluationJson(e);
  (*report)["mesh"]["path"] = options.mesh_path;
}

// The tie points, the dense cloud and the mesh against the true surface.
void EvaluateSurfaces(const EvaluationOptions& options,
                      const Truth& truth,
                      const Scene& truth_model,
                      const Sim3d& truth_from_model,
                      const Scene* model,
                      std::FILE* tables,
                      Json* report) {
  const TriangleMesh surface = ReadMeshPly(truth.surface_path);
  // Accuracy against everything the photographs show: a point on the
  // ground around the object is judged against the ground, not against the
  // object's nearest face. Completeness stays the object's.
  const bool with_ground = !truth.ground_path.empty();
  const TriangleMesh ground =
      with_ground ? ReadMeshPly(truth.ground_path) : TriangleMesh();
  const MeshDistance truth_distance(
      with_ground ? MergedGeometry({&surface, &ground}) : surface);
  if (with_ground) (*report)["accuracy_includes_ground"] = truth.ground_path;

  if (model != nullptr) {
    const Json tie_points = EvaluateTiePoints(
        *model, truth_from_model, truth, truth_distance, tables);
    if (!tie_points.is_null()) {
      (*report)["points3D_to_surface_m"] = tie_points;
    }
  }
  if (options.cloud_path.empty() && options.mesh_path.empty()) return;

  VisibleSurfaceOptions visible_options;
  visible_options.num_samples = options.num_samples;
  visible_options.region = truth.region;
  visible_options.num_threads = options.num_threads;
  const VisibleSurface visible =
      FindVisibleSurface(surface, truth_model, visible_options);
  std::fprintf(tables,
               "\ntrue surface: %.3f m2, %zu of %zu samples visible in 2 "
               "or more images\n%s\n",
               visible.area,
               visible.samples.size(),
               visible.num_candidates,
               SurfaceTableHeader().c_str());
  TrueSurface true_surface{surface, truth_distance, visible, {}};
  true_surface.options.gsd_m = truth.gsd_m;
  true_surface.options.region = truth.region;
  true_surface.options.num_mesh_samples = options.num_samples;
  true_surface.options.num_threads = options.num_threads;
  true_surface.options.completeness_threshold_m =
      CompletenessThreshold(options, truth);
  if (!options.cloud_path.empty()) {
    EvaluateDenseCloud(options, true_surface, truth_from_model, tables, report);
  }
  if (!options.mesh_path.empty()) {
    EvaluateDenseMesh(options, true_surface, truth_from_model, tables, report);
  }
}

// The textured model rendered from held-out viewpoints against the textured
// true surface.
Json EvaluateTexture(const EvaluationOptions& options,
                     const Truth& truth,
                     const Sim3d& truth_from_model,
                     std::FILE* tables) {
  cv::Mat model_texture;
  TriangleMesh model = ReadTexturedModel(
      options.textured_mesh_path, options.texture_path, &model_texture);
  Transform(truth_from_model, &model.vertices);
  const TriangleMesh surface = ReadMeshPly(truth.surface_path);
  const std::string truth_texture_path = PlyTextureFile(truth.surface_path);
  const cv::Mat truth_texture =
      truth_texture_path.empty()
          ? cv::Mat()
          : ReadImage(truth_texture_path, ImageReadMode::kColor);
  const TextureEvaluation e =
      EvaluateTexturedModel(model,
                            model_texture,
                            surface,
                            truth_texture,
                            ReadModel(truth.heldout_path),
                            TextureOptions(options));
  std::fprintf(tables,
               "\ntextured model from held-out viewpoints:\n%s",
               TextureTable(e).c_str());
  Json texture = {{"path", options.textured_mesh_path}};
  texture.update(TextureEvaluationJson(e));
  return texture;
}

// Every product named in the options against the truth, in the order a run
// makes them.
Json EvaluateAgainstTruth(const EvaluationOptions& options, std::FILE* tables) {
  const Truth truth = FindTruth(options);
  CheckTruthCovers(options, truth);
  const Scene truth_model = ReadModel(truth.model_path);
  const std::string name =
      !options.label.empty()
          ? options.label
          : (!options.input_path.empty() ? options.input_path
                                         : options.database_path);
  Json report;
  report["ground_truth_path"] = options.ground_truth_path;
  if (!options.database_path.empty()) {
    report["database_path"] = options.database_path;
    report["relative"] = EvaluatePairs(options, truth_model, name, tables);
  }
  Sim3d truth_from_model;  // identity unless a sparse model is aligned
  std::optional<Scene> model;
  if (!options.input_path.empty()) {
    report["input_path"] = options.input_path;
    model = ReadModel(options.input_path);
    truth_from_model = EvaluateSparseModel(
        options, truth, truth_model, *model, name, tables, &report);
  }
  const bool surfaces = !options.cloud_path.empty() ||
                        !options.mesh_path.empty() ||
                        (model && !truth.surface_path.empty());
  if (surfaces) {
    EvaluateSurfaces(options,
                     truth,
                     truth_model,
                     truth_from_model,
                     model ? &*model : nullptr,
                     tables,
                     &report);
  }
  if (!options.textured_mesh_path.empty()) {
    report["texture"] =
        EvaluateTexture(options, truth, truth_from_model, tables);
  }
  return report;
}

}  // namespace

void EvaluationOptions::Register(OptionRegistry* r) {
  r->Add("ground_truth_path",
         &ground_truth_path,
         "True model folder, or a synthetic workspace's gt/ folder "
         "(required but for silhouettes)");
  r->Add("input_path", &input_path, "Sparse model to evaluate");
  r->Add("calibration_path",
         &calibration_path,
         "calibration.json of the model (default: the one beside it)");
  r->Add("database_path",
         &database_path,
         "Database whose pair orientations (`bayon relative`) to "
         "evaluate");
  r->Add("adjacent_pairs",
         &adjacent_pairs,
         "With --database_path, 1: only neighbouring images in the "
         "database's order, the last with the first (a ring)");
  r->Add("cloud_path", &cloud_path, "Dense cloud (PLY) to evaluate");
  r->Add("cloud_errors_path",
         &cloud_errors_path,
         "Write the cloud, in the truth's frame, with each point's "
         "distance to the true surface (PLY attribute distance_m)");
  r->Add("edit_input_path",
         &edit_input_path,
         "The cloud before `bayon edit`, with blunders flagged "
         "(`bayon synth_cloud`); --cloud_path is the edited one: "
         "blunders and good points removed, and the RMS of the "
         "kept points against the blunder-free input's");
  r->Add("off_surface_m",
         &off_surface_m,
         "With --edit_input_path: unflagged points farther than this "
         "from the truth (the input's own blunders) are also counted "
         "apart");
  r->Add("mesh_path", &mesh_path, "Mesh (PLY) to evaluate");
  r->Add("textured_mesh_path",
         &textured_mesh_path,
         "Textured model (PLY with texcoord and a TextureFile "
         "comment, or per-vertex colours)");
  r->Add("texture_path",
         &texture_path,
         "Its texture atlas (default: the PLY's TextureFile)");
  r->Add("surface_path",
         &surface_path,
         "True surface (default: <ground truth>/surface.ply)");
  r->Add("heldout_path",
         &heldout_path,
         "Held-out viewpoints (default: <ground truth>/heldout)");
  r->Add(
      "gsd_m", &gsd_m, "Ground sampling distance (default: from synth.json)");
  r->Add("completeness_threshold_m",
         &completeness_threshold_m,
         "Distance within which the truth counts as reached; 0: "
         "completeness_threshold_gsd GSDs");
  r->Add("completeness_threshold_gsd",
         &completeness_threshold_gsd,
         "The same in GSDs");
  r->Add(
      "num_samples", &num_samples, "Samples of the true surface and of meshes");
  r->Add("render_path",
         &render_path,
         "Write the renders of the texture evaluation here");
  r->Add("silhouette_image_path",
         &silhouette_image_path,
         "Photographs of an object on a dark background: --mesh_path "
         "carried into them through --input_path's cameras, its "
         "silhouette's IoU with the object (no ground truth needed)");
  r->Add("silhouette_threshold",
         &silhouette.grey_threshold,
         "Silhouettes: grey value above which a pixel is the object's");
  r->Add("silhouette_mask_path",
         &silhouette.mask_dir,
         "Silhouettes: write the masks here (white both, red model "
         "only, blue photograph only)");
  r->Add("image_path",
         &image_path,
         "Photographs the textured model (--textured_mesh_path) was "
         "not made from (leave one out): it is rendered through "
         "their cameras (--input_path) and compared with them");
  r->Add("image_names", &image_names, "Those photographs' names");
  r->Add("align", &align, "1: fit a similarity first; 0: both share a datum");
  r->Add("label", &label, "Name of the model in the tables");
  r->Add("num_threads", &num_threads, "Threads (-1: all cores)");
}

void EvaluationOptions::Check() const {
  if (image_path.empty() && !image_names.empty()) {
    ThrowInputError(
        "image_names needs image_path, the folder of those photographs");
  }
  if (!image_path.empty()) {
    if (textured_mesh_path.empty() || input_path.empty() ||
        image_names.empty()) {
      ThrowInputError(
          "image_path needs the textured model (textured_mesh_path), the "
          "model whose cameras took the photographs (input_path) and the "
          "photographs to compare with (image_names)");
    }
    CheckFileExists(textured_mesh_path, "textured_mesh_path");
    return;
  }
  if (!silhouette_image_path.empty()) {
    if (mesh_path.empty() || input_path.empty()) {
      ThrowInputError(
          "silhouette_image_path needs the mesh (mesh_path) and the "
          "model whose cameras see it (input_path)");
    }
    SilhouetteOptionsOf(*this).Check();
    CheckFileExists(mesh_path, "mesh_path");
    return;
  }
  if (ground_truth_path.empty()) {
    ThrowInputError("ground_truth_path is required");
  }
  if (input_path.empty() && cloud_path.empty() && mesh_path.empty() &&
      textured_mesh_path.empty() && database_path.empty()) {
    ThrowInputError(
        "nothing to evaluate: give input_path, cloud_path, "
        "mesh_path, textured_mesh_path or database_path");
  }
  if (!database_path.empty()) {
    CheckFileExists(database_path, "database_path");
  }
  if (!edit_input_path.empty()) {
    if (cloud_path.empty()) {
      ThrowInputError("edit_input_path needs the edited cloud as cloud_path");
    }
    CheckFileExists(edit_input_path, "edit_input_path");
  }
  if (!(off_surface_m >= 0)) {
    ThrowInputError("off_surface_m must be >= 0 (got ", off_surface_m, ")");
  }
}

Json RunEvaluation(const EvaluationOptions& options, std::FILE* tables) {
  options.Check();
  if (!options.image_path.empty()) return EvaluateLeaveOneOut(options, tables);
  if (!options.silhouette_image_path.empty()) {
    return EvaluateMeshSilhouettes(options, tables);
  }
  return EvaluateAgainstTruth(options, tables);
}

}  // namespace bayon
