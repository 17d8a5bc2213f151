// SPDX-License-Identifier: BSD-3-Clause
//
// Z-buffer rasterisation of screen-space triangles into a depth key and a
// triangle id per raster pixel. The renderer uses it twice: as a visibility
// raster of a pinhole view (which triangle to intersect for each ray) and as
// the shadow map seen from the sun (orthographic).
//
// Raster pixel (x, y) has its centre at (x + 0.5, y + 0.5); a triangle covers
// the pixels whose centres lie inside or on its edges (both orientations,
// no back-face culling). The depth key must be affine in screen space
// (-1/z for a perspective view, the distance along the projection direction
// for an orthographic one); the smallest key wins.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <vector>

namespace bayon {

struct RasterTriangle {
  Eigen::Vector2d position[3];  // raster pixels
  float key[3];                 // depth key per vertex, smaller is nearer
  int32_t id = -1;              // written to the id buffer
};

struct DepthRaster {
  int width = 0;
  int height = 0;
  // Row-major; key = +infinity and id = -1 where no triangle was drawn.
  // `id` stays empty when the raster was reset without ids (a shadow map).
  std::vector<float> key;
  std::vector<int32_t> id;

  void Reset(int new_width, int new_height, bool with_ids = true);
  float Key(int x, int y) const { return key[size_t(y) * width + x]; }
  int32_t Id(int x, int y) const { return id[size_t(y) * width + x]; }
};

// Draws the triangles into `raster` (which keeps what it already holds), in
// horizontal bands on up to `num_threads` threads. The result does not
// depend on the thread count: within a band triangles are drawn in input
// order and ties keep the earlier triangle.
void RasterizeTriangles(const std::vector<RasterTriangle>& triangles,
                        int num_threads,
                        DepthRaster* raster);

}  // namespace bayon
