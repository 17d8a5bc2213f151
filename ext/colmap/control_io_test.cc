// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/control_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace bayon {
namespace {

TEST(ControlIo, RoundTrip) {
  const std::string dir = testing::TempDir("control_io");
  std::vector<ControlPoint> points(2);
  points[0].name = "P1";
  points[0].xyz = Eigen::Vector3d(1.5, -2.25, 3.1234567890123);
  points[1].name = "C7";
  points[1].sigma = Eigen::Vector3d(0.002, 0.002, 0.004);
  points[1].type = ControlPointType::kCheck;
  WriteControlPoints(dir + "/points.txt", points);
  const auto back = ReadControlPoints(dir + "/points.txt");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].xyz, points[0].xyz);
  EXPECT_TRUE(back[0].IsFixed());
  EXPECT_EQ(back[1].type, ControlPointType::kCheck);
  EXPECT_EQ(back[1].sigma, points[1].sigma);

  std::vector<ImageMeasurement> measurements = {
      {"P1", "img 1.png", {10.5, 20.25}, 0.3}, {"P1", "b.png", {1, 2}, 0}};
  measurements[0].image_name = "a.png";
  WriteImageMeasurements(dir + "/observations.txt", measurements);
  const auto observations = ReadImageMeasurements(dir + "/observations.txt");
  ASSERT_EQ(observations.size(), 2u);
  EXPECT_EQ(observations[0].xy, Eigen::Vector2d(10.5, 20.25));
  EXPECT_EQ(observations[0].sigma_px, 0.3);
  EXPECT_EQ(observations[1].sigma_px, 0);

  WriteDistances(dir + "/distances.txt", {{"BAR1", "BAR2", 2.0, 0.0005, true}});
  const auto distances = ReadDistances(dir + "/distances.txt");
  ASSERT_EQ(distances.size(), 1u);
  EXPECT_TRUE(distances[0].vertical);
  EXPECT_EQ(distances[0].distance_m, 2.0);
}

TEST(ControlIo, ErrorsNameTheLine) {
  const std::string dir = testing::TempDir("control_io_bad");
  const std::pair<const char*, const char*> cases[] = {
      {"# header\nP1 1 2\n", "points.txt:2"},
      {"P1 1 2 3\nP1 4 5 6\n", "appears twice"},
      {"P1 1 2 nan\n", "not finite"},
      {"P1 1 2 3 -1 0 0\n", "must not be negative"},
      {"P1 1 2 3 0 0 0 maybe\n", "TYPE must be"},
  };
  for (const auto& [content, expected] : cases) {
    WriteFileAtomically(dir + "/points.txt", content);
    try {
      ReadControlPoints(dir + "/points.txt");
      ADD_FAILURE() << content;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(expected), std::string::npos)
          << error.what();
    }
  }
  WriteFileAtomically(dir + "/obs.txt", "P1 a.png 1 2\nP1 a.png 3 4\n");
  EXPECT_THROW(ReadImageMeasurements(dir + "/obs.txt"), InputError);
  WriteFileAtomically(dir + "/d.txt", "A A 1\n");
  EXPECT_THROW(ReadDistances(dir + "/d.txt"), InputError);
}

}  // namespace
}  // namespace bayon
