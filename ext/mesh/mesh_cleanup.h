// SPDX-License-Identifier: BSD-3-Clause
//
// Cleanup of a raw triangulation on OpenMesh's halfedge structure (which
// only holds manifold meshes, so building it is itself the manifold test):
//  1. vertices closer than merge_distance_m merged, faces that repeat a
//     vertex or repeat another face dropped;
//  2. faces oriented consistently across shared edges (breadth-first), each
//     component turned to agree with the point normals, or outward when
//     there are none;
//  3. faces that would make an edge or a vertex non-manifold refused;
//  4. degenerate (zero-area) faces removed by collapsing their shortest edge
//     or flipping their longest one, deleted where neither is allowed;
//  5. small face-connected components removed;
//  6. optionally, holes of at most max_hole_edges boundary edges filled with
//     the minimum-area triangulation of their boundary polygon (dynamic
//     programming over the loop, as in Liepa 2003 without refinement);
//  7. vertices where two boundary fans touch (OpenMesh holds them) split
//     into one vertex per fan, so the result is manifold.
// Vertex attributes (normals, colours, sx/sy/sz, ...) follow their vertices;
// unreferenced vertices go.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

namespace bayon {

struct MeshCleanupOptions {
  // Vertices closer than this are one (metres); 0 = identical positions.
  double merge_distance_m = 0;
  // A component is removed when it has fewer faces than
  // max(min_component_faces, min_component_fraction * largest component).
  double min_component_fraction = 0.01;
  int min_component_faces = 20;
  // Fill holes whose boundary has at most this many edges; 0 = off.
  int max_hole_edges = 0;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct MeshCleanupReport {
  size_t num_merged_vertices = 0;
  size_t num_repeated_vertex_faces = 0;
  size_t num_duplicate_faces = 0;
  size_t num_flipped_faces = 0;
  size_t num_non_manifold_faces = 0;
  size_t num_degenerate_faces = 0;
  size_t num_small_components = 0;
  size_t num_small_component_faces = 0;
  size_t num_holes_filled = 0;
  size_t num_fill_faces = 0;
  size_t num_split_vertices = 0;
};

TriangleMesh CleanupMesh(const TriangleMesh& mesh,
                         const MeshCleanupOptions& options,
                         MeshCleanupReport* report);

}  // namespace bayon
