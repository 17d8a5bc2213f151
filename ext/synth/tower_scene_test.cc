// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_scene.h"

#include "ext/core/errors.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <map>
#include <numeric>
#include <set>

namespace bayon {
namespace {

// A coarse tower and small photographs (600 x 400 pixels of 60 um on the
// 36 x 24 mm frame) taken from close by, so that the 8 cm target discs are
// 5 to 7 pixels wide.
TowerSceneOptions SmallSceneOptions() {
  TowerSceneOptions options;
  options.tower.mesh_spacing_m = 0.06;
  options.tower.texel_size_m = 0.01;
  options.tower.ground_texel_size_m = 0.1;
  options.camera.width = 600;
  options.camera.height = 400;
  options.camera.pixel_pitch_mm = 0.06;
  options.min_distance_m = 6.5;
  options.max_distance_m = 8.0;
  options.noise_sigma = 0;
  options.num_views = 8;
  return options;
}

// Linear intensity of an 8-bit sRGB grey value.
double Linear(double value) {
  const double v = value / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// Where the ray through `pixel` meets the target's plane, in metres from
// the disc centre.
double PlaneDistance(const TowerScene& scene,
                     const TowerStation& station,
                     const ControlTarget& target,
                     const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d ray =
      scene.camera.CamFromImg(pixel, station.frame ? &*station.frame : nullptr);
  const Rigid3d world_from_cam = station.cam_from_world.Inverse();
  const Eigen::Vector3d origin = world_from_cam.translation;
  const Eigen::Vector3d direction = world_from_cam.rotation * ray;
  const double t =
      target.normal.dot(target.center - origin) / target.normal.dot(direction);
  return (origin + t * direction - target.center).norm();
}

// The intensity-weighted centroid of the white disc: over the pixels whose
// centre lies on the plate within `radius` of the disc centre, weights are
// the linear intensity above the black plate's level.
Eigen::Vector2d DiscCentroid(const TowerScene& scene,
                             const TowerStation& station,
                             const ControlTarget& target,
                             const cv::Mat& photo,
                             const Eigen::Vector2d& approximate) {
  const double radius = 0.5 * (target.disc_radius_m + target.plate_half_size_m);
  std::vector<std::pair<Eigen::Vector2d, double>> samples;
  std::vector<double> black;
  for (int y = int(approximate.y()) - 15; y <= int(approximate.y()) + 15; ++y) {
    for (int x = int(approximate.x()) - 15; x <= int(approximate.x()) + 15;
         ++x) {
      if (x < 0 || y < 0 || x >= photo.cols || y >= photo.rows) continue;
      const Eigen::Vector2d pixel(x + 0.5, y + 0.5);
      const double distance = PlaneDistance(scene, station, target, pixel);
      if (distance > radius) continue;
      const cv::Vec3b bgr = photo.at<cv::Vec3b>(y, x);
      const double value =
          (Linear(bgr[0]) + Linear(bgr[1]) + Linear(bgr[2])) / 3;
      samples.push_back({pixel, value});
      if (distance > target.disc_radius_m + 0.008) black.push_back(value);
    }
  }
  EXPECT_GE(black.size(), 4u);
  std::sort(black.begin(), black.end());
  const double level = black.empty() ? 0 : black[black.size() / 2];
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double weight = 0;
  for (const auto& [pixel, value] : samples) {
    const double w = std::max(0.0, value - level);
    sum += w * pixel;
    weight += w;
  }
  return sum / weight;
}

TEST(TowerScene, TargetCentroidsAgreeWithTheCameraModel) {
  const TowerSceneOptions options = SmallSceneOptions();
  const TowerScene scene = PlanTowerScene(options);
  const MeshRenderer renderer = MakeTowerRenderer(scene);
  std::map<std::string, const ControlTarget*> targets;
  for (const ControlTarget& target : scene.model.targets) {
    targets[target.name] = &target;
  }
  double max_error = 0, sum_squares = 0;
  int count = 0;
  std::set<std::string> seen;
  for (int i = 0; i < static_cast<int>(scene.stations.size()); ++i) {
    RenderResult render;
    const cv::Mat photo =
        RenderTowerPhotograph(scene, renderer, i, options, &render);
    EXPECT_LT(render.stats.max_ray_residual_px, 1e-6);
    for (const ImageMeasurement& m : VisibleTargets(scene, i, render)) {
      const ControlTarget& target = *targets.at(m.point_name);
      // The truth is the projection of the disc centre by the camera model.
      const Eigen::Vector2d projected = scene.camera.ImgFromCam(
          scene.stations[i].cam_from_world * target.center,
          scene.stations[i].frame ? &*scene.stations[i].frame : nullptr);
      EXPECT_LT((projected - m.xy).norm(), 1e-9);
      const Eigen::Vector2d centroid =
          DiscCentroid(scene, scene.stations[i], target, photo, m.xy);
      const double error = (centroid - m.xy).norm();
      EXPECT_LT(error, 0.1) << m.point_name << " in " << m.image_name;
      max_error = std::max(max_error, error);
      sum_squares += error * error;
      ++count;
      seen.insert(m.point_name);
    }
  }
  // Every kind of target is measured: platform, tower and levelling bar.
  EXPECT_GE(count, 15);
  EXPECT_GE(seen.size(), 6u);
  EXPECT_TRUE(seen.count("B1") || seen.count("B2"));
  std::cout << "target centroids: " << count << " measured, RMS "
            << std::sqrt(sum_squares / count) << " px, max " << max_error
            << " px" << std::endl;
}

// Fits x = a y + b (or y = a x + b) to edge points, rejecting points more
// than 1 px off a first fit.
Eigen::Vector2d FitLine(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d line = Eigen::Vector2d::Zero();
  std::vector<bool> keep(points.size(), true);
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < points.size(); ++i) {
      if (!keep[i]) continue;
      const Eigen::Vector2d row(points[i].x(), 1.0);
      normal += row * row.transpose();
      rhs += row * points[i].y();
    }
    line = normal.ldlt().solve(rhs);
    for (size_t i = 0; i < points.size(); ++i) {
      keep[i] =
          std::abs(line.x() * points[i].x() + line.y() - points[i].y()) < 1.0;
    }
  }
  return line;
}

// Sub-pixel position of the border-to-photograph transition along a line of
// linear intensities (index 0 at the outer edge of the scan), in pixels from
// that edge: the first pixel above the (uniform) border level is partly
// border, partly photograph, in proportion to its value between the border
// and its inner neighbour.
std::optional<double> EdgeAlong(const std::vector<double>& values) {
  const double border = values[0];
  for (size_t k = 1; k + 1 < values.size(); ++k) {
    if (values[k] > border + 0.002) {
      const double inner = values[k + 1];
      if (inner - border < 0.01) return std::nullopt;  // too dark to tell
      const double covered =
          std::clamp((values[k] - border) / (inner - border), 0.0, 1.0);
      return double(k) + 1 - covered;
    }
  }
  return std::nullopt;
}

TEST(TowerScene, FilmFrameCornersMatchTheRenderedBorder) {
  TowerSceneOptions options = SmallSceneOptions();
  options.film_scan = true;
  options.num_views = 3;
  const TowerScene scene = PlanTowerScene(options);
  EXPECT_EQ(scene.camera.width, 667u);  // (36 + 2 * 2) mm / 60 um
  EXPECT_EQ(scene.camera.height, 467u);
  const MeshRenderer renderer = MakeTowerRenderer(scene);
  for (int i = 0; i < 3; ++i) {
    const TowerStation& station = scene.stations[i];
    ASSERT_TRUE(station.frame);
    const cv::Mat photo = RenderTowerPhotograph(scene, renderer, i, options);
    cv::Mat gray(photo.size(), CV_64F);
    for (int y = 0; y < photo.rows; ++y) {
      for (int x = 0; x < photo.cols; ++x) {
        const cv::Vec3b bgr = photo.at<cv::Vec3b>(y, x);
        gray.at<double>(y, x) =
            (Linear(bgr[0]) + Linear(bgr[1]) + Linear(bgr[2])) / 3;
      }
    }
    // Edge points of the four sides, measured from the scan's borders
    // inwards along rows (left, right) and columns (top, bottom), away from
    // the corners.
    std::vector<Eigen::Vector2d> left, right, top, bottom;
    const int w = photo.cols, h = photo.rows;
    for (int y = h / 5; y < 4 * h / 5; ++y) {
      std::vector<double> from_left, from_right;
      for (int x = 0; x < w / 3; ++x) {
        from_left.push_back(gray.at<double>(y, x));
        from_right.push_back(gray.at<double>(y, w - 1 - x));
      }
      if (auto e = EdgeAlong(from_left)) left.push_back({y + 0.5, *e});
      if (auto e = EdgeAlong(from_right)) right.push_back({y + 0.5, w - *e});
    }
    for (int x = w / 5; x < 4 * w / 5; ++x) {
      std::vector<double> from_top, from_bottom;
      for (int y = 0; y < h / 3; ++y) {
        from_top.push_back(gray.at<double>(y, x));
        from_bottom.push_back(gray.at<double>(h - 1 - y, x));
      }
      if (auto e = EdgeAlong(from_top)) top.push_back({x + 0.5, *e});
      if (auto e = EdgeAlong(from_bottom)) bottom.push_back({x + 0.5, h - *e});
    }
    ASSERT_GT(left.size(), 100u);
    ASSERT_GT(top.size(), 150u);
    // x = a y + b for the sides, y = a x + b for top and bottom.
    const Eigen::Vector2d l = FitLine(left), r = FitLine(right);
    const Eigen::Vector2d t = FitLine(top), b = FitLine(bottom);
    auto corner = [](const Eigen::Vector2d& side, const Eigen::Vector2d& row) {
      // x = s0 y + s1, y = r0 x + r1.
      const double y =
          (row.x() * side.y() + row.y()) / (1 - row.x() * side.x());
      return Eigen::Vector2d(side.x() * y + side.y(), y);
    };
    const Eigen::Vector2d measured[4] = {
        corner(l, t), corner(r, t), corner(r, b), corner(l, b)};
    for (int k = 0; k < 4; ++k) {
      EXPECT_LT((measured[k] - station.frame_corners_px[k]).norm(), 0.5)
          << "image " << i << " corner " << k << ": measured "
          << measured[k].transpose() << ", truth "
          << station.frame_corners_px[k].transpose();
    }
  }
}

TEST(TowerScene, StationsFollowThePlan) {
  TowerSceneOptions options = SmallSceneOptions();
  options.num_views = 16;
  const TowerScene scene = PlanTowerScene(options);
  ASSERT_EQ(scene.stations.size(), 16u);
  double total = 0;
  for (int i = 0; i < 16; ++i) {
    const double step = std::fmod(scene.stations[(i + 1) % 16].azimuth_deg -
                                      scene.stations[i].azimuth_deg + 720,
                                  360.0);
    EXPECT_GE(step, 15 - 1e-6) << i;
    EXPECT_LE(step, 45 + 1e-6) << i;
    total += step;
  }
  EXPECT_NEAR(total, 360, 1e-6);
  ASSERT_GE(scene.converging_pairs.size(), 3u);
  for (int pair : scene.converging_pairs) {
    EXPECT_GT(
        ConvergenceAngleDeg(scene.stations[pair].cam_from_world,
                            scene.stations[(pair + 1) % 16].cam_from_world),
        45.0);
  }
  const Eigen::Vector3d base =
      scene.stations[scene.vertical_pair + 1].cam_from_world.Center() -
      scene.stations[scene.vertical_pair].cam_from_world.Center();
  EXPECT_GT(std::abs(base.z()), base.head<2>().norm());  // mostly vertical
  // Light changes: some images much darker than others.
  double darkest = 1e9, brightest = 0;
  for (const TowerStation& station : scene.stations) {
    darkest = std::min(darkest, station.exposure);
    brightest = std::max(brightest, station.exposure);
  }
  EXPECT_GT(brightest / darkest, 2.5);
  // Same seed, same plan; another seed, another plan.
  const TowerScene again = PlanTowerScene(options);
  EXPECT_EQ(again.stations[5].cam_from_world.translation,
            scene.stations[5].cam_from_world.translation);
  options.seed = 2;
  const TowerScene other = PlanTowerScene(options);
  EXPECT_NE(other.stations[5].cam_from_world.translation,
            scene.stations[5].cam_from_world.translation);
}

// One light: the same stations, every photograph in the first one's light.
TEST(TowerScene, OneLightKeepsTheStationsAndTakesTheFirstLight) {
  TowerSceneOptions options = SmallSceneOptions();
  options.num_views = 16;
  const TowerScene changing = PlanTowerScene(options);
  options.one_light = true;
  const TowerScene one = PlanTowerScene(options);
  ASSERT_EQ(one.stations.size(), changing.stations.size());
  for (size_t i = 0; i < one.stations.size(); ++i) {
    const TowerStation& a = one.stations[i];
    EXPECT_EQ(a.cam_from_world.translation,
              changing.stations[i].cam_from_world.translation);
    EXPECT_EQ(a.exposure, changing.stations[0].exposure);
    EXPECT_EQ(a.weather, changing.stations[0].weather);
    EXPECT_EQ(a.lighting.sun_direction,
              changing.stations[0].lighting.sun_direction);
    EXPECT_EQ(a.lighting.sun_intensity,
              changing.stations[0].lighting.sun_intensity);
    EXPECT_EQ(a.lighting.ambient_intensity,
              changing.stations[0].lighting.ambient_intensity);
  }
}

TEST(TowerScene, RejectsBadOptions) {
  TowerSceneOptions options = SmallSceneOptions();
  options.num_views = 1;
  EXPECT_THROW(PlanTowerScene(options), InputError);
  options = SmallSceneOptions();
  options.min_distance_m = 2.0;  // on the platform
  EXPECT_THROW(PlanTowerScene(options), InputError);
  options = SmallSceneOptions();
  options.film_max_shift_mm = 5;  // more than the margin
  EXPECT_THROW(PlanTowerScene(options), InputError);
}

}  // namespace
}  // namespace bayon
