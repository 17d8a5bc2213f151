// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/relative_orientation.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

namespace bayon {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A pinhole camera like the paper's (35 mm on a 36 x 24 mm frame at 20 um:
// 1750 px, 1800 x 1200).
constexpr double kFocal = 1750, kWidth = 1800, kHeight = 1200;

// Image vector u = (x, y, -c) of a COLMAP pixel for that camera.
Eigen::Vector3d ImageVector(const Eigen::Vector2d& pixel) {
  return Eigen::Vector3d(
      pixel.x() - kWidth / 2, -(pixel.y() - kHeight / 2), -kFocal);
}

struct Synthetic {
  ConjugatePoints points;
  Rigid3d cam2_from_cam1;  // truth
  std::vector<uint8_t> is_blunder;
};

// Two stations of a ring around an object (radius 10 m, camera height
// 2 m), `step_deg` apart in azimuth; random points of the object seen by
// both; Gaussian noise on the image coordinates; a share of the points
// replaced by blunders (random positions in image 2). With base_m >= 0 the
// second station is that far sideways from the first instead (0: a pure
// rotation).
Synthetic MakePair(int n,
                   double noise_px,
                   double blunder_share,
                   unsigned seed,
                   double step_deg = 22.5,
                   double base_m = -1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  std::uniform_real_distribution<double> unit(0, 1);
  const Eigen::Vector3d target(0, 0, 2);
  const Eigen::Vector3d c1(10, 0, 2);
  Eigen::Vector3d c2(
      10 * std::cos(step_deg * kDeg), 10 * std::sin(step_deg * kDeg), 2.6);
  if (base_m >= 0) c2 = c1 + Eigen::Vector3d(0, base_m, 0);
  const Rigid3d cam1_from_world = LookAt(c1, target);
  const Rigid3d cam2_from_world =
      base_m >= 0 ? LookAt(c2, target + Eigen::Vector3d(0, 1.5, 0.3))
                  : LookAt(c2, target, Eigen::Vector3d::UnitZ(), 0.05);
  Synthetic pair;
  pair.cam2_from_cam1 = cam2_from_world * cam1_from_world.Inverse();
  const auto project = [](const Rigid3d& pose, const Eigen::Vector3d& X) {
    const Eigen::Vector3d p = pose * X;
    return Eigen::Vector2d(kFocal * p.x() / p.z() + kWidth / 2,
                           kFocal * p.y() / p.z() + kHeight / 2);
  };
  const Rigid3d world_from_cam1 = cam1_from_world.Inverse();
  while (pair.points.size() < n) {
    // A point anywhere in image 1, 8 to 12 m away: an object that fills
    // the frame, with relief.
    const Eigen::Vector2d pixel = RandomVector<2>(unit, rng).cwiseProduct(
        Eigen::Vector2d(kWidth, kHeight));
    const Eigen::Vector3d ray((pixel.x() - kWidth / 2) / kFocal,
                              (pixel.y() - kHeight / 2) / kFocal,
                              1.0);
    const Eigen::Vector3d X = world_from_cam1 * (ray * (8 + 4 * unit(rng)));
    Eigen::Vector2d x1 = project(cam1_from_world, X);
    Eigen::Vector2d x2 = project(cam2_from_world, X);
    const auto inside = [](const Eigen::Vector2d& x) {
      return x.x() > 0 && x.y() > 0 && x.x() < kWidth && x.y() < kHeight;
    };
    if (!inside(x1) || !inside(x2)) continue;
    x1 += RandomVector<2>(noise, rng);
    x2 += RandomVector<2>(noise, rng);
    const bool blunder = unit(rng) < blunder_share;
    if (blunder) {
      x2 = RandomVector<2>(unit, rng).cwiseProduct(
          Eigen::Vector2d(kWidth, kHeight));
    }
    pair.points.u1.push_back(ImageVector(x1));
    pair.points.u2.push_back(ImageVector(x2));
    pair.points.pixel1.push_back(x1);
    pair.points.pixel2.push_back(x2);
    pair.is_blunder.push_back(blunder);
  }
  return pair;
}

double RotationErrorDeg(const Rigid3d& a, const Rigid3d& b) {
  return RotationAngleBetween(a.rotation, b.rotation) / kDeg;
}

double BaseErrorDeg(const Rigid3d& a, const Rigid3d& b) {
  const Eigen::Vector3d ca = a.Center().normalized();
  const Eigen::Vector3d cb = b.Center().normalized();
  return std::atan2(ca.cross(cb).norm(), ca.dot(cb)) / kDeg;
}

TEST(RelativeOrientation, ExactPointsGiveTheExactElements) {
  const Synthetic pair = MakePair(60, 0.0, 0.0, 1);
  const RelativeOrientation result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  ASSERT_TRUE(result.success) << result.reason;
  const Rigid3d estimate = result.Cam2FromCam1();
  EXPECT_LT(RotationErrorDeg(estimate, pair.cam2_from_cam1), 1e-7);
  EXPECT_LT(BaseErrorDeg(estimate, pair.cam2_from_cam1), 1e-6);
  EXPECT_NEAR(estimate.translation.norm(), 1.0, 1e-12);
  EXPECT_LT(result.sigma0_px, 1e-6);
  EXPECT_EQ(result.num_blunders, 0);
  // The convergence angle of two stations 22.5 degrees apart on the ring.
  EXPECT_NEAR(result.convergence_angle_deg, 22.5, 2.0);
  // Eq. (1) with the paper's L is the coplanarity condition.
  ASSERT_TRUE(result.L.has_value());
  const Eigen::Matrix<double, 8, 1>& L = *result.L;
  for (int i = 0; i < 5; ++i) {
    const double x1 = pair.points.u1[i].x(), y1 = pair.points.u1[i].y();
    const double x2 = pair.points.u2[i].x(), y2 = pair.points.u2[i].y();
    const double c = kFocal;
    const double eq1 = L(0) * x2 * y1 + L(1) * y2 * y1 - L(2) * y1 * c +
                       L(3) * x2 * c - L(4) * c * c + L(5) * x1 * x2 +
                       L(6) * x1 * y2 - L(7) * x1 * c + c * y2;
    EXPECT_NEAR(eq1 / (c * c), 0.0, 1e-9);
  }
}

TEST(RelativeOrientation, NoisyPointsStayWithinTheirStandardDeviations) {
  // 0.5 px: whole-pixel matching; the errors scale with it.
  const Synthetic pair = MakePair(300, 0.5, 0.0, 2);
  const RelativeOrientation result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  ASSERT_TRUE(result.success) << result.reason;
  const Rigid3d estimate = result.Cam2FromCam1();
  const double rotation_error = RotationErrorDeg(estimate, pair.cam2_from_cam1);
  const double base_error = BaseErrorDeg(estimate, pair.cam2_from_cam1);
  EXPECT_LT(rotation_error, 0.05);
  EXPECT_LT(base_error, 0.2);
  // sigma0 estimates the noise of the four coordinates of a point.
  EXPECT_NEAR(result.sigma0_px, 0.5, 0.08);
  // The errors are of the size the covariance predicts.
  const double std_rotation = result.std_omega_phi_kappa_deg.norm();
  const double std_base = result.std_base_deg.norm();
  EXPECT_GT(std_rotation, 0);
  EXPECT_LT(rotation_error, 4 * std_rotation);
  EXPECT_LT(base_error, 4 * std_base);
  EXPECT_LT(result.num_blunders, 300 * 0.03);
}

// Points of two precisions (least-squares points and correlation peaks, as
// `bayon match --lsm_refinement 1 --lsm_keep_unrefined 1` gives them): with
// their standard deviations the imprecise ones count by theirs instead of
// being taken for blunders, and the precise ones set sigma0.
TEST(RelativeOrientation, PointsAreWeightedByTheirStandardDeviations) {
  constexpr int kPrecise = 240, kImprecise = 160;
  Synthetic pair = MakePair(kPrecise + kImprecise, 0.05, 0.0, 11);
  std::mt19937 rng(12);
  std::normal_distribution<double> noise(0, 1.0);
  for (int i = 0; i < kPrecise + kImprecise; ++i) {
    double sigma = 0.05;
    if (i >= kPrecise) {
      sigma = 1.0;
      const Eigen::Vector2d shift = RandomVector<2>(noise, rng);
      pair.points.pixel2[i] += shift;
      pair.points.u2[i] = ImageVector(pair.points.pixel2[i]);
    }
    pair.points.sigma.push_back(sigma);
  }
  const RelativeOrientation weighted =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  ASSERT_TRUE(weighted.success) << weighted.reason;
  ConjugatePoints unweighted_points = pair.points;
  unweighted_points.sigma.clear();
  const RelativeOrientation unweighted = EstimateRelativeOrientation(
      unweighted_points, RelativeOrientationOptions());
  ASSERT_TRUE(unweighted.success) << unweighted.reason;
  // Without weights most imprecise points fail the blunder test (the robust
  // sigma is the precise points'); with them nearly all take part.
  EXPECT_GT(unweighted.num_blunders, kImprecise / 2);
  EXPECT_LT(weighted.num_blunders, (kPrecise + kImprecise) / 30);
  // sigma0 is the typical (median, precise) point's.
  EXPECT_GT(weighted.sigma0_px, 0.03);
  EXPECT_LT(weighted.sigma0_px, 0.07);
  const Rigid3d estimate = weighted.Cam2FromCam1();
  EXPECT_LT(RotationErrorDeg(estimate, pair.cam2_from_cam1),
            4 * weighted.std_omega_phi_kappa_deg.norm());
  EXPECT_LT(BaseErrorDeg(estimate, pair.cam2_from_cam1),
            4 * weighted.std_base_deg.norm());

  // Equal standard deviations change nothing.
  ConjugatePoints equal = unweighted_points;
  equal.sigma.assign(equal.size(), 0.3);
  const RelativeOrientation same =
      EstimateRelativeOrientation(equal, RelativeOrientationOptions());
  EXPECT_EQ(same.num_inliers, unweighted.num_inliers);
  EXPECT_NEAR(same.sigma0_px, unweighted.sigma0_px, 1e-12);
  EXPECT_LT(RotationErrorDeg(same.Cam2FromCam1(), unweighted.Cam2FromCam1()),
            1e-9);
}

// The paper: "the epipolar geometry can be robustly recovered from the
// matching results containing 5 - 40% blunders using the LMedS method".
// 0.2 px noise: sub-pixel conjugate points as `bayon match` gives them.
TEST(RelativeOrientation, LmedsFlagsBlundersFromFiveToFortyPercent) {
  const Synthetic clean = MakePair(400, 0.2, 0.0, 7);
  const RelativeOrientation reference =
      EstimateRelativeOrientation(clean.points, RelativeOrientationOptions());
  ASSERT_TRUE(reference.success);
  const double clean_error =
      RotationErrorDeg(reference.Cam2FromCam1(), clean.cam2_from_cam1);
  for (double share : {0.05, 0.20, 0.40}) {
    for (unsigned seed : {11u, 12u, 13u}) {
      const Synthetic pair = MakePair(400, 0.2, share, seed);
      const RelativeOrientation result = EstimateRelativeOrientation(
          pair.points, RelativeOrientationOptions());
      ASSERT_TRUE(result.success) << share << ": " << result.reason;
      int blunders = 0, flagged = 0, good = 0, lost = 0;
      for (size_t i = 0; i < pair.is_blunder.size(); ++i) {
        if (pair.is_blunder[i]) {
          ++blunders;
          flagged += !result.inliers[i];
        } else {
          ++good;
          lost += !result.inliers[i];
        }
      }
      EXPECT_GE(flagged, 0.98 * blunders)
          << share << ": " << flagged << " of " << blunders << " flagged";
      EXPECT_LE(lost, 0.02 * good)
          << share << ": " << lost << " of " << good << " good points lost";
      const Rigid3d estimate = result.Cam2FromCam1();
      // The same accuracy as without blunders: the bounds the clean pair
      // meets, and within what the good points allow (their standard
      // deviations).
      const double rotation_error =
          RotationErrorDeg(estimate, pair.cam2_from_cam1);
      const double base_error = BaseErrorDeg(estimate, pair.cam2_from_cam1);
      EXPECT_LT(rotation_error, 0.02) << share;
      EXPECT_LT(rotation_error, 4 * result.std_omega_phi_kappa_deg.norm())
          << share;
      EXPECT_LT(base_error, 0.2) << share;
      std::printf(
          "blunders %2.0f %%: %3d of %3d flagged, %d of %d good lost, "
          "rotation error %.4f deg (clean %.4f), base %.3f deg, "
          "sigma0 %.3f px\n",
          100 * share,
          flagged,
          blunders,
          lost,
          good,
          rotation_error,
          clean_error,
          base_error,
          result.sigma0_px);
    }
  }
}

TEST(RelativeOrientation, AlgebraicResidualsOfThePaperWorkToo) {
  const Synthetic pair = MakePair(300, 0.5, 0.2, 21);
  RelativeOrientationOptions options;
  options.residual = DrtResidual::kAlgebraic;
  const RelativeOrientation result =
      EstimateRelativeOrientation(pair.points, options);
  ASSERT_TRUE(result.success) << result.reason;
  EXPECT_LT(RotationErrorDeg(result.Cam2FromCam1(), pair.cam2_from_cam1), 0.02);
}

TEST(RelativeOrientation, NoBaseNoOrientation) {
  // Pure rotation: the second camera turns on the spot.
  Synthetic pair = MakePair(200, 0.3, 0.0, 3, 0.0, 0.0);
  RelativeOrientation result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("no base"), std::string::npos) << result.reason;
  // Identical images.
  pair.points.u2 = pair.points.u1;
  pair.points.pixel2 = pair.points.pixel1;
  result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("identical images"), std::string::npos)
      << result.reason;
  // Too few points, and points that follow no geometry at all.
  pair = MakePair(10, 0.3, 0.0, 4);
  result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("too few"), std::string::npos);
  pair = MakePair(100, 0.3, 1.0, 5);
  result =
      EstimateRelativeOrientation(pair.points, RelativeOrientationOptions());
  EXPECT_FALSE(result.success);
  EXPECT_FALSE(result.reason.empty());
}

TEST(RelativeOrientation, ElementsAndColmapPosesConvert) {
  const Eigen::Vector3d opk(0.1, -0.4, 2.5);
  const Eigen::Matrix3d R = RotationFromOmegaPhiKappa(opk);
  EXPECT_LT((OmegaPhiKappaFromRotation(R) - opk).norm(), 1e-12);
  // R = Rx(omega) Ry(phi) Rz(kappa): element (0, 2) is sin(phi).
  EXPECT_NEAR(R(0, 2), std::sin(-0.4), 1e-12);
  const Eigen::Vector3d b = Eigen::Vector3d(0.9, 0.2, -0.3).normalized();
  const Rigid3d pose = Cam2FromCam1FromElements(R, b);
  Eigen::Matrix3d R2;
  Eigen::Vector3d b2;
  ElementsFromCam2FromCam1(pose, &R2, &b2);
  EXPECT_LT((R2 - R).norm(), 1e-12);
  EXPECT_LT((b2 - b).norm(), 1e-12);
  // The base is camera 2's centre in camera 1's frame, y and z flipped.
  EXPECT_LT(
      (pose.Inverse().translation - Eigen::Vector3d(b.x(), -b.y(), -b.z()))
          .norm(),
      1e-12);
}

TEST(RelativeOrientation, OptionsAreChecked) {
  RelativeOrientationOptions options;
  options.num_samples = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = RelativeOrientationOptions();
  options.min_num_points = 8;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
