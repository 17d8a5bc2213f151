// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/upright.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace bayon {
namespace {

// A camera at `centre` looking at `target`, level (x axis horizontal)
// before it is rolled about its optical axis by `roll` radians.
Rigid3d LookAt(const Eigen::Vector3d& centre,
               const Eigen::Vector3d& target,
               double roll) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, z.cross(x), z;
  const Eigen::Quaterniond cam_from_world =
      Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ())) *
      Eigen::Quaterniond(world_from_cam.transpose());
  return Rigid3d(cam_from_world, -(cam_from_world * centre));
}

// The same block in a frame turned and moved arbitrarily, as a free
// network's relative orientation leaves it.
const Rigid3d& ArbitraryFromTrue() {
  static const Rigid3d transform(
      Eigen::Quaterniond(
          Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -1, 0.6).normalized())),
      Eigen::Vector3d(4, -7, 1.5));
  return transform;
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) *
         180 / M_PI;
}

// A ring of 16 stations 25 degrees above the object, looking down onto it,
// rolled by `quarter_turns(k)` quarter turns and 2 degrees (one sigma).
void ExpectRingRecovered(const std::function<int(int)>& quarter_turns) {
  std::mt19937 rng(7);
  std::normal_distribution<double> roll(0, 2 * M_PI / 180);
  const Eigen::Vector3d object(0.5, -0.2, 1.0);
  std::vector<Rigid3d> poses;
  for (int k = 0; k < 16; ++k) {
    const double azimuth = 2 * M_PI * k / 16;
    // Stations 25 degrees above the object, looking down onto it.
    const Eigen::Vector3d centre =
        object + 4 * Eigen::Vector3d(std::cos(azimuth) * std::cos(0.44),
                                     std::sin(azimuth) * std::cos(0.44),
                                     std::sin(0.44));
    poses.push_back(
        LookAt(centre, object, quarter_turns(k) * M_PI / 2 + roll(rng)) *
        ArbitraryFromTrue().Inverse());
  }
  std::vector<Eigen::Vector3d> points;
  std::uniform_real_distribution<double> spread(-0.5, 0.5);
  for (int k = 0; k < 500; ++k) {
    points.push_back(
        ArbitraryFromTrue() *
        (object + Eigen::Vector3d(spread(rng), spread(rng), spread(rng))));
  }
  const std::optional<UprightFrame> frame = EstimateUprightFrame(poses, points);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->source, "the images' horizontal axes (cameras held level)");
  // Rolls of 2 degrees (one sigma) over 16 images: about 0.7 degrees
  // expected. The mean of the images' -y axes would be 25 degrees off.
  EXPECT_LT(AngleDeg(frame->up,
                     ArbitraryFromTrue().rotation * Eigen::Vector3d::UnitZ()),
            2.0);
  const Eigen::Vector3d up_after = frame->new_from_old.rotation * frame->up;
  EXPECT_LT(AngleDeg(up_after, Eigen::Vector3d::UnitZ()), 1e-9);
  // The object's centre at the origin (to the sampling of its points).
  EXPECT_LT((frame->new_from_old * (ArbitraryFromTrue() * object)).norm(), 0.1);
}

TEST(Upright, RingLookingDownRecoversTheVerticalAndTheCentre) {
  ExpectRingRecovered([](int) { return 0; });
}

TEST(Upright, PortraitAndLandscapePhotographsAgree) {
  // Every other photograph portrait, turned either way.
  ExpectRingRecovered(
      [](int k) { return k % 2 == 0 ? 0 : (k % 4 == 1 ? 1 : -1); });
}

TEST(Upright, PortraitPhotographsTurnedBothWaysLookDown) {
  // temple-ring's case: every photograph portrait, the first half turned
  // one way, the second the other; the stations above the object.
  ExpectRingRecovered([](int k) { return k < 8 ? 1 : -1; });
}

TEST(Upright, StripFacingOneWayUsesTheMeanUpDirection) {
  std::mt19937 rng(11);
  std::normal_distribution<double> tilt(0, 3 * M_PI / 180);
  std::vector<Rigid3d> poses;
  for (int k = 0; k < 10; ++k) {
    // Along a facade at y = 10, level within a few degrees.
    const Eigen::Vector3d centre(k, 0, 1.6);
    poses.push_back(LookAt(centre,
                           centre + Eigen::Vector3d(0, 10, 10 * tilt(rng)),
                           tilt(rng)) *
                    ArbitraryFromTrue().Inverse());
  }
  const std::optional<UprightFrame> frame = EstimateUprightFrame(poses, {});
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->source, "the images' mean up axis (all facing one way)");
  EXPECT_LT(AngleDeg(frame->up,
                     ArbitraryFromTrue().rotation * Eigen::Vector3d::UnitZ()),
            5.0);
  // Without points, the centre is the stations'.
  EXPECT_LT((frame->centre - ArbitraryFromTrue() * Eigen::Vector3d(4.5, 0, 1.6))
                .norm(),
            0.6);
}

TEST(Upright, NeedsTwoImagesThatAgreeOnUp) {
  const Rigid3d level = LookAt({0, 0, 0}, {0, 1, 0}, 0);
  EXPECT_FALSE(EstimateUprightFrame({level}, {}));
  // Upside down against upright, the stations level with the object: no
  // telling which way is up.
  const Rigid3d flipped = LookAt({1, 0, 0}, {1, 1, 0}, M_PI);
  EXPECT_FALSE(EstimateUprightFrame({level, flipped}, {{0.5, 1, 0}}));
}

}  // namespace
}  // namespace bayon
