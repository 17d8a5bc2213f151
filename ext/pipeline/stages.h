// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// The stages of `bayon pipeline`: their order, the configs that set their
// options, and each stage's command with the workspace's paths, the outputs
// that make it complete and the inputs outside the chain it depends on.
// stamps.h decides which stages must run; tools/pipeline.cc runs them.

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

// A command's options in order, as --key value pairs.
using StageOptions = std::vector<std::pair<std::string, std::string>>;

// Sets key to value: in its place where the key is there, else at the end.
void SetStageOption(StageOptions* options,
                    const std::string& key,
                    const std::string& value);

// Whether `name` is one of the pipeline's stages.
bool IsStageName(const std::string& name);

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
  std::map<std::string, StageOptions> colmap_options;
};

struct PipelineConfig {
  std::string description;  // the files read, for the summary
  PipelineSettings settings;
  std::map<std::string, StageOptions> stage_options;  // by stage name
};

// Reads the configs in order (later ones win): INI or TOML, one section per
// stage with the stage's own option names, [pipeline] for the settings above,
// and [feature_extractor] etc. for stock COLMAP's options (COLMAP's names,
// e.g. SiftExtraction.max_image_size). A key outside any section, an unknown
// section or an unknown [pipeline] key is an error naming the file.
PipelineConfig ReadPipelineConfigs(const std::vector<std::string>& paths);

struct Stage {
  std::string name;           // the pipeline's stage, e.g. "features"
  std::string program;        // "bayon" or "colmap"
  std::string command;        // the bayon or COLMAP command it runs
  StageOptions options;       // in order; the config's after the pipeline's own
  bool has_overwrite = true;  // pass --overwrite 1 when it runs again
  std::vector<std::string> outputs;  // must exist when the stage is complete
  // Outside the chain: images, control/. For COLMAP's mapper, outputs[0] is
  // the folder its largest model becomes.
  std::vector<std::string> inputs;
};

// The workspace's paths, as the pipeline resolved them.
struct PipelineContext {
  std::string workspace, image_path, database, control;
  int num_threads = 2;
};

// Makes the workspace and image paths absolute (the images by default in
// <workspace>/images) and finds the database and control/ in it; returns
// the number of photographs, refusing a folder without any.
size_t ResolveWorkspace(PipelineContext* c);

// The stages with the pipeline's paths; each stage's config section is
// applied on top (a key given there replaces the pipeline's value).
std::vector<Stage> MakeStages(const PipelineContext& c,
                              const PipelineConfig& config);

// The stage's command line: program, command, then --key value; with
// `overwrite`, --overwrite 1 where the command takes it.
std::vector<std::string> CommandWords(const Stage& stage, bool overwrite);

// Runs a stock COLMAP stage, its log to `log_path`; the mapper's largest
// model is copied to the stage's output (COLMAP numbers its models 0, 1,
// ...).
void RunColmapStage(const Stage& stage, const std::string& log_path);

}  // namespace bayon
