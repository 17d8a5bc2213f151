// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/cloud_scene.h"

#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/eval/mesh_distance.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bayon {
namespace {

TEST(CloudScene, SurfacesAreOrientedManifolds) {
  ReliefCylinderOptions cylinder;
  cylinder.num_angles = 180;
  cylinder.num_heights = 60;
  BoxTowerOptions tower;
  tower.num_angles = 240;
  tower.num_heights = 120;
  for (const TriangleMesh& tube :
       {MakeReliefCylinder(cylinder), MakeBoxTower(tower)}) {
    const MeshTopology t = ComputeMeshTopology(tube);
    EXPECT_TRUE(t.IsManifold());
    EXPECT_EQ(t.num_boundary_loops, 2u);
    EXPECT_EQ(t.num_inconsistent_edges, 0u);
    EXPECT_EQ(t.euler_characteristic, 0);
    // Outward: the normal of a face points away from the z axis.
    const Eigen::Vector3d n = FaceNormal(tube, 0);
    const Eigen::Vector3d p = tube.vertices.positions[tube.faces[0](0)];
    EXPECT_GT(n.dot(Eigen::Vector3d(p.x(), p.y(), 0).normalized()), 0.5);
  }
  TorusOptions torus_options;
  torus_options.num_major = 64;
  torus_options.num_minor = 24;
  const TriangleMesh torus = MakeTorus(torus_options);
  const MeshTopology t = ComputeMeshTopology(torus);
  EXPECT_TRUE(t.IsClosed());
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_GT(FaceNormal(torus, 0).x(), 0.5);  // at u = 0, v = 0: +x is out
  cylinder.relief_m = -1;
  EXPECT_THROW(MakeReliefCylinder(cylinder), InputError);
}

// A relief cylinder at half a degree by 2 cm.
TriangleMesh SmallReliefCylinder() {
  ReliefCylinderOptions cylinder;
  cylinder.num_angles = 360;
  cylinder.num_heights = 200;
  return MakeReliefCylinder(cylinder);
}

TEST(CloudScene, NoiseAndBlundersAsAsked) {
  const TriangleMesh truth = SmallReliefCylinder();
  NoisyCloudOptions options;
  options.num_points = 20000;
  options.sigma_m = 0.003;
  options.with_normals = true;
  const PointCloud cloud = SampleNoisyCloud(truth, options);
  ASSERT_EQ(cloud.size(), 20000u);
  ASSERT_TRUE(cloud.HasNormals());
  const PointAttribute* flags = cloud.FindAttribute(kBlunderAttribute);
  const PointAttribute* sx = cloud.FindAttribute("sx");
  ASSERT_NE(flags, nullptr);
  ASSERT_NE(sx, nullptr);
  const std::vector<double> d = PointToMeshDistances(cloud, truth, 2);
  size_t num_blunders = 0;
  double good_sum2 = 0, sigma_sum2 = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_GE(sx->values[i], 0.0015 - 1e-12);
    EXPECT_LE(sx->values[i], 0.0045 + 1e-12);
    if (flags->values[i] != 0) {
      ++num_blunders;
      // Moved along the normal by 1 to 20 cm (the relief bends the surface
      // a little under the displaced point).
      EXPECT_GT(d[i], 0.009);
      EXPECT_LT(d[i], 0.2 + 1e-6);
    } else {
      good_sum2 += d[i] * d[i];
      sigma_sum2 += sx->values[i] * sx->values[i];
    }
  }
  EXPECT_EQ(num_blunders, 400u);
  // The distance to the surface is the noise along the normal: about one
  // per-axis sigma.
  const double good_rms = std::sqrt(good_sum2 / (cloud.size() - num_blunders));
  const double sigma_rms =
      std::sqrt(sigma_sum2 / (cloud.size() - num_blunders));
  EXPECT_NEAR(good_rms / sigma_rms, 1.0, 0.1);
}

// Blunders injected into an existing cloud: exactly the share asked of the
// whole cloud, only points on the surface chosen, moved 1 to 20 cm off it,
// everything else (other points, attributes) left as it was.
TEST(CloudScene, BlundersInjectedIntoAnExistingCloud) {
  const TriangleMesh truth = SmallReliefCylinder();
  NoisyCloudOptions options;
  options.num_points = 10000;
  options.blunder_fraction = 0;
  PointCloud cloud = SampleNoisyCloud(truth, options);
  // A tenth of the points far off the surface (the ground a dense matcher
  // also delivers): never chosen.
  for (size_t i = 0; i < cloud.size(); i += 10) {
    cloud.positions[i] += Eigen::Vector3d(0, 0, 10);
  }
  const PointCloud before = cloud;
  options.blunder_fraction = 0.02;
  options.seed = 7;
  EXPECT_EQ(InjectBlunders(truth, options, &cloud), 200u);
  const PointAttribute* flags = cloud.FindAttribute(kBlunderAttribute);
  ASSERT_NE(flags, nullptr);
  ASSERT_NE(cloud.FindAttribute("sx"), nullptr);
  const std::vector<double> d = PointToMeshDistances(cloud, truth, 2);
  size_t num_blunders = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (flags->values[i] != 0) {
      ++num_blunders;
      EXPECT_NE(i % 10, 0u);
      EXPECT_GT(d[i], 0.009);
      EXPECT_LT(d[i], 0.2 + 1e-6);
    } else {
      EXPECT_EQ(cloud.positions[i], before.positions[i]);
    }
  }
  EXPECT_EQ(num_blunders, 200u);
  // Nothing on the surface: refused.
  PointCloud far;
  far.positions.assign(10, Eigen::Vector3d(0, 0, 100));
  EXPECT_THROW(InjectBlunders(truth, options, &far), InputError);
  PointCloud empty;
  EXPECT_THROW(InjectBlunders(truth, options, &empty), InputError);
}

}  // namespace
}  // namespace bayon
