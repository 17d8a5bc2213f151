// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/cylinder_mesher.h"

#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/eval/mesh_distance.h"
#include "ext/mesh/meshing.h"
#include "ext/synth/cloud_scene.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace bayon {
namespace {

struct Scene {
  TriangleMesh truth;
  PointCloud cloud;
};

Scene ReliefCylinder(int num_points) {
  ReliefCylinderOptions surface;
  surface.num_angles = 540;
  surface.num_heights = 300;
  Scene scene;
  scene.truth = MakeReliefCylinder(surface);
  NoisyCloudOptions options;
  options.num_points = num_points;
  options.blunder_fraction = 0;
  options.sigma_m = 0.002;
  scene.cloud = SampleNoisyCloud(scene.truth, options);
  return scene;
}

// The share of triangles whose smallest angle is below 20 degrees.
double ShareOfThinTriangles(const TriangleMesh& mesh) {
  const auto& p = mesh.vertices.positions;
  size_t thin = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    double smallest = 180;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = p[f((k + 1) % 3)] - p[f(k)];
      const Eigen::Vector3d b = p[f((k + 2) % 3)] - p[f(k)];
      smallest = std::min(
          smallest,
          std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) *
              180 / M_PI);
    }
    thin += smallest < 20;
  }
  return static_cast<double>(thin) / mesh.faces.size();
}

TEST(CylinderMesher, ClosedAroundTheAxisAndOnTheSurface) {
  const Scene scene = ReliefCylinder(20000);
  MeshOptions options;
  MeshReport report;
  const TriangleMesh mesh = MeshPointCloud(scene.cloud, options, &report);
  const MeshTopology& t = report.topology;
  std::cout << report.Summary() << std::endl;
  // A tube: one component, manifold, open only at top and bottom. A gap at
  // the seam would join those two loops into one; an overlap would leave
  // non-manifold edges.
  EXPECT_EQ(t.num_components, 1u);
  EXPECT_TRUE(t.IsManifold());
  EXPECT_EQ(t.num_boundary_loops, 2u);
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_GT(report.cylinder.num_seam_faces, 50u);
  EXPECT_EQ(report.cleanup.num_flipped_faces, 0u);  // already outward
  // Both ways within the noise (sigma 2 mm per axis).
  MeshComparisonOptions compare;
  compare.num_samples = 30000;
  const MeshComparison c = CompareMeshes(mesh, scene.truth, compare);
  std::cout << "mesh to truth RMS " << c.mesh_to_truth.rms
            << " m, truth to mesh RMS " << c.truth_to_mesh.rms << " m"
            << std::endl;
  EXPECT_LT(c.mesh_to_truth.rms, 0.0025);
  EXPECT_LT(c.truth_to_mesh.rms, 0.0025);
}

TEST(CylinderMesher, SeamClosedAtAnyAngle) {
  Scene scene = ReliefCylinder(4000);
  // A point exactly on the seam as well.
  scene.cloud.positions[0] = Eigen::Vector3d(-2.0, 0.0, 2.0);
  for (double angle_deg = 0; angle_deg < 360; angle_deg += 11.25) {
    PointCloud rotated = scene.cloud;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(angle_deg * M_PI / 180, Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    for (Eigen::Vector3d& p : rotated.positions) p = r * p;
    CylinderMeshOptions options;
    options.axis_point = Eigen::Vector3d::Zero();
    CylinderMeshReport report;
    TriangleMesh mesh = CylinderDelaunayMesh(rotated, options, 2, &report);
    const MeshTopology t = ComputeMeshTopology(mesh);
    EXPECT_EQ(t.num_non_manifold_edges, 0u) << angle_deg;
    EXPECT_EQ(t.num_boundary_loops, 2u) << angle_deg;
    EXPECT_EQ(t.num_components, 1u) << angle_deg;
    EXPECT_GT(report.num_seam_faces, 20u);
    // Only the hull's fringe along top and bottom.
    EXPECT_LT(report.num_seam_unsafe, report.num_faces_once / 50);
  }
}

TEST(CylinderMesher, ProfileMetricKeepsTrianglesWellShaped) {
  BoxTowerOptions surface;
  surface.num_angles = 480;
  surface.num_heights = 360;
  NoisyCloudOptions noise;
  noise.num_points = 20000;
  noise.blunder_fraction = 0;
  const PointCloud cloud = SampleNoisyCloud(MakeBoxTower(surface), noise);
  CylinderMeshOptions options;
  CylinderMeshReport report;
  const double profile =
      ShareOfThinTriangles(CylinderDelaunayMesh(cloud, options, 2, &report));
  options.metric = CylinderMetric::kMeanRadius;
  const double mean_radius =
      ShareOfThinTriangles(CylinderDelaunayMesh(cloud, options, 2, &report));
  std::cout << "thin triangles: profile " << profile << ", mean radius "
            << mean_radius << std::endl;
  EXPECT_LT(profile, mean_radius);
}

TEST(CylinderMesher, Options) {
  CylinderMeshOptions options;
  options.axis_direction = Eigen::Vector3d::Zero();
  EXPECT_THROW(options.Check(), InputError);
  options = CylinderMeshOptions();
  options.seam_band_deg = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
