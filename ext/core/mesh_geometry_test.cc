// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/mesh_geometry.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bayon {
namespace {

TriangleMesh Tetrahedron() {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  // Counter-clockwise seen from outside.
  mesh.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

// An open tube of n segments around the z axis, two rings of vertices.
TriangleMesh Tube(int n) {
  TriangleMesh mesh;
  for (int ring = 0; ring < 2; ++ring) {
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      mesh.vertices.positions.emplace_back(std::cos(a), std::sin(a), ring);
    }
  }
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    mesh.faces.emplace_back(i, j, n + j);
    mesh.faces.emplace_back(i, n + j, n + i);
  }
  return mesh;
}

TEST(MeshTopology, ClosedTetrahedron) {
  const MeshTopology t = ComputeMeshTopology(Tetrahedron());
  EXPECT_EQ(t.num_edges, 6u);
  EXPECT_EQ(t.num_boundary_edges, 0u);
  EXPECT_EQ(t.num_boundary_loops, 0u);
  EXPECT_EQ(t.num_components, 1u);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_TRUE(t.IsClosed());
  EXPECT_NEAR(t.longest_edge, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(t.shortest_edge, 1.0, 1e-12);
  // Three right triangles of area 1/2 and one equilateral of side sqrt(2).
  EXPECT_NEAR(t.area, 1.5 + std::sqrt(3.0) / 2, 1e-12);
}

TEST(MeshTopology, OpenTubeHasTwoBoundaryLoops) {
  const TriangleMesh tube = Tube(12);
  const MeshTopology t = ComputeMeshTopology(tube);
  EXPECT_EQ(t.num_boundary_edges, 24u);
  EXPECT_EQ(t.num_boundary_loops, 2u);
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_TRUE(t.IsManifold());
  EXPECT_FALSE(t.IsClosed());
  for (const auto& loop : FindBoundaryLoops(tube)) EXPECT_EQ(loop.size(), 12u);

  // Cutting the tube open along one seam leaves one loop.
  TriangleMesh cut = tube;
  cut.faces.resize(cut.faces.size() - 2);
  EXPECT_EQ(ComputeMeshTopology(cut).num_boundary_loops, 1u);
}

TEST(MeshTopology, FindsNonManifoldAndInconsistentFaces) {
  TriangleMesh fin = Tetrahedron();
  // A third face on edge (0, 1).
  fin.vertices.positions.emplace_back(0.5, -1, 0);
  fin.faces.emplace_back(0, 4, 1);
  MeshTopology t = ComputeMeshTopology(fin);
  EXPECT_EQ(t.num_non_manifold_edges, 1u);
  EXPECT_FALSE(t.IsManifold());

  // Two triangles touching at one vertex.
  TriangleMesh bowtie;
  bowtie.vertices.positions = {
      {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bowtie.faces = {{0, 1, 2}, {0, 3, 4}};
  t = ComputeMeshTopology(bowtie);
  EXPECT_EQ(t.num_non_manifold_edges, 0u);
  EXPECT_EQ(t.num_non_manifold_vertices, 1u);
  EXPECT_EQ(t.num_components, 2u);

  bowtie.vertices.AddAttribute("sx", PlyScalarType::kFloat, 0.5);
  EXPECT_EQ(SplitNonManifoldVertices(&bowtie), 1u);
  ASSERT_EQ(bowtie.NumVertices(), 6u);
  EXPECT_EQ(bowtie.vertices.positions[5], bowtie.vertices.positions[0]);
  EXPECT_EQ(bowtie.vertices.FindAttribute("sx")->values.size(), 6u);
  t = ComputeMeshTopology(bowtie);
  EXPECT_EQ(t.num_non_manifold_vertices, 0u);
  EXPECT_EQ(t.num_faces, 2u);

  TriangleMesh flipped = Tetrahedron();
  std::swap(flipped.faces[3](0), flipped.faces[3](1));
  t = ComputeMeshTopology(flipped);
  EXPECT_EQ(t.num_inconsistent_edges, 3u);

  TriangleMesh degenerate = Tetrahedron();
  degenerate.vertices.positions.emplace_back(2, 0, 0);
  degenerate.faces.emplace_back(0, 1, 4);  // collinear
  t = ComputeMeshTopology(degenerate);
  EXPECT_EQ(t.num_degenerate_faces, 1u);
  EXPECT_EQ(t.num_unreferenced_vertices, 0u);
}

TEST(SampleMeshSurface, AreaUniformAndDeterministic) {
  TriangleMesh mesh;
  // A unit triangle and one with three times its area.
  mesh.vertices.positions = {
      {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 5}, {3, 0, 5}, {0, 1, 5}};
  mesh.faces = {{0, 1, 2}, {3, 4, 5}};
  const std::vector<SurfaceSample> samples = SampleMeshSurface(mesh, 20000, 7);
  ASSERT_EQ(samples.size(), 20000u);
  size_t on_big = 0;
  for (const SurfaceSample& s : samples) {
    if (s.face == 1) {
      ++on_big;
      EXPECT_DOUBLE_EQ(s.position.z(), 5);
      EXPECT_LE(s.position.x() / 3 + s.position.y(), 1 + 1e-12);
    }
  }
  EXPECT_NEAR(on_big / 20000.0, 0.75, 0.015);
  const std::vector<SurfaceSample> again = SampleMeshSurface(mesh, 20000, 7);
  EXPECT_EQ(again[123].position, samples[123].position);
}

}  // namespace
}  // namespace bayon
