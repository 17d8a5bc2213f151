// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/calibration_json.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"
#include "ext/render/model_export.h"
#include "ext/render/model_views.h"
#include "ext/render/views.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <glog/logging.h>

#include <filesystem>
#include <iomanip>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

int RunRender(int argc, char** argv) {
  std::string model_path, output_path, input_path, database_path, log_path;
  std::string viewpoints_name = "orbit";
  int max_image_size = 1600;
  bool overwrite = false;
  OrbitOptions orbit;
  ModelRenderOptions options;
  CommandLine command(
      "render",
      "Pictures of a model: hidden-line wireframe, shaded (grey, sun and "
      "shadows) and textured (the atlas, unlit) views from orbit viewpoints "
      "around it or from the photographs' stations, and stereo pairs (red-cyan "
      "anaglyphs, side by side, row-interleaved for polarised displays). "
      "Writes <mode>_<view>.png, anaglyph_<view>.png, side_by_side_<view>.png "
      "and interleaved_<view>.png into the output folder.");
  CLI::App& app = command.app();
  app.add_option("--model_path", model_path, "Model: .obj, .ply, .wrl or .glb")
      ->required();
  app.add_option("--output_path", output_path, "Folder for the images")
      ->required();
  app.add_option("--viewpoints", viewpoints_name, "orbit or stations")
      ->transform(CLI::IsMember({"orbit", "stations"}));
  app.add_option("--input_path",
                 input_path,
                 "stations: the sparse model (e.g. sparse/adjusted)");
  app.add_option("--database_path",
                 database_path,
                 "stations: database with the scanned frames' interior "
                 "orientations (optional)");
  app.add_option("--max_image_size",
                 max_image_size,
                 "stations: longer image side in pixels (0 = the camera's)");
  command.AddOptions(&orbit);
  command.AddOptions(&options);
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/render.log)");
  if (!command.Parse(argc, argv)) return 0;

  // Options and paths first, before any expensive work.
  orbit.up = options.up;
  orbit.Check();
  CheckFileExists(model_path, "--model_path");
  const bool stations = viewpoints_name == "stations";
  if (stations) {
    if (input_path.empty()) {
      ThrowInputError(
          "--viewpoints stations needs --input_path (a sparse "
          "model folder)");
    }
    CheckDirectoryExists(input_path, "--input_path");
    if (!database_path.empty()) {
      CheckFileExists(database_path, "--database_path");
    }
  }
  OutputDirectory output(output_path, overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(model_path), "render");
  }
  command.StartLog(log_path);

  const TexturedModel model = ReadTexturedModel(model_path);
  const bool has_atlas = !model.atlas.empty();
  options.FitToModel(model_path,
                     has_atlas,
                     app.count("--modes") > 0,
                     app.count("--stereo_mode") > 0);
  options.Check(has_atlas);

  const std::vector<Eigen::Vector3d>& points = model.mesh.vertices.positions;
  std::vector<Viewpoint> viewpoints;
  if (stations) {
    const Scene scene = ReadOrientedModel(input_path, database_path);
    // Without --up, the photographer's vertical lights the shaded views
    // from above.
    const Eigen::Vector3d image_up = MeanImageUp(scene);
    if (app.count("--up") == 0 && image_up.norm() > 0) options.up = image_up;
    viewpoints = StationViewpoints(scene, points, max_image_size);
    if (viewpoints.empty()) {
      ThrowInputError(input_path, ": no image of the model sees the model");
    }
  } else {
    viewpoints = OrbitViewpoints(points, orbit);
  }
  LOG(INFO) << model.mesh.NumFaces() << " faces, " << viewpoints.size() << " "
            << viewpoints_name << " viewpoints";

  const ModelRenderSummary summary =
      RenderModelViews(model,
                       viewpoints,
                       options,
                       [&](const std::string& name, const cv::Mat& image) {
                         WriteImage(output.File(name), image);
                       });
  output.Commit();

  std::ostringstream text;
  text << summary.num_views << " " << viewpoints_name << " views, "
       << summary.num_images << " images in " << std::fixed
       << std::setprecision(1) << summary.seconds << " s";
  if (options.HasStereo()) {
    text << std::setprecision(3) << "; stereo base " << summary.stereo_base_m
         << " m";
  }
  text << "\n  -> " << output_path;
  command.PrintSummary(text.str());
  return 0;
}

}  // namespace bayon
