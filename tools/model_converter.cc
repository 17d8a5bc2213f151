// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

int RunModelConverter(int argc, char** argv) {
  std::string input_path, output_path, output_type;
  bool overwrite = false;
  CommandLine command("model_converter",
                      "Convert a COLMAP sparse model between binary, text and "
                      "a PLY point cloud, as `colmap model_converter` does.");
  CLI::App& app = command.app();
  app.add_option("--input_path", input_path, "Model folder (.bin or .txt)")
      ->required();
  app.add_option(
         "--output_path", output_path, "Output folder (BIN, TXT) or file (PLY)")
      ->required();
  app.add_option("--output_type", output_type, "BIN, TXT or PLY")
      ->required()
      ->transform(CLI::IsMember({"BIN", "TXT", "PLY"}, CLI::ignore_case));
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  if (!command.Parse(argc, argv)) return 0;
  CheckDirectoryExists(input_path, "--input_path");
  for (char& c : output_type) c = static_cast<char>(std::toupper(c));

  const Scene scene = ReadModel(input_path);
  if (output_type == "PLY") {
    CheckOutputPath(output_path, overwrite);
    WritePointsPly(scene, output_path);
  } else {
    const ModelFormat format =
        output_type == "BIN" ? ModelFormat::kBinary : ModelFormat::kText;
    const char* ext = format == ModelFormat::kBinary ? ".bin" : ".txt";
    std::error_code ec;
    if (fs::exists(output_path, ec) && !fs::is_directory(output_path, ec)) {
      ThrowInputError(output_path, ": exists and is not a folder");
    }
    for (const char* name : {"cameras", "images", "points3D"}) {
      CheckOutputPath(
          (fs::path(output_path) / (std::string(name) + ext)).string(),
          overwrite);
    }
    // The three files are written into a temporary folder and moved in
    // only when all are complete: a full disk or a kill midway never leaves
    // a new cameras file beside an old images file.
    OutputDirectory staging(output_path, /*overwrite=*/true);
    WriteModel(scene, staging.temp_path(), format);
    if (!fs::exists(output_path, ec)) {
      staging.Commit();
    } else {
      for (const char* name : {"cameras", "images", "points3D"}) {
        const std::string file = std::string(name) + ext;
        fs::rename(staging.File(file), fs::path(output_path) / file, ec);
        if (ec) ThrowInputError(output_path, "/", file, ": ", ec.message());
      }
    }
  }
  const SceneStats stats = scene.Stats();
  command.PrintSummary(StrCat(stats.num_cameras,
                              " cameras, ",
                              stats.num_images,
                              " images, ",
                              stats.num_points3D,
                              " points -> ",
                              output_path,
                              " (",
                              output_type,
                              ")"));
  return 0;
}

}  // namespace bayon
