// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon pipeline`: every stage in order on one workspace, each with its
// options from a config file, like `make`: a stage whose outputs are complete
// and newer than its inputs is skipped, so a run that was interrupted (even
// by kill -9) resumes where it stopped.
//
// Completeness is judged by a stamp, W/pipeline/<stage>.done, written only
// after the stage returned successfully and removed before it starts. Each
// stage writes its own outputs atomically (or in one database transaction),
// so an interrupted stage leaves either its old outputs or none, and never a
// stamp: it is run again. A stamp is stale when the stage's command changed
// (config or flags), when it is older than the previous stage's stamp, or
// when an input outside the chain (the image folder, control/) changed later.
//
// The stages run in this process (kill -9 of the pipeline stops the stage
// with it); stock COLMAP stages, swapped in by the config, run as a child.
#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

using Options = std::vector<std::pair<std::string, std::string>>;

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

// Stages whose work can be done by stock COLMAP instead ([pipeline] keys).
// features = colmap_sift replaces features and match (SIFT on the CPU and
// COLMAP's matcher with its geometric verification) and leaves out relative,
// disparity and tiepoints; sparse = colmap_mapper replaces strip (the mapper's
// model is adjusted by bayon adjust, which hosts COLMAP models).
struct PipelineSettings {
  std::string features = "bayon";             // bayon | colmap_sift
  std::string sparse = "bayon";               // bayon | colmap_mapper
  std::string colmap_matcher = "exhaustive";  // exhaustive | sequential
  std::string compare_colmap = "0";           // 0 | 1
  // Options of COLMAP's commands by command name ([feature_extractor] ...).
  std::map<std::string, Options> colmap_options;
};

// The values each [pipeline] key takes, its default first.
const std::map<std::string, std::vector<std::string>> kPipelineChoices = {
    {"features", {"bayon", "colmap_sift"}},
    {"sparse", {"bayon", "colmap_mapper"}},
    {"colmap_matcher", {"exhaustive", "sequential"}},
    {"compare_colmap", {"0", "1"}}};

struct Config {
  std::string description;  // the files read, for the summary
  PipelineSettings settings;
  std::map<std::string, Options> stage_options;  // by stage name
};

bool IsStageName(const std::string& name) {
  return std::find_if(std::begin(kStageNames),
                      std::end(kStageNames),
                      [&](const char* s) { return name == s; }) !=
         std::end(kStageNames);
}

bool IsColmapCommand(const std::string& name) {
  return name == "feature_extractor" || name == "exhaustive_matcher" ||
         name == "sequential_matcher" || name == "mapper";
}

void SetOption(Options* options,
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

// Reads the configs in order (later ones win): INI or TOML, one section per
// stage with the stage's own option names, [pipeline] for the settings above,
// and [feature_extractor] etc. for stock COLMAP's options (COLMAP's names,
// e.g. SiftExtraction.max_image_size). A key outside any section, an unknown
// section or an unknown [pipeline] key is an error naming the file.
Config ReadConfigs(const std::vector<std::string>& paths) {
  Config config;
  for (const std::string& path : paths) {
    CheckFileExists(path, "--config");
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
        SetOption(&config.stage_options[section], key, value);
      } else if (IsColmapCommand(section)) {
        SetOption(&config.settings.colmap_options[section], key, value);
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

struct Stage {
  std::string name;           // the pipeline's stage, e.g. "features"
  std::string program;        // "bayon" or "colmap"
  std::string command;        // the bayon or COLMAP command it runs
  Options options;            // in order; the config's after the pipeline's own
  bool has_overwrite = true;  // pass --overwrite 1 when it runs again
  std::vector<std::string> outputs;  // must exist when the stage is complete
  // Outside the chain: images, control/. For COLMAP's mapper, outputs[0] is
  // the folder its largest model becomes.
  std::vector<std::string> inputs;
};

struct Context {
  std::string workspace, image_path, database, control;
  int num_threads = 2;
};

std::string In(const std::string& folder, const std::string& name) {
  return (fs::path(folder) / name).string();
}

// The stages with the pipeline's paths; each stage's config section is
// applied on top (a key given there replaces the pipeline's value).
std::vector<Stage> MakeStages(const Context& c, const Config& config) {
  const std::string w = c.workspace;
  const std::string threads = std::to_string(c.num_threads);
  const bool control = !c.control.empty();
  const PipelineSettings& s = config.settings;
  std::vector<Stage> stages;
  auto add = [&](Stage stage) { stages.push_back(std::move(stage)); };
  const Options db = {{"database_path", c.database}};
  const Options db_images = {{"database_path", c.database},
                             {"image_path", c.image_path}};
  auto with = [](Options base, const Options& more) {
    for (const auto& [k, v] : more) SetOption(&base, k, v);
    return base;
  };
  const Options threads_option = {{"num_threads", threads}};
  const std::string targets = In(w, "targets/targets.txt");

  add({"import",
       "bayon",
       "import",
       with(db_images, {{"single_camera", "1"}}),
       false,
       {c.database},
       {c.image_path}});
  // Interior orientation measures scanned film frames (virtual fiducials);
  // a digital photograph's frame is its camera's own (pixel pitch, image
  // centre), so the stage runs only where the config has an [interior]
  // section, as configs/film.ini does.
  if (config.stage_options.count("interior")) {
    add({"interior", "bayon", "interior", db_images, true, {c.database}, {}});
  }
  if (s.features == "colmap_sift") {
    add({"features",
         "colmap",
         "feature_extractor",
         with(db_images,
              {{"SiftExtraction.use_gpu", "0"},
               {"SiftExtraction.num_threads", threads}}),
         false,
         {c.database},
         {}});
    const std::string matcher = s.colmap_matcher + "_matcher";
    add({"match",
         "colmap",
         matcher,
         with(db,
              {{"SiftMatching.use_gpu", "0"},
               {"SiftMatching.num_threads", threads}}),
         false,
         {c.database},
         {}});
  } else {
    // Coded targets, wherever any are found: keypoints that match by name
    // (they close a ring where texture fails), then named tie points.
    add({"targets",
         "bayon",
         "targets",
         with(db_images,
              {{"output_path", targets},
               {"report_path", In(w, "targets/targets.json")},
               {"num_threads", threads}}),
         true,
         {targets},
         {}});
    add({"features",
         "bayon",
         "features",
         with(db_images, {{"targets_path", targets}, {"num_threads", threads}}),
         true,
         {c.database},
         {}});
    add({"match",
         "bayon",
         "match",
         with(db_images, threads_option),
         true,
         {c.database},
         {}});
  }
  // COLMAP's matcher writes its own verified two-view geometries; bayon's
  // relative orientation would replace them, and disparity surfaces and
  // least-squares tie points build on bayon's, so they go with it.
  const bool bayon_front_end = s.features == "bayon";
  if (bayon_front_end) {
    add({"relative",
         "bayon",
         "relative",
         with(db, threads_option),
         true,
         {c.database},
         {}});
    add({"disparity",
         "bayon",
         "disparity",
         with(db, threads_option),
         true,
         {c.database},
         {}});
    const std::string tie_report = In(w, "pipeline/tiepoints.json");
    add({"tiepoints",
         "bayon",
         "tiepoints",
         with(db_images,
              {{"num_threads", threads},
               {"report_path", tie_report},
               {"targets_path", targets}}),
         true,
         {c.database, tie_report},
         {}});
  }
  const std::string initial = In(w, "sparse/initial");
  const std::vector<std::string> control_input =
      control ? std::vector<std::string>{c.control}
              : std::vector<std::string>{};
  if (s.sparse == "colmap_mapper") {
    add({"strip",
         "colmap",
         "mapper",
         with(db_images,
              {{"output_path", In(w, "sparse/colmap_mapper")},
               {"Mapper.num_threads", threads}}),
         false,
         {initial},
         {}});
  } else {
    Options strip =
        with(db, {{"output_path", initial}, {"num_threads", threads}});
    if (control) SetOption(&strip, "control_path", c.control);
    add({"strip", "bayon", "strip", strip, true, {initial}, control_input});
  }
  const std::string adjusted = In(w, "sparse/adjusted");
  Options adjust = with(db,
                        {{"input_path", initial},
                         {"output_path", adjusted},
                         {"num_threads", threads}});
  if (control) SetOption(&adjust, "control_path", c.control);
  add({"adjust",
       "bayon",
       "adjust",
       adjust,
       true,
       {In(adjusted, "adjustment.json")},
       control_input});
  const std::string points = In(w, "dense/points.ply");
  add({"dense",
       "bayon",
       "dense",
       {{"workspace_path", w},
        {"image_path", c.image_path},
        {"database_path", c.database},
        {"input_path", adjusted},
        {"output_path", points},
        {"num_threads", threads}},
       true,
       {points, In(w, "dense/points.json")},
       {}});
  const std::string edited = In(w, "dense/points_edited.ply");
  add({"edit",
       "bayon",
       "edit",
       {{"input_path", points},
        {"output_path", edited},
        {"report_path", In(w, "dense/edit.json")},
        {"num_threads", threads}},
       true,
       {edited},
       {}});
  const std::string mesh = In(w, "mesh/mesh.ply");
  add({"mesh",
       "bayon",
       "mesh",
       // The oriented model gives delaunay_graph_cut its rays.
       {{"input_path", edited},
        {"sparse_path", adjusted},
        {"output_path", mesh},
        {"report_path", In(w, "mesh/mesh.json")},
        {"num_threads", threads}},
       true,
       {mesh},
       {}});
  add({"texture",
       "bayon",
       "texture",
       {{"workspace_path", w},
        {"image_path", c.image_path},
        {"database_path", c.database},
        {"input_path", adjusted},
        {"mesh_path", mesh},
        {"output_path", In(w, "model")},
        {"num_threads", threads}},
       true,
       {In(w, "model/texture.json")},
       {}});
  add({"render",
       "bayon",
       "render",
       // The oriented model is read only for --viewpoints stations.
       {{"model_path", In(w, "model/model.glb")},
        {"output_path", In(w, "renders")},
        {"input_path", adjusted},
        {"database_path", c.database},
        {"num_threads", threads}},
       true,
       {In(w, "renders")},
       {}});
  add({"viewer",
       "bayon",
       "viewer",
       {{"model_path", In(w, "model/model.glb")},
        {"output_path", In(w, "viewer")}},
       true,
       {In(w, "viewer/index.html")},
       {}});
  if (s.compare_colmap == "1") {
    Options compare = {{"workspace_path", w},
                       {"image_path", c.image_path},
                       {"num_threads", threads}};
    // A calibrated camera given to bayon's import is given to COLMAP too
    // (held fixed there), so that both know the same.
    const auto import = config.stage_options.find("import");
    if (import != config.stage_options.end()) {
      for (const auto& [key, value] : import->second) {
        if (key == "camera_model" || key == "camera_params") {
          SetOption(&compare, key, value);
        }
      }
    }
    if (fs::is_directory(In(w, "gt"))) {
      SetOption(&compare, "ground_truth_path", In(w, "gt"));
    }
    add({"compare_colmap",
         "bayon",
         "compare_colmap",
         compare,
         true,
         {In(w, "colmap/comparison.json")},
         {}});
  }
  if (fs::is_directory(In(w, "gt"))) {
    // gt/ is a synthetic workspace's truth (with the true surface and
    // held-out views) or a benchmark's cameras (import_ground_truth).
    Options evaluate = {{"ground_truth_path", In(w, "gt")},
                        {"input_path", adjusted},
                        {"output_path", In(w, "evaluation.json")},
                        {"num_threads", threads}};
    if (fs::exists(In(w, "gt/surface.ply"))) {
      SetOption(&evaluate, "cloud_path", points);
      SetOption(&evaluate, "mesh_path", mesh);
    }
    // A truth rendered with no held-out views (synth --num_heldout_views
    // 0) has an empty gt/heldout: nothing to compare renders with.
    if (fs::is_directory(In(w, "gt/heldout")) &&
        ReadModel(In(w, "gt/heldout")).images.size() > 0) {
      // evaluate reads the textured model as PLY (its TextureFile comment
      // names the atlas).
      SetOption(&evaluate, "textured_mesh_path", In(w, "model/model.ply"));
    }
    add({"evaluate",
         "bayon",
         "evaluate",
         evaluate,
         false,
         {In(w, "evaluation.json")},
         {}});
  }
  add({"report",
       "bayon",
       "report",
       {{"workspace_path", w}},
       true,
       {In(w, "report.html")},
       {}});

  for (Stage& stage : stages) {
    const auto section = config.stage_options.find(stage.name);
    if (stage.program == "bayon" && section != config.stage_options.end()) {
      for (const auto& [k, v] : section->second)
        SetOption(&stage.options, k, v);
    }
    if (stage.program == "colmap") {
      const auto colmap = s.colmap_options.find(stage.command);
      if (colmap != s.colmap_options.end()) {
        for (const auto& [k, v] : colmap->second) {
          SetOption(&stage.options, k, v);
        }
      }
    }
  }
  return stages;
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

// The in-process entry point of a bayon stage.
int RunBayonCommand(const std::string& command,
                    const std::vector<std::string>& words) {
  static const std::map<std::string, int (*)(int, char**)> kRun = {
      {"import", RunImport},
      {"interior", RunInterior},
      {"targets", RunTargets},
      {"features", RunFeatures},
      {"match", RunMatch},
      {"relative", RunRelative},
      {"disparity", RunDisparity},
      {"tiepoints", RunTiePoints},
      {"strip", RunStripCommand},
      {"adjust", RunAdjust},
      {"dense", RunDense},
      {"edit", RunEdit},
      {"mesh", RunMesh},
      {"texture", RunTexture},
      {"render", RunRender},
      {"viewer", RunViewer},
      {"compare_colmap", RunCompareColmap},
      {"evaluate", RunEvaluate},
      {"report", RunReport}};
  // words[0] is "bayon": the command function sees argv[0] = its name.
  std::vector<std::string> args(words.begin() + 1, words.end());
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  return kRun.at(command)(static_cast<int>(args.size()), argv.data());
}

// The newest modification time of a file, or of a folder and everything in
// it (a photograph replaced in the image folder counts as a change).
std::optional<fs::file_time_type> NewestTime(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  fs::file_time_type newest = fs::last_write_time(path, ec);
  if (fs::is_directory(path, ec)) {
    for (const auto& entry : fs::recursive_directory_iterator(path, ec)) {
      const fs::file_time_type t = entry.last_write_time(ec);
      if (!ec) newest = std::max(newest, t);
    }
  }
  return newest;
}

std::string StampPath(const Context& c, const std::string& stage) {
  return In(In(c.workspace, "pipeline"), stage + ".done");
}

// Why the stage must run, or empty when its stamp says it is complete and
// nothing it depends on changed since.
std::string WhyRun(const Stage& stage,
                   const std::vector<std::string>& words,
                   const Context& c,
                   const std::optional<fs::file_time_type>& previous_stamp) {
  const std::string stamp_path = StampPath(c, stage.name);
  std::ifstream file(stamp_path);
  if (!file) return "not run yet";
  nlohmann::json stamp;
  try {
    stamp = nlohmann::json::parse(file);
  } catch (const std::exception&) {
    return "its stamp is unreadable";
  }
  if (stamp.value("command", std::vector<std::string>()) != words) {
    return "its options changed";
  }
  for (const std::string& output : stage.outputs) {
    if (!fs::exists(output)) return output + " is missing";
  }
  const fs::file_time_type done = fs::last_write_time(stamp_path);
  if (previous_stamp && *previous_stamp > done) {
    return "an earlier stage ran since";
  }
  for (const std::string& input : stage.inputs) {
    const auto t = NewestTime(input);
    if (t && *t > done) return input + " changed since";
  }
  return std::string();
}

std::string FormatSeconds(double seconds) {
  std::ostringstream out;
  if (seconds < 60) {
    out << std::fixed << std::setprecision(1) << seconds << " s";
  } else {
    out << static_cast<int>(seconds) / 60 << " min " << std::setw(2)
        << std::setfill('0') << static_cast<int>(seconds) % 60 << " s";
  }
  return out.str();
}

// Runs a stock COLMAP stage; the mapper's largest model is copied to the
// stage's output (COLMAP numbers its models 0, 1, ...).
void RunColmapStage(const Stage& stage, const Context& c) {
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
  run.log_path = WorkspaceLogPath(c.workspace, "colmap_" + stage.command);
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

// Temporary files of the stage's outputs left by an interrupted run (the
// atomic writes' "<name>.tmp-<pid>-<n>"): they were never complete.
void RemoveStaleTemporaries(const Stage& stage) {
  std::error_code ec;
  for (const std::string& output : stage.outputs) {
    const fs::path path(output);
    const fs::path folder = path.parent_path();
    if (!fs::is_directory(folder, ec)) continue;
    const std::string prefix = path.filename().string() + ".tmp-";
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      if (entry.path().filename().string().rfind(prefix, 0) == 0) {
        fs::remove_all(entry.path(), ec);
      }
    }
  }
}

struct StageRun {
  std::string name, program, status;  // ran | skipped | failed | not selected
  double seconds = 0;
  std::vector<std::string> command;
  std::string reason;
};

void WriteRunJson(const Context& c,
                  const std::string& config,
                  const std::vector<StageRun>& runs,
                  double total_seconds) {
  nlohmann::ordered_json json;
  json["workspace_path"] = fs::absolute(c.workspace).string();
  json["image_path"] = fs::absolute(c.image_path).string();
  json["config"] = config;
  json["stages"] = nlohmann::ordered_json::array();
  for (const StageRun& run : runs) {
    nlohmann::ordered_json entry;
    entry["name"] = run.name;
    entry["program"] = run.program;
    entry["status"] = run.status;
    entry["seconds"] = run.seconds;
    entry["command"] = run.command;
    if (!run.reason.empty()) entry["reason"] = run.reason;
    json["stages"].push_back(entry);
  }
  json["total_seconds"] = total_seconds;
  WriteFileAtomically(In(c.workspace, "pipeline.json"), json.dump(2) + "\n");
}

// Each stage checks its options (CommandLine::SetCheckOnly) before any
// stage runs: a misspelt key in a config stops the run at once.
void CheckStageOptions(const std::vector<Stage>& stages,
                       const std::string& config) {
  // Back to running the stages however this ends.
  struct CheckOnly {
    CheckOnly() { CommandLine::SetCheckOnly(true); }
    ~CheckOnly() { CommandLine::SetCheckOnly(false); }
  } check_only;
  for (const Stage& stage : stages) {
    if (stage.program != "bayon") continue;
    try {
      RunBayonCommand(stage.command, CommandWords(stage, true));
    } catch (const CLI::ParseError& error) {
      ThrowInputError(config.empty() ? "pipeline" : config,
                      ": stage ",
                      stage.name,
                      ": ",
                      error.what());
    }
  }
}

}  // namespace

int RunPipeline(int argc, char** argv) {
  CommandLine command("pipeline",
                      "Runs every stage in order, from photographs to the "
                      "textured model and its report, skipping stages whose "
                      "outputs are complete and newer than their inputs.");
  CLI::App& app = command.app();
  // The pipeline's --config has sections per stage, not this command's own
  // options, so it is read here rather than by CLI11.
  app.set_config();
  Context c;
  std::vector<std::string> config_paths;
  std::string from_stage, to_stage;
  bool force = false;
  int compare_colmap = -1;
  app.add_option("--workspace_path", c.workspace, "Workspace folder (created)")
      ->required();
  app.add_option("--image_path",
                 c.image_path,
                 "Folder of the photographs (default: <workspace>/images); "
                 "never modified");
  app.add_option("--config",
                 config_paths,
                 "INI/TOML with a section per stage ([dense] num_masters = 5) "
                 "and [pipeline] (features = colmap_sift, sparse = "
                 "colmap_mapper, compare_colmap = 1); several: later ones win")
      ->check(CLI::ExistingFile);
  app.add_option("--from_stage",
                 from_stage,
                 "Run from this stage on, even where up to date; earlier "
                 "stages are left as they are");
  app.add_option("--to_stage", to_stage, "Stop after this stage");
  app.add_option("--force", force, "1: run every selected stage again");
  app.add_option("--compare_colmap",
                 compare_colmap,
                 "1: also run stock COLMAP and compare (overrides the "
                 "config's [pipeline] compare_colmap)")
      ->check(CLI::Range(0, 1));
  app.add_option("--num_threads", c.num_threads, "Threads for every stage")
      ->check(CLI::Range(1, 1024));
  if (!command.Parse(argc, argv)) return 0;

  for (const std::string* stage : {&from_stage, &to_stage}) {
    if (!stage->empty() && !IsStageName(*stage)) {
      ThrowInputError("--from_stage/--to_stage: unknown stage '", *stage, "'");
    }
  }
  Config config = ReadConfigs(config_paths);
  if (compare_colmap >= 0) {
    config.settings.compare_colmap = std::to_string(compare_colmap);
  }
  if (c.image_path.empty()) c.image_path = In(c.workspace, "images");
  CheckDirectoryExists(c.image_path, "--image_path");
  const size_t num_images = ListImages(c.image_path).size();
  if (num_images == 0) {
    ThrowInputError(c.image_path,
                    ": no images found (looked for jpg, png, tif, bmp, "
                    "pgm/ppm, webp, jp2, exr, hdr)");
  }
  c.image_path = fs::absolute(c.image_path).lexically_normal().string();
  c.workspace = fs::absolute(c.workspace).lexically_normal().string();
  c.database = In(c.workspace, "database.db");
  if (fs::is_directory(In(c.workspace, "control"))) {
    c.control = In(c.workspace, "control");
  }
  const std::vector<Stage> stages = MakeStages(c, config);
  auto index_of = [&](const std::string& name) {
    for (size_t i = 0; i < stages.size(); ++i) {
      if (stages[i].name == name) return static_cast<int>(i);
    }
    ThrowInputError("stage ", name, " is not part of this pipeline's run");
  };
  const int first = from_stage.empty() ? 0 : index_of(from_stage);
  const int last = to_stage.empty() ? static_cast<int>(stages.size()) - 1
                                    : index_of(to_stage);
  if (first > last) {
    ThrowInputError(
        "--from_stage ", from_stage, " comes after --to_stage ", to_stage);
  }
  CheckStageOptions(stages, config.description);
  // Matching and everything after it need a second photograph.
  if (num_images < 2 && stages[last].name != "import" &&
      stages[last].name != "interior" && stages[last].name != "features") {
    ThrowInputError(c.image_path,
                    ": one image; a model needs two or more overlapping "
                    "photographs (--to_stage features stops before matching)");
  }

  // Every stage logs in full to W/logs/<stage>.log; the terminal shows the
  // pipeline's progress, the stages' progress bars, summaries and warnings.
  FLAGS_logtostderr = false;
  FLAGS_stderrthreshold = google::GLOG_WARNING;
  for (int severity = 0; severity < google::NUM_SEVERITIES; ++severity) {
    google::SetLogDestination(severity, "");
  }
  fs::create_directories(In(c.workspace, "pipeline"));
  // One run per workspace: a second would run the same stages into the
  // same files.
  const FileLock lock(In(c.workspace, "pipeline/lock"),
                      StrCat("workspace ", c.workspace));
  command.StartLog(WorkspaceLogPath(c.workspace, "pipeline"));
  LOG(INFO) << "config: "
            << (config.description.empty() ? "(built-in defaults)"
                                           : config.description);

  const auto start = std::chrono::steady_clock::now();
  auto seconds_since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
        .count();
  };
  auto elapsed = [&] { return seconds_since(start); };
  std::vector<StageRun> runs;
  std::optional<fs::file_time_type> previous_stamp;
  const int num_selected = last - first + 1;
  bool ran_any = false;
  for (int i = 0; i < static_cast<int>(stages.size()); ++i) {
    const Stage& stage = stages[i];
    StageRun run;
    run.name = stage.name;
    run.program = stage.program;
    if (i < first || i > last) {
      run.status = "not selected";
      runs.push_back(run);
      if (const auto t = NewestTime(StampPath(c, stage.name)))
        previous_stamp = t;
      continue;
    }
    const std::vector<std::string> words = CommandWords(stage, true);
    run.command = words;
    std::string why = WhyRun(stage, words, c, previous_stamp);
    if (force || (i == first && !from_stage.empty())) {
      why = force ? "--force" : "--from_stage";
    } else if (ran_any && why.empty()) {
      why = "an earlier stage ran";
    }
    const std::string counter =
        StrCat("[", i - first + 1, "/", num_selected, "] ");
    if (why.empty()) {
      std::cout << "pipeline: " << counter << stage.name
                << ": up to date, skipped" << std::endl;
      run.status = "skipped";
      runs.push_back(run);
      previous_stamp = NewestTime(StampPath(c, stage.name));
      continue;
    }
    std::cout << "pipeline: " << counter << stage.name << " (" << why << "), "
              << FormatSeconds(elapsed()) << " so far" << std::endl;
    LOG(INFO) << "stage " << stage.name << ": " << why;
    fs::remove(StampPath(c, stage.name));
    RemoveStaleTemporaries(stage);
    const auto stage_start = std::chrono::steady_clock::now();
    // A stage that fails is recorded in pipeline.json before the run stops:
    // bad input (exit 2, the stage named), or nothing usable (exit 1).
    auto record_failure = [&](const std::string& reason) {
      run.seconds = seconds_since(stage_start);
      run.status = "failed";
      run.reason = reason;
      runs.push_back(run);
      WriteRunJson(c, config.description, runs, elapsed());
    };
    std::string failure;
    try {
      if (stage.program == "colmap") {
        RunColmapStage(stage, c);
      } else if (RunBayonCommand(stage.command, words) != 0) {
        failure = "produced nothing usable (exit 1)";
      }
    } catch (const InputError& error) {
      record_failure(error.what());
      ThrowInputError("stage ", stage.name, ": ", error.what());
    } catch (const std::exception& error) {
      failure = error.what();
    }
    if (!failure.empty()) {
      record_failure(failure);
      std::cerr << "pipeline: stage " << stage.name << " failed: " << failure
                << "; its log is in " << In(c.workspace, "logs") << std::endl;
      return 1;
    }
    run.seconds = seconds_since(stage_start);
    nlohmann::ordered_json stamp;
    stamp["command"] = words;
    stamp["seconds"] = run.seconds;
    WriteFileAtomically(StampPath(c, stage.name), stamp.dump(2) + "\n");
    previous_stamp = NewestTime(StampPath(c, stage.name));
    ran_any = true;
    run.status = "ran";
    runs.push_back(run);
    // After every stage, so that later stages (compare_colmap, report) and
    // an interrupted run's reader see the times so far.
    WriteRunJson(c, config.description, runs, elapsed());
    std::cout << "pipeline: " << counter << stage.name << " done in "
              << FormatSeconds(run.seconds) << std::endl;
  }
  const double total = elapsed();
  WriteRunJson(c, config.description, runs, total);

  std::ostringstream table;
  table << "\n  stage            program  status         time\n";
  int num_ran = 0, num_skipped = 0;
  for (const StageRun& run : runs) {
    if (run.status == "not selected") continue;
    num_ran += run.status == "ran";
    num_skipped += run.status == "skipped";
    table << "  " << std::left << std::setw(17) << run.name << std::setw(9)
          << run.program << std::setw(10) << run.status << std::right
          << std::setw(10)
          << (run.status == "ran" ? FormatSeconds(run.seconds) : "-") << "\n";
  }
  std::cout << table.str() << std::endl;
  // Where the products are, those this run (or an earlier one) made.
  std::string products;
  for (const auto& [label, path] :
       std::vector<std::pair<std::string, std::string>>{
           {"report", "report.html"},
           {"model", "model/model.glb"},
           {"viewer", "viewer/index.html"}}) {
    if (fs::exists(In(c.workspace, path))) {
      products += StrCat("; ", label, ": ", In(c.workspace, path));
    }
  }
  command.PrintSummary(
      StrCat(num_ran,
             " stages ran, ",
             num_skipped,
             " up to date, in ",
             FormatSeconds(total),
             products.empty() ? StrCat(" -> ", c.workspace) : products));
  return 0;
}

}  // namespace bayon
