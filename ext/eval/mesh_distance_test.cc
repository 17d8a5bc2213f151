// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/mesh_distance.h"

#include "ext/core/errors.h"
#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace bayon {
namespace {

TriangleMesh UnitSquare() {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// A closed UV sphere of radius r around the origin.
TriangleMesh Sphere(double r, int rings, int segments) {
  TriangleMesh mesh;
  auto& p = mesh.vertices.positions;
  p.emplace_back(0, 0, r);
  for (int i = 1; i < rings; ++i) {
    const double polar = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double a = 2 * M_PI * j / segments;
      p.emplace_back(r * std::sin(polar) * std::cos(a),
                     r * std::sin(polar) * std::sin(a),
                     r * std::cos(polar));
    }
  }
  p.emplace_back(0, 0, -r);
  const int south = static_cast<int>(p.size()) - 1;
  auto ring = [&](int i, int j) {
    return 1 + (i - 1) * segments + j % segments;
  };
  for (int j = 0; j < segments; ++j) {
    mesh.faces.emplace_back(0, ring(1, j), ring(1, j + 1));
    mesh.faces.emplace_back(south, ring(rings - 1, j + 1), ring(rings - 1, j));
  }
  for (int i = 1; i < rings - 1; ++i) {
    for (int j = 0; j < segments; ++j) {
      mesh.faces.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      mesh.faces.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  return mesh;
}

TEST(MeshDistance, VertexEdgeAndFaceRegions) {
  const MeshDistance distance(UnitSquare());
  EXPECT_NEAR(distance.Closest({0.25, 0.75, 2}).distance, 2, 1e-12);
  EXPECT_NEAR(distance.Closest({2, 0.5, 0}).distance, 1, 1e-12);
  EXPECT_NEAR(distance.Closest({-1, -1, 0}).distance, std::sqrt(2.0), 1e-12);
  const MeshDistance::Hit hit = distance.Closest({0.9, 0.2, -3});
  EXPECT_EQ(hit.face, 0);
  EXPECT_NEAR(
      (hit.closest_point - Eigen::Vector3d(0.9, 0.2, 0)).norm(), 0, 1e-12);
  EXPECT_THROW(MeshDistance{TriangleMesh{}}, InputError);
}

TEST(MeshDistance, HierarchyAgreesWithBruteForce) {
  const TriangleMesh sphere = Sphere(1.0, 24, 48);
  const MeshDistance distance(sphere);
  TriangleMesh single;
  single.faces = {{0, 1, 2}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 300; ++i) points.push_back(RandomVector<3>(u, rng));
  const std::vector<double> fast = distance.Distances(points, 2);
  for (size_t i = 0; i < points.size(); ++i) {
    double best = 1e300;
    for (const Eigen::Vector3i& face : sphere.faces) {
      const auto& p = sphere.vertices.positions;
      single.vertices.positions = {p[face(0)], p[face(1)], p[face(2)]};
      best = std::min(best, MeshDistance(single).Closest(points[i]).distance);
    }
    EXPECT_NEAR(fast[i], best, 1e-12) << i;
  }
}

TEST(MeshDistance, StatisticsAndBothWays) {
  const DistanceStatistics stats = ComputeDistanceStatistics({3, 1, 2, 4, 0});
  EXPECT_EQ(stats.count, 5u);
  EXPECT_DOUBLE_EQ(stats.mean, 2);
  EXPECT_DOUBLE_EQ(stats.rms, std::sqrt(6.0));
  EXPECT_DOUBLE_EQ(stats.median, 2);
  EXPECT_DOUBLE_EQ(stats.max, 4);

  // A sphere against one 1 cm larger: 1 cm both ways, up to the facets'
  // sagitta (a few tenths of a millimetre at this resolution).
  const TriangleMesh truth = Sphere(1.0, 60, 120);
  const TriangleMesh mesh = Sphere(1.01, 60, 120);
  MeshComparisonOptions options;
  options.num_samples = 20000;
  MeshComparison c = CompareMeshes(mesh, truth, options);
  EXPECT_NEAR(c.mesh_to_truth.rms, 0.01, 5e-4);
  EXPECT_NEAR(c.truth_to_mesh.rms, 0.01, 5e-4);
  EXPECT_DOUBLE_EQ(c.truth_fraction_covered, 1.0);

  // Half a sphere against the whole truth: the missing half is far away one
  // way, unless the comparison is limited to the truth the points covered.
  TriangleMesh half = mesh;
  half.faces.clear();
  for (const Eigen::Vector3i& f : mesh.faces) {
    if (mesh.vertices.positions[f(0)].z() > 0.05) half.faces.push_back(f);
  }
  c = CompareMeshes(half, truth, options);
  EXPECT_GT(c.truth_to_mesh.rms, 0.3);
  options.coverage_points = half.vertices.positions;
  options.coverage_points.erase(
      std::remove_if(options.coverage_points.begin(),
                     options.coverage_points.end(),
                     [](const Eigen::Vector3d& p) { return p.z() < 0.1; }),
      options.coverage_points.end());
  options.coverage_radius = 0.05;
  c = CompareMeshes(half, truth, options);
  EXPECT_NEAR(c.truth_to_mesh.rms, 0.01, 1e-3);
  EXPECT_NEAR(c.truth_fraction_covered, 0.5, 0.1);
}

}  // namespace
}  // namespace bayon
