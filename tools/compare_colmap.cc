// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon compare_colmap`: stock COLMAP on the photographs of a bayon
// workspace, in W/colmap/, set beside bayon's model
// (ext/eval/colmap_comparison.h). Prints the table and writes
// W/colmap/comparison.json and comparison.txt.
//
// W/database.db is only read (bayon's scanned frames, for its model); COLMAP
// works on W/colmap/database.db. When the mapper makes no model (it
// registers nothing, or fewer images than its minimum model size) the
// comparison is still written, with COLMAP's column at 0 registered and no
// figures (null) beside it, and the command exits 1.
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/colmap_comparison.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

int RunCompareColmap(int argc, char** argv) {
  CompareColmapOptions options;
  CommandLine command(
      "compare_colmap",
      "Run stock COLMAP (CPU SIFT, exhaustive or sequential matching, "
      "mapper) on the images of a bayon workspace in <workspace>/colmap/ and "
      "set its model beside bayon's: registered images, points, "
      "observations, track length, reprojection errors, sigma0, the "
      "agreement of the cameras, the time of every stage, and with "
      "--ground_truth_path both against the truth. Writes "
      "colmap/comparison.json and colmap/comparison.txt; reuses a finished "
      "earlier COLMAP run unless --overwrite 1. The workspace's database.db "
      "is not touched.");
  CLI::App& app = command.app();
  app.add_option("--workspace_path",
                 options.workspace_path,
                 "bayon workspace (after bayon pipeline)")
      ->required();
  app.add_option("--image_path",
                 options.image_path,
                 "Image folder (default: the one in <workspace>/pipeline.json, "
                 "else <workspace>/images)");
  app.add_option("--bayon_model_path",
                 options.bayon_model_path,
                 "bayon's model (default <workspace>/sparse/adjusted)");
  app.add_option("--ground_truth_path",
                 options.ground_truth_path,
                 "True COLMAP model or a synthetic workspace's gt/ folder");
  app.add_option("--matching", options.matching, "exhaustive or sequential")
      ->transform(CLI::IsMember({"exhaustive", "sequential"}));
  app.add_option("--num_neighbors",
                 options.num_neighbors,
                 "Sequential matching: successors matched with each image");
  app.add_option("--camera_model",
                 options.camera_model,
                 "COLMAP camera model of the one shared camera");
  app.add_option("--camera_params",
                 options.camera_params,
                 "The calibrated camera bayon was given (COLMAP's order): "
                 "COLMAP gets it too, held fixed; empty: both calibrate");
  app.add_option("--max_image_size",
                 options.max_image_size,
                 "COLMAP SIFT: longest image side in pixels");
  app.add_option("--num_threads", options.num_threads, "-1 = all cores");
  app.add_option("--overwrite",
                 options.overwrite,
                 "Run COLMAP again even where a finished run is in "
                 "<workspace>/colmap");
  if (!command.Parse(argc, argv)) return 0;

  // Everything is checked before COLMAP runs.
  CheckDirectoryExists(options.workspace_path, "--workspace_path");
  const fs::path workspace =
      fs::absolute(options.workspace_path).lexically_normal();
  const PipelineRecord pipeline = ReadPipelineRecord(workspace);
  // COLMAP knows what bayon knew: the calibrated camera bayon's import was
  // given (pipeline.json), unless the command line says otherwise.
  if (app.count("--camera_params") == 0 && !pipeline.camera_params.empty()) {
    options.camera_params = pipeline.camera_params;
    if (app.count("--camera_model") == 0 && !pipeline.camera_model.empty()) {
      options.camera_model = pipeline.camera_model;
    }
  }
  options.Check();
  if (options.bayon_model_path.empty()) {
    options.bayon_model_path = (workspace / "sparse" / "adjusted").string();
  }
  if (!fs::is_directory(options.bayon_model_path)) {
    ThrowInputError(options.bayon_model_path,
                    ": no bayon model to compare (run bayon pipeline first, "
                    "or give --bayon_model_path)");
  }
  // With its full calibration (calibration.json): the FULL_OPENCV cameras
  // of the COLMAP files cannot express every Brown/Beyer parameter (affinity
  // and shear), which would add their fit residual to bayon's errors.
  const std::string database = (workspace / "database.db").string();
  const Scene bayon_model = ReadOrientedModel(
      options.bayon_model_path, fs::exists(database) ? database : "");
  if (options.image_path.empty()) {
    options.image_path = DefaultImagePath(workspace, pipeline);
  }
  options.image_path = fs::absolute(options.image_path).string();
  const std::vector<std::string> image_names = ListImages(options.image_path);
  if (image_names.empty()) {
    ThrowInputError(options.image_path, ": image folder holds no images");
  }
  std::optional<Scene> truth;
  std::string truth_model_path;
  if (!options.ground_truth_path.empty()) {
    CheckDirectoryExists(options.ground_truth_path, "--ground_truth_path");
    const fs::path root(options.ground_truth_path);
    truth_model_path = fs::is_directory(root / "sparse")
                           ? (root / "sparse").string()
                           : root.string();
    truth = ReadModel(truth_model_path);
  }
  command.StartLog(WorkspaceLogPath(options.workspace_path, "compare_colmap"));

  const fs::path colmap_dir = workspace / "colmap";
  const ColmapRun run = RunOrReuseColmap(options, colmap_dir);
  if (run.reused) {
    std::printf(
        "COLMAP: reusing the finished run in %s (colmap.json; --overwrite 1 "
        "runs it again)\n",
        colmap_dir.string().c_str());
  }
  const std::string colmap_model_path =
      run.model_path.empty() ? "" : (colmap_dir / run.model_path).string();
  const Scene colmap_model =
      colmap_model_path.empty() ? Scene() : ReadModel(colmap_model_path);

  const Json c = CompareModels(options,
                               workspace,
                               pipeline,
                               image_names,
                               bayon_model,
                               run,
                               colmap_model_path,
                               colmap_model,
                               truth);
  const std::string table = ComparisonTable(c);
  std::printf("\n%s\n", table.c_str());
  const std::string json_path = (colmap_dir / "comparison.json").string();
  WriteFileAtomically(json_path, c.dump(2) + "\n");
  WriteFileAtomically((colmap_dir / "comparison.txt").string(), table);
  if (colmap_model_path.empty()) {
    throw RunFailure(StrCat("colmap mapper made no model (",
                            run.mapper_message,
                            "; log: ",
                            (colmap_dir / "mapper.log").string(),
                            "); the comparison, with COLMAP's column empty, "
                            "is in ",
                            json_path));
  }
  command.PrintSummary(ComparisonSummary(c, run.reused, json_path));
  return 0;
}

}  // namespace bayon
