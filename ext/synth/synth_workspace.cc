// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/synth_workspace.h"

#include "ext/core/errors.h"
#include "ext/synth/tower_workspace.h"
#include "ext/synth/workspace_writer.h"

#include <cmath>

namespace bayon {
namespace {

std::string WriteTowerScene(TowerSceneOptions tower,
                            const SynthOptions& options,
                            const std::string& output_path,
                            bool overwrite) {
  tower.num_views = options.points.num_views;
  tower.seed = options.points.seed;
  tower.tower.seed = options.points.seed;
  tower.camera.distortion = options.points.camera.distortion;
  tower.truth_in_database = !options.nominal_calibration;
  if (!std::isnan(options.control_sigma_m)) {
    tower.control_sigma_m = options.control_sigma_m;
  }
  tower.camera.width = options.image_width;
  tower.camera.height = options.image_width * 2 / 3;
  tower.camera.pixel_pitch_mm = 36.0 / options.image_width;
  tower.Check();
  const TowerWorkspaceSummary summary =
      WriteTowerWorkspace(tower, output_path, overwrite);
  return StrCat("tower: ",
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
                output_path);
}

std::string WritePointsScene(const SynthOptions& options,
                             const std::string& output_path,
                             bool overwrite) {
  SyntheticControlOptions control = options.control;
  if (!std::isnan(options.control_sigma_m)) {
    control.control_sigma_m = options.control_sigma_m;
  }
  const SyntheticTruth truth = SynthesizePointsScene(options.points);
  SyntheticWorkspaceExtras extras;
  extras.control = SynthesizeControl(truth, options.points, control);
  extras.nominal_calibration = options.nominal_calibration;
  const SyntheticWorkspaceSummary summary =
      WriteSyntheticWorkspace(truth, output_path, overwrite, extras);
  return StrCat(options.scene,
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
                output_path);
}

}  // namespace

void SynthOptions::Register(OptionRegistry* r) {
  r->AddChoice("scene",
               &scene,
               {{"points", "points"}, {"tower", "tower"}},
               "Scene to make: points or tower");
  r->Add("num_views", &points.num_views, "Camera stations");
  r->Add("seed", &points.seed, "Random seed (same seed, same scene)");
  r->Add("num_points", &points.num_points, "points scene: 3D points");
  r->Add("keypoint_noise_px",
         &points.keypoint_noise_px,
         "points scene: observation noise, pixels (1 sigma)");
  r->Add("ring_radius_m",
         &points.ring_radius_m,
         "points scene: distance of the stations from the axis");
  r->Add("distortion",
         &points.camera.distortion,
         "1: a real lens (all additional parameters non-zero)");
  r->Add("alternate_roll_deg",
         &points.alternate_roll_deg,
         "points scene: every other station turned about its axis");
  r->Add("max_view_angle_deg",
         &points.max_view_angle_deg,
         "points scene: a point is seen within this angle of its "
         "normal");
  r->Add("num_control_points",
         &control.num_control_points,
         "control/: control points around the object");
  r->Add(
      "num_check_points", &control.num_check_points, "control/: check points");
  r->Add("levelling_bar",
         &control.levelling_bar,
         "control/: a vertical levelling bar (minimum datum)");
  r->Add("control_sigma_m",
         &control_sigma_m,
         "control/: standard deviation of the control coordinates "
         "(points: 0 = fixed; tower default 0.002)");
  r->Add("nominal_calibration",
         &nominal_calibration,
         "1: the database gets the nominal camera (additional "
         "parameters zero), the truth stays in gt/");
  r->Add("tower_width_m",
         &tower.tower.width_m,
         "tower scene: width of the lowest tier's walls");
  r->Add("tower_height_m",
         &tower.tower.height_m,
         "tower scene: height above the platform, finial included");
  r->Add("relief_depth_m",
         &tower.tower.relief_depth_m,
         "tower scene: how far the carved faces stand out");
  r->Add("num_tiers",
         &tower.tower.num_tiers,
         "tower scene: tiers with four faces each");
  r->Add("coded_targets",
         &tower.tower.num_coded_targets,
         "tower scene: coded targets (bayon targets' default "
         "dictionary, codes 0 to N - 1) on the walls and platform; "
         "their truth in gt/control");
  r->Add("coded_target_side_m",
         &tower.tower.coded_target_side_m,
         "tower scene: side of a coded target's black square");
  r->Add("mesh_spacing_m",
         &tower.tower.mesh_spacing_m,
         "tower scene: vertex spacing of the true surface");
  r->Add("texel_size_m",
         &tower.tower.texel_size_m,
         "tower scene: texture resolution on the stone");
  r->Add("image_width",
         &image_width,
         "tower scene: pixels across the 36 x 24 mm frame (the "
         "height is 2/3 of it, the pitch 36 mm / width)");
  r->Add("supersampling",
         &tower.supersampling,
         "tower scene: anti-aliasing samples per pixel and axis");
  r->Add("noise_sigma",
         &tower.noise_sigma,
         "tower scene: sensor noise, grey values (1 sigma); 0: none");
  r->Add("jpeg_quality",
         &tower.jpeg_quality,
         "tower scene: 0 writes PNG, 1..100 JPEG at that quality");
  r->Add("one_light",
         &tower.one_light,
         "tower scene: 1: every photograph in the first one's light "
         "(sun, sky, exposure)");
  r->Add("film_scan",
         &tower.film_scan,
         "tower scene: 1: scanned film frames (rotated, shifted, "
         "dark border)");
  r->Add("num_heldout_views",
         &tower.num_heldout_views,
         "tower scene: viewpoints for texture evaluation");
  r->Add("control_sigma_px",
         &tower.control_sigma_px,
         "tower scene: noise of the measured target positions");
  r->Add("num_threads",
         &tower.num_threads,
         "tower scene: rendering threads (-1: all cores)");
}

void SynthOptions::Check() const {
  if (scene != "tower") return;
  CheckOption(image_width >= 60 && image_width % 3 == 0,
              "image_width",
              ">= 60 and divisible by 3 (a 3:2 frame)",
              image_width);
}

std::string WriteSynthWorkspace(const SynthOptions& options,
                                const std::string& output_path,
                                bool overwrite) {
  options.Check();
  if (options.scene == "tower") {
    return WriteTowerScene(options.tower, options, output_path, overwrite);
  }
  return WritePointsScene(options, output_path, overwrite);
}

}  // namespace bayon
