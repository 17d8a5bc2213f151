// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/cloud_edit.h"

#include "ext/core/errors.h"
#include "ext/eval/cloud_edit_eval.h"
#include "ext/synth/cloud_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>

namespace bayon {
namespace {

struct Scene {
  TriangleMesh truth;
  PointCloud cloud;
};

Scene ReliefCylinderScene(int num_points, bool with_sigmas, uint64_t seed) {
  ReliefCylinderOptions surface;
  surface.num_angles = 540;
  surface.num_heights = 300;
  Scene scene;
  scene.truth = MakeReliefCylinder(surface);
  NoisyCloudOptions options;
  options.num_points = num_points;
  options.with_sigmas = with_sigmas;
  options.seed = seed;
  scene.cloud = SampleNoisyCloud(scene.truth, options);
  return scene;
}

CloudEditEvaluation Edit(const Scene& scene,
                         const CloudEditOptions& options,
                         const std::string& label,
                         CloudEditReport* report) {
  const PointCloud edited = EditPointCloud(scene.cloud, options, report);
  const CloudEditEvaluation e = EvaluateCloudEdit(
      scene.cloud, edited, MeshDistance(scene.truth), 0.01, 2);
  std::cout << report->Summary() << "\n"
            << CloudEditEvaluation::TableHeader() << "\n"
            << e.Table(label) << std::endl;
  return e;
}

TEST(CloudEdit, SurfaceFitRemovesBlundersWithoutSmoothing) {
  const Scene scene = ReliefCylinderScene(40000, true, 11);
  CloudEditReport report;
  const CloudEditEvaluation e =
      Edit(scene, CloudEditOptions(), "surface_fit", &report);
  EXPECT_GE(e.BlundersRemovedFraction(), 0.95);
  EXPECT_LT(e.GoodRemovedFraction(), 0.01);
  EXPECT_LE(e.kept_after.rms, e.good_before.rms);
  EXPECT_TRUE(report.used_point_precision);
  EXPECT_GE(report.iterations.size(), 2u);
  // The stated precision matches the noise: |d| / sigma has the median of a
  // standard normal's absolute value.
  EXPECT_NEAR(report.iterations.back().median_normalized_deviation, 0.674, 0.1);
  // The kept points are the input points, unchanged and in order.
  const PointCloud edited = EditPointCloud(scene.cloud, {}, &report);
  size_t j = 0;
  for (size_t i = 0; i < scene.cloud.size(); ++i) {
    if (report.reasons[i] != EditReason::kKept) continue;
    ASSERT_EQ(edited.positions[j], scene.cloud.positions[i]);
    ++j;
  }
  EXPECT_EQ(j, edited.size());
}

TEST(CloudEdit, WorksWithoutPrecisionAndComparesWithPcl) {
  const Scene scene = ReliefCylinderScene(40000, false, 12);
  CloudEditReport report;
  CloudEditEvaluation e =
      Edit(scene, CloudEditOptions(), "surface_fit (no sigma)", &report);
  EXPECT_FALSE(report.used_point_precision);
  EXPECT_GE(e.BlundersRemovedFraction(), 0.95);
  EXPECT_LT(e.GoodRemovedFraction(), 0.01);
  EXPECT_LE(e.kept_after.rms, e.good_before.rms);

  CloudEditOptions options;
  options.method = CloudEditMethod::kStatistical;
  e = Edit(scene, options, "pcl statistical", &report);
  EXPECT_GT(report.num_removed, 0u);
  EXPECT_EQ(report.iterations.size(), 1u);
  options.method = CloudEditMethod::kRadius;
  e = Edit(scene, options, "pcl radius", &report);
  EXPECT_GT(report.radius_m, 0);
}

// A 2 m cube, each side a 20 x 20 grid: sharp edges, where one quadric
// across two faces fits neither (the two-face test).
TriangleMesh Cube() {
  TriangleMesh mesh;
  const int n = 20;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int base = static_cast<int>(mesh.vertices.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          Eigen::Vector3d p;
          p(axis) = sign;
          p(u) = -1 + 2.0 * i / n;
          p(v) = -1 + 2.0 * j / n;
          mesh.vertices.positions.push_back(p);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 2,
                    d = a + n + 1;
          if (sign > 0) {
            mesh.faces.emplace_back(a, b, c);
            mesh.faces.emplace_back(a, c, d);
          } else {
            mesh.faces.emplace_back(a, c, b);
            mesh.faces.emplace_back(a, d, c);
          }
        }
      }
    }
  }
  return mesh;
}

TEST(CloudEdit, SharpEdges) {
  Scene scene;
  scene.truth = Cube();
  NoisyCloudOptions options;
  options.num_points = 30000;
  options.seed = 15;
  scene.cloud = SampleNoisyCloud(scene.truth, options);
  CloudEditReport report;
  const CloudEditEvaluation e =
      Edit(scene, CloudEditOptions(), "surface_fit (cube)", &report);
  EXPECT_GE(e.BlundersRemovedFraction(), 0.98);
  EXPECT_LT(e.GoodRemovedFraction(), 0.005);
}

TEST(CloudEdit, AbsoluteThreshold) {
  const Scene scene = ReliefCylinderScene(20000, true, 13);
  CloudEditOptions options;
  options.surface_fit.max_deviation_sigma = 1000;  // only the absolute test
  options.surface_fit.num_close_neighbors = 0;
  options.surface_fit.max_deviation_m = 0.05;
  CloudEditReport report;
  const CloudEditEvaluation e = Edit(scene, options, "absolute 5 cm", &report);
  // Blunders are uniform in 1..20 cm: about (20 - 5) / 19 of them go.
  EXPECT_NEAR(e.BlundersRemovedFraction(), 15.0 / 19, 0.08);
  EXPECT_EQ(e.num_good_after, e.num_good_before);
  for (EditReason reason : report.reasons) {
    EXPECT_TRUE(reason == EditReason::kKept ||
                reason == EditReason::kDeviationAbsolute);
  }
}

// A dense matcher's stated precision leaves out errors common to all its
// points. Here every point gets 3 mm of noise its sigmas (1 to 3 mm) do not
// state: the edit estimates what was left out and, with it, deletes fewer
// good points with small stated sigmas than when it takes them as they
// are.
TEST(CloudEdit, EstimatesTheSigmaTheStatedPrecisionLeavesOut) {
  Scene scene = ReliefCylinderScene(40000, true, 16);
  std::mt19937_64 rng(16);
  std::normal_distribution<double> unstated(0.0, 0.003);
  for (Eigen::Vector3d& p : scene.cloud.positions) {
    p += Eigen::Vector3d(unstated(rng), unstated(rng), unstated(rng));
  }
  CloudEditReport report;
  const CloudEditEvaluation estimated =
      Edit(scene, CloudEditOptions(), "sigma added, estimated", &report);
  EXPECT_NEAR(report.added_sigma_m, 0.003, 0.001);
  EXPECT_NE(report.Summary().find("in quadrature"), std::string::npos);
  CloudEditOptions as_stated;
  as_stated.surface_fit.added_sigma_m = 0;
  const CloudEditEvaluation stated =
      Edit(scene, as_stated, "stated sigmas only", &report);
  EXPECT_EQ(report.added_sigma_m, 0);
  EXPECT_LT(estimated.GoodRemovedFraction(), 0.01);
  EXPECT_GT(stated.GoodRemovedFraction(), 2 * estimated.GoodRemovedFraction());
  EXPECT_GE(estimated.BlundersRemovedFraction(), 0.9);
}

// A flight of 10 steps, 2 m wide: treads 20 cm deep, risers 10 cm high
// (the tower's ledges and cornices in small).
TriangleMesh Stairs() {
  TriangleMesh mesh;
  auto quad = [&](const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b,
                  const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
    const int base = static_cast<int>(mesh.vertices.size());
    for (const Eigen::Vector3d& p : {a, b, c, d}) {
      mesh.vertices.positions.push_back(p);
    }
    mesh.faces.emplace_back(base, base + 1, base + 2);
    mesh.faces.emplace_back(base, base + 2, base + 3);
  };
  for (int step = 0; step < 10; ++step) {
    const double x0 = 0.2 * step, x1 = x0 + 0.2, z = 0.1 * step;
    quad({x0, 0, z}, {x1, 0, z}, {x1, 2, z}, {x0, 2, z});  // tread
    quad({x1, 0, z}, {x1, 0, z + 0.1}, {x1, 2, z + 0.1}, {x1, 2, z});
  }
  return mesh;
}

// Blunders over a thin cloud of the stairs: the patch of 24 neighbours
// reaches over two or three treads and the risers between them, which no
// quadric fits and the two-face test cannot split (the treads share their
// normal), so its inflated scatter lets blunders pass; the close test, the
// plane of the 8 nearest points, most on the tread below, catches them.
TEST(CloudEdit, CloseTestCatchesBlundersOverLedges) {
  Scene scene;
  scene.truth = Stairs();
  NoisyCloudOptions options;
  options.num_points = 3000;  // about 4.5 cm apart
  options.seed = 17;
  options.blunder_min_m = 0.03;
  scene.cloud = SampleNoisyCloud(scene.truth, options);
  CloudEditReport report;
  CloudEditOptions without;
  without.surface_fit.num_close_neighbors = 0;
  const CloudEditEvaluation patch_only =
      Edit(scene, without, "patch only", &report);
  const CloudEditEvaluation with_close =
      Edit(scene, CloudEditOptions(), "patch and close", &report);
  EXPECT_GT(
      report.CountByReason()[static_cast<int>(EditReason::kDeviationClose)],
      0u);
  EXPECT_GT(with_close.BlundersRemovedFraction(),
            patch_only.BlundersRemovedFraction());
  EXPECT_LT(with_close.GoodRemovedFraction(), 0.01);
}

TEST(CloudEdit, RefusesBadClouds) {
  CloudEditReport report;
  PointCloud empty;
  EXPECT_THROW(EditPointCloud(empty, {}, &report, "e.ply"), InputError);
  PointCloud line;
  for (int i = 0; i < 100; ++i) line.positions.emplace_back(i, 2 * i, 3 * i);
  try {
    EditPointCloud(line, {}, &report, "line.ply");
    FAIL() << "a line was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what())
                  .find("line.ply: all 100 points lie on "
                        "one line"),
              std::string::npos)
        << error.what();
  }
  Scene scene = ReliefCylinderScene(2000, true, 14);
  scene.cloud.FindAttribute("sy")->values[17] = -1;
  EXPECT_THROW(EditPointCloud(scene.cloud, {}, &report), InputError);
  scene.cloud.positions[3].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(EditPointCloud(scene.cloud, {}, &report), InputError);
  CloudEditOptions options;
  options.surface_fit.num_iterations = 0;
  EXPECT_THROW(options.Check(), InputError);
}

// A dense matcher's precision across the surface (s_normal) stands for all
// three axes where the cloud has it; otherwise sx, sy, sz.
TEST(CloudEdit, PrecisionAlongTheNormalWhereGiven) {
  PointCloud cloud;
  cloud.positions.assign(2, Eigen::Vector3d::Zero());
  cloud.AddAttribute("sx", PlyScalarType::kFloat, 0.004);
  cloud.AddAttribute("sy", PlyScalarType::kFloat, 0.005);
  cloud.AddAttribute("sz", PlyScalarType::kFloat, 0.006);
  EXPECT_EQ(PointSigmas(cloud, "c")[1], Eigen::Vector3d(0.004, 0.005, 0.006));
  cloud.AddAttribute("s_normal", PlyScalarType::kFloat, 0.001);
  EXPECT_EQ(PointSigmas(cloud, "c")[1], Eigen::Vector3d::Constant(0.001));
  cloud.FindAttribute("s_normal")->values[0] = 0;
  EXPECT_THROW(PointSigmas(cloud, "c"), InputError);
}

}  // namespace
}  // namespace bayon
