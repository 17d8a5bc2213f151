// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_scene.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/targets/coded_targets.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>

namespace bayon {

void TowerSceneOptions::Check() const {
  tower.Check();
  camera.Check();
  CheckOption(num_views >= 2 && num_views <= 200,
              "num_views",
              "in [2, 200]",
              num_views);
  CheckOption(min_distance_m > 0.75 * tower.platform_width_m,
              "min_distance_m",
              "> 0.75 * platform width (outside the platform)",
              min_distance_m);
  CheckOption(max_distance_m >= min_distance_m,
              "max_distance_m",
              ">= min_distance_m",
              max_distance_m);
  CheckOption(min_height_m > 0.1, "min_height_m", "> 0.1", min_height_m);
  CheckOption(max_height_m >= min_height_m,
              "max_height_m",
              ">= min_height_m",
              max_height_m);
  CheckOption(vertical_pair_height_m > min_height_m,
              "vertical_pair_height_m",
              "> min_height_m",
              vertical_pair_height_m);
  CheckOption(supersampling >= 1 && supersampling <= 8,
              "supersampling",
              "in [1, 8]",
              supersampling);
  CheckOption(noise_sigma >= 0 && noise_sigma <= 50,
              "noise_sigma",
              "in [0, 50]",
              noise_sigma);
  CheckOption(jpeg_quality >= 0 && jpeg_quality <= 100,
              "jpeg_quality",
              "in [0, 100] (0: PNG)",
              jpeg_quality);
  CheckOption(
      film_margin_mm >= 0.5, "film_margin_mm", ">= 0.5", film_margin_mm);
  CheckOption(film_max_rotation_deg >= 0 && film_max_rotation_deg <= 5,
              "film_max_rotation_deg",
              "in [0, 5]",
              film_max_rotation_deg);
  CheckOption(film_max_shift_mm >= 0 && film_max_shift_mm < film_margin_mm,
              "film_max_shift_mm",
              "in [0, film_margin_mm)",
              film_max_shift_mm);
  CheckOption(control_sigma_m >= 0, "control_sigma_m", ">= 0", control_sigma_m);
  CheckOption(
      control_sigma_px >= 0, "control_sigma_px", ">= 0", control_sigma_px);
  CheckOption(num_heldout_views >= 0 && num_heldout_views <= 64,
              "num_heldout_views",
              "in [0, 64]",
              num_heldout_views);
}

double ConvergenceAngleDeg(const Rigid3d& a, const Rigid3d& b) {
  const Eigen::Vector3d axis_a =
      a.rotation.inverse() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d axis_b =
      b.rotation.inverse() * Eigen::Vector3d::UnitZ();
  return std::acos(std::clamp(axis_a.dot(axis_b), -1.0, 1.0)) * 180 / M_PI;
}

namespace {

// Azimuth steps (degrees) summing to 360: `fixed` steps keep their value,
// the others are drawn in [low, high] and scaled until the sum fits.
std::vector<double> AzimuthSteps(
    int n,
    double low,
    double high,
    const std::vector<std::pair<int, double>>& fixed,
    std::mt19937* rng) {
  std::uniform_real_distribution<double> uniform(low, high);
  std::vector<double> steps(n);
  std::vector<bool> is_fixed(n, false);
  for (double& step : steps) step = uniform(*rng);
  for (const auto& [index, value] : fixed) {
    steps[index] = value;
    is_fixed[index] = true;
  }
  for (int iteration = 0; iteration < 100; ++iteration) {
    double sum_fixed = 0, sum_free = 0;
    for (int i = 0; i < n; ++i)
      (is_fixed[i] ? sum_fixed : sum_free) += steps[i];
    if (std::abs(sum_fixed + sum_free - 360) < 1e-9) break;
    if (sum_free <= 0) break;
    const double scale = (360 - sum_fixed) / sum_free;
    for (int i = 0; i < n; ++i) {
      if (!is_fixed[i]) steps[i] = std::clamp(steps[i] * scale, low, high);
    }
  }
  // If the free steps could not absorb the rest, scale everything.
  const double total = std::accumulate(steps.begin(), steps.end(), 0.0);
  for (double& step : steps) step *= 360 / total;
  return steps;
}

Eigen::Vector3d SunDirection(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * M_PI / 180, el = elevation_deg * M_PI / 180;
  // Azimuth from north (+y) clockwise towards east (+x).
  return Eigen::Vector3d(
      std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el));
}

}  // namespace

TowerScene PlanTowerScene(const TowerSceneOptions& options) {
  options.Check();
  TowerScene scene;
  scene.model = BuildTower(options.tower);
  std::mt19937 rng(options.seed * 7919u + 13u);
  std::uniform_real_distribution<double> unit(0, 1);
  auto uniform = [&](double a, double b) { return a + (b - a) * unit(rng); };

  // The camera; for film scans the scan is larger than the frame.
  SyntheticCameraOptions camera_options = options.camera;
  const double pitch = camera_options.pixel_pitch_mm;
  const double frame_w_mm = camera_options.width * pitch;
  const double frame_h_mm = camera_options.height * pitch;
  if (options.film_scan) {
    camera_options.width = static_cast<int>(
        std::lround((frame_w_mm + 2 * options.film_margin_mm) / pitch));
    camera_options.height = static_cast<int>(
        std::lround((frame_h_mm + 2 * options.film_margin_mm) / pitch));
    scene.frame_window_mm = Eigen::AlignedBox2d(
        Eigen::Vector2d(-0.5 * frame_w_mm, -0.5 * frame_h_mm),
        Eigen::Vector2d(0.5 * frame_w_mm, 0.5 * frame_h_mm));
  }
  scene.camera = SyntheticCamera(camera_options);

  // Azimuth steps: the vertical pair gets the smallest, the converging
  // pairs nearly the largest.
  const int n = options.num_views;
  double low = 15, high = 45;
  if (n * low > 360 || n * high < 360) {
    low = 0.6 * 360.0 / n;
    high = 1.4 * 360.0 / n;
  }
  std::vector<std::pair<int, double>> fixed;
  if (n >= 4) {
    scene.vertical_pair = n / 2;
    fixed.push_back({scene.vertical_pair, low});
    const int num_converging = n >= 12 ? 3 : (n >= 8 ? 2 : 1);
    for (int k = 0; k < num_converging; ++k) {
      const int pair = (1 + k * n / num_converging) % n;
      if (pair == scene.vertical_pair || pair + 1 == scene.vertical_pair ||
          pair == scene.vertical_pair + 1) {
        continue;
      }
      fixed.push_back({pair, 0.97 * high});
      scene.converging_pairs.push_back(pair);
    }
  }
  const std::vector<double> steps = AzimuthSteps(n, low, high, fixed, &rng);

  const double platform_top = options.tower.platform_height_m;
  const double tower_top = platform_top + options.tower.height_m;
  double azimuth = uniform(0, 360);
  for (int i = 0; i < n; ++i) {
    TowerStation station;
    char name[32];
    std::snprintf(name,
                  sizeof(name),
                  "image_%03d.%s",
                  i + 1,
                  options.jpeg_quality > 0 ? "jpg" : "png");
    station.name = name;
    station.azimuth_deg = std::fmod(azimuth, 360.0);
    const double distance =
        uniform(options.min_distance_m, options.max_distance_m);
    double height = uniform(options.min_height_m, options.max_height_m);
    if (i == scene.vertical_pair) height = options.min_height_m;
    if (n >= 4 && i == (scene.vertical_pair + 1) % n) {
      height = options.vertical_pair_height_m;
    }
    const double az = station.azimuth_deg * M_PI / 180;
    const Eigen::Vector3d center(
        distance * std::cos(az), distance * std::sin(az), height);
    // Aim at the tower's middle, a little off as by hand; the converging
    // pairs turn apart (the first station of a pair aims towards increasing
    // azimuth, the second back) so that their axes meet at more than 45 deg.
    const Eigen::Vector3d tangent(-std::sin(az), std::cos(az), 0);
    double lateral = uniform(-0.3, 0.3);
    for (int pair : scene.converging_pairs) {
      if (i == pair) lateral = 0.9;
      if (i == (pair + 1) % n) lateral = -0.9;
    }
    const Eigen::Vector3d target =
        Eigen::Vector3d(0, 0, uniform(0.42, 0.55) * tower_top) +
        lateral * tangent;
    station.cam_from_world = LookAt(
        center, target, Eigen::Vector3d::UnitZ(), uniform(-3, 3) * M_PI / 180);
    // The light of this photograph.
    Lighting& light = station.lighting;
    light.enabled = true;
    light.shadows = true;
    const double day = unit(rng);
    const double sun_azimuth = 90 + 180 * day + uniform(-10, 10);
    const double sun_elevation =
        std::clamp(12 + 55 * std::sin(M_PI * day) + uniform(-5, 5), 8.0, 75.0);
    light.sun_direction = SunDirection(sun_azimuth, sun_elevation);
    const double weather = unit(rng);
    if (weather < 0.6) {
      station.weather = "sunny";
      light.sun_intensity = uniform(0.9, 1.15);
      light.ambient_intensity = uniform(0.25, 0.35);
    } else if (weather < 0.85) {
      station.weather = "hazy";
      light.sun_intensity = uniform(0.35, 0.55);
      light.ambient_intensity = uniform(0.45, 0.55);
    } else {
      station.weather = "overcast";
      light.sun_intensity = uniform(0.05, 0.15);
      light.ambient_intensity = uniform(0.7, 0.8);
    }
    // Exposure: about right for a sunlit wall, a quarter of the images
    // much darker (under-exposed, late light).
    station.exposure = 1.9 * uniform(0.85, 1.15) /
                       (light.sun_intensity * 0.6 + light.ambient_intensity);
    if (unit(rng) < 0.25) station.exposure *= uniform(0.3, 0.45);
    if (options.film_scan) {
      const double angle =
          uniform(-1, 1) * options.film_max_rotation_deg * M_PI / 180;
      const Eigen::Vector2d shift(uniform(-1, 1) * options.film_max_shift_mm,
                                  uniform(-1, 1) * options.film_max_shift_mm);
      // pixel = diag(1/p, -1/p) * (R(angle) * xy + shift) + centre.
      Eigen::Matrix2d rotation;
      rotation << std::cos(angle), -std::sin(angle), std::sin(angle),
          std::cos(angle);
      const Eigen::Matrix2d flip =
          Eigen::Vector2d(1 / pitch, -1 / pitch).asDiagonal();
      ImageFrame frame;
      frame.pixel_from_frame.leftCols<2>() = flip * rotation;
      frame.pixel_from_frame.col(2) =
          flip * shift +
          Eigen::Vector2d(0.5 * scene.camera.width, 0.5 * scene.camera.height);
      station.frame = frame;
      const Eigen::Vector2d corners_mm[4] = {
          {-0.5 * frame_w_mm, 0.5 * frame_h_mm},
          {0.5 * frame_w_mm, 0.5 * frame_h_mm},
          {0.5 * frame_w_mm, -0.5 * frame_h_mm},
          {-0.5 * frame_w_mm, -0.5 * frame_h_mm}};
      for (int k = 0; k < 4; ++k) {
        station.frame_corners_px[k] = frame.PixelFromFrame(corners_mm[k]);
      }
    }
    scene.stations.push_back(station);
    azimuth += steps[i];
  }
  if (options.one_light) {
    for (TowerStation& station : scene.stations) {
      station.lighting = scene.stations.front().lighting;
      station.weather = scene.stations.front().weather;
      station.exposure = scene.stations.front().exposure;
    }
  }
  // Held-out viewpoints: between stations, at heights the photographs did
  // not use.
  for (int k = 0; k < options.num_heldout_views; ++k) {
    const double az =
        (uniform(0, 360) + 360.0 * k / std::max(1, options.num_heldout_views)) *
        M_PI / 180;
    const double distance =
        uniform(options.min_distance_m, options.max_distance_m);
    const Eigen::Vector3d center(
        distance * std::cos(az),
        distance * std::sin(az),
        uniform(options.max_height_m, options.vertical_pair_height_m));
    scene.heldout_cam_from_world.push_back(
        LookAt(center, Eigen::Vector3d(0, 0, 0.5 * tower_top)));
  }
  return scene;
}

MeshRenderer MakeTowerRenderer(const TowerScene& scene) {
  MeshRenderer renderer(scene.model.mesh, scene.model.texture);
  renderer.SetUnlitFaces(scene.model.UnlitFaces());
  return renderer;
}

RenderOptions TowerRenderOptions(const TowerScene& scene,
                                 const TowerSceneOptions& options) {
  RenderOptions render;
  render.supersampling = options.supersampling;
  render.num_threads = options.num_threads;
  render.shadow_map.region = scene.model.object_bounds;
  render.shadow_map.num_threads = options.num_threads;
  // A hazy tropical sky, and distant forest below the horizon.
  render.background_horizon_bgr = Eigen::Vector3f(0.62f, 0.60f, 0.55f);
  render.background_zenith_bgr = Eigen::Vector3f(0.55f, 0.33f, 0.17f);
  return render;
}

namespace {

// sRGB encoding of a linear value, to grey values 0..255: a table over
// [0, 1] with linear interpolation (pow per channel and pixel is slow).
class SrgbCurve {
 public:
  SrgbCurve() : table_(kSize + 1) {
    for (int i = 0; i <= kSize; ++i) {
      const double linear = static_cast<double>(i) / kSize;
      table_[i] = static_cast<float>(
          255 * (linear <= 0.0031308
                     ? 12.92 * linear
                     : 1.055 * std::pow(linear, 1 / 2.4) - 0.055));
    }
  }
  float operator()(float linear) const {
    const float x = std::clamp(linear, 0.0f, 1.0f) * kSize;
    const int i = std::min(static_cast<int>(x), kSize - 1);
    return table_[i] + (x - i) * (table_[i + 1] - table_[i]);
  }

 private:
  static constexpr int kSize = 8192;
  std::vector<float> table_;
};

}  // namespace

cv::Mat RenderTowerPhotograph(const TowerScene& scene,
                              const MeshRenderer& renderer,
                              int index,
                              const TowerSceneOptions& options,
                              RenderResult* render) {
  const TowerStation& station = scene.stations.at(index);
  RenderView view;
  view.camera = scene.camera;
  view.cam_from_world = station.cam_from_world;
  view.frame = station.frame;
  view.frame_window_mm = scene.frame_window_mm;
  RenderOptions render_options = TowerRenderOptions(scene, options);
  // The film border: nearly black film base whatever the exposure.
  render_options.border_bgr =
      Eigen::Vector3f::Constant(static_cast<float>(0.003 / station.exposure));
  RenderResult result = renderer.Render(view, station.lighting, render_options);
  // Tone curve, then sensor noise in grey values, deterministic per image
  // and row (rows in parallel).
  cv::Mat photo(result.color.size(), CV_8UC3);
  static const SrgbCurve srgb;
  const float exposure = static_cast<float>(station.exposure);
  ParallelFor(photo.rows, options.num_threads, [&](int y) {
    std::seed_seq seed{
        options.seed, static_cast<uint32_t>(index), static_cast<uint32_t>(y)};
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, options.noise_sigma);
    const cv::Vec3f* in = result.color.ptr<cv::Vec3f>(y);
    cv::Vec3b* out = photo.ptr<cv::Vec3b>(y);
    for (int x = 0; x < photo.cols; ++x) {
      for (int c = 0; c < 3; ++c) {
        double value = srgb(exposure * in[x][c]);
        if (options.noise_sigma > 0) value += noise(rng);
        out[x][c] = cv::saturate_cast<uint8_t>(value);
      }
    }
  });
  if (render) *render = std::move(result);
  return photo;
}

std::vector<ImageMeasurement> VisibleTargets(const TowerScene& scene,
                                             int index,
                                             const RenderResult& render,
                                             double max_view_angle_deg) {
  std::vector<ImageMeasurement> measurements;
  const TowerStation& station = scene.stations.at(index);
  const ImageFrame* frame = station.frame ? &*station.frame : nullptr;
  const Eigen::Vector3d center = station.cam_from_world.Center();
  const double cos_max = std::cos(max_view_angle_deg * M_PI / 180);
  const size_t first_plate = scene.model.num_object_faces;
  for (size_t k = 0; k < scene.model.targets.size(); ++k) {
    const ControlTarget& target = scene.model.targets[k];
    const Eigen::Vector3d to_camera = (center - target.center).normalized();
    if (to_camera.dot(target.normal) < cos_max) continue;
    // Plate k has faces first_plate + 2k and + 2k + 1.
    const int face0 = static_cast<int>(first_plate + 2 * k);
    auto on_plate = [&](const Eigen::Vector3d& point, Eigen::Vector2d* pixel) {
      if (!scene.camera.ImgFromCam(
              station.cam_from_world * point, pixel, frame)) {
        return false;
      }
      const int x = static_cast<int>(std::floor(pixel->x()));
      const int y = static_cast<int>(std::floor(pixel->y()));
      if (x < 0 || y < 0 || x >= render.triangle_id.cols ||
          y >= render.triangle_id.rows) {
        return false;
      }
      const int face = render.triangle_id.at<int>(y, x);
      return face == face0 || face == face0 + 1;
    };
    Eigen::Vector2d pixel;
    if (!on_plate(target.center, &pixel)) continue;
    if (scene.frame_window_mm) {
      const Eigen::Vector2d xy = station.frame->FrameFromPixel(pixel);
      if (!scene.frame_window_mm->contains(xy)) continue;
    }
    const Eigen::Vector3d right =
        Eigen::Vector3d::UnitZ().cross(target.normal).normalized();
    const Eigen::Vector3d up = target.normal.cross(right);
    bool visible = true;
    if (target.code < 0) {
      // The whole disc and a rim of black plate must be unoccluded.
      for (int a = 0; a < 12 && visible; ++a) {
        const double angle = 2 * M_PI * a / 12;
        const double radius =
            0.5 * (target.disc_radius_m + target.plate_half_size_m);
        Eigen::Vector2d rim;
        visible = on_plate(target.center + radius * (std::cos(angle) * right +
                                                     std::sin(angle) * up),
                           &rim);
      }
    } else {
      // A coded target: the marker's corners and the middles of its sides,
      // half a cell out into the white margin, must be unoccluded, and each
      // side at least min_side_px long in the photograph (smaller markers
      // cannot be decoded).
      const double half = target.marker_half_size_m;
      const double reach = 0.5 * (half + target.plate_half_size_m);
      for (int sx = -1; sx <= 1; ++sx) {
        for (int sy = -1; sy <= 1; ++sy) {
          Eigen::Vector2d at;
          visible =
              visible &&
              on_plate(target.center + reach * (sx * right + sy * up), &at);
        }
      }
      std::array<Eigen::Vector2d, 4> corners;
      for (int c = 0; c < 4 && visible; ++c) {
        const int sx = c == 0 || c == 3 ? -1 : 1;
        const int sy = c < 2 ? 1 : -1;
        visible = scene.camera.ImgFromCam(
            station.cam_from_world *
                (target.center + half * (sx * right + sy * up)),
            &corners[c],
            frame);
      }
      for (int c = 0; c < 4 && visible; ++c) {
        visible = (corners[(c + 1) % 4] - corners[c]).norm() >=
                  CodedTargetOptions().min_side_px;
      }
    }
    if (!visible) continue;
    ImageMeasurement measurement;
    measurement.point_name = target.name;
    measurement.image_name = station.name;
    measurement.xy = pixel;
    measurements.push_back(measurement);
  }
  return measurements;
}

}  // namespace bayon
