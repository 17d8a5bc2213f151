// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/meshing.h"

#include "ext/core/errors.h"
#include "ext/eval/mesh_distance.h"
#include "ext/synth/cloud_scene.h"

#include <gtest/gtest.h>

#include <iostream>
#include <limits>

namespace bayon {
namespace {

struct Torus {
  TriangleMesh truth;
  PointCloud cloud;
};

// A wavy torus, 2 mm noise, no blunders: closed and not star-shaped.
const Torus& SharedTorus() {
  static const Torus torus = [] {
    TorusOptions surface;
    surface.num_major = 240;
    surface.num_minor = 96;
    Torus t;
    t.truth = MakeTorus(surface);
    NoisyCloudOptions noise;
    noise.num_points = 12000;
    noise.blunder_fraction = 0;
    noise.with_normals = true;
    t.cloud = SampleNoisyCloud(t.truth, noise);
    return t;
  }();
  return torus;
}

MeshComparison Compare(const TriangleMesh& mesh, const TriangleMesh& truth) {
  MeshComparisonOptions options;
  options.num_samples = 20000;
  return CompareMeshes(mesh, truth, options);
}

TEST(Meshing, ThreeDimensionalMethodsOnATorus) {
  const Torus& torus = SharedTorus();
  for (MeshMethod method : {MeshMethod::kAdvancingFront,
                            MeshMethod::kPoisson,
                            MeshMethod::kGreedyProjection}) {
    MeshOptions options;
    options.method = method;
    options.poisson.depth = 7;
    options.num_threads = 2;
    MeshReport report;
    const TriangleMesh mesh = MeshPointCloud(torus.cloud, options, &report);
    const MeshComparison c = Compare(mesh, torus.truth);
    std::cout << report.Summary() << "\n  mesh to truth RMS "
              << c.mesh_to_truth.rms << ", truth to mesh RMS "
              << c.truth_to_mesh.rms << std::endl;
    const MeshTopology& t = report.topology;
    EXPECT_TRUE(t.IsManifold()) << MeshMethodName(method);
    EXPECT_EQ(t.num_inconsistent_edges, 0u) << MeshMethodName(method);
    EXPECT_EQ(t.num_components, 1u) << MeshMethodName(method);
    EXPECT_LT(c.mesh_to_truth.rms, 0.003) << MeshMethodName(method);
    EXPECT_FALSE(report.normals_estimated);
    if (method == MeshMethod::kPoisson) {
      // Watertight, genus one.
      EXPECT_TRUE(t.IsClosed());
      EXPECT_EQ(t.euler_characteristic, 0);
      EXPECT_LT(c.truth_to_mesh.rms, 0.003);
    } else if (method == MeshMethod::kAdvancingFront) {
      EXPECT_LE(t.num_boundary_loops, 4u);
      EXPECT_LT(c.truth_to_mesh.rms, 0.003);
    } else {
      // Greedy projection leaves holes where its angle criteria fail.
      EXPECT_LT(c.truth_to_mesh.rms, 0.02);
    }
  }
}

// Several masters' points of one surface, interleaved (a dense cloud from
// overlapping masters): the nearest neighbours are far closer than the
// sampling of the surface, and the trimming must allow for the octree's
// cells (judged by the spacing alone, most of a well-covered surface was
// cut away).
TEST(Meshing, PoissonTrimAllowsForItsOctreeCells) {
  const Torus& torus = SharedTorus();
  PointCloud cloud = torus.cloud;
  PointCloud second = torus.cloud;
  for (Eigen::Vector3d& p : second.positions)
    p += Eigen::Vector3d::Constant(3e-4);
  cloud.Append(second);
  MeshOptions options;
  options.method = MeshMethod::kPoisson;
  options.poisson.depth = 6;
  options.num_threads = 2;
  MeshReport report;
  MeshPointCloud(cloud, options, &report);
  std::cout << report.Summary() << std::endl;
  EXPECT_TRUE(report.topology.IsClosed());
  EXPECT_EQ(report.num_trimmed_faces, 0u);
}

TEST(Meshing, NormalsEstimatedOrRefused) {
  PointCloud cloud = SharedTorus().cloud;
  cloud.normals.clear();
  MeshOptions options;
  options.method = MeshMethod::kPoisson;
  options.poisson.depth = 6;
  MeshReport report;
  const TriangleMesh mesh = MeshPointCloud(cloud, options, &report, "t.ply");
  EXPECT_TRUE(report.normals_estimated);
  EXPECT_TRUE(report.topology.IsClosed());
  // Outward: the enclosed volume is positive.
  double volume = 0;
  const auto& p = mesh.vertices.positions;
  for (const Eigen::Vector3i& f : mesh.faces) {
    volume += p[f(0)].dot(p[f(1)].cross(p[f(2)])) / 6;
  }
  // 2 pi^2 R r^2 = 10.66 m^3 for R = 1.5 m, r = 0.6 m.
  EXPECT_NEAR(volume, 10.66, 0.5);

  options.estimate_normals = false;
  try {
    MeshPointCloud(cloud, options, &report, "t.ply");
    FAIL() << "a cloud without normals was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what())
                  .find("t.ply: poisson needs point "
                        "normals"),
              std::string::npos)
        << error.what();
  }
}

TEST(Meshing, RefusesBadClouds) {
  MeshReport report;
  EXPECT_THROW(MeshPointCloud(PointCloud(), MeshOptions(), &report),
               InputError);
  PointCloud line;
  for (int i = 0; i < 50; ++i) line.positions.emplace_back(i, i, i);
  for (MeshMethod method : {MeshMethod::kCylinder,
                            MeshMethod::kGreedyProjection,
                            MeshMethod::kPoisson,
                            MeshMethod::kAdvancingFront}) {
    MeshOptions options;
    options.method = method;
    EXPECT_THROW(MeshPointCloud(line, options, &report), InputError);
  }
  PointCloud nan = SharedTorus().cloud;
  nan.positions[7].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(MeshPointCloud(nan, MeshOptions(), &report), InputError);
  MeshOptions options;
  options.poisson.depth = 20;
  try {
    options.Check();
    FAIL() << "depth 20 passed";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("poisson.depth must be", 0), 0u)
        << error.what();
  }
}

}  // namespace
}  // namespace bayon
