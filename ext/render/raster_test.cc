// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/raster.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

RasterTriangle Triangle(Eigen::Vector2d a,
                        Eigen::Vector2d b,
                        Eigen::Vector2d c,
                        float key,
                        int id) {
  RasterTriangle triangle;
  triangle.position[0] = a;
  triangle.position[1] = b;
  triangle.position[2] = c;
  triangle.key[0] = triangle.key[1] = triangle.key[2] = key;
  triangle.id = id;
  return triangle;
}

TEST(Raster, CoversPixelCentresAndKeepsTheNearest) {
  DepthRaster raster;
  raster.Reset(100, 80);
  // Two triangles making a square [10, 50] x [20, 60], and a nearer
  // triangle over part of it.
  std::vector<RasterTriangle> triangles = {
      Triangle({10, 20}, {50, 20}, {50, 60}, 5.0f, 0),
      Triangle({10, 20}, {50, 60}, {10, 60}, 5.0f, 1),
      Triangle({0, 0}, {30, 0}, {0, 30}, 1.0f, 2)};
  RasterizeTriangles(triangles, 2, &raster);
  int covered = 0;
  for (int y = 0; y < raster.height; ++y) {
    for (int x = 0; x < raster.width; ++x) {
      const bool in_square =
          x + 0.5 > 10 && x + 0.5 < 50 && y + 0.5 > 20 && y + 0.5 < 60;
      const bool in_near = x + 0.5 + y + 0.5 <= 30;
      if (in_near) {
        EXPECT_EQ(raster.Id(x, y), 2);
        EXPECT_EQ(raster.Key(x, y), 1.0f);
      } else if (in_square) {
        EXPECT_GE(raster.Id(x, y), 0);
        EXPECT_LE(raster.Id(x, y), 1);
        ++covered;
      } else {
        EXPECT_EQ(raster.Id(x, y), -1) << x << " " << y;
      }
    }
  }
  EXPECT_GT(covered, 1400);
}

TEST(Raster, InterpolatesTheKeyAffinely) {
  DepthRaster raster;
  raster.Reset(64, 64);
  RasterTriangle triangle = Triangle({0, 0}, {64, 0}, {0, 64}, 0, 7);
  triangle.key[0] = 0;
  triangle.key[1] = 64;  // key = x
  triangle.key[2] = 0;
  RasterizeTriangles({triangle}, 1, &raster);
  EXPECT_NEAR(raster.Key(10, 20), 10.5, 1e-4);
  EXPECT_NEAR(raster.Key(30, 3), 30.5, 1e-4);
}

TEST(Raster, SameResultOnAnyNumberOfThreads) {
  std::vector<RasterTriangle> triangles;
  for (int i = 0; i < 500; ++i) {
    const double x = (i * 37) % 200, y = (i * 91) % 150;
    triangles.push_back(
        Triangle({x, y}, {x + 30, y + 5}, {x + 7, y + 40}, float(i % 13), i));
  }
  DepthRaster one, two;
  one.Reset(200, 150);
  two.Reset(200, 150);
  RasterizeTriangles(triangles, 1, &one);
  RasterizeTriangles(triangles, 2, &two);
  EXPECT_EQ(one.id, two.id);
  EXPECT_EQ(one.key, two.key);
}

TEST(Raster, WithoutIdsKeepsOnlyKeys) {
  DepthRaster raster;
  raster.Reset(16, 16, /*with_ids=*/false);
  RasterizeTriangles({Triangle({0, 0}, {16, 0}, {0, 16}, 2.0f, 3)}, 1, &raster);
  EXPECT_TRUE(raster.id.empty());
  EXPECT_EQ(raster.Key(1, 1), 2.0f);
}

}  // namespace
}  // namespace bayon
