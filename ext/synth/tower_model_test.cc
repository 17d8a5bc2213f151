// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_model.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

namespace bayon {
namespace {

TowerOptions CoarseTower() {
  TowerOptions options;
  options.mesh_spacing_m = 0.08;
  options.texel_size_m = 0.02;
  options.ground_texel_size_m = 0.2;
  return options;
}

TEST(TowerModel, SurfaceIsClosedAndConsistentlyOriented) {
  const TowerModel model = BuildTower(CoarseTower());
  const TriangleMesh surface = model.Surface();
  surface.Check("tower surface");
  EXPECT_EQ(surface.NumFaces(), model.num_object_faces);
  // Every directed edge once, and its reverse once: closed, manifold at the
  // edges, outward-consistent.
  std::map<std::pair<int, int>, int> directed;
  for (const Eigen::Vector3i& f : surface.faces) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  int bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad;
  }
  EXPECT_EQ(bad, 0);
  // Two closed parts (tower with platform, levelling bar): V - E + F = 2 each.
  const int64_t v = surface.NumVertices(), e = directed.size() / 2,
                f = surface.NumFaces();
  EXPECT_EQ(v - e + f, 4);
  // Outward: the signed volume is positive and about the tower's.
  double volume = 0;
  for (const Eigen::Vector3i& face : surface.faces) {
    const auto& p = surface.vertices.positions;
    volume += p[face[0]].dot(p[face[1]].cross(p[face[2]])) / 6;
  }
  EXPECT_GT(volume, 0.7 * 0.7 * 7 * 7 * 0.5);
  EXPECT_LT(volume, 7 * 7 * 0.7 + 4 * 4 * 6);
}

TEST(TowerModel, SizeFollowsTheOptions) {
  TowerOptions options = CoarseTower();
  const TowerModel model = BuildTower(options);
  const Eigen::Vector3d size = model.tower_bounds.sizes();
  // 4 m walls, plus cornices, plus the faces' relief.
  EXPECT_GT(size.x(), 4.0);
  EXPECT_LT(size.x(), 4.0 + 2 * (0.15 + options.relief_depth_m));
  EXPECT_NEAR(model.tower_bounds.max().z(),
              options.platform_height_m + options.height_m,
              1e-9);
  EXPECT_NEAR(model.object_bounds.min().z(), 0, 1e-9);
  for (const auto& texcoords : model.mesh.face_texcoords) {
    for (const Eigen::Vector2f& tc : texcoords) {
      EXPECT_GE(tc.minCoeff(), 0.0f);
      EXPECT_LE(tc.maxCoeff(), 1.0f);
    }
  }
}

TEST(TowerModel, TargetsSitOnFlatSpots) {
  const TowerModel model = BuildTower(CoarseTower());
  ASSERT_GE(model.targets.size(), 9u);  // >= 7 control points + 2 on the bar
  int num_bar = 0;
  for (const ControlTarget& target : model.targets) {
    num_bar += target.on_bar;
    if (target.on_bar) continue;
    // The wall within the plate's reach lies in one plane, 3 mm behind it.
    int near = 0;
    for (size_t f = 0; f < model.num_object_faces; ++f) {
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& p =
            model.mesh.vertices.positions[model.mesh.faces[f][k]];
        const Eigen::Vector3d d = p - target.center;
        if (std::abs(target.normal.dot(d)) > 0.1) continue;
        if ((d - target.normal.dot(d) * target.normal).norm() > 0.1) continue;
        EXPECT_NEAR(target.normal.dot(d), -0.003, 1e-9) << target.name;
        ++near;
      }
    }
    EXPECT_GT(near, 0) << target.name;
  }
  EXPECT_EQ(num_bar, 2);
  const ControlTarget& b1 = model.targets[model.targets.size() - 2];
  const ControlTarget& b2 = model.targets.back();
  EXPECT_NEAR((b2.center - b1.center).norm(), 1.5, 1e-12);
  EXPECT_NEAR((b2.center - b1.center).normalized().z(), 1.0, 1e-12);
}

// Coded targets: codes 0..N-1 after the bar, each on a flat spot of its
// own, clear of every other plate.
TEST(TowerModel, CodedTargetsSitOnFlatSpotsOfTheirOwn) {
  TowerOptions options = CoarseTower();
  options.num_coded_targets = 12;
  const TowerModel model = BuildTower(options);
  const TowerModel plain = BuildTower(CoarseTower());
  ASSERT_EQ(model.targets.size(), plain.targets.size() + 12);
  for (size_t k = 0; k < model.targets.size(); ++k) {
    const ControlTarget& target = model.targets[k];
    if (k < plain.targets.size()) {
      EXPECT_EQ(target.code, -1);
      EXPECT_EQ(target.center, plain.targets[k].center) << target.name;
      continue;
    }
    const int code = static_cast<int>(k - plain.targets.size());
    EXPECT_EQ(target.code, code);
    EXPECT_EQ(target.name, "CT" + std::to_string(code));
    EXPECT_LT(std::abs(target.normal.z()), 1e-9);  // on a wall
    // The wall behind the plate is flat, 3 mm behind it.
    int near = 0;
    for (size_t f = 0; f < model.num_object_faces; ++f) {
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d d =
            model.mesh.vertices.positions[model.mesh.faces[f][c]] -
            target.center;
        if (std::abs(target.normal.dot(d)) > 0.1 ||
            (d - target.normal.dot(d) * target.normal).norm() > 0.1) {
          continue;
        }
        EXPECT_NEAR(target.normal.dot(d), -0.003, 1e-9) << target.name;
        ++near;
      }
    }
    EXPECT_GT(near, 0) << target.name;
    for (size_t j = 0; j < k; ++j) {
      const ControlTarget& other = model.targets[j];
      EXPECT_GT(
          (target.center - other.center).norm(),
          (target.plate_half_size_m + other.plate_half_size_m) * std::sqrt(2.0))
          << target.name << " and " << other.name;
    }
  }
  // Plates after the object's faces: two per target.
  EXPECT_EQ(model.num_target_faces, 2 * model.targets.size());
  options.num_coded_targets = 51;
  EXPECT_THROW(BuildTower(options), InputError);
}

TEST(TowerModel, RejectsBadOptions) {
  TowerOptions options;
  options.relief_depth_m = -0.1;
  EXPECT_THROW(BuildTower(options), InputError);
  options = TowerOptions();
  options.platform_width_m = 3;
  EXPECT_THROW(BuildTower(options), InputError);
}

}  // namespace
}  // namespace bayon
