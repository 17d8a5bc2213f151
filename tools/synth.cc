// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/synth/control_scene.h"
#include "ext/synth/points_scene.h"
#include "ext/synth/tower_workspace.h"
#include "ext/synth/workspace_writer.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {
namespace {

int RunTowerScene(TowerSceneOptions tower,
                  const std::string& output_path,
                  bool overwrite,
                  int image_width,
                  CommandLine* command) {
  CheckOption(image_width >= 60 && image_width % 3 == 0,
              "--image_width",
              ">= 60 and divisible by 3 (a 3:2 frame)",
              image_width);
  tower.camera.width = image_width;
  tower.camera.height = image_width * 2 / 3;
  tower.camera.pixel_pitch_mm = 36.0 / image_width;
  tower.Check();
  const TowerWorkspaceSummary summary =
      WriteTowerWorkspace(tower, output_path, overwrite);
  command->PrintSummary(StrCat("tower: ",
                               summary.num_images,
                               " images rendered in ",
                               summary.render_seconds,
                               " s (",
                               summary.total_seconds,
                               " s in all), ",
                               summary.num_targets,
                               " targets seen ",
                               summary.num_observations,
                               " times, surface of ",
                               summary.num_surface_faces,
                               " triangles, GSD ",
                               1000 * summary.gsd_m,
                               " mm -> ",
                               output_path));
  return 0;
}

}  // namespace

int RunSynth(int argc, char** argv) {
  std::string scene_name = "points";
  std::string output_path;
  bool overwrite = false;
  PointsSceneOptions points;
  SyntheticControlOptions control;
  bool nominal_calibration = false;
  TowerSceneOptions tower;
  int image_width = tower.camera.width;
  double control_sigma_m = 0;
  CommandLine command("synth",
                      "Write a synthetic workspace with known truth: the true "
                      "cameras, calibration and points (points scene) or "
                      "surface (tower scene) in gt/, and a COLMAP database.");
  CLI::App& app = command.app();
  app.add_option("--scene", scene_name, "Scene to make: points or tower")
      ->transform(CLI::IsMember({"points", "tower"}));
  app.add_option("--output_path", output_path, "Workspace folder to create")
      ->required();
  app.add_option("--overwrite", overwrite, "Replace an existing workspace");
  app.add_option("--num_views", points.num_views, "Camera stations");
  app.add_option("--seed", points.seed, "Random seed (same seed, same scene)");
  app.add_option("--num_points", points.num_points, "points scene: 3D points");
  app.add_option("--keypoint_noise_px",
                 points.keypoint_noise_px,
                 "points scene: observation noise, pixels (1 sigma)");
  app.add_option("--ring_radius_m",
                 points.ring_radius_m,
                 "points scene: distance of the stations from the axis");
  app.add_option("--distortion",
                 points.camera.distortion,
                 "1: a real lens (all additional parameters non-zero)");
  app.add_option("--alternate_roll_deg",
                 points.alternate_roll_deg,
                 "points scene: every other station turned about its axis");
  app.add_option("--max_view_angle_deg",
                 points.max_view_angle_deg,
                 "points scene: a point is seen within this angle of its "
                 "normal");
  app.add_option("--num_control_points",
                 control.num_control_points,
                 "control/: control points around the object");
  app.add_option(
      "--num_check_points", control.num_check_points, "control/: check points");
  app.add_option("--levelling_bar",
                 control.levelling_bar,
                 "control/: a vertical levelling bar (minimum datum)");
  CLI::Option* control_sigma =
      app.add_option("--control_sigma_m",
                     control_sigma_m,
                     "control/: standard deviation of the control coordinates "
                     "(points: 0 = fixed; tower default 0.002)");
  app.add_option("--nominal_calibration",
                 nominal_calibration,
                 "1: the database gets the nominal camera (additional "
                 "parameters zero), the truth stays in gt/");
  app.add_option("--tower_width_m",
                 tower.tower.width_m,
                 "tower scene: width of the lowest tier's walls");
  app.add_option("--tower_height_m",
                 tower.tower.height_m,
                 "tower scene: height above the platform, finial included");
  app.add_option("--relief_depth_m",
                 tower.tower.relief_depth_m,
                 "tower scene: how far the carved faces stand out");
  app.add_option("--num_tiers",
                 tower.tower.num_tiers,
                 "tower scene: tiers with four faces each");
  app.add_option("--coded_targets",
                 tower.tower.num_coded_targets,
                 "tower scene: coded targets (bayon targets' default "
                 "dictionary, codes 0 to N - 1) on the walls and platform; "
                 "their truth in gt/control");
  app.add_option("--coded_target_side_m",
                 tower.tower.coded_target_side_m,
                 "tower scene: side of a coded target's black square");
  app.add_option("--mesh_spacing_m",
                 tower.tower.mesh_spacing_m,
                 "tower scene: vertex spacing of the true surface");
  app.add_option("--texel_size_m",
                 tower.tower.texel_size_m,
                 "tower scene: texture resolution on the stone");
  app.add_option("--image_width",
                 image_width,
                 "tower scene: pixels across the 36 x 24 mm frame (the "
                 "height is 2/3 of it, the pitch 36 mm / width)");
  app.add_option("--supersampling",
                 tower.supersampling,
                 "tower scene: anti-aliasing samples per pixel and axis");
  app.add_option("--noise_sigma",
                 tower.noise_sigma,
                 "tower scene: sensor noise, grey values (1 sigma); 0: none");
  app.add_option("--jpeg_quality",
                 tower.jpeg_quality,
                 "tower scene: 0 writes PNG, 1..100 JPEG at that quality");
  app.add_option("--one_light",
                 tower.one_light,
                 "tower scene: 1: every photograph in the first one's light "
                 "(sun, sky, exposure)");
  app.add_option("--film_scan",
                 tower.film_scan,
                 "tower scene: 1: scanned film frames (rotated, shifted, "
                 "dark border)");
  app.add_option("--num_heldout_views",
                 tower.num_heldout_views,
                 "tower scene: viewpoints for texture evaluation");
  app.add_option("--control_sigma_px",
                 tower.control_sigma_px,
                 "tower scene: noise of the measured target positions");
  app.add_option("--num_threads",
                 tower.num_threads,
                 "tower scene: rendering threads (-1: all cores)");
  if (!command.Parse(argc, argv)) return 0;

  if (scene_name == "tower") {
    tower.num_views = points.num_views;
    tower.seed = points.seed;
    tower.tower.seed = points.seed;
    tower.camera.distortion = points.camera.distortion;
    tower.truth_in_database = !nominal_calibration;
    if (control_sigma->count() > 0) tower.control_sigma_m = control_sigma_m;
    return RunTowerScene(tower, output_path, overwrite, image_width, &command);
  }
  if (control_sigma->count() > 0) control.control_sigma_m = control_sigma_m;
  const SyntheticTruth truth = SynthesizePointsScene(points);
  SyntheticWorkspaceExtras extras;
  extras.control = SynthesizeControl(truth, points, control);
  extras.nominal_calibration = nominal_calibration;
  const SyntheticWorkspaceSummary summary =
      WriteSyntheticWorkspace(truth, output_path, overwrite, extras);
  command.PrintSummary(StrCat(scene_name,
                              ": ",
                              summary.num_images,
                              " images, ",
                              summary.num_points3D,
                              " points, ",
                              summary.num_observations,
                              " observations, ",
                              summary.num_pairs,
                              " image pairs; COLMAP camera fit RMS ",
                              summary.colmap_fit_rms_px,
                              " px; ",
                              extras.control.points.size(),
                              " control/check points with ",
                              extras.control.measurements.size(),
                              " image measurements -> ",
                              output_path));
  return 0;
}

}  // namespace bayon
