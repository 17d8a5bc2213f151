// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/calibration_json.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/progress.h"
#include "ext/georef/crs.h"
#include "ext/mesh/mesh_io.h"
#include "ext/render/model_export.h"
#include "ext/texture/texture_mapping.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

int RunTexture(int argc, char** argv) {
  OrientedInput in;
  std::string mesh_path, output_path, log_path;
  TextureOptions options;
  ModelExportOptions export_options;
  CommandLine command(
      "texture",
      "View-dependent texture mapping (the Bayon paper's sec. 3.5): the "
      "photographs' exposures and white balances balanced (a gain and offset "
      "per photograph and channel over their overlaps; or the paper's high "
      "pass and histogram equalisation, or Wallis), every triangle's "
      "visibility in every photograph, its geometrically optimal image "
      "(largest projected area), the texture averaged over all photographs "
      "that see it with weights area_j / area_max, each transformed affinely "
      "into the optimal image's geometry, and the chart borders levelled. "
      "Writes a texture atlas (PNG) with the model as OBJ + MTL, PLY, VRML "
      "2.0 and glTF binary, and texture.json.");
  CLI::App& app = command.app();
  in.AddOptions(app,
                "Workspace: defaults images/, sparse/adjusted, database.db, "
                "mesh/mesh.ply and model/ under it");
  app.add_option("--mesh_path", mesh_path, "Mesh to texture (PLY, OBJ, OFF)");
  app.add_option("--output_path", output_path, "Folder of the textured model");
  command.AddOptions(&export_options);
  command.AddOptions(&options);
  bool overwrite = false;
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <workspace>/logs/texture.log)");
  if (!command.Parse(argc, argv)) return 0;
  if (in.ApplyWorkspace()) {
    if (mesh_path.empty()) mesh_path = in.workspace_path + "/mesh/mesh.ply";
    if (output_path.empty()) output_path = in.workspace_path + "/model";
  }
  if (in.image_path.empty() || in.input_path.empty() || mesh_path.empty() ||
      output_path.empty()) {
    ThrowInputError(
        "give --workspace_path, or --image_path, --input_path, --mesh_path "
        "and --output_path");
  }
  options.Check();
  export_options.Check();
  in.Check();
  CheckFileExists(mesh_path, "--mesh_path");
  const std::string report_path = output_path + "/texture.json";
  CheckOutputPath(report_path, overwrite);
  for (const std::string& name : export_options.FileNames()) {
    CheckOutputPath(output_path + "/" + name, overwrite);
  }
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(
        WorkspaceOfStageFile(output_path + "/texture.json"), "texture");
  }
  command.StartLog(log_path);

  const Scene scene = ReadOrientedModel(in.input_path, in.database_path);
  const TriangleMesh mesh = ReadMesh(mesh_path);
  Timer timer;
  const std::vector<TextureImage> images =
      LoadTextureImages(scene, in.image_path, options);
  const double seconds_load = timer.Seconds();
  TexturedMesh textured = MapTexture(mesh, images, options);
  // A georeferenced model says in its .glb where it lies (and beside it,
  // crs.json, below).
  const std::optional<GeoFrame> frame = ReadModelGeoFrame(in.input_path);
  if (frame) export_options.georeference_json = GeoFrameJson(*frame);
  textured.report.seconds_load = seconds_load;
  fs::create_directories(output_path);
  // The files are written into a temporary folder and moved in when all are
  // complete: a full disk midway never leaves a new atlas beside an old
  // model (or a model without its texture.json).
  OutputDirectory staging(output_path, /*overwrite=*/true);
  std::vector<std::string> files;
  for (const std::string& file :
       WriteTexturedModel(TexturedModel{textured.mesh, textured.atlas},
                          staging.temp_path(),
                          export_options)) {
    files.push_back(
        (fs::path(output_path) / fs::path(file).filename()).string());
  }
  WriteFileAtomically(
      staging.File("texture.json"),
      TextureReportJson(textured.report, options, mesh_path, files)
              .dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
          "\n");
  for (const std::string& file : files) {
    const std::string name = fs::path(file).filename().string();
    fs::rename(staging.File(name), file);
  }
  fs::rename(staging.File("texture.json"), report_path);
  PlaceGeoFrame(frame, output_path);
  std::string written;
  for (const std::string& file : files) {
    written +=
        (written.empty() ? "" : ", ") + fs::path(file).filename().string();
  }
  command.PrintSummary(TextureSummary(textured.report) + "\n  -> " +
                       output_path + "/: " + written + ", texture.json");
  return 0;
}

}  // namespace bayon
