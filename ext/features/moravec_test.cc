// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/moravec.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <random>
#include <set>

namespace bayon {
namespace {

cv::Mat RandomTexture(int width, int height, unsigned seed) {
  cv::Mat image(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.5);
  return image;
}

// The definition, written out: min over four directions of the window mean
// of squared differences.
float BruteForceInterest(const cv::Mat& g, int x, int y, int w) {
  const int r = w / 2;
  const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  float best = 1e30f;
  for (const auto& d : dirs) {
    double sum = 0;
    for (int v = -r; v <= r; ++v) {
      for (int u = -r; u <= r; ++u) {
        const float a = g.at<float>(y + v, x + u);
        const float b = g.at<float>(y + v + d[1], x + u + d[0]);
        sum += (b - a) * (b - a);
      }
    }
    best = std::min(best, static_cast<float>(sum / (w * w)));
  }
  return best;
}

TEST(Moravec, InterestMatchesTheDefinition) {
  const cv::Mat image = RandomTexture(40, 30, 7);
  for (int w : {3, 5, 7}) {
    const cv::Mat interest = MoravecInterest(image, w);
    for (int y = w; y < 30 - w; y += 3) {
      for (int x = w; x < 40 - w; x += 3) {
        EXPECT_NEAR(
            interest.at<float>(y, x), BruteForceInterest(image, x, y, w), 1e-2)
            << "w=" << w << " at " << x << "," << y;
      }
    }
  }
}

TEST(Moravec, EdgesAndRampsHaveNoInterestCornersDo) {
  // A bright rectangle: its straight edges change the grey value in only one
  // direction, its corners in all of them.
  cv::Mat image(80, 100, CV_32F, cv::Scalar(20));
  image(cv::Rect(30, 20, 40, 30)).setTo(220);
  const cv::Mat interest = MoravecInterest(image, 5);
  EXPECT_FLOAT_EQ(interest.at<float>(35, 30), 0.f);  // left edge
  EXPECT_FLOAT_EQ(interest.at<float>(20, 50), 0.f);  // top edge
  EXPECT_GT(interest.at<float>(20, 30), 100.f);      // corner
  MoravecOptions options;
  options.patch_size = 8;
  options.min_interest = 50;
  const std::vector<InterestPoint> points = DetectMoravecPoints(image, options);
  ASSERT_EQ(points.size(), 4u);
  const Eigen::Vector2f corners[4] = {
      {30, 20}, {70, 20}, {30, 50}, {70, 50}};  // pixel edges, COLMAP coords
  for (const Eigen::Vector2f& corner : corners) {
    float nearest = 1e9f;
    for (const InterestPoint& p : points) {
      nearest = std::min(nearest, (p.xy - corner).norm());
    }
    // Moravec localises a step corner within about half a window.
    EXPECT_LT(nearest, 0.75f * 5) << corner.transpose();
  }
  // A ramp has the same difference everywhere in one direction, none in the
  // other: no points at all.
  cv::Mat ramp(60, 60, CV_32F);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) ramp.at<float>(y, x) = 3.f * x;
  EXPECT_TRUE(DetectMoravecPoints(ramp, options).empty());
  EXPECT_TRUE(
      DetectMoravecPoints(cv::Mat(60, 60, CV_32F, cv::Scalar(9)), options)
          .empty());
}

TEST(Moravec, GridThinningSpreadsPointsOnePerPatch) {
  const cv::Mat image = RandomTexture(320, 240, 3);
  MoravecOptions options;
  options.patch_size = 20;
  options.max_num_features = 0;
  options.border_px = 8;
  const std::vector<InterestPoint> points = DetectMoravecPoints(image, options);
  // (320 - 16) / 20 -> 16 columns, (240 - 16) / 20 -> 12 rows of patches;
  // a textured image fills most of them.
  EXPECT_GT(points.size(), 0.6 * 16 * 12);
  EXPECT_LE(points.size(), 16u * 12u);
  std::set<std::pair<int, int>> cells;
  for (const InterestPoint& p : points) {
    const int cx = (static_cast<int>(p.xy.x()) - 8) / 20;
    const int cy = (static_cast<int>(p.xy.y()) - 8) / 20;
    EXPECT_TRUE(cells.insert({cx, cy}).second) << "two points in one patch";
    EXPECT_GE(p.xy.x(), 8);
    EXPECT_LT(p.xy.x(), 320 - 8);
    EXPECT_GE(p.interest, options.min_interest);
  }
  for (size_t i = 1; i < points.size(); ++i) {
    EXPECT_GE(points[i - 1].interest, points[i].interest);
  }
  // A limit keeps the strongest ones.
  options.max_num_features = 50;
  const std::vector<InterestPoint> strongest =
      DetectMoravecPoints(image, options);
  ASSERT_EQ(strongest.size(), 50u);
  EXPECT_EQ(strongest.back().interest, points[49].interest);
}

TEST(Moravec, AutomaticPatchSizeGivesAboutTheRequestedCount) {
  const cv::Mat image = RandomTexture(400, 300, 5);
  MoravecOptions options;
  options.max_num_features = 300;
  EXPECT_EQ(ThinningPatchSize(options, 400, 300), 20);  // sqrt(384*284/300)
  const size_t n = DetectMoravecPoints(image, options).size();
  EXPECT_GT(n, 150u);
  EXPECT_LE(n, 300u);
}

TEST(Moravec, TinyImagesAndBadOptions) {
  MoravecOptions options;
  EXPECT_TRUE(DetectMoravecPoints(RandomTexture(10, 12, 1), options).empty());
  EXPECT_TRUE(DetectMoravecPoints(cv::Mat(1, 1, CV_32F, cv::Scalar(0)), options)
                  .empty());
  options.window_size = 4;
  EXPECT_THROW(options.Check(), InputError);
  options.window_size = 5;
  options.max_num_features = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
