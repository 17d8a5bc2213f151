// SPDX-License-Identifier: BSD-3-Clause
//
// PLY files (Turk 1994) for point clouds and triangle meshes: ASCII and
// binary (either byte order) on read, binary little-endian or ASCII on write.
// Vertex properties x y z are required; nx ny nz, red green blue (uchar) and
// any other scalar properties are kept (as PointAttribute); faces come from a
// `vertex_indices` (or `vertex_index`) list, polygons split into triangles as
// fans, and an optional `texcoord` list of 6 floats per triangle (MeshLab's
// convention). Other elements are skipped. Readers check every count against
// the bytes left and name the file, the element and the line or byte.
#pragma once

#include "ext/core/point_cloud.h"

#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

struct PlyWriteOptions {
  bool binary = true;
  // x y z as double (bayon's own files) or float (what COLMAP's
  // poisson_mesher and most viewers expect).
  bool double_coordinates = true;
  // Written as a comment line in the header, e.g. the producing command.
  std::string comment;
};

// Reads vertices and faces. A file without faces gives an empty face list.
TriangleMesh ReadPly(const std::string& path);
// Reads a point cloud (faces, if any, are ignored).
PointCloud ReadPointCloudPly(const std::string& path);
// Reads a mesh; throws InputError if the file has no faces.
TriangleMesh ReadMeshPly(const std::string& path);
// The texture atlas a mesh's `texcoord`s refer to: the header line
// `comment TextureFile NAME` (MeshLab's convention), resolved against the
// file's folder; empty when the header names none.
std::string PlyTextureFile(const std::string& path);

// Writes atomically (temporary name, rename).
void WritePointCloudPly(const PointCloud& cloud,
                        const std::string& path,
                        const PlyWriteOptions& options = {});
void WriteMeshPly(const TriangleMesh& mesh,
                  const std::string& path,
                  const PlyWriteOptions& options = {});

// COLMAP's `fused.ply` (what `colmap stereo_fusion` writes and
// `colmap poisson_mesher` reads): float x y z, nx ny nz and uchar colours
// (grey where the cloud has none; PoissonRecon with COLMAP's default
// --PoissonMeshing.color refuses a file without them), no other properties.
// With `visibility`, also `<path>.vis`: per point the indices of the images
// that see it, indices into the sparse model's image list (0-based, in the
// order of its images file), as COLMAP's fusion writes them for
// `colmap delaunay_mesher`. The .vis first, so that a complete fused.ply
// implies a complete .vis beside it.
void WriteColmapFusedPly(
    const PointCloud& cloud,
    const std::string& path,
    const std::string& comment,
    const std::vector<std::vector<uint32_t>>* visibility = nullptr);

// A fused.ply.vis as WriteColmapFusedPly and COLMAP's fusion write it.
// Throws InputError naming the file when it is missing, truncated or longer
// than its counts say.
std::vector<std::vector<uint32_t>> ReadColmapVisibility(
    const std::string& path);

}  // namespace bayon
