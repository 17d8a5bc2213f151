// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/ground_truth_import.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunImportGroundTruth(int argc, char** argv) {
  GroundTruthImportOptions options;
  std::string format_name, output_path, log_path;
  bool overwrite = false;
  CommandLine command(
      "import_ground_truth",
      "The calibrated cameras of a benchmark image set (Middlebury *_par.txt, "
      "Strecha *.camera) as a COLMAP text model (cameras and poses, no "
      "points), image names kept, ids from the sorted names, for bayon "
      "evaluate --ground_truth_path.");
  CLI::App& app = command.app();
  app.add_option("--format", format_name, "middlebury or strecha")->required();
  app.add_option("--input_path",
                 options.input_path,
                 "Middlebury: the *_par.txt file; Strecha: the folder of "
                 "*.camera files (or one file)")
      ->required();
  command.AddOptions(&options);
  app.add_option("--output_path", output_path, "Model folder to create")
      ->required();
  app.add_option("--overwrite", overwrite, "Replace an existing model folder");
  app.add_option("--log_path", log_path, "Append the log to this file");
  if (!command.Parse(argc, argv)) return 0;
  const auto format = GroundTruthFormatFromName(format_name);
  if (!format) {
    ThrowInputError(
        "--format '", format_name, "' is unknown (known: middlebury, strecha)");
  }
  options.format = *format;
  options.Check();
  if (options.format == GroundTruthFormat::kMiddlebury) {
    CheckFileExists(options.input_path, "--input_path");
  }
  if (!options.image_path.empty()) {
    CheckDirectoryExists(options.image_path, "--image_path");
  }
  CheckOutputPath(output_path, overwrite);
  command.StartLog(log_path);

  const Scene scene = ImportGroundTruth(options);
  OutputDirectory output(output_path, overwrite);
  WriteModel(scene, output.temp_path(), ModelFormat::kText);
  output.Commit();
  std::string cameras;
  for (const auto& [camera_id, camera] : scene.cameras) {
    cameras += StrCat(cameras.empty() ? "" : "; ",
                      camera.ModelName(),
                      " ",
                      camera.width,
                      "x",
                      camera.height,
                      " ",
                      camera.ParamsToString());
  }
  command.PrintSummary(
      StrCat(scene.images.size(),
             " images, ",
             scene.cameras.size(),
             scene.cameras.size() == 1 ? " camera (" : " cameras (",
             cameras,
             ") from ",
             GroundTruthFormatName(options.format),
             " ",
             options.input_path,
             " -> ",
             output_path));
  return 0;
}

}  // namespace bayon
