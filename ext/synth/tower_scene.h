// SPDX-License-Identifier: BSD-3-Clause
//
// Photographs of the synthetic tower (tower_model.h) with everything known:
// the camera of the Bayon paper (c = 35 mm on a 36 x 24 mm frame, every
// Brown/Beyer parameter set), hand-held-like stations around the tower,
// sunlight that changes between photographs, optional sensor noise, JPEG
// and scanned-film frames, and the true image positions of the control
// targets.
//
// Stations: `num_views` stations cover the full horizon. Azimuth steps lie
// between 15 and 45 degrees (for 8 to 24 views; otherwise between 0.6 and
// 1.4 times 360 / num_views), distances and heights vary, aims and roll are
// a little off as in hand-held photographs. A few adjacent pairs converge by
// more than 45 degrees (wide steps, aims turned apart), and one adjacent pair
// has a mostly vertical base (the smallest step, one station low, the next
// high up), as in the paper's one model that failed.
//
// Light: each photograph has its own sun (azimuth from east through south
// to west, elevation 12 to 70 degrees), sunny, hazy or overcast; and its own
// exposure, some much darker than the rest. Tone curve: exposure times the
// rendered radiance, clipped and sRGB-encoded to 8 bits.
//
// Film scans (`film_scan`): the 36 x 24 mm photograph lies in a larger scan
// at the same pixel pitch, rotated by up to `film_max_rotation_deg` and
// shifted by up to `film_max_shift_mm`, surrounded by the dark film border;
// the camera's image size is the scan's, and each image's ImageFrame maps
// its frame into the scan. The truth lists the frame's corners in pixels.
#pragma once

#include "ext/colmap/control_io.h"
#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/rigid3.h"
#include "ext/render/mesh_renderer.h"
#include "ext/synth/synthetic_camera.h"
#include "ext/synth/tower_model.h"

#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct TowerSceneOptions {
  TowerOptions tower;
  SyntheticCameraOptions camera;
  int num_views = 16;
  // Distance of the stations from the tower axis, and their heights above
  // the ground; the upper station of the vertical pair is higher.
  double min_distance_m = 10.5;
  double max_distance_m = 13.5;
  double min_height_m = 1.2;
  double max_height_m = 2.8;
  double vertical_pair_height_m = 6.0;
  // Anti-aliasing: samples per pixel along each axis.
  int supersampling = 3;
  // Gaussian noise added to the 8-bit values (sigma in grey values); 0: none.
  double noise_sigma = 1.0;
  // 0: PNG; 1..100: JPEG at that quality.
  int jpeg_quality = 0;
  // Every photograph in the light of the first (its sun, sky and
  // exposure), as if all were taken at one moment: a control for the
  // stages whose matching the changing light limits (dense, texture). The
  // random draws are the same either way, so the scene is otherwise the
  // one with changing light.
  bool one_light = false;
  // Scanned film: see the header comment.
  bool film_scan = false;
  double film_margin_mm = 2.0;
  double film_max_rotation_deg = 1.0;
  double film_max_shift_mm = 0.8;
  // Held-out viewpoints (not photographed) for texture evaluation.
  int num_heldout_views = 4;
  // The workspace's database gets the true calibration (bayon_calibration,
  // its FULL_OPENCV fit in `cameras`) and the true image frames
  // (bayon_interior); off: the nominal camera (c, pixel pitch, no
  // additional parameters) that `bayon import --camera_model BROWN_BEYER
  // --focal_length_mm --pixel_size_um --single_camera 1` would write, and
  // no interior, for blind runs.
  bool truth_in_database = true;
  // The control files in the workspace's control/ folder are what a user
  // would have: object coordinates surveyed with this standard deviation,
  // image positions measured with this one (both applied as noise; the
  // exact values are in gt/control/).
  double control_sigma_m = 0.002;
  double control_sigma_px = 0.3;
  uint32_t seed = 1;
  int num_threads = -1;
  void Check() const;
};

// One photograph: its pose, light, exposure and (film scans) frame.
struct TowerStation {
  std::string name;  // image file name
  Rigid3d cam_from_world;
  double azimuth_deg = 0;  // of the station around the tower
  Lighting lighting;
  double exposure = 1;
  std::string weather;              // "sunny", "hazy" or "overcast"
  std::optional<ImageFrame> frame;  // film scans
  // Film scans: the frame corners in scan pixels, in the order
  // (-x, +y) (+x, +y) (+x, -y) (-x, -y) of the image coordinates in mm,
  // i.e. upper left, upper right, lower right, lower left.
  std::array<Eigen::Vector2d, 4> frame_corners_px;
};

struct TowerScene {
  TowerModel model;
  // The true camera: BROWN_BEYER, camera_id 1; for film scans its size is
  // the scan's.
  Camera camera;
  std::vector<TowerStation> stations;
  std::vector<Rigid3d> heldout_cam_from_world;
  // Adjacent station pairs (indices into `stations`, i and i + 1 modulo
  // the count) planned to converge by more than 45 degrees, and the pair
  // with the mostly vertical base.
  std::vector<int> converging_pairs;
  int vertical_pair = -1;
  // The frame window of film scans (image coordinates, mm).
  std::optional<Eigen::AlignedBox2d> frame_window_mm;
};

// Builds the tower and plans the stations, deterministic for the seed.
TowerScene PlanTowerScene(const TowerSceneOptions& options);

// A renderer for the scene's mesh (targets unlit) and the render options
// the photographs use (shadow map over the object).
MeshRenderer MakeTowerRenderer(const TowerScene& scene);
RenderOptions TowerRenderOptions(const TowerScene& scene,
                                 const TowerSceneOptions& options);

// Renders photograph `index`: 8-bit BGR with the tone curve and noise
// applied (not yet JPEG-compressed). `render`, when given, receives the
// renderer's output (linear colour and geometry buffers).
cv::Mat RenderTowerPhotograph(const TowerScene& scene,
                              const MeshRenderer& renderer,
                              int index,
                              const TowerSceneOptions& options,
                              RenderResult* render = nullptr);

// The control targets seen in a rendered photograph: exact projections of
// their disc centres where the disc is unoccluded (the plate's faces at
// the centre and around the disc, from the geometry buffers), inside the
// frame, and seen at less than `max_view_angle_deg` from its normal.
std::vector<ImageMeasurement> VisibleTargets(const TowerScene& scene,
                                             int index,
                                             const RenderResult& render,
                                             double max_view_angle_deg = 75);

// Convergence angle of two stations' optical axes, degrees.
double ConvergenceAngleDeg(const Rigid3d& a, const Rigid3d& b);

}  // namespace bayon
