// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/point_cloud.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <limits>

namespace bayon {
namespace {

TEST(PointCloud, FilterAndAppendKeepEveryArrayAligned) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  cloud.colors = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
  PointAttribute& sx = cloud.AddAttribute("sx", PlyScalarType::kFloat);
  sx.values = {0.1, 0.2, 0.3};
  cloud.Filter({true, false, true});
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[1].x(), 2);
  EXPECT_EQ(cloud.colors[1](0), 3);
  EXPECT_EQ(cloud.FindAttribute("sx")->values[1], 0.3);
  cloud.Append(cloud);
  EXPECT_EQ(cloud.size(), 4u);
  cloud.Check("cloud");
  PointCloud other;
  other.positions = {{0, 0, 0}};
  EXPECT_THROW(cloud.Append(other), InputError);
  cloud.positions[0].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(cloud.Check("cloud"), InputError);
}

TEST(TriangleMesh, CheckFindsBadFaces) {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  mesh.Check("mesh");
  mesh.faces = {{0, 1, 3}};
  EXPECT_THROW(mesh.Check("mesh"), InputError);
  mesh.faces = {{0, 1, 1}};
  EXPECT_THROW(mesh.Check("mesh"), InputError);
}

}  // namespace
}  // namespace bayon
