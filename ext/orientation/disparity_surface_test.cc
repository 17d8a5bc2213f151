// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/disparity_surface.h"

#include "ext/colmap/table_disparity.h"
#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/core/random.h"
#include "ext/orientation/disparity.h"
#include "ext/synth/synthetic_camera.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <random>

#include "tests/testing.h"

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;

// An object as an implicit function: > 0 outside (towards the cameras),
// < 0 inside.
using Surface = std::function<double(const Eigen::Vector3d&)>;

// A curved wall: part of a vertical cylinder of radius 8 m (axis 6 m behind
// the origin, so that its limbs lie outside the images), 4 m high, with a
// relief of +-8 cm: smooth at the scale of a few cells, not a plane.
double ReliefWall(const Eigen::Vector3d& p) {
  if (p.z() < 0 || p.z() > 4) return 1;
  const double arc = 8 * std::atan2(p.y(), p.x() + 6);
  const double radius = 8.0 + 0.08 * std::sin(M_PI * arc) * std::cos(3 * p.z());
  return std::hypot(p.x() + 6, p.y()) - radius;
}

// A flat wall whose upper part (above z = 2.2 m) stands 0.5 m further out:
// a tier with its cornice, a step in depth of 6 % of the distance.
constexpr double kStepHeight = 2.2;
double SteppedWall(const Eigen::Vector3d& p) {
  if (p.z() < 0 || p.z() > 4.5) return 1;
  const double face = 2.0 + (p.z() > kStepHeight ? 0.5 : 0.0) +
                      0.03 * std::sin(2 * p.y()) * std::cos(2 * p.z());
  return p.x() - face;
}

// A tilted plane facing the cameras.
double TiltedPlane(const Eigen::Vector3d& p) {
  return p.dot(Eigen::Vector3d(0.95, 0.25, 0.12).normalized()) - 0.5;
}

// Two stations of a ring around the object (radius 10 m), `step_deg` apart,
// seeing it through the synthetic Brown/Beyer camera (distortion on).
struct Pair {
  Camera camera;
  Rigid3d cam1_from_world, cam2_from_world;
  ImageVectors vectors;
  Surface surface;

  // cam2_from_cam1 with |t| = 1, as the relative orientation gives it.
  Rigid3d Cam2FromCam1() const {
    Rigid3d relative = cam2_from_world * cam1_from_world.Inverse();
    relative.translation.normalize();
    return relative;
  }
};

Pair MakePair(const Surface& surface, double step_deg = 22.5) {
  Pair pair;
  pair.camera = SyntheticCamera(SyntheticCameraOptions());
  const Eigen::Vector3d target(0, 0, 2);
  pair.cam1_from_world = LookAt(Eigen::Vector3d(10, 0, 2), target);
  pair.cam2_from_world = LookAt(
      Eigen::Vector3d(
          10 * std::cos(step_deg * kDeg), 10 * std::sin(step_deg * kDeg), 2.4),
      target + Eigen::Vector3d(0, 0.3, 0),
      Eigen::Vector3d::UnitZ(),
      0.03);
  pair.vectors = ImageVectors(pair.camera, std::nullopt, true, false);
  pair.surface = surface;
  return pair;
}

// The first point of the surface along a ray (marching, then bisection).
bool FirstHit(const Surface& surface,
              const Eigen::Vector3d& origin,
              const Eigen::Vector3d& direction,
              Eigen::Vector3d* hit) {
  const Eigen::Vector3d d = direction.normalized();
  double previous = 3;
  for (double t = 3 + 0.01; t < 25; t += 0.01) {
    if (surface(origin + t * d) > 0) {
      previous = t;
      continue;
    }
    double lo = previous, hi = t;
    for (int k = 0; k < 60; ++k) {
      const double mid = 0.5 * (lo + hi);
      (surface(origin + mid * d) > 0 ? lo : hi) = mid;
    }
    *hit = origin + 0.5 * (lo + hi) * d;
    return true;
  }
  return false;
}

bool Inside(const Camera& camera, const Eigen::Vector2d& pixel) {
  return pixel.x() > 0 && pixel.y() > 0 && pixel.x() < camera.width &&
         pixel.y() < camera.height;
}

// A true conjugate pair: image-1 pixel -> surface point seen by both.
bool TruePair(const Pair& pair,
              const Eigen::Vector2d& pixel1,
              Eigen::Vector2d* pixel2,
              Eigen::Vector3d* point = nullptr) {
  const Eigen::Vector3d ray = pair.camera.CamFromImg(pixel1);
  const Rigid3d world_from_cam1 = pair.cam1_from_world.Inverse();
  const Eigen::Vector3d c1 = pair.cam1_from_world.Center();
  Eigen::Vector3d X;
  if (!FirstHit(
          pair.surface, c1, world_from_cam1.rotation * ray.normalized(), &X)) {
    return false;
  }
  const Eigen::Vector3d c2 = pair.cam2_from_world.Center();
  Eigen::Vector3d seen;
  if (!FirstHit(pair.surface, c2, X - c2, &seen) || (seen - X).norm() > 1e-4) {
    return false;  // hidden from image 2
  }
  if (!pair.camera.ImgFromCam(pair.cam2_from_world * X, pixel2) ||
      !Inside(pair.camera, *pixel2)) {
    return false;
  }
  if (point) *point = X;
  return true;
}

struct Samples {
  ConjugatePoints points;
  std::vector<uint8_t> is_blunder;
};

// Which true points to take: by image-1 pixel and object point.
using Where =
    std::function<bool(const Eigen::Vector2d&, const Eigen::Vector3d&)>;
bool Anywhere(const Eigen::Vector2d&, const Eigen::Vector3d&) { return true; }

// n conjugate points at random image-1 positions accepted by `where`, with
// Gaussian noise; a share replaced by blunders that still lie on the
// epipolar line (a wrong depth: what the epipolar test cannot catch).
Samples MakeSamples(const Pair& pair,
                    int n,
                    double noise_px,
                    double blunder_share,
                    unsigned seed,
                    const Where& where = Anywhere) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, noise_px);
  Samples samples;
  int attempts = 0;
  while (samples.points.size() < n && ++attempts < 100 * n) {
    const Eigen::Vector2d pixel1 = RandomVector<2>(unit, rng).cwiseProduct(
        Eigen::Vector2d(pair.camera.width, pair.camera.height));
    Eigen::Vector2d pixel2;
    Eigen::Vector3d X;
    if (!TruePair(pair, pixel1, &pixel2, &X) || !where(pixel1, X)) continue;
    const bool blunder = unit(rng) < blunder_share;
    if (blunder) {
      // The same ray of image 1, 0.6 to 3 m nearer or farther.
      const Eigen::Vector3d c1 = pair.cam1_from_world.Center();
      const double size = 0.6 + 2.4 * unit(rng);
      const double shift = (unit(rng) < 0.5 ? -1 : 1) * size;
      const Eigen::Vector3d Y = X + shift * (X - c1).normalized();
      if (!pair.camera.ImgFromCam(pair.cam2_from_world * Y, &pixel2) ||
          !Inside(pair.camera, pixel2)) {
        continue;
      }
    }
    const Eigen::Vector2d p1 = pixel1 + RandomVector<2>(noise, rng);
    const Eigen::Vector2d p2 = pixel2 + RandomVector<2>(noise, rng);
    Eigen::Vector3d u1, u2;
    if (!pair.vectors.FromPixel(p1, &u1) || !pair.vectors.FromPixel(p2, &u2)) {
      continue;
    }
    samples.points.u1.push_back(u1);
    samples.points.u2.push_back(u2);
    samples.points.pixel1.push_back(p1);
    samples.points.pixel2.push_back(p2);
    samples.is_blunder.push_back(blunder);
  }
  return samples;
}

ConjugatePoints Swapped(const ConjugatePoints& points) {
  ConjugatePoints swapped;
  swapped.u1 = points.u2;
  swapped.u2 = points.u1;
  swapped.pixel1 = points.pixel2;
  swapped.pixel2 = points.pixel1;
  return swapped;
}

double Median(std::vector<double> values) {
  std::nth_element(
      values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

struct HeldOut {
  int num_supported = 0;
  int num_inside = 0;  // of the supported ones
  double median_band_px = 0;
  double median_range_px = 0;
  double max_across_px = 0;
};

// True conjugate points not used in the fit, against the band.
HeldOut CheckHeldOut(const Pair& pair,
                     const DisparitySurface& surface,
                     bool reverse,
                     int n,
                     unsigned seed,
                     const Where& where = Anywhere) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  HeldOut result;
  std::vector<double> bands, ranges;
  for (int attempt = 0; attempt < 50 * n && result.num_supported < n;
       ++attempt) {
    const Eigen::Vector2d pixel = RandomVector<2>(unit, rng).cwiseProduct(
        Eigen::Vector2d(pair.camera.width, pair.camera.height));
    Eigen::Vector2d other;
    Eigen::Vector3d X;
    if (!TruePair(pair, pixel, &other, &X) || !where(pixel, X)) continue;
    const Eigen::Vector2d pixel1 = reverse ? other : pixel;
    const Eigen::Vector2d pixel2 = reverse ? pixel : other;
    const SearchInterval interval = surface.Search(pixel1);
    if (!interval.valid || !interval.supported) continue;
    ++result.num_supported;
    const EpipolarPosition position = surface.Locate(pixel1, pixel2);
    result.max_across_px =
        std::max(result.max_across_px, std::abs(position.across_px));
    result.num_inside += surface.Contains(pixel1, pixel2, 1.0);
    bands.push_back(interval.length_px);
    ranges.push_back(surface.FullRangePx(pixel1));
  }
  if (!bands.empty()) {
    result.median_band_px = Median(bands);
    result.median_range_px = Median(ranges);
  }
  return result;
}

// The statistical band alone: no depth tolerance, no neighbour range.
DisparitySurfaceOptions StatisticalOnly() {
  DisparitySurfaceOptions options;
  options.depth_tolerance = 0;
  options.range_neighbors = 0;
  return options;
}

TEST(DisparitySurface, PlaneIsReproducedExactly) {
  const Pair pair = MakePair(TiltedPlane);
  const Samples samples = MakeSamples(pair, 300, 0.0, 0.0, 1);
  ASSERT_EQ(samples.points.size(), 300);
  DisparityFitReport report;
  const DisparitySurface surface = DisparitySurface::Fit(samples.points,
                                                         pair.Cam2FromCam1(),
                                                         pair.vectors,
                                                         pair.vectors,
                                                         StatisticalOnly(),
                                                         &report);
  ASSERT_TRUE(surface.success()) << surface.record().reason;
  EXPECT_EQ(report.num_used, 300);
  // The inverse depth of a plane is affine in the image coordinates: the
  // fit and its cross-validated predictions are exact.
  EXPECT_LT(surface.record().robust_sigma_px, 1e-4);
  EXPECT_LT(surface.record().cv_sigma_px, 1e-4);
  const HeldOut held_out = CheckHeldOut(pair, surface, false, 300, 2);
  EXPECT_EQ(held_out.num_inside, held_out.num_supported);
  EXPECT_LT(held_out.max_across_px, 1e-4);
  // So the band is the floor, min_band_k * min_sigma_px on either side, at
  // the data (and grows with the distance from it).
  EXPECT_NEAR(surface.record().band_k, 3.0, 1e-12);
  for (int k = 0; k < 20; ++k) {
    Eigen::Vector2d truth;
    ASSERT_TRUE(TruePair(pair, samples.points.pixel1[k], &truth));
    const SearchInterval interval = surface.Search(samples.points.pixel1[k]);
    EXPECT_LT((interval.predicted - truth).norm(), 1e-4) << k;
    EXPECT_NEAR(interval.half_width_px, 3 * 0.5, 1e-9);
    EXPECT_NEAR(interval.length_px, 2 * 3 * 0.5, 1e-3);
  }
}

TEST(DisparitySurface, CurvedWallWithBlundersBothDirections) {
  const Pair pair = MakePair(ReliefWall);
  const Samples samples = MakeSamples(pair, 600, 0.3, 0.1, 3);
  ASSERT_EQ(samples.points.size(), 600);
  for (const bool reverse : {false, true}) {
    SCOPED_TRACE(reverse ? "image 2 -> image 1" : "image 1 -> image 2");
    Rigid3d cam2_from_cam1 = pair.Cam2FromCam1();
    if (reverse) {
      cam2_from_cam1 = cam2_from_cam1.Inverse();
      cam2_from_cam1.translation.normalize();
    }
    DisparityFitReport report;
    const DisparitySurface surface = DisparitySurface::Fit(
        reverse ? Swapped(samples.points) : samples.points,
        cam2_from_cam1,
        pair.vectors,
        pair.vectors,
        StatisticalOnly(),
        &report);
    ASSERT_TRUE(surface.success()) << surface.record().reason;
    int num_blunders = 0, flagged = 0, good_lost = 0;
    for (size_t k = 0; k < samples.is_blunder.size(); ++k) {
      num_blunders += samples.is_blunder[k];
      if (samples.is_blunder[k]) {
        flagged += !report.used[k];
      } else {
        good_lost += !report.used[k];
      }
    }
    const HeldOut held_out = CheckHeldOut(pair, surface, reverse, 1000, 4);
    const DisparitySurfaceRecord& r = surface.record();
    std::printf(
        "%s: %d points, %d of %d blunders flagged, %d good lost, sigma %.2f "
        "px (cv %.2f), band_k %.2f, %d x %d cells, smoothness %g; held out: "
        "%d of %d inside, median band %.1f px of %.0f px\n",
        reverse ? "2->1" : "1->2",
        r.num_points,
        flagged,
        num_blunders,
        good_lost,
        r.robust_sigma_px,
        r.cv_sigma_px,
        r.band_k,
        r.cols,
        r.rows,
        r.smoothness,
        held_out.num_inside,
        held_out.num_supported,
        held_out.median_band_px,
        held_out.median_range_px);
    EXPECT_GE(flagged, 0.9 * num_blunders);
    EXPECT_LE(good_lost, 0.03 * (r.num_points - num_blunders));
    EXPECT_GE(held_out.num_supported, 900);
    // The statistical band alone holds a smooth object's truth.
    EXPECT_GE(held_out.num_inside, 0.99 * held_out.num_supported);
    // True points lie on the line (exact orientation): a check of the
    // geometry, not of the surface.
    EXPECT_LT(held_out.max_across_px, 1e-3);
    // A few pixels of a line some 1600 px long.
    EXPECT_LT(held_out.median_band_px, 0.02 * held_out.median_range_px);
    EXPECT_GE(r.cv_coverage, 0.99);
  }
}

TEST(DisparitySurface, DepthToleranceHoldsAnUnsampledStep) {
  const Pair pair = MakePair(SteppedWall);
  // No conjugate points on the 40 cm around the step (a cornice the
  // matching missed); true points there are held out.
  const auto off_step = [](const Eigen::Vector2d&, const Eigen::Vector3d& X) {
    return std::abs(X.z() - kStepHeight) > 0.2;
  };
  const auto at_step = [](const Eigen::Vector2d&, const Eigen::Vector3d& X) {
    return std::abs(X.z() - kStepHeight) < 0.2;
  };
  const Samples samples = MakeSamples(pair, 500, 0.3, 0.0, 13, off_step);
  DisparitySurfaceOptions options;
  options.support_radius_spacings = 3;  // let the step's band count
  const DisparitySurface plain = [&] {
    DisparitySurfaceOptions statistical = StatisticalOnly();
    statistical.support_radius_spacings = options.support_radius_spacings;
    return DisparitySurface::Fit(samples.points,
                                 pair.Cam2FromCam1(),
                                 pair.vectors,
                                 pair.vectors,
                                 statistical);
  }();
  const DisparitySurface tolerant = DisparitySurface::Fit(
      samples.points, pair.Cam2FromCam1(), pair.vectors, pair.vectors, options);
  ASSERT_TRUE(plain.success() && tolerant.success());
  const HeldOut plain_held = CheckHeldOut(pair, plain, false, 300, 14, at_step);
  const HeldOut tolerant_held =
      CheckHeldOut(pair, tolerant, false, 300, 14, at_step);
  std::printf(
      "step: statistical band holds %d of %d (median %.1f px), with the "
      "depth tolerance %d of %d (median %.1f px of %.0f px)\n",
      plain_held.num_inside,
      plain_held.num_supported,
      plain_held.median_band_px,
      tolerant_held.num_inside,
      tolerant_held.num_supported,
      tolerant_held.median_band_px,
      tolerant_held.median_range_px);
  ASSERT_GE(plain_held.num_supported, 200);
  EXPECT_LT(plain_held.num_inside, 0.9 * plain_held.num_supported);
  EXPECT_GE(tolerant_held.num_inside, 0.99 * tolerant_held.num_supported);
  // Wide here (the step is 6 % of the depth, and these points lie up to
  // three spacings from the data), yet a small part of the line.
  EXPECT_LT(tolerant_held.median_band_px, 0.12 * tolerant_held.median_range_px);
}

TEST(DisparitySurface, IntervalLiesOnTheEpipolarLine) {
  const Pair pair = MakePair(ReliefWall);
  const Samples samples = MakeSamples(pair, 400, 0.3, 0.0, 5);
  const DisparitySurface surface =
      DisparitySurface::Fit(samples.points,
                            pair.Cam2FromCam1(),
                            pair.vectors,
                            pair.vectors,
                            DisparitySurfaceOptions());
  ASSERT_TRUE(surface.success());
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d& pixel1 = samples.points.pixel1[k];
    const SearchInterval interval = surface.Search(pixel1);
    ASSERT_TRUE(interval.valid);
    EXPECT_GT(interval.min_inverse_depth, 0);
    EXPECT_LT(interval.min_inverse_depth, interval.inverse_depth);
    EXPECT_GT(interval.max_inverse_depth, interval.inverse_depth);
    const EpipolarPosition predicted =
        surface.Locate(pixel1, interval.predicted);
    const EpipolarPosition begin = surface.Locate(pixel1, interval.begin);
    const EpipolarPosition end = surface.Locate(pixel1, interval.end);
    for (const EpipolarPosition& p : {predicted, begin, end}) {
      EXPECT_TRUE(p.valid);
      EXPECT_LT(std::abs(p.across_px), 1e-6);
    }
    EXPECT_NEAR(predicted.along_px, 0, 1e-6);
    EXPECT_NEAR(predicted.inverse_depth, interval.inverse_depth, 1e-9);
    // Along the line in the distortion-free plane of image 2.
    EXPECT_NEAR(begin.along_px, interval.along_begin_px, 1e-5);
    EXPECT_NEAR(end.along_px, interval.along_end_px, 1e-5);
    EXPECT_LE(interval.along_begin_px, -interval.half_width_px);
    EXPECT_GE(interval.along_end_px, interval.half_width_px);
    EXPECT_NEAR(interval.length_px,
                interval.along_end_px - interval.along_begin_px,
                1e-9);
    EXPECT_NEAR(begin.inverse_depth, interval.min_inverse_depth, 1e-9);
    EXPECT_NEAR(end.inverse_depth, interval.max_inverse_depth, 1e-9);
    // The depth tolerance, 6 % by default, on either side (and a little
    // more).
    EXPECT_LT(interval.max_inverse_depth / interval.min_inverse_depth, 1.3);
    EXPECT_GT(interval.max_inverse_depth / interval.min_inverse_depth,
              1.06 / 0.94);
    EXPECT_GT(
        (interval.end - interval.begin).normalized().dot(interval.direction),
        0.999);
    Eigen::Vector2d at;
    ASSERT_TRUE(surface.PointAt(pixel1, interval.inverse_depth, &at));
    EXPECT_LT((at - interval.predicted).norm(), 1e-9);
  }
}

TEST(DisparitySurface, BandGrowsOffTheData) {
  const Pair pair = MakePair(TiltedPlane);
  // Points only in the left half of image 1.
  const Samples samples =
      MakeSamples(pair,
                  200,
                  0.3,
                  0.0,
                  7,
                  [](const Eigen::Vector2d& pixel, const Eigen::Vector3d&) {
                    return pixel.x() < 800;
                  });
  const DisparitySurface surface =
      DisparitySurface::Fit(samples.points,
                            pair.Cam2FromCam1(),
                            pair.vectors,
                            pair.vectors,
                            DisparitySurfaceOptions());
  ASSERT_TRUE(surface.success());
  // A true point far right in image 1 (seen in image 2 too).
  Eigen::Vector2d far_pixel, truth;
  for (double x = 1750; x > 1300; x -= 10) {
    far_pixel = Eigen::Vector2d(x, 600);
    if (TruePair(pair, far_pixel, &truth)) break;
  }
  ASSERT_GT(far_pixel.x(), 1300);
  const SearchInterval near = surface.Search(samples.points.pixel1[0]);
  const SearchInterval edge = surface.Search(Eigen::Vector2d(1000, 600));
  const SearchInterval far = surface.Search(far_pixel);
  ASSERT_TRUE(near.valid && edge.valid && far.valid);
  EXPECT_TRUE(near.supported);
  EXPECT_FALSE(edge.supported);
  EXPECT_FALSE(far.supported);
  EXPECT_GT(far.support_distance_px, 500);
  EXPECT_LT(near.support_distance_px, 1e-3);
  EXPECT_GT(far.half_width_px, near.half_width_px + 100);
  EXPECT_GT(edge.half_width_px, near.half_width_px);
  EXPECT_GT(far.length_px, edge.length_px);
  // A plane extrapolates exactly, so the wide band still holds the truth.
  EXPECT_TRUE(surface.Contains(far_pixel, truth, 2.0));
}

TEST(DisparitySurface, TooFewPointsIsAReportNotAnError) {
  const Pair pair = MakePair(TiltedPlane);
  const Samples samples = MakeSamples(pair, 8, 0.3, 0.0, 9);
  DisparityFitReport report;
  const DisparitySurface surface =
      DisparitySurface::Fit(samples.points,
                            pair.Cam2FromCam1(),
                            pair.vectors,
                            pair.vectors,
                            DisparitySurfaceOptions(),
                            &report);
  EXPECT_FALSE(surface.success());
  EXPECT_NE(surface.record().reason.find("too few"), std::string::npos)
      << surface.record().reason;
  EXPECT_FALSE(surface.Search(samples.points.pixel1[0]).valid);
}

TEST(DisparitySurface, OptionsAreChecked) {
  DisparitySurfaceOptions options;
  options.band_quantile = 1.5;
  EXPECT_THROW(options.Check(), InputError);
  options = DisparitySurfaceOptions();
  options.smoothness_candidates = {1.0, -1.0};
  EXPECT_THROW(options.Check(), InputError);
  options = DisparitySurfaceOptions();
  options.num_folds = 1;
  try {
    options.Check();
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("num_folds"), std::string::npos);
  }
}

// A database with the pair as `bayon relative` leaves it: a PINHOLE camera
// with a known focal length, keypoints, matches, the two-view geometry and
// the bayon orientation.
std::string PairDatabase(const std::string& dir,
                         const ConjugatePoints& points,
                         const Rigid3d& cam2_from_cam1) {
  const std::string path = dir + "/database.db";
  Database db(path, Database::Mode::kCreate);
  Camera camera = Camera::Create(CameraModelId::kPinhole, 1750, 1800, 1200);
  camera.has_prior_focal_length = true;
  const camera_t camera_id = db.WriteCamera(camera);
  const image_t id1 =
      db.WriteImage(DatabaseImage{kInvalidImageId, "a.png", camera_id, {}, {}});
  const image_t id2 =
      db.WriteImage(DatabaseImage{kInvalidImageId, "b.png", camera_id, {}, {}});
  db.WriteKeypoints(id1, KeypointsFromXY(points.pixel1));
  db.WriteKeypoints(id2, KeypointsFromXY(points.pixel2));
  FeatureMatches matches(points.size(), 2);
  for (int k = 0; k < points.size(); ++k) matches.row(k) << k, k;
  db.WriteMatches(id1, id2, matches);
  TwoViewGeometry geometry;
  geometry.config = TwoViewConfig::kCalibrated;
  geometry.inlier_matches = matches;
  const Eigen::Quaterniond& q = cam2_from_cam1.rotation;
  geometry.qvec = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  geometry.tvec = cam2_from_cam1.translation;
  db.WriteTwoViewGeometry(id1, id2, geometry);
  RelativeOrientationRecord record;
  record.success = true;
  record.calibrated = true;
  record.num_matches = record.num_inliers = points.size();
  record.cam2_from_cam1 = cam2_from_cam1;
  record.inliers.assign(points.size(), 1);
  WriteRelativeOrientation(&db, id1, id2, record);
  return path;
}

TEST(DisparityStage, FitsStoresLoadsAndNoticesStaleSurfaces) {
  // An ideal pinhole pair (the database's PINHOLE camera).
  Pair pair = MakePair(ReliefWall);
  pair.camera = Camera::Create(CameraModelId::kPinhole, 1750, 1800, 1200);
  pair.vectors = ImageVectors(pair.camera, std::nullopt, true, false);
  const Samples samples = MakeSamples(pair, 300, 0.3, 0.0, 11);
  const std::string dir = testing::TempDir("disparity_stage");
  const std::string db_path =
      PairDatabase(dir, samples.points, pair.Cam2FromCam1());

  DisparityOptions options;
  options.num_threads = 2;
  const DisparitySummary first = FitDisparitySurfaces(db_path, options);
  EXPECT_EQ(first.num_pairs, 1);
  EXPECT_EQ(first.num_fitted, 2);
  ASSERT_EQ(first.surfaces.size(), 2u);
  EXPECT_EQ(first.surfaces[0].image_id1, 1u);
  EXPECT_EQ(first.surfaces[1].image_id1, 2u);
  EXPECT_EQ(first.surfaces[0].num_points, 300);

  {
    Database db(db_path, Database::Mode::kReadWrite);
    std::string reason;
    const auto forward = LoadDisparitySurface(&db, 1, 2, &reason);
    ASSERT_TRUE(forward) << reason;
    const auto backward = LoadDisparitySurface(&db, 2, 1, &reason);
    ASSERT_TRUE(backward) << reason;
    // What was stored answers as the surface fitted in memory does.
    const DisparitySurface fitted = DisparitySurface::Fit(samples.points,
                                                          pair.Cam2FromCam1(),
                                                          pair.vectors,
                                                          pair.vectors,
                                                          options.surface);
    for (int k = 0; k < 30; ++k) {
      const Eigen::Vector2d& pixel1 = samples.points.pixel1[k];
      const SearchInterval a = forward->Search(pixel1);
      const SearchInterval b = fitted.Search(pixel1);
      ASSERT_TRUE(a.valid && b.valid);
      // Keypoints are stored as float32: the same up to that.
      EXPECT_LT((a.predicted - b.predicted).norm(), 1e-3);
      EXPECT_NEAR(a.length_px, b.length_px, 1e-3 * b.length_px);
      EXPECT_TRUE(forward->Contains(pixel1, samples.points.pixel2[k], 2.0));
      EXPECT_TRUE(backward->Contains(
          samples.points.pixel2[k], samples.points.pixel1[k], 2.0));
    }
    EXPECT_EQ(ReadAllDisparitySurfaces(&db).size(), 2u);
  }

  // Current surfaces are kept...
  const DisparitySummary second = FitDisparitySurfaces(db_path, options);
  EXPECT_EQ(second.num_skipped, 2);
  EXPECT_EQ(second.num_fitted, 0);

  // ... until the pair is oriented again: then they are stale.
  {
    Database db(db_path, Database::Mode::kReadWrite);
    RelativeOrientationRecord record = *ReadRelativeOrientation(&db, 1, 2);
    record.cam2_from_cam1.rotation =
        record.cam2_from_cam1.rotation *
        Eigen::Quaterniond(Eigen::AngleAxisd(1e-3, Eigen::Vector3d::UnitY()));
    WriteRelativeOrientation(&db, 1, 2, record);
    std::string reason;
    EXPECT_FALSE(LoadDisparitySurface(&db, 1, 2, &reason));
    EXPECT_NE(reason.find("stale"), std::string::npos) << reason;
  }
  const DisparitySummary third = FitDisparitySurfaces(db_path, options);
  EXPECT_EQ(third.num_fitted, 2);
  {
    Database db(db_path, Database::Mode::kReadWrite);
    EXPECT_TRUE(LoadDisparitySurface(&db, 2, 1));
    // Deleting an image takes its surfaces with it.
    db.connection()->Execute("DELETE FROM images WHERE image_id = 2");
    EXPECT_TRUE(ReadAllDisparitySurfaces(&db).empty());
  }
}

TEST(DisparityStage, RefusesADatabaseWithoutOrientedPairs) {
  const std::string dir = testing::TempDir("disparity_no_pairs");
  {
    Database db(dir + "/database.db", Database::Mode::kCreate);
    const camera_t camera_id =
        db.WriteCamera(Camera::Create(CameraModelId::kPinhole, 1000, 800, 600));
    db.WriteImage(DatabaseImage{kInvalidImageId, "a.png", camera_id, {}, {}});
    db.WriteImage(DatabaseImage{kInvalidImageId, "b.png", camera_id, {}, {}});
  }
  try {
    FitDisparitySurfaces(dir + "/database.db", DisparityOptions());
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("no oriented image pairs"),
              std::string::npos)
        << error.what();
  }
  EXPECT_THROW(FitDisparitySurfaces(dir + "/missing.db", DisparityOptions()),
               InputError);
}

}  // namespace
}  // namespace bayon
