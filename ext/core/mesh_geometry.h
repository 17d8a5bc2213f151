// SPDX-License-Identifier: BSD-3-Clause
//
// Measures of a TriangleMesh that the mesh, eval, texture and render stages
// share: its topology (edges, boundary loops, manifoldness, components, Euler
// characteristic), edge lengths and areas, and area-uniform random samples of
// its surface. Works on the plain indexed face list, so it also judges meshes
// that a halfedge structure would refuse (non-manifold edges and vertices).
#pragma once

#include "ext/core/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace bayon {

struct MeshTopology {
  size_t num_vertices = 0;  // all vertices, referenced or not
  size_t num_unreferenced_vertices = 0;
  size_t num_faces = 0;
  size_t num_edges = 0;  // undirected, distinct
  // Edges used by exactly one face, and the closed loops they form.
  size_t num_boundary_edges = 0;
  size_t num_boundary_loops = 0;
  // Edges used by more than two faces.
  size_t num_non_manifold_edges = 0;
  // Vertices whose faces form more than one edge-connected fan (two cones
  // touching at a tip, or two boundary loops through one vertex).
  size_t num_non_manifold_vertices = 0;
  // Manifold edges that both faces traverse in the same direction (the two
  // faces disagree about which side is outside).
  size_t num_inconsistent_edges = 0;
  // Faces with a repeated vertex or zero area.
  size_t num_degenerate_faces = 0;
  // Face-connected components (faces sharing an edge).
  size_t num_components = 0;
  // V - E + F over referenced vertices (2 for a sphere, 0 for a torus or an
  // open tube).
  int64_t euler_characteristic = 0;
  // Edge lengths (object units).
  double shortest_edge = 0;
  double mean_edge = 0;
  double longest_edge = 0;
  double area = 0;

  bool IsManifold() const {
    return num_non_manifold_edges == 0 && num_non_manifold_vertices == 0;
  }
  bool IsClosed() const { return IsManifold() && num_boundary_edges == 0; }
};

// Computes every field of MeshTopology in O(F log F).
MeshTopology ComputeMeshTopology(const TriangleMesh& mesh);

// A fan label for every face corner (index 3 * face + k): corners of one
// vertex share a label when their faces are joined around the vertex by
// edges with exactly two faces; -1 for faces that repeat a vertex. A vertex
// whose corners carry more than one label is non-manifold.
std::vector<int> CornerFans(const TriangleMesh& mesh);

// Gives every fan after the first of a non-manifold vertex its own copy of
// the vertex (with its normal, colour and attributes), so that the faces
// stay and every vertex becomes manifold. Returns the number of copies.
size_t SplitNonManifoldVertices(TriangleMesh* mesh);

// The boundary loops as vertex sequences (each loop listed once, following
// the boundary in the direction opposite to its face's edge).
std::vector<std::vector<int>> FindBoundaryLoops(const TriangleMesh& mesh);

// Area-uniform random points on the surface with the face each lies on,
// deterministic for a seed.
struct SurfaceSample {
  Eigen::Vector3d position;
  int face = -1;
};
std::vector<SurfaceSample> SampleMeshSurface(const TriangleMesh& mesh,
                                             size_t num_samples,
                                             uint64_t seed);

// Unit normal of a face (counter-clockwise seen from outside); zero for a
// degenerate face.
Eigen::Vector3d FaceNormal(const TriangleMesh& mesh, int face);

// The mean of the points (zero for none): where the meshers shift a cloud
// to, for the same numerics whatever its coordinates.
Eigen::Vector3d Centroid(const std::vector<Eigen::Vector3d>& points);

}  // namespace bayon
