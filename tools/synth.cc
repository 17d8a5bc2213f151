// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/synth/control_scene.h"
#include "ext/synth/points_scene.h"
#include "ext/synth/workspace_writer.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunSynth(int argc, char** argv) {
  std::string scene_name = "points";
  std::string output_path;
  bool overwrite = false;
  PointsSceneOptions points;
  SyntheticControlOptions control;
  bool nominal_calibration = false;
  CommandLine command("synth",
                      "Write a synthetic workspace with known truth: the true "
                      "cameras, calibration and points in gt/, and a COLMAP "
                      "database with the observations.");
  CLI::App& app = command.app();
  app.add_option("--scene", scene_name, "Scene to make")
      ->transform(CLI::IsMember({"points"}));
  app.add_option("--output_path", output_path, "Workspace folder to create")
      ->required();
  app.add_option("--overwrite", overwrite, "Replace an existing workspace");
  app.add_option(
      "--num_views", points.num_views, "Camera stations on the ring");
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
  app.add_option("--control_sigma_m",
                 control.control_sigma_m,
                 "control/: standard deviation of the control coordinates "
                 "(0: fixed)");
  app.add_option("--nominal_calibration",
                 nominal_calibration,
                 "1: the database gets the nominal camera (additional "
                 "parameters zero), the truth stays in gt/");
  if (!command.Parse(argc, argv)) return 0;

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
