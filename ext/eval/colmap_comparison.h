// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// Stock COLMAP (CPU SIFT, exhaustive or sequential matching, mapper) on the
// photographs of a bayon workspace, in its own folder W/colmap/, set beside
// bayon's model: images registered, 3D points, observations, track length,
// reprojection errors and sigma0 of each model (model_statistics.h), the
// agreement of their cameras after a 7-parameter similarity, the runtime of
// every stage, and with a truth each model against it (sparse_eval.h).
// `bayon compare_colmap` runs it and writes W/colmap/comparison.json and
// comparison.txt.
//
// W/colmap/colmap.json, written last, records a finished COLMAP run (stage
// times, the model); a complete earlier run is reused unless overwrite.

#include "ext/core/option_registry.h"
#include "ext/core/scene.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct CompareColmapOptions {
  std::string workspace_path;
  // Default: the image_path of W/pipeline.json, else W/images.
  std::string image_path;
  // Default: W/sparse/adjusted.
  std::string bayon_model_path;
  // A COLMAP model or a synthetic workspace's gt/ folder; empty: no truth.
  std::string ground_truth_path;
  // COLMAP's matcher: "exhaustive" or "sequential" (images sorted by name,
  // each matched with its num_neighbors successors).
  std::string matching = "exhaustive";
  int num_neighbors = 10;
  // COLMAP's camera model for the one camera all images share.
  std::string camera_model = "SIMPLE_RADIAL";
  // The camera's parameters (COLMAP's order, comma separated) where bayon
  // was given a calibrated camera: COLMAP gets the same, held fixed in its
  // bundle adjustment, so that both sides know the same. Empty: COLMAP
  // calibrates the camera itself, as bayon did.
  std::string camera_params;
  // SIFT works on images downsampled to this long side (pixels).
  int max_image_size = 3200;
  int num_threads = -1;  // -1 = all cores
  // Run COLMAP again even where W/colmap holds a complete earlier run.
  bool overwrite = false;

  // Refuses bad values with one line naming the option.
  void Register(OptionRegistry* registry);
  void Check() const;

  bool calibrated() const { return !camera_params.empty(); }
  std::string MatcherCommand() const { return matching + "_matcher"; }
};

// What `bayon pipeline` recorded: the image folder (W/pipeline.json) and
// the time of every sparse stage. A stage's time is that of the run that
// made its current output: its stamp W/pipeline/<stage>.done where there is
// one (pipeline.json says 0 s for a stage it skipped as up to date, and is
// written only at the end of a run, after compare_colmap), else
// pipeline.json's entry if that stage ran. Absent for a workspace built by
// hand.
struct PipelineRecord {
  bool present = false;
  std::string image_path;
  nlohmann::ordered_json stage_seconds = nlohmann::ordered_json::object();
  nlohmann::ordered_json total_seconds = nullptr;  // of the sparse stages
  nlohmann::ordered_json pipeline_total_seconds =
      nullptr;  // the whole recorded run
  // The camera bayon's import was given (its --camera_model and
  // --camera_params), empty where it was not.
  std::string camera_model, camera_params;
};

// What `bayon pipeline` recorded in the workspace; `present` is false for a
// workspace built by hand.
PipelineRecord ReadPipelineRecord(const std::filesystem::path& workspace);

// The image folder: the one in W/pipeline.json, else W/images.
std::string DefaultImagePath(const std::filesystem::path& workspace,
                             const PipelineRecord& pipeline);

// ---------------------------------------------------------------------------
// COLMAP in W/colmap/.

struct ColmapRun {
  bool reused = false;
  nlohmann::ordered_json record;  // colmap.json
  std::string model_path;         // empty: the mapper registered nothing
  std::string mapper_message;     // why there is no model
};

// COLMAP's run in colmap_dir: a finished earlier one with the same options
// (reused), or a new one (the folder cleared first).
ColmapRun RunOrReuseColmap(const CompareColmapOptions& options,
                           const std::filesystem::path& colmap_dir);

// The comparison as comparison.json holds it: both models' figures over the
// images of the folder, their agreement, and with a truth both against it.
nlohmann::ordered_json CompareModels(
    const CompareColmapOptions& options,
    const std::filesystem::path& workspace,
    const PipelineRecord& pipeline,
    const std::vector<std::string>& image_names,
    const Scene& bayon_model,
    const ColmapRun& run,
    const std::string& colmap_model_path,
    const Scene& colmap_model,
    const std::optional<Scene>& truth);

// comparison.txt: the comparison as a table.
std::string ComparisonTable(const nlohmann::ordered_json& comparison);

// What the comparison reads before COLMAP runs, each checked.
struct ComparisonInputs {
  std::filesystem::path workspace;  // absolute
  PipelineRecord pipeline;
  Scene bayon_model;  // with its calibration.json where there is one
  std::vector<std::string> image_names;
  std::optional<Scene> truth;
};

// Reads the workspace, bayon's model, the photographs and the truth, and
// fills the options' defaults from them. COLMAP knows what bayon knew: the
// calibrated camera bayon's import was given (pipeline.json) unless
// `camera_params_given` (the command named one, or none with "").
ComparisonInputs ReadComparisonInputs(CompareColmapOptions* options,
                                      bool camera_params_given,
                                      bool camera_model_given);

struct ComparisonOutcome {
  ColmapRun run;
  nlohmann::ordered_json comparison;
  std::string table;      // ComparisonTable
  std::string json_path;  // <workspace>/colmap/comparison.json
  // Why COLMAP's column is empty (the mapper made no model); empty when it
  // is not.
  std::string failure;
};

// Runs COLMAP in <workspace>/colmap (or reuses its finished run), sets its
// model beside bayon's and writes comparison.json and comparison.txt.
ComparisonOutcome RunComparison(const CompareColmapOptions& options,
                                const ComparisonInputs& inputs);

// The command's summary line.
std::string ComparisonSummary(const nlohmann::ordered_json& comparison,
                              bool reused,
                              const std::string& output);

}  // namespace bayon
