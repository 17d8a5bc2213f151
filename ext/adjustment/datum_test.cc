// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/datum.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

TieObservation Observed(image_t image_id, double x, double y, double sigma) {
  TieObservation observation;
  observation.image_id = image_id;
  observation.xy = Eigen::Vector2d(x, y);
  observation.covariance =
      Eigen::Vector2d(sigma * sigma, 0.25 * sigma * sigma).asDiagonal();
  return observation;
}

TiePointRecord Named(const std::string& name,
                     const std::vector<TieObservation>& observations) {
  TiePointRecord point;
  point.name = name;
  point.source = name.empty() ? "alsm" : "target";
  point.observations = observations;
  return point;
}

// A coded target whose name is a control point becomes that point's
// measurements, beside (not over) the ones measured by hand; a target the
// control does not name and an unnamed tie point stay tie points.
TEST(Datum, NamedTiePointsWithControlCoordinatesBecomeControl) {
  ControlData control;
  control.folder = "control";
  ControlPoint a, b;
  a.name = "CT3";
  b.name = "CT6";
  b.type = ControlPointType::kCheck;
  control.points = {a, b};
  control.measurements = {{"CT3", "one.jpg", {10, 20}, 0.3}};
  const std::vector<TiePointRecord> tie_points = {
      Named("", {Observed(1, 1, 2, 0.05), Observed(2, 3, 4, 0.05)}),
      Named("CT3", {Observed(1, 11, 21, 0.04), Observed(2, 31, 41, 0.04)}),
      Named("CT4", {Observed(1, 5, 6, 0.04), Observed(2, 7, 8, 0.04)}),
      Named("CT6", {Observed(2, 50, 60, 0.06), Observed(9, 1, 1, 0.06)})};
  const std::map<image_t, std::string> names = {{1, "one.jpg"}, {2, "two.jpg"}};
  const std::set<size_t> taken =
      TakeControlFromNamedTiePoints(tie_points, names, &control);
  EXPECT_EQ(taken, (std::set<size_t>{1, 3}));
  ASSERT_EQ(control.measurements.size(), 3u);
  // The hand measurement of CT3 in one.jpg stays; the target adds two.jpg.
  EXPECT_EQ(control.measurements[0].xy, Eigen::Vector2d(10, 20));
  EXPECT_EQ(control.measurements[1].point_name, "CT3");
  EXPECT_EQ(control.measurements[1].image_name, "two.jpg");
  EXPECT_EQ(control.measurements[1].xy, Eigen::Vector2d(31, 41));
  EXPECT_DOUBLE_EQ(control.measurements[1].sigma_px, 0.04);  // larger axis
  // CT6 in an image the database does not name is left out.
  EXPECT_EQ(control.measurements[2].point_name, "CT6");
  EXPECT_EQ(control.measurements[2].image_name, "two.jpg");
}

}  // namespace
}  // namespace bayon
