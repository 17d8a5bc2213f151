// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/colmap_comparison.h"

#include "ext/colmap/calibration_json.h"
#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/model_io.h"
#include "ext/core/camera.h"
#include "ext/core/camera_models.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/model_statistics.h"
#include "ext/eval/sparse_eval.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace bayon {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

Json ParseJsonFile(const std::string& path) {
  try {
    return Json::parse(ReadFileToString(path));
  } catch (const Json::exception& e) {
    ThrowInputError(path, ": not valid JSON (", e.what(), ")");
  }
}

// The stages of `bayon pipeline` that make the sparse model compared here
// (W/sparse/adjusted), in order; the later ones (dense, mesh, ...) have no
// counterpart in COLMAP's column.
constexpr const char* kSparseStages[] = {"import",
                                         "interior",
                                         "features",
                                         "match",
                                         "relative",
                                         "disparity",
                                         "tiepoints",
                                         "strip",
                                         "adjust"};

std::optional<double> StampSeconds(const fs::path& workspace,
                                   const std::string& stage) {
  const fs::path path = workspace / "pipeline" / (stage + ".done");
  if (!fs::is_regular_file(path)) return std::nullopt;
  try {
    const Json stamp = Json::parse(ReadFileToString(path.string()));
    if (stamp.contains("seconds") && stamp["seconds"].is_number()) {
      return stamp["seconds"].get<double>();
    }
  } catch (const Json::exception& e) {
    LOG(WARNING) << path.string() << ": unreadable (" << e.what() << ")";
  }
  return std::nullopt;
}

// The adjustment's own sigma0 from adjustment.json beside the model, or
// null: "sigma0_px" (the a posteriori sigma0, in the reference pixels of
// the a priori weights) with the a priori value and their ratio.
struct AdjustmentSigma0 {
  Json sigma0 = nullptr;
  Json apriori_px = nullptr;
  Json variance_factor = nullptr;
};

AdjustmentSigma0 ReadAdjustmentSigma0(const fs::path& model_path) {
  AdjustmentSigma0 result;
  const fs::path path = model_path / "adjustment.json";
  if (!fs::exists(path)) return result;
  const Json json = ParseJsonFile(path.string());
  if (!json.contains("statistics")) return result;
  const Json& s = json["statistics"];
  auto number = [&](const char* key) -> Json {
    return s.contains(key) && s[key].is_number() ? s[key] : Json(nullptr);
  };
  result.sigma0 = number("sigma0_px");
  result.apriori_px = number("sigma0_apriori_px");
  result.variance_factor = number("variance_factor");
  return result;
}

bool HasModelFiles(const fs::path& folder) {
  for (const char* ext : {".bin", ".txt"}) {
    bool all = true;
    for (const char* name : {"cameras", "images", "points3D"}) {
      all = all && fs::is_regular_file(folder / (std::string(name) + ext));
    }
    if (all) return true;
  }
  return false;
}

// colmap.json of a finished earlier run whose model is still there, or
// nullopt (no run, an unfinished one, or one without a model).
std::optional<Json> CompleteColmapRecord(const fs::path& colmap_dir) {
  const fs::path path = colmap_dir / "colmap.json";
  if (!fs::exists(path)) return std::nullopt;
  Json record;
  try {
    record = Json::parse(ReadFileToString(path.string()));
    const Json& stages = record.at("stage_seconds");
    if (!stages.contains("feature_extractor") || !stages.contains("mapper") ||
        !(stages.contains("exhaustive_matcher") ||
          stages.contains("sequential_matcher")) ||
        !record.at("model_path").is_string()) {
      return std::nullopt;
    }
  } catch (const Json::exception& e) {
    LOG(WARNING) << path.string() << ": unreadable (" << e.what()
                 << "); running COLMAP again";
    return std::nullopt;
  }
  if (!HasModelFiles(colmap_dir / record["model_path"].get<std::string>())) {
    return std::nullopt;
  }
  return record;
}

// Removes what an earlier run left in W/colmap, colmap.json first so that
// an interrupted cleanup never looks finished.
void ClearColmapFolder(const fs::path& colmap_dir) {
  for (const char* name : {"colmap.json",
                           "comparison.json",
                           "comparison.txt",
                           "database.db",
                           "database.db-journal",
                           "database.db-wal",
                           "database.db-shm",
                           "feature_extractor.log",
                           "exhaustive_matcher.log",
                           "sequential_matcher.log",
                           "mapper.log",
                           "sparse"}) {
    fs::remove_all(colmap_dir / name);
  }
}

// Runs one COLMAP stage with its output in W/colmap/<stage>.log, the wall
// clock time appended there.
ColmapResult RunStage(const ColmapCall& call, const fs::path& colmap_dir) {
  ColmapRunOptions run_options;
  run_options.log_path = (colmap_dir / (call.command + ".log")).string();
  const ColmapResult result = RunColmap(call, run_options);
  std::ofstream(run_options.log_path, std::ios::app)
      << "# bayon compare_colmap: wall clock " << result.seconds
      << " s, exit code " << result.exit_code << "\n";
  LOG(INFO) << "colmap " << call.command << ": " << result.seconds << " s";
  return result;
}

Json OptionsJson(const CompareColmapOptions& options) {
  return {{"image_path", options.image_path},
          {"matching", options.matching},
          {"num_neighbors", options.num_neighbors},
          {"camera_model", options.camera_model},
          {"camera_params", options.camera_params},
          {"max_image_size", options.max_image_size},
          {"num_threads", options.num_threads}};
}

// The options that change COLMAP's result (not the thread count; the
// number of neighbours only for sequential matching).
Json ResultOptions(Json options) {
  options.erase("num_threads");
  if (options.value("matching", "") != "sequential") {
    options.erase("num_neighbors");
  }
  return options;
}

ColmapRun RunColmapPipeline(const CompareColmapOptions& options,
                            const fs::path& colmap_dir) {
  const std::string& image_path = options.image_path;
  ClearColmapFolder(colmap_dir);
  fs::create_directories(colmap_dir / "sparse");
  const std::string database = (colmap_dir / "database.db").string();
  const std::string threads = std::to_string(options.num_threads);

  std::vector<ColmapCall> calls(3);
  calls[0].command = "feature_extractor";
  calls[0].options = {{"--database_path", database},
                      {"--image_path", image_path},
                      {"--ImageReader.single_camera", "1"},
                      {"--ImageReader.camera_model", options.camera_model},
                      {"--SiftExtraction.use_gpu", "0"},
                      {"--SiftExtraction.max_image_size",
                       std::to_string(options.max_image_size)},
                      {"--SiftExtraction.num_threads", threads}};
  if (options.calibrated()) {
    calls[0].options.emplace_back("--ImageReader.camera_params",
                                  options.camera_params);
  }
  calls[0].expected_outputs = {database};
  calls[1].command = options.MatcherCommand();
  calls[1].options = {{"--database_path", database},
                      {"--SiftMatching.use_gpu", "0"},
                      {"--SiftMatching.num_threads", threads}};
  if (options.matching == "sequential") {
    calls[1].options.emplace_back("--SequentialMatching.overlap",
                                  std::to_string(options.num_neighbors));
  }
  calls[2].command = "mapper";
  calls[2].options = {{"--database_path", database},
                      {"--image_path", image_path},
                      {"--output_path", (colmap_dir / "sparse").string()},
                      {"--Mapper.num_threads", threads}};
  if (options.calibrated()) {
    // What bayon was given is known, not estimated, on COLMAP's side too.
    for (const char* refine : {"--Mapper.ba_refine_focal_length",
                               "--Mapper.ba_refine_principal_point",
                               "--Mapper.ba_refine_extra_params"}) {
      calls[2].options.emplace_back(refine, "0");
    }
  }

  ColmapRun run;
  run.record["colmap_version"] = ColmapVersion();
  run.record["options"] = OptionsJson(options);
  run.record["stages"] = Json::array();
  run.record["stage_seconds"] = Json::object();
  double total = 0;
  for (const ColmapCall& call : calls) {
    std::printf("colmap %s ...\n", call.command.c_str());
    std::fflush(stdout);
    const ColmapResult result = RunStage(call, colmap_dir);
    // Without features or matches there is nothing to compare. The mapper
    // exits 1 when it registers nothing ("failed to create sparse model"):
    // a valid outcome, compared as COLMAP's empty model.
    if (!result.success && call.command != "mapper") {
      throw RunFailure(StrCat(result.message, " (log: ", result.log_path, ")"));
    }
    if (!result.success) {
      LOG(WARNING) << result.message;
      run.mapper_message = result.message;
    }
    run.record["stages"].push_back({{"name", call.command},
                                    {"seconds", result.seconds},
                                    {"exit_code", result.exit_code},
                                    {"command", result.command_line},
                                    {"log", call.command + ".log"}});
    run.record["stage_seconds"][call.command] = result.seconds;
    total += result.seconds;
  }
  run.record["total_seconds"] = total;
  // Relative to W/colmap, as colmap.json records it.
  const std::string largest = LargestModel((colmap_dir / "sparse").string());
  if (!largest.empty()) {
    run.model_path = fs::relative(largest, colmap_dir).string();
  }
  run.record["model_path"] =
      run.model_path.empty() ? Json(nullptr) : Json(run.model_path);
  if (run.model_path.empty() && run.mapper_message.empty()) {
    run.mapper_message = "colmap mapper wrote no model";
  }
  // Written last: its presence marks the run as finished.
  WriteFileAtomically((colmap_dir / "colmap.json").string(),
                      run.record.dump(2) + "\n");
  return run;
}

// ---------------------------------------------------------------------------
// The figures.

// The figures of one model (an empty scene where there is none);
// `registered` counts its images that are in the image folder. Figures
// without data (no observations, no redundancy) are null.
Json ModelJson(const std::string& model_path,
               const Scene& model,
               const std::set<std::string>& folder_images) {
  const ModelStatistics s = ComputeModelStatistics(model);
  int registered = 0;
  for (const auto& [image_id, image] : model.images) {
    registered += folder_images.count(image.name) > 0;
  }
  auto or_null = [&](double value) {
    return s.num_observations > 0 ? Json(value) : Json(nullptr);
  };
  Json json;
  json["model_path"] = model_path.empty() ? Json(nullptr) : Json(model_path);
  json["registered"] = registered;
  json["points3D"] = s.num_points3D;
  json["observations"] = s.num_observations;
  json["mean_track_length"] = or_null(s.mean_track_length);
  json["mean_reprojection_error_px"] = or_null(s.mean_reprojection_error_px);
  json["rms_reprojection_error_px"] = or_null(s.rms_reprojection_error_px);
  json["sigma0_px"] = s.redundancy > 0 ? Json(s.sigma0_px) : Json(nullptr);
  json["adjustment_sigma0"] = nullptr;
  json["stage_seconds"] = Json::object();
  json["total_seconds"] = nullptr;
  json["median_reprojection_error_px"] =
      or_null(s.median_reprojection_error_px);
  json["max_reprojection_error_px"] = or_null(s.max_reprojection_error_px);
  json["images_in_model"] = s.num_images;
  json["unprojected_observations"] = s.num_unprojected;
  json["unknowns"] = s.num_unknowns;
  json["redundancy"] = s.redundancy;
  json["cameras"] = Json::array();
  for (const auto& [camera_id, camera] : model.cameras) {
    json["cameras"].push_back({{"camera_id", camera_id},
                               {"model", camera.ModelName()},
                               {"width", camera.width},
                               {"height", camera.height},
                               {"params", camera.params}});
  }
  return json;
}

int CountCommonNames(const Scene& a, const Scene& b) {
  std::set<std::string> names;
  for (const auto& [image_id, image] : a.images) names.insert(image.name);
  int count = 0;
  for (const auto& [image_id, image] : b.images) {
    count += names.count(image.name) > 0;
  }
  return count;
}

// `model` against `reference` by EvaluateSparse (a similarity fitted to the
// common camera centres, errors in the reference's units); the figures are
// null where fewer than 3 images are shared or the centres are collinear.
Json CameraComparisonJson(const Scene& model,
                          const Scene& reference,
                          const char* count_key) {
  Json json;
  json[count_key] = CountCommonNames(model, reference);
  for (const char* key :
       {"center_rms", "center_max", "center_rms_percent", "rotation_rms_deg"}) {
    json[key] = nullptr;
  }
  try {
    const SparseEvaluation e = EvaluateSparse(model, reference);
    json["center_rms"] = e.center_rms;
    json["center_max"] = e.center_max;
    json["center_rms_percent"] = 100.0 * e.center_rms_relative;
    json["rotation_rms_deg"] = e.rotation_rms_deg;
    json["center_max_percent"] = 100.0 * e.center_max_relative;
    json["rotation_max_deg"] = e.rotation_max_deg;
    json["mean_camera_distance"] = e.mean_camera_distance;
    json["scale"] = e.truth_from_model.scale;
  } catch (const InputError& error) {
    // Fewer than 3 common images, or collinear centres.
    json["note"] = json[count_key].get<int>() < 3
                       ? StrCat("only ",
                                json[count_key].get<int>(),
                                " common images; a similarity needs 3")
                       : std::string(error.what());
  }
  return json;
}

// ---------------------------------------------------------------------------
// The table.

std::string Cell(const Json& value, const char* format) {
  if (value.is_null()) return "-";
  char text[64];
  if (value.is_number_integer()) {
    std::snprintf(text, sizeof(text), "%lld", value.get<long long>());
  } else {
    std::snprintf(text, sizeof(text), format, value.get<double>());
  }
  return text;
}

class Table {
 public:
  void Row(const std::string& label,
           const std::string& bayon,
           const std::string& colmap) {
    char line[256];
    std::snprintf(line,
                  sizeof(line),
                  "%-36s %18s %18s\n",
                  label.c_str(),
                  bayon.c_str(),
                  colmap.c_str());
    text_ += line;
  }
  void Row(const std::string& label,
           const Json& bayon,
           const Json& colmap,
           const char* format) {
    Row(label, Cell(bayon, format), Cell(colmap, format));
  }
  void Heading(const std::string& text) { text_ += text + "\n"; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

// A model's path as shown in the table: relative to the workspace when
// inside it.
std::string Display(const std::string& path, const fs::path& workspace) {
  if (path.empty()) return "(none)";
  const fs::path relative =
      fs::absolute(path).lexically_normal().lexically_relative(
          fs::absolute(workspace).lexically_normal());
  if (!relative.empty() && *relative.begin() != "..") return relative.string();
  return path;
}

}  // namespace

void CompareColmapOptions::Register(OptionRegistry* r) {
  r->Add("workspace_path",
         &workspace_path,
         "bayon workspace (after bayon pipeline)");
  r->Add("image_path",
         &image_path,
         "Image folder (default: the one in <workspace>/pipeline.json, else "
         "<workspace>/images)");
  r->Add("bayon_model_path",
         &bayon_model_path,
         "bayon's model (default <workspace>/sparse/adjusted)");
  r->Add("ground_truth_path",
         &ground_truth_path,
         "True COLMAP model or a synthetic workspace's gt/ folder");
  r->AddChoice("matching",
               &matching,
               {{"exhaustive", "exhaustive"}, {"sequential", "sequential"}},
               "exhaustive or sequential");
  r->Add("num_neighbors",
         &num_neighbors,
         "Sequential matching: successors matched with each image");
  r->Add("camera_model",
         &camera_model,
         "COLMAP camera model of the one shared camera");
  r->Add("camera_params",
         &camera_params,
         "The calibrated camera bayon was given (COLMAP's order): COLMAP gets "
         "it too, held fixed; empty: both calibrate");
  r->Add("max_image_size",
         &max_image_size,
         "COLMAP SIFT: longest image side in pixels");
  r->Add("num_threads", &num_threads, "-1 = all cores");
  r->Add("overwrite",
         &overwrite,
         "Run COLMAP again even where a finished run is in <workspace>/colmap");
}

void CompareColmapOptions::Check() const {
  CheckOption(num_neighbors >= 1, "num_neighbors", ">= 1", num_neighbors);
  CheckOption(max_image_size >= 16, "max_image_size", ">= 16", max_image_size);
  CheckOption(num_threads == -1 || num_threads >= 1,
              "num_threads",
              "-1 or >= 1",
              num_threads);
  const auto model = CameraModelIdFromName(camera_model);
  if (!model || !IsColmapCameraModel(*model)) {
    std::string names;
    for (const CameraModelInfo& info : CameraModels()) {
      if (!IsColmapCameraModel(info.id)) continue;
      names += (names.empty() ? "" : ", ") + std::string(info.name);
    }
    ThrowInputError("camera_model must be a COLMAP model: ",
                    names,
                    " (got ",
                    camera_model,
                    ")");
  }
  if (!camera_params.empty()) {
    CheckNumCameraParams(
        *model,
        std::count(camera_params.begin(), camera_params.end(), ',') + 1,
        "camera_params");
  }
}

PipelineRecord ReadPipelineRecord(const fs::path& workspace) {
  PipelineRecord record;
  std::map<std::string, double> ran;  // pipeline.json's stages that ran
  const fs::path path = workspace / "pipeline.json";
  if (fs::exists(path)) {
    const Json json = ParseJsonFile(path.string());
    record.present = true;
    try {
      if (json.contains("image_path") && json["image_path"].is_string()) {
        record.image_path = json["image_path"].get<std::string>();
      }
      for (const Json& stage : json.value("stages", Json::array())) {
        const Json words = stage.value("command", Json::array());
        if (stage.value("name", "") == "import") {
          for (size_t i = 0; i + 1 < words.size(); ++i) {
            if (words[i] == "--camera_model") {
              record.camera_model = words[i + 1].get<std::string>();
            } else if (words[i] == "--camera_params") {
              record.camera_params = words[i + 1].get<std::string>();
            }
          }
        }
        if (stage.value("status", "") == "ran" && stage.contains("seconds") &&
            stage["seconds"].is_number()) {
          ran[stage.at("name").get<std::string>()] =
              stage["seconds"].get<double>();
        }
      }
      if (json.contains("total_seconds") && json["total_seconds"].is_number()) {
        record.pipeline_total_seconds = json["total_seconds"];
      }
    } catch (const Json::exception& e) {
      ThrowInputError(
          path.string(), ": not a pipeline record (", e.what(), ")");
    }
  }
  double total = 0;
  for (const char* stage : kSparseStages) {
    std::optional<double> seconds = StampSeconds(workspace, stage);
    if (!seconds && ran.count(stage)) seconds = ran.at(stage);
    if (!seconds) continue;
    record.stage_seconds[stage] = *seconds;
    total += *seconds;
  }
  if (!record.stage_seconds.empty()) record.total_seconds = total;
  return record;
}

std::string DefaultImagePath(const fs::path& workspace,
                             const PipelineRecord& pipeline) {
  if (pipeline.image_path.empty()) return (workspace / "images").string();
  const fs::path path(pipeline.image_path);
  // A relative folder is the workspace's where it is not the caller's.
  if (path.is_relative() && !fs::exists(path)) {
    return (workspace / path).string();
  }
  return path.string();
}

ColmapRun RunOrReuseColmap(const CompareColmapOptions& options,
                           const fs::path& colmap_dir) {
  if (!options.overwrite) {
    if (std::optional<Json> record = CompleteColmapRecord(colmap_dir)) {
      ColmapRun run;
      run.reused = true;
      run.record = *record;
      run.model_path = record->at("model_path").get<std::string>();
      const Json wanted = OptionsJson(options);
      if (ResultOptions(record->value("options", Json::object())) !=
          ResultOptions(wanted)) {
        LOG(WARNING) << "the COLMAP run in " << colmap_dir.string()
                     << " was made with other options ("
                     << record->value("options", Json::object()).dump()
                     << "); --overwrite 1 runs it again with " << wanted.dump();
      }
      return run;
    }
    if (fs::exists(colmap_dir)) {
      LOG(INFO) << colmap_dir.string()
                << " holds no finished COLMAP run; running COLMAP";
    }
  }
  return RunColmapPipeline(options, colmap_dir);
}

Json CompareModels(const CompareColmapOptions& options,
                   const fs::path& workspace,
                   const PipelineRecord& pipeline,
                   const std::vector<std::string>& image_names,
                   const Scene& bayon_model,
                   const ColmapRun& run,
                   const std::string& colmap_model_path,
                   const Scene& colmap_model,
                   const std::optional<Scene>& truth) {
  const std::set<std::string> folder_images(image_names.begin(),
                                            image_names.end());
  Json c;
  c["workspace_path"] = workspace.string();
  c["image_path"] = options.image_path;
  c["num_images"] = image_names.size();
  c["colmap_version"] = run.record.value("colmap_version", "");
  c["colmap_reused"] = run.reused;
  // What COLMAP's run was given (a reused run's own record).
  const Json run_options = run.record.value("options", Json::object());
  const std::string given_params = run_options.value("camera_params", "");
  const std::string given_model =
      run_options.value("camera_model", options.camera_model);
  c["camera_given_to_colmap"] = given_params.empty()
                                    ? Json(nullptr)
                                    : Json({{"model", given_model},
                                            {"params", given_params},
                                            {"held_fixed", true}});
  c["camera"] =
      given_params.empty()
          ? StrCat("camera: COLMAP calibrates its own (",
                   given_model,
                   "), knowing no calibration")
          : StrCat(
                "camera: the calibration bayon was given, given to COLMAP "
                "too and held fixed (",
                given_model,
                " ",
                given_params,
                ")");
  c["bayon"] = ModelJson(options.bayon_model_path, bayon_model, folder_images);
  const AdjustmentSigma0 adjustment =
      ReadAdjustmentSigma0(options.bayon_model_path);
  c["bayon"]["adjustment_sigma0"] = adjustment.sigma0;
  c["bayon"]["adjustment_sigma0_apriori_px"] = adjustment.apriori_px;
  c["bayon"]["adjustment_variance_factor"] = adjustment.variance_factor;
  c["bayon"]["stage_seconds"] = pipeline.stage_seconds;
  c["bayon"]["total_seconds"] = pipeline.total_seconds;
  c["bayon"]["pipeline_total_seconds"] = pipeline.pipeline_total_seconds;
  c["bayon"]["model_display"] = Display(options.bayon_model_path, workspace);
  c["colmap"] = ModelJson(colmap_model_path, colmap_model, folder_images);
  c["colmap"]["stage_seconds"] = run.record["stage_seconds"];
  c["colmap"]["total_seconds"] = run.record["total_seconds"];
  c["colmap"]["model_display"] = Display(colmap_model_path, workspace);
  if (!run.mapper_message.empty()) {
    c["colmap"]["message"] = run.mapper_message;
  }

  c["agreement"] =
      CameraComparisonJson(colmap_model, bayon_model, "num_common");
  c["truth"] = nullptr;
  if (truth) {
    c["truth"] = {
        {"path", options.ground_truth_path},
        {"num_images", truth->images.size()},
        {"bayon", CameraComparisonJson(bayon_model, *truth, "registered")},
        {"colmap", CameraComparisonJson(colmap_model, *truth, "registered")}};
  }

  return c;
}

std::string ComparisonTable(const Json& c) {
  const Json& b = c["bayon"];
  const Json& m = c["colmap"];
  const std::string num_images = std::to_string(c["num_images"].get<int>());
  Table table;
  table.Row("",
            "bayon",
            c["colmap_reused"].get<bool>() ? "colmap (reused)" : "colmap");
  table.Row("model",
            b["model_display"].get<std::string>(),
            m["model_display"].get<std::string>());
  table.Heading(c["camera"].get<std::string>());
  table.Row("registered images",
            Cell(b["registered"], "") + "/" + num_images,
            Cell(m["registered"], "") + "/" + num_images);
  table.Row("3D points", b["points3D"], m["points3D"], "");
  table.Row("observations", b["observations"], m["observations"], "");
  table.Row("mean track length",
            b["mean_track_length"],
            m["mean_track_length"],
            "%.2f");
  table.Row("mean reprojection error [px]",
            b["mean_reprojection_error_px"],
            m["mean_reprojection_error_px"],
            "%.3f");
  table.Row("RMS reprojection error [px]",
            b["rms_reprojection_error_px"],
            m["rms_reprojection_error_px"],
            "%.3f");
  table.Row("sigma0 [px]", b["sigma0_px"], m["sigma0_px"], "%.3f");
  // The adjustment weighs every observation by its own precision, so its
  // sigma0 is in the pixels of the a priori sigma0 (1 ratio = as expected).
  table.Row("adjustment's sigma0 [px]",
            b["adjustment_sigma0"],
            m["adjustment_sigma0"],
            "%.4f");
  table.Row("  a priori sigma0 [px]",
            b["adjustment_sigma0_apriori_px"],
            nullptr,
            "%.4f");
  table.Row("  ratio (a posteriori / a priori)",
            b["adjustment_variance_factor"],
            nullptr,
            "%.3f");
  for (const auto& [name, seconds] : b["stage_seconds"].items()) {
    table.Row("time " + name + " [s]", seconds, nullptr, "%.1f");
  }
  for (const auto& [name, seconds] : m["stage_seconds"].items()) {
    table.Row("time " + name + " [s]", nullptr, seconds, "%.1f");
  }
  table.Row("time total [s]", b["total_seconds"], m["total_seconds"], "%.1f");

  const Json& truth = c["truth"];
  if (!truth.is_null()) {
    table.Heading("against the truth " + truth["path"].get<std::string>() +
                  " (" + Cell(truth["num_images"], "") + " images):");
    const Json& tb = truth["bayon"];
    const Json& tm = truth["colmap"];
    table.Row("  registered", tb["registered"], tm["registered"], "");
    table.Row("  centre RMS [truth units]",
              tb["center_rms"],
              tm["center_rms"],
              "%.5g");
    table.Row("  centre max [truth units]",
              tb["center_max"],
              tm["center_max"],
              "%.5g");
    table.Row("  centre RMS [%]",
              tb["center_rms_percent"],
              tm["center_rms_percent"],
              "%.4f");
    table.Row("  rotation RMS [deg]",
              tb["rotation_rms_deg"],
              tm["rotation_rms_deg"],
              "%.4f");
  }

  const Json& a = c["agreement"];
  table.Heading(
      "agreement of the cameras (colmap fitted to bayon by a "
      "similarity, " +
      Cell(a["num_common"], "") + " common images):");
  table.Row("  centre RMS [bayon units]", "", Cell(a["center_rms"], "%.5g"));
  table.Row("  centre max [bayon units]", "", Cell(a["center_max"], "%.5g"));
  table.Row("  centre RMS [% of camera distance]",
            "",
            Cell(a["center_rms_percent"], "%.4f"));
  table.Row("  rotation RMS [deg]", "", Cell(a["rotation_rms_deg"], "%.4f"));
  return table.text();
}

std::string ComparisonSummary(const Json& c,
                              bool reused,
                              const std::string& output) {
  const Json& a = c["agreement"];
  std::string text = StrCat("bayon ",
                            Cell(c["bayon"]["registered"], ""),
                            "/",
                            c["num_images"].get<int>(),
                            ", colmap ",
                            Cell(c["colmap"]["registered"], ""),
                            "/",
                            c["num_images"].get<int>(),
                            " registered");
  if (!a["center_rms_percent"].is_null()) {
    text += StrCat("; cameras agree to ",
                   Cell(a["center_rms_percent"], "%.3f"),
                   " % (centre RMS) and ",
                   Cell(a["rotation_rms_deg"], "%.3f"),
                   " deg (rotation RMS)");
  }
  text += StrCat("; COLMAP ",
                 Cell(c["colmap"]["total_seconds"], "%.1f"),
                 " s",
                 reused ? " (reused)" : "",
                 " -> ",
                 output);
  return text;
}

ComparisonInputs ReadComparisonInputs(CompareColmapOptions* options,
                                      bool camera_params_given,
                                      bool camera_model_given) {
  CheckDirectoryExists(options->workspace_path, "workspace_path");
  ComparisonInputs inputs;
  inputs.workspace = fs::absolute(options->workspace_path).lexically_normal();
  inputs.pipeline = ReadPipelineRecord(inputs.workspace);
  if (!camera_params_given && !inputs.pipeline.camera_params.empty()) {
    options->camera_params = inputs.pipeline.camera_params;
    if (!camera_model_given && !inputs.pipeline.camera_model.empty()) {
      options->camera_model = inputs.pipeline.camera_model;
    }
  }
  options->Check();
  if (options->bayon_model_path.empty()) {
    options->bayon_model_path =
        (inputs.workspace / "sparse" / "adjusted").string();
  }
  if (!fs::is_directory(options->bayon_model_path)) {
    ThrowInputError(options->bayon_model_path,
                    ": no bayon model to compare (run bayon pipeline first, "
                    "or give --bayon_model_path)");
  }
  // With its full calibration (calibration.json): the FULL_OPENCV cameras
  // of the COLMAP files cannot express every Brown/Beyer parameter (affinity
  // and shear), which would add their fit residual to bayon's errors.
  const std::string database = (inputs.workspace / "database.db").string();
  inputs.bayon_model = ReadOrientedModel(options->bayon_model_path,
                                         fs::exists(database) ? database : "");
  if (options->image_path.empty()) {
    options->image_path = DefaultImagePath(inputs.workspace, inputs.pipeline);
  }
  options->image_path = fs::absolute(options->image_path).string();
  inputs.image_names = ListImages(options->image_path);
  if (inputs.image_names.empty()) {
    ThrowInputError(options->image_path, ": image folder holds no images");
  }
  if (!options->ground_truth_path.empty()) {
    CheckDirectoryExists(options->ground_truth_path, "ground_truth_path");
    const fs::path root(options->ground_truth_path);
    inputs.truth =
        ReadModel(fs::is_directory(root / "sparse") ? (root / "sparse").string()
                                                    : root.string());
  }
  return inputs;
}

ComparisonOutcome RunComparison(const CompareColmapOptions& options,
                                const ComparisonInputs& inputs) {
  const fs::path colmap_dir = inputs.workspace / "colmap";
  ComparisonOutcome outcome;
  outcome.run = RunOrReuseColmap(options, colmap_dir);
  const ColmapRun& run = outcome.run;
  const std::string colmap_model_path =
      run.model_path.empty() ? "" : (colmap_dir / run.model_path).string();
  const Scene colmap_model =
      colmap_model_path.empty() ? Scene() : ReadModel(colmap_model_path);
  outcome.comparison = CompareModels(options,
                                     inputs.workspace,
                                     inputs.pipeline,
                                     inputs.image_names,
                                     inputs.bayon_model,
                                     run,
                                     colmap_model_path,
                                     colmap_model,
                                     inputs.truth);
  outcome.table = ComparisonTable(outcome.comparison);
  outcome.json_path = (colmap_dir / "comparison.json").string();
  WriteFileAtomically(outcome.json_path, outcome.comparison.dump(2) + "\n");
  WriteFileAtomically((colmap_dir / "comparison.txt").string(), outcome.table);
  if (colmap_model_path.empty()) {
    outcome.failure = StrCat("colmap mapper made no model (",
                             run.mapper_message,
                             "; log: ",
                             (colmap_dir / "mapper.log").string(),
                             "); the comparison, with COLMAP's column empty, "
                             "is in ",
                             outcome.json_path);
  }
  return outcome;
}

}  // namespace bayon
