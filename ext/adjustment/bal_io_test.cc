// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/bal_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>

#include "tests/testing.h"

namespace bayon {
namespace {

struct BalCamera {
  Eigen::Vector3d rodrigues;
  Eigen::Vector3d t;
  double f, k1, k2;
};

// BAL's own projection (Snavely's bundler convention), as its README
// states it.
Eigen::Vector2d BalProject(const BalCamera& c, const Eigen::Vector3d& X) {
  const double angle = c.rodrigues.norm();
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(angle, c.rodrigues / angle).toRotationMatrix();
  const Eigen::Vector3d P = R * X + c.t;
  const Eigen::Vector2d p = -P.head<2>() / P.z();
  const double r2 = p.squaredNorm();
  return c.f * (1 + c.k1 * r2 + c.k2 * r2 * r2) * p;
}

TEST(BalIo, ProjectionsMatchBalsCameraModel) {
  const std::vector<BalCamera> cameras = {
      {{0.1, -0.2, 0.05}, {0.3, -0.1, -5.0}, 500, -0.1, 0.02},
      {{-0.05, 0.3, 0.1}, {-0.4, 0.2, -6.0}, 520, 0.05, -0.01}};
  const std::vector<Eigen::Vector3d> points = {
      {0.2, 0.1, 0.3}, {-0.5, 0.4, -0.2}, {0.6, -0.3, 0.1}};
  std::ostringstream text;
  text.precision(17);
  text << cameras.size() << " " << points.size() << " "
       << cameras.size() * points.size() << "\n";
  std::vector<Eigen::Vector2d> observed;
  for (size_t c = 0; c < cameras.size(); ++c) {
    for (size_t p = 0; p < points.size(); ++p) {
      observed.push_back(BalProject(cameras[c], points[p]));
      text << c << " " << p << " " << observed.back().x() << " "
           << observed.back().y() << "\n";
    }
  }
  for (const BalCamera& c : cameras) {
    text << c.rodrigues.x() << "\n"
         << c.rodrigues.y() << "\n"
         << c.rodrigues.z() << "\n"
         << c.t.x() << "\n"
         << c.t.y() << "\n"
         << c.t.z() << "\n"
         << c.f << "\n"
         << c.k1 << "\n"
         << c.k2 << "\n";
  }
  for (const Eigen::Vector3d& X : points) {
    text << X.x() << "\n" << X.y() << "\n" << X.z() << "\n";
  }
  const std::string path = testing::TempDir("bal_io") + "/problem.txt";
  WriteFileAtomically(path, text.str());

  const Scene scene = ReadBalProblem(path);
  ASSERT_EQ(scene.images.size(), 2u);
  ASSERT_EQ(scene.points3D.size(), 3u);
  scene.CheckConsistency(path);
  // Every point lies in front of its cameras in COLMAP's convention and
  // reprojects exactly onto its keypoint.
  for (const auto& [id, point] : scene.points3D) {
    for (const TrackElement& e : point.track) {
      const Image& image = scene.images.at(e.image_id);
      EXPECT_GT((image.cam_from_world * point.xyz).z(), 0);
    }
  }
  EXPECT_LT(scene.Stats().mean_reprojection_error_px, 1e-9);
  // Keypoints are the BAL observations shifted to the principal point with
  // y turned down.
  const Camera& camera = scene.cameras.at(1);
  const Eigen::Vector2d& xy = scene.images.at(1).points2D[0].xy;
  EXPECT_NEAR(xy.x(), observed[0].x() + camera.params[1], 1e-9);
  EXPECT_NEAR(xy.y(), camera.params[2] - observed[0].y(), 1e-9);
}

TEST(BalIo, MalformedProblemsNameTheLine) {
  const std::string dir = testing::TempDir("bal_io_bad");
  WriteFileAtomically(dir + "/short.txt", "2 1 2\n0 0 1.0 2.0\n1 0 3.0\n");
  try {
    ReadBalProblem(dir + "/short.txt");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("short.txt:4: file ends"),
              std::string::npos)
        << error.what();
  }
  WriteFileAtomically(dir + "/index.txt", "1 1 2\n0 5 1.0 2.0\n");
  EXPECT_THROW(ReadBalProblem(dir + "/index.txt"), InputError);
}

}  // namespace
}  // namespace bayon
