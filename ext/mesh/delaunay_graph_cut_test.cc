// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/mesh/meshing.h"
#include "ext/synth/cloud_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bayon {
namespace {

// A unit sphere sampled evenly, each point seen from the stations of a
// ring around it (radius 4, 30 degrees above and below) that face it.
struct SphereScene {
  PointCloud cloud;
  std::vector<Eigen::Vector3d> stations;
  std::vector<std::vector<int>> point_stations;
};

SphereScene MakeSphereScene(int num_points) {
  SphereScene scene;
  for (int k = 0; k < 12; ++k) {
    const double azimuth = 2 * M_PI * k / 12;
    const double elevation = (k % 2 == 0 ? 1 : -1) * M_PI / 6;
    scene.stations.push_back(
        4 * Eigen::Vector3d(std::cos(azimuth) * std::cos(elevation),
                            std::sin(azimuth) * std::cos(elevation),
                            std::sin(elevation)));
  }
  // A Fibonacci sphere: even spacing without a random gap.
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < num_points; ++i) {
    const double z = 1 - 2 * (i + 0.5) / num_points;
    const double r = std::sqrt(1 - z * z);
    const Eigen::Vector3d p(
        r * std::cos(golden * i), r * std::sin(golden * i), z);
    std::vector<int> seen;
    for (size_t s = 0; s < scene.stations.size(); ++s) {
      if ((scene.stations[s] - p).dot(p) > 0.2)
        seen.push_back(static_cast<int>(s));
    }
    if (seen.empty()) continue;  // the poles no station sees
    scene.cloud.positions.push_back(p);
    scene.point_stations.push_back(seen);
  }
  return scene;
}

double SignedVolume(const TriangleMesh& mesh) {
  double volume = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const auto& p = mesh.vertices.positions;
    volume += p[f[0]].dot(p[f[1]].cross(p[f[2]])) / 6;
  }
  return volume;
}

// The sphere scene of 4000 points meshed with the default options.
TriangleMesh MeshSphere(const SphereScene& scene) {
  return DelaunayGraphCutMesh(scene.cloud,
                              scene.stations,
                              scene.point_stations,
                              DelaunayGraphCutOptions(),
                              std::sqrt(4 * M_PI / 4000),
                              2);
}

TEST(DelaunayGraphCut, ClosesASphereSeenAllRoundFacingOutwards) {
  const SphereScene scene = MakeSphereScene(4000);
  const TriangleMesh mesh = MeshSphere(scene);
  ASSERT_GT(mesh.faces.size(), 4000u);
  // Faces on the sphere (their centroids within a chord's sag of it) and
  // counter-clockwise from outside: the enclosed volume is the sphere's,
  // less the caps at the poles that no station sees and the chords' sag.
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d centroid =
        (mesh.vertices.positions[f[0]] + mesh.vertices.positions[f[1]] +
         mesh.vertices.positions[f[2]]) /
        3;
    EXPECT_NEAR(centroid.norm(), 1.0, 0.05);
  }
  EXPECT_NEAR(SignedVolume(mesh), 4 * M_PI / 3, 0.15 * 4 * M_PI / 3);
}

// Distance from the surface of a torus around z (major radius 1.5, minor
// 0.6); negative inside.
double TorusDistance(const Eigen::Vector3d& p) {
  return std::hypot(std::hypot(p.x(), p.y()) - 1.5, p.z()) - 0.6;
}

TEST(DelaunayGraphCut, CarvesTheHoleOfATorus) {
  // The torus's points, each seen from the stations of a ring (radius 6,
  // 40 degrees above and below) in front of it and not hidden by the torus.
  TorusOptions torus;
  torus.relief_m = 0;
  torus.num_major = 120;
  torus.num_minor = 48;
  const TriangleMesh truth = MakeTorus(torus);
  std::vector<Eigen::Vector3d> stations;
  for (int k = 0; k < 16; ++k) {
    const double azimuth = 2 * M_PI * k / 16;
    const double elevation = (k % 2 == 0 ? 1 : -1) * 40 * M_PI / 180;
    stations.push_back(6 *
                       Eigen::Vector3d(std::cos(azimuth) * std::cos(elevation),
                                       std::sin(azimuth) * std::cos(elevation),
                                       std::sin(elevation)));
  }
  PointCloud cloud;
  std::vector<std::vector<int>> point_stations;
  for (const Eigen::Vector3d& p : truth.vertices.positions) {
    std::vector<int> seen;
    for (size_t s = 0; s < stations.size(); ++s) {
      bool hidden = false;
      for (int j = 1; j < 200 && !hidden; ++j) {
        hidden = TorusDistance(p + (stations[s] - p) * j / 200.0) < -1e-3;
      }
      if (!hidden) seen.push_back(static_cast<int>(s));
    }
    if (seen.empty()) continue;
    cloud.positions.push_back(p);
    point_stations.push_back(seen);
  }
  const double spacing = 2 * M_PI * 0.6 / 48;
  const TriangleMesh mesh = DelaunayGraphCutMesh(
      cloud, stations, point_stations, DelaunayGraphCutOptions(), spacing, 2);
  ASSERT_GT(mesh.faces.size(), 5000u);
  // No face across the hole or through the tube: all on the surface.
  int off = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d centroid =
        (mesh.vertices.positions[f[0]] + mesh.vertices.positions[f[1]] +
         mesh.vertices.positions[f[2]]) /
        3;
    off += std::abs(TorusDistance(centroid)) > 0.05;
  }
  EXPECT_EQ(off, 0);
  const double volume = 2 * M_PI * M_PI * 1.5 * 0.6 * 0.6;
  EXPECT_NEAR(SignedVolume(mesh), volume, 0.1 * volume);
}

TEST(DelaunayGraphCut, CarvesABlunderInFreeSpace) {
  SphereScene scene = MakeSphereScene(4000);
  // A point a tenth of the radius in front of the sphere, towards station
  // 0 and seen only from it: the neighbouring stations' rays to the surface
  // behind it pass through its space.
  const Eigen::Vector3d blunder = 1.1 * scene.stations[0].normalized();
  scene.cloud.positions.push_back(blunder);
  scene.point_stations.push_back({0});
  const TriangleMesh mesh = MeshSphere(scene);
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_FALSE(mesh.vertices.positions[f[k]].isApprox(blunder))
          << "the blunder is a corner of a face";
    }
  }
}

TEST(DelaunayGraphCut, RefusesVisibilityThatDoesNotFit) {
  const SphereScene scene = MakeSphereScene(500);
  std::vector<std::vector<int>> too_few(scene.point_stations.begin(),
                                        scene.point_stations.end() - 1);
  EXPECT_THROW(
      DelaunayGraphCutMesh(scene.cloud, scene.stations, too_few, {}, 0.1, 1),
      InputError);
  std::vector<std::vector<int>> unknown = scene.point_stations;
  unknown[3] = {99};
  EXPECT_THROW(
      DelaunayGraphCutMesh(scene.cloud, scene.stations, unknown, {}, 0.1, 1),
      InputError);
}

}  // namespace
}  // namespace bayon
