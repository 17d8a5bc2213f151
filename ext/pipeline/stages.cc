// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/stages.h"

#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The bayon stages in processing order (architecture.md); compare_colmap
// (when asked for), evaluate (in workspaces with a truth, W/gt) and report
// close the run.
constexpr const char* kStageNames[] = {"import",
                                       "interior",
                                       "targets",
                                       "features",
                                       "match",
                                       "relative",
                                       "disparity",
                                       "tiepoints",
                                       "strip",
                                       "adjust",
                                       "dense",
                                       "edit",
                                       "mesh",
                                       "texture",
                                       "render",
                                       "viewer",
                                       "compare_colmap",
                                       "evaluate",
                                       "report"};

// The values each [pipeline] key takes, its default first.
const std::map<std::string, std::vector<std::string>> kPipelineChoices = {
    {"features", {"bayon", "colmap_sift"}},
    {"sparse", {"bayon", "colmap_mapper"}},
    {"colmap_matcher", {"exhaustive", "sequential"}},
    {"compare_colmap", {"0", "1"}}};

bool IsColmapCommand(const std::string& name) {
  return name == "feature_extractor" || name == "exhaustive_matcher" ||
         name == "sequential_matcher" || name == "mapper";
}

// The stages with the workspace's paths, added in the chain's order by
// named steps; the members are the paths and options they share.
struct StageMaker {
  StageMaker(const PipelineContext& c, const PipelineConfig& config)
      : c(c),
        config(config),
        s(config.settings),
        w(c.workspace),
        threads(std::to_string(c.num_threads)),
        control(!c.control.empty()),
        db({{"database_path", c.database}}),
        db_images(
            {{"database_path", c.database}, {"image_path", c.image_path}}),
        threads_option({{"num_threads", threads}}),
        targets(JoinPath(w, "targets/targets.txt")),
        initial(JoinPath(w, "sparse/initial")),
        adjusted(JoinPath(w, "sparse/adjusted")),
        points(JoinPath(w, "dense/points.ply")),
        edited(JoinPath(w, "dense/points_edited.ply")),
        mesh(JoinPath(w, "mesh/mesh.ply")),
        control_input(control ? std::vector<std::string>{c.control}
                              : std::vector<std::string>{}) {}

  // import, interior, and features and match (bayon's, or COLMAP's SIFT and
  // matcher).
  void AddFrontEnd();
  // relative, disparity and tiepoints, after bayon's features and match.
  void AddPairStages();
  // strip (or COLMAP's mapper) and adjust.
  void AddOrientation();
  // dense, edit, mesh, texture, render and viewer.
  void AddProducts();
  // compare_colmap (when asked for), evaluate (with a truth) and report.
  void AddClosingStages();
  // Each stage's config section on top of the pipeline's options.
  void ApplyConfigSections();

  void Add(Stage stage) { stages.push_back(std::move(stage)); }
  static StageOptions With(StageOptions base, const StageOptions& more) {
    for (const auto& [k, v] : more) SetStageOption(&base, k, v);
    return base;
  }

  const PipelineContext& c;
  const PipelineConfig& config;
  const PipelineSettings& s;
  const std::string w, threads;
  const bool control;
  const StageOptions db, db_images, threads_option;
  const std::string targets, initial, adjusted, points, edited, mesh;
  const std::vector<std::string> control_input;
  std::vector<Stage> stages;
};

void StageMaker::AddFrontEnd() {
  Add({"import",
       "bayon",
       "import",
       With(db_images, {{"single_camera", "1"}}),
       false,
       {c.database},
       {c.image_path}});
  // Interior orientation measures scanned film frames (virtual fiducials);
  // a digital photograph's frame is its camera's own (pixel pitch, image
  // centre), so the stage runs only where the config has an [interior]
  // section, as configs/film.ini does.
  if (config.stage_options.count("interior")) {
    Add({"interior", "bayon", "interior", db_images, true, {c.database}, {}});
  }
  if (s.features == "colmap_sift") {
    Add({"features",
         "colmap",
         "feature_extractor",
         With(db_images,
              {{"SiftExtraction.use_gpu", "0"},
               {"SiftExtraction.num_threads", threads}}),
         false,
         {c.database},
         {}});
    const std::string matcher = s.colmap_matcher + "_matcher";
    Add({"match",
         "colmap",
         matcher,
         With(db,
              {{"SiftMatching.use_gpu", "0"},
               {"SiftMatching.num_threads", threads}}),
         false,
         {c.database},
         {}});
  } else {
    // Coded targets, wherever any are found: keypoints that match by name
    // (they close a ring where texture fails), then named tie points.
    Add({"targets",
         "bayon",
         "targets",
         With(db_images,
              {{"output_path", targets},
               {"report_path", JoinPath(w, "targets/targets.json")},
               {"num_threads", threads}}),
         true,
         {targets},
         {}});
    Add({"features",
         "bayon",
         "features",
         With(db_images, {{"targets_path", targets}, {"num_threads", threads}}),
         true,
         {c.database},
         {}});
    Add({"match",
         "bayon",
         "match",
         With(db_images, threads_option),
         true,
         {c.database},
         {}});
  }
}

void StageMaker::AddPairStages() {
  // COLMAP's matcher writes its own verified two-view geometries; bayon's
  // relative orientation would replace them, and disparity surfaces and
  // least-squares tie points build on bayon's, so they go with it.
  if (s.features != "bayon") return;
  Add({"relative",
       "bayon",
       "relative",
       With(db, threads_option),
       true,
       {c.database},
       {}});
  Add({"disparity",
       "bayon",
       "disparity",
       With(db, threads_option),
       true,
       {c.database},
       {}});
  const std::string tie_report = JoinPath(w, "pipeline/tiepoints.json");
  Add({"tiepoints",
       "bayon",
       "tiepoints",
       With(db_images,
            {{"num_threads", threads},
             {"report_path", tie_report},
             {"targets_path", targets}}),
       true,
       {c.database, tie_report},
       {}});
}

void StageMaker::AddOrientation() {
  if (s.sparse == "colmap_mapper") {
    Add({"strip",
         "colmap",
         "mapper",
         With(db_images,
              {{"output_path", JoinPath(w, "sparse/colmap_mapper")},
               {"Mapper.num_threads", threads}}),
         false,
         {initial},
         {}});
  } else {
    StageOptions strip =
        With(db, {{"output_path", initial}, {"num_threads", threads}});
    if (control) SetStageOption(&strip, "control_path", c.control);
    Add({"strip", "bayon", "strip", strip, true, {initial}, control_input});
  }
  StageOptions adjust = With(db,
                             {{"input_path", initial},
                              {"output_path", adjusted},
                              {"num_threads", threads}});
  if (control) SetStageOption(&adjust, "control_path", c.control);
  Add({"adjust",
       "bayon",
       "adjust",
       adjust,
       true,
       {JoinPath(adjusted, "adjustment.json")},
       control_input});
}

void StageMaker::AddProducts() {
  Add({"dense",
       "bayon",
       "dense",
       {{"workspace_path", w},
        {"image_path", c.image_path},
        {"database_path", c.database},
        {"input_path", adjusted},
        {"output_path", points},
        {"num_threads", threads}},
       true,
       {points, JoinPath(w, "dense/points.json")},
       {}});
  Add({"edit",
       "bayon",
       "edit",
       {{"input_path", points},
        {"output_path", edited},
        {"report_path", JoinPath(w, "dense/edit.json")},
        {"num_threads", threads}},
       true,
       {edited},
       {}});
  Add({"mesh",
       "bayon",
       "mesh",
       // The oriented model gives delaunay_graph_cut its rays.
       {{"input_path", edited},
        {"sparse_path", adjusted},
        {"output_path", mesh},
        {"report_path", JoinPath(w, "mesh/mesh.json")},
        {"num_threads", threads}},
       true,
       {mesh},
       {}});
  Add({"texture",
       "bayon",
       "texture",
       {{"workspace_path", w},
        {"image_path", c.image_path},
        {"database_path", c.database},
        {"input_path", adjusted},
        {"mesh_path", mesh},
        {"output_path", JoinPath(w, "model")},
        {"num_threads", threads}},
       true,
       {JoinPath(w, "model/texture.json")},
       {}});
  Add({"render",
       "bayon",
       "render",
       // The oriented model is read only for --viewpoints stations.
       {{"model_path", JoinPath(w, "model/model.glb")},
        {"output_path", JoinPath(w, "renders")},
        {"input_path", adjusted},
        {"database_path", c.database},
        {"num_threads", threads}},
       true,
       {JoinPath(w, "renders")},
       {}});
  Add({"viewer",
       "bayon",
       "viewer",
       {{"model_path", JoinPath(w, "model/model.glb")},
        {"output_path", JoinPath(w, "viewer")}},
       true,
       {JoinPath(w, "viewer/index.html")},
       {}});
}

void StageMaker::AddClosingStages() {
  if (s.compare_colmap == "1") {
    StageOptions compare = {{"workspace_path", w},
                            {"image_path", c.image_path},
                            {"num_threads", threads}};
    // A calibrated camera given to bayon's import is given to COLMAP too
    // (held fixed there), so that both know the same.
    const auto import = config.stage_options.find("import");
    if (import != config.stage_options.end()) {
      for (const auto& [key, value] : import->second) {
        if (key == "camera_model" || key == "camera_params") {
          SetStageOption(&compare, key, value);
        }
      }
    }
    if (fs::is_directory(JoinPath(w, "gt"))) {
      SetStageOption(&compare, "ground_truth_path", JoinPath(w, "gt"));
    }
    Add({"compare_colmap",
         "bayon",
         "compare_colmap",
         compare,
         true,
         {JoinPath(w, "colmap/comparison.json")},
         {}});
  }
  if (fs::is_directory(JoinPath(w, "gt"))) {
    // gt/ is a synthetic workspace's truth (with the true surface and
    // held-out views) or a benchmark's cameras (import_ground_truth).
    StageOptions evaluate = {{"ground_truth_path", JoinPath(w, "gt")},
                             {"input_path", adjusted},
                             {"output_path", JoinPath(w, "evaluation.json")},
                             {"num_threads", threads}};
    if (fs::exists(JoinPath(w, "gt/surface.ply"))) {
      SetStageOption(&evaluate, "cloud_path", points);
      SetStageOption(&evaluate, "mesh_path", mesh);
    }
    // A truth rendered with no held-out views (synth --num_heldout_views
    // 0) has an empty gt/heldout: nothing to compare renders with.
    if (fs::is_directory(JoinPath(w, "gt/heldout")) &&
        ReadModel(JoinPath(w, "gt/heldout")).images.size() > 0) {
      // evaluate reads the textured model as PLY (its TextureFile comment
      // names the atlas).
      SetStageOption(
          &evaluate, "textured_mesh_path", JoinPath(w, "model/model.ply"));
    }
    Add({"evaluate",
         "bayon",
         "evaluate",
         evaluate,
         false,
         {JoinPath(w, "evaluation.json")},
         {}});
  }
  Add({"report",
       "bayon",
       "report",
       {{"workspace_path", w}},
       true,
       {JoinPath(w, "report.html")},
       {}});
}

void StageMaker::ApplyConfigSections() {
  for (Stage& stage : stages) {
    const auto section = config.stage_options.find(stage.name);
    if (stage.program == "bayon" && section != config.stage_options.end()) {
      for (const auto& [k, v] : section->second)
        SetStageOption(&stage.options, k, v);
    }
    if (stage.program == "colmap") {
      const auto colmap = s.colmap_options.find(stage.command);
      if (colmap != s.colmap_options.end()) {
        for (const auto& [k, v] : colmap->second) {
          SetStageOption(&stage.options, k, v);
        }
      }
    }
  }
}

}  // namespace

void SetStageOption(StageOptions* options,
                    const std::string& key,
                    const std::string& value) {
  for (auto& [k, v] : *options) {
    if (k == key) {
      v = value;
      return;
    }
  }
  options->emplace_back(key, value);
}

bool IsStageName(const std::string& name) {
  return std::find_if(std::begin(kStageNames),
                      std::end(kStageNames),
                      [&](const char* s) { return name == s; }) !=
         std::end(kStageNames);
}

PipelineConfig ReadPipelineConfigs(const std::vector<std::string>& paths) {
  PipelineConfig config;
  for (const std::string& path : paths) {
    CheckFileExists(path, "config");
    std::vector<CLI::ConfigItem> items;
    try {
      items = CLI::ConfigINI().from_file(path);
    } catch (const std::exception& error) {
      ThrowInputError(path, ": not a readable INI/TOML file: ", error.what());
    }
    for (const CLI::ConfigItem& item : items) {
      // CLI11 marks the opening and closing of sections with these names.
      if (item.name == "++" || item.name == "--") continue;
      if (item.parents.empty()) {
        ThrowInputError(path,
                        ": '",
                        item.name,
                        "' is outside any section; put it under [pipeline] or "
                        "under the stage it belongs to, e.g. [dense]");
      }
      const std::string section = item.parents[0];
      // Dotted keys (COLMAP's SiftExtraction.max_image_size) come back as
      // deeper parents.
      const std::string key = item.fullname().substr(section.size() + 1);
      std::string value;
      for (const std::string& input : item.inputs) {
        value += (value.empty() ? "" : ",") + input;
      }
      if (section == "pipeline") {
        PipelineSettings& s = config.settings;
        std::string* setting = key == "features"         ? &s.features
                               : key == "sparse"         ? &s.sparse
                               : key == "colmap_matcher" ? &s.colmap_matcher
                               : key == "compare_colmap" ? &s.compare_colmap
                                                         : nullptr;
        if (setting == nullptr) {
          ThrowInputError(path,
                          ": unknown key '",
                          key,
                          "' in [pipeline] (known: features, sparse, "
                          "colmap_matcher, compare_colmap)");
        }
        const std::vector<std::string>& allowed = kPipelineChoices.at(key);
        if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
          ThrowInputError(path,
                          ": [pipeline] ",
                          key,
                          " must be ",
                          allowed[0],
                          " or ",
                          allowed[1],
                          " (got ",
                          value,
                          ")");
        }
        *setting = value;
      } else if (IsStageName(section)) {
        SetStageOption(&config.stage_options[section], key, value);
      } else if (IsColmapCommand(section)) {
        SetStageOption(&config.settings.colmap_options[section], key, value);
      } else {
        std::string known;
        for (const char* name : kStageNames) known += std::string(" ") + name;
        ThrowInputError(path,
                        ": unknown section [",
                        section,
                        "]; stages are",
                        known,
                        ", plus [pipeline] and stock COLMAP's "
                        "[feature_extractor] [exhaustive_matcher] "
                        "[sequential_matcher] [mapper]");
      }
    }
    config.description += (config.description.empty() ? "" : " + ") + path;
  }
  return config;
}

std::vector<Stage> MakeStages(const PipelineContext& c,
                              const PipelineConfig& config) {
  StageMaker maker(c, config);
  maker.AddFrontEnd();
  maker.AddPairStages();
  maker.AddOrientation();
  maker.AddProducts();
  maker.AddClosingStages();
  maker.ApplyConfigSections();
  return maker.stages;
}

size_t ResolveWorkspace(PipelineContext* c) {
  if (c->image_path.empty()) c->image_path = JoinPath(c->workspace, "images");
  CheckDirectoryExists(c->image_path, "image_path");
  const size_t num_images = ListImages(c->image_path).size();
  if (num_images == 0) {
    ThrowInputError(c->image_path,
                    ": no images found (looked for jpg, png, tif, bmp, "
                    "pgm/ppm, webp, jp2, exr, hdr)");
  }
  c->image_path = fs::absolute(c->image_path).lexically_normal().string();
  c->workspace = fs::absolute(c->workspace).lexically_normal().string();
  c->database = JoinPath(c->workspace, "database.db");
  if (fs::is_directory(JoinPath(c->workspace, "control"))) {
    c->control = JoinPath(c->workspace, "control");
  }
  return num_images;
}

std::vector<std::string> CommandWords(const Stage& stage, bool overwrite) {
  std::vector<std::string> words = {stage.program, stage.command};
  for (const auto& [key, value] : stage.options) {
    words.push_back("--" + key);
    words.push_back(value);
  }
  if (overwrite && stage.has_overwrite) {
    words.push_back("--overwrite");
    words.push_back("1");
  }
  return words;
}

void RunColmapStage(const Stage& stage, const std::string& log_path) {
  ColmapCall call;
  call.command = stage.command;
  for (const auto& [key, value] : stage.options) {
    call.options.emplace_back("--" + key, value);
  }
  const bool mapper = stage.command == "mapper";
  std::string mapper_output;
  if (mapper) {
    for (const auto& [key, value] : stage.options) {
      if (key == "output_path") mapper_output = value;
    }
    fs::remove_all(mapper_output);
    fs::create_directories(mapper_output);
  }
  ColmapRunOptions run;
  run.log_path = log_path;
  fs::create_directories(fs::path(run.log_path).parent_path());
  const ColmapResult result = RunColmap(call, run);
  if (!result.success) {
    throw std::runtime_error(StrCat("colmap ",
                                    stage.command,
                                    " failed: ",
                                    result.message,
                                    " (log: ",
                                    result.log_path,
                                    ")"));
  }
  if (!mapper) return;
  const std::string best = LargestModel(mapper_output);
  if (best.empty()) {
    throw std::runtime_error(StrCat(
        "colmap mapper registered no images (log: ", result.log_path, ")"));
  }
  const std::string& model = stage.outputs[0];
  const std::string temp = model + TempSuffix();
  fs::copy(best, temp, fs::copy_options::recursive);
  fs::remove_all(model);
  fs::rename(temp, model);
}

}  // namespace bayon
