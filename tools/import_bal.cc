// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/bal_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/scene_database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

int RunImportBal(int argc, char** argv) {
  std::string input_path, output_path, log_path;
  bool overwrite = false;
  CommandLine command(
      "import_bal",
      "A Bundle Adjustment in the Large problem as a workspace: database.db "
      "(one RADIAL camera per BAL camera, the observations as keypoints, "
      "matches of the tracks) and the model sparse/0, so that bayon adjust "
      "and colmap bundle_adjuster run the same problem.");
  CLI::App& app = command.app();
  app.add_option("--input_path", input_path, "BAL problem (text)")->required();
  app.add_option("--output_path", output_path, "Workspace folder to create")
      ->required();
  app.add_option("--overwrite", overwrite, "Replace an existing workspace");
  app.add_option("--log_path", log_path, "Append the log to this file");
  if (!command.Parse(argc, argv)) return 0;
  CheckFileExists(input_path, "--input_path");
  CheckOutputPath(output_path, overwrite);
  command.StartLog(log_path);

  const Scene scene = ReadBalProblem(input_path);
  OutputDirectory output(output_path, overwrite);
  fs::create_directories(output.File("images"));
  fs::create_directories(output.File("sparse/0"));
  WriteModel(scene, output.File("sparse/0"), ModelFormat::kBinary);
  {
    Database database(output.File("database.db"), Database::Mode::kCreate);
    ImportSceneIntoDatabase(scene, SceneImportOptions(), &database);
  }
  output.Commit();
  const SceneStats stats = scene.Stats();
  command.PrintSummary(StrCat(stats.num_images,
                              " cameras, ",
                              stats.num_points3D,
                              " points, ",
                              stats.num_observations,
                              " observations, ",
                              "mean reprojection error ",
                              stats.mean_reprojection_error_px,
                              " px -> ",
                              output_path));
  return 0;
}

}  // namespace bayon
