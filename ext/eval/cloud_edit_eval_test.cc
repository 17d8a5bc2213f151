// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/cloud_edit_eval.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

// Points over the unit square z = 0 at the given heights, flagged as given.
PointCloud Column(const std::vector<double>& heights,
                  const std::vector<double>& flags) {
  PointCloud cloud;
  for (size_t i = 0; i < heights.size(); ++i) {
    cloud.positions.emplace_back(0.1 + 0.05 * i, 0.5, heights[i]);
  }
  cloud.AddAttribute("blunder", PlyScalarType::kUChar).values = flags;
  return cloud;
}

TEST(CloudEditEval, CountsTheInputsOwnBlundersApart) {
  TriangleMesh square;
  square.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  const MeshDistance truth(square);
  // Four points on the surface, two unflagged ones 3 cm off it (the
  // input's own blunders), two injected blunders.
  const PointCloud before =
      Column({0, 0.002, -0.001, 0.004, 0.03, -0.03, 0.1, -0.15},
             {0, 0, 0, 0, 0, 0, 1, 1});
  // The edit removed one blunder, one own blunder and one point on the
  // surface.
  const PointCloud after =
      Column({0, 0.002, -0.001, 0.03, -0.15}, {0, 0, 0, 0, 1});
  const CloudEditEvaluation e = EvaluateCloudEdit(before, after, truth, 0.01);
  EXPECT_EQ(e.num_blunders_before, 2u);
  EXPECT_EQ(e.num_good_before, 6u);
  EXPECT_EQ(e.num_off_surface_before, 2u);
  EXPECT_EQ(e.num_off_surface_after, 1u);
  EXPECT_DOUBLE_EQ(e.BlundersRemovedFraction(), 0.5);
  EXPECT_DOUBLE_EQ(e.GoodRemovedFraction(), 2.0 / 6);
  EXPECT_DOUBLE_EQ(e.OnSurfaceRemovedFraction(), 0.25);
  EXPECT_DOUBLE_EQ(e.OffSurfaceRemovedFraction(), 0.5);
  EXPECT_NE(e.Table("t").find("50.00"), std::string::npos);
  // Without the distance nothing is counted apart.
  const CloudEditEvaluation plain = EvaluateCloudEdit(before, after, truth);
  EXPECT_EQ(plain.num_off_surface_before, 0u);
  EXPECT_DOUBLE_EQ(plain.OnSurfaceRemovedFraction(),
                   plain.GoodRemovedFraction());
  PointCloud unflagged;
  unflagged.positions = before.positions;
  EXPECT_THROW(EvaluateCloudEdit(unflagged, after, truth), InputError);
}

}  // namespace
}  // namespace bayon
