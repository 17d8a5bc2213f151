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
#include <optional>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

int RunRender(int argc, char** argv) {
  std::string model_path, output_path, input_path, database_path, log_path;
  std::string modes_text = "wireframe,shaded,textured";
  std::string viewpoints_name = "orbit", stereo_text, stereo_mode_name;
  std::string anaglyph_name = "color", up_text = "0,0,1";
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
  app.add_option("--modes",
                 modes_text,
                 "Comma-separated: wireframe, shaded, textured (textured is "
                 "left out by default for a model without texture)");
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
  app.add_option("--num_views", orbit.num_views, "orbit: number of cameras");
  app.add_option("--elevation_deg",
                 orbit.elevation_deg,
                 "orbit: angle of the cameras above the model's centre");
  app.add_option("--start_azimuth_deg",
                 orbit.start_azimuth_deg,
                 "orbit: azimuth of the first camera (from x, counter-"
                 "clockwise seen from above; -90 = looking along +y)");
  app.add_option("--width", orbit.width, "orbit: image width in pixels");
  app.add_option("--height", orbit.height, "orbit: image height in pixels");
  app.add_option(
      "--fov_deg", orbit.fov_deg, "orbit: horizontal field of view (degrees)");
  app.add_option("--fill",
                 orbit.fill,
                 "orbit: share of the frame the model fills (0.05 to 1)");
  app.add_option("--up",
                 up_text,
                 "World vertical x,y,z (bayon's datum: z; with stations "
                 "viewpoints and no --up, the cameras' mean image up)");
  app.add_option("--stereo",
                 stereo_text,
                 "Comma-separated: anaglyph, side_by_side, interleaved "
                 "(default none)");
  app.add_option("--stereo_mode",
                 stereo_mode_name,
                 "Mode of the stereo images (default textured, shaded for a "
                 "model without texture)");
  app.add_option("--stereo_base",
                 options.stereo.base_m,
                 "Stereo base in metres (0 = 1/30 of the nearest model "
                 "distance)");
  app.add_option("--anaglyph_type", anaglyph_name, "color or gray")
      ->transform(CLI::IsMember({"color", "gray"}));
  app.add_option("--wireframe_on_shaded",
                 options.wireframe_on_shaded,
                 "1: wireframe lines on the shaded view instead of white");
  app.add_option("--supersampling",
                 options.supersampling,
                 "Samples per pixel along each axis (anti-aliasing)");
  app.add_option("--sun_elevation_deg",
                 options.sun_elevation_deg,
                 "shaded: sun above the horizontal (degrees)");
  app.add_option("--sun_azimuth_deg",
                 options.sun_azimuth_deg,
                 "shaded: sun to the left of the viewer's direction (degrees)");
  app.add_option("--num_threads", options.num_threads, "-1 = all cores");
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/render.log)");
  if (!command.Parse(argc, argv)) return 0;

  // Options and paths first, before any expensive work.
  const bool modes_given = app.count("--modes") > 0;
  options.modes.clear();
  try {
    for (const std::string& name : SplitList(modes_text)) {
      options.modes.push_back(ParseRenderMode(name));
    }
  } catch (const InputError& error) {
    ThrowInputError("--modes: ", error.what());
  }
  for (const std::string& name : SplitList(stereo_text)) {
    if (name == "anaglyph") {
      options.anaglyph = true;
    } else if (name == "side_by_side") {
      options.side_by_side = true;
    } else if (name == "interleaved") {
      options.interleaved = true;
    } else {
      ThrowInputError("--stereo: unknown stereo form '",
                      name,
                      "' (choose from anaglyph, side_by_side, interleaved)");
    }
  }
  std::optional<RenderMode> stereo_mode;
  if (!stereo_mode_name.empty()) {
    try {
      stereo_mode = ParseRenderMode(stereo_mode_name);
    } catch (const InputError& error) {
      ThrowInputError("--stereo_mode: ", error.what());
    }
  }
  options.anaglyph_type =
      anaglyph_name == "gray" ? AnaglyphType::kGray : AnaglyphType::kColor;
  options.up = ParseVector(up_text, "--up");
  orbit.up = options.up;
  orbit.Check();
  CheckFileExists(model_path, "--model_path");
  if (viewpoints_name == "stations") {
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
  if (!has_atlas) {
    auto textured = std::find(
        options.modes.begin(), options.modes.end(), RenderMode::kTextured);
    if (textured != options.modes.end()) {
      if (modes_given) {
        ThrowInputError(model_path,
                        ": the model has no texture, so there is no textured "
                        "mode (choose --modes wireframe,shaded)");
      }
      LOG(INFO) << model_path << " has no texture: textured mode left out";
      options.modes.erase(textured);
    }
  }
  options.stereo_mode = has_atlas ? RenderMode::kTextured : RenderMode::kShaded;
  if (stereo_mode) {
    options.stereo_mode = *stereo_mode;
    if (options.stereo_mode == RenderMode::kTextured && !has_atlas) {
      ThrowInputError(model_path,
                      ": the model has no texture, so no textured stereo "
                      "(choose --stereo_mode shaded or wireframe)");
    }
  }
  options.Check(has_atlas);

  const std::vector<Eigen::Vector3d>& points = model.mesh.vertices.positions;
  std::vector<Viewpoint> viewpoints;
  if (viewpoints_name == "stations") {
    const Scene scene = ReadOrientedModel(input_path, database_path);
    // A datum from relative orientation has no known vertical: without
    // --up, the photographer's (the mean of the cameras' image up, -y)
    // lights the shaded views from above.
    if (app.count("--up") == 0 && !scene.images.empty()) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (const auto& [image_id, image] : scene.images) {
        sum +=
            image.cam_from_world.rotation.inverse() * Eigen::Vector3d(0, -1, 0);
      }
      if (sum.norm() > 1e-6) options.up = sum.normalized();
    }
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
