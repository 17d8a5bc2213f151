// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/image_compose.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

cv::Mat Noise(int seed) {
  cv::Mat image(6, 5, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(ImageCompose, ToneMapClampsAndRounds) {
  cv::Mat color(1, 3, CV_32FC3);
  color.at<cv::Vec3f>(0, 0) = cv::Vec3f(-0.5f, 0.0f, 0.5f);
  color.at<cv::Vec3f>(0, 1) = cv::Vec3f(1.0f, 2.0f, 0.2f);
  color.at<cv::Vec3f>(0, 2) = cv::Vec3f(0.999f, 1e-3f, 0.75f);
  const cv::Mat out = ToneMap8(color);
  ASSERT_EQ(out.type(), CV_8UC3);
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 128));
  EXPECT_EQ(out.at<cv::Vec3b>(0, 1), cv::Vec3b(255, 255, 51));
  EXPECT_EQ(out.at<cv::Vec3b>(0, 2), cv::Vec3b(255, 0, 191));
}

TEST(ImageCompose, WireframeDrawsEdgesAndSilhouette) {
  // At 3x: background left of column 30, triangle 4 from column 30 to 59,
  // triangle 7 from 60 on; rows alike. Output 30 x 20.
  cv::Mat ids(60, 90, CV_32S, cv::Scalar(-1));
  ids.colRange(30, 60).setTo(4);
  ids.colRange(60, 90).setTo(7);
  // Two triangles of 30 x 20 output pixels: lines of full width.
  EXPECT_EQ(WireframeLineWidth(ids, 3), 3);
  const cv::Mat coverage = WireframeCoverage(ids, 3, 3);
  ASSERT_EQ(coverage.size(), cv::Size(30, 20));
  for (int y = 0; y < 20; ++y) {
    // Lines around output columns 10 (silhouette) and 20 (shared edge),
    // about one pixel of ink each, nothing elsewhere.
    for (int edge : {10, 20}) {
      const float ink =
          coverage.at<float>(y, edge - 1) + coverage.at<float>(y, edge);
      EXPECT_NEAR(ink, 1.0f, 1e-6) << "row " << y << " edge " << edge;
    }
    for (int x : {0, 5, 14, 16, 25, 29}) {
      EXPECT_EQ(coverage.at<float>(y, x), 0.0f) << x;
    }
  }
  // Without supersampling: a hard line on one side of each edge.
  // A third of the width: a third of the ink.
  const cv::Mat thin = WireframeCoverage(ids, 3, 1);
  EXPECT_NEAR(thin.at<float>(7, 9) + thin.at<float>(7, 10), 1 / 3.0f, 1e-6);
  const cv::Mat hard = WireframeCoverage(ids, 1, 1);
  EXPECT_EQ(hard.at<float>(0, 29), 1.0f);
  EXPECT_EQ(hard.at<float>(0, 59), 1.0f);
  EXPECT_EQ(cv::countNonZero(hard), 2 * 60);

  const cv::Mat painted = PaintLines(coverage, cv::Mat(), {0, 0, 0});
  EXPECT_EQ(painted.at<cv::Vec3f>(3, 3), cv::Vec3f(1, 1, 1));
  EXPECT_LT(painted.at<cv::Vec3f>(3, 10)[0] + painted.at<cv::Vec3f>(3, 9)[0],
            1.01f);
}

TEST(ImageCompose, WireframeLinesThinOutOnDenseMeshes) {
  // Triangles of 2 x 2 fine pixels at scale 3: (4 / 9) output pixels each,
  // edges of about 1 output pixel: the thinnest lines.
  cv::Mat dense(60, 60, CV_32S);
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 60; ++x) dense.at<int32_t>(y, x) = (y / 2) * 30 + x / 2;
  }
  EXPECT_EQ(WireframeLineWidth(dense, 3), 1);
  // Triangles of 36 x 36 fine pixels, 12 x 12 output: full width.
  cv::Mat sparse(72, 72, CV_32S);
  for (int y = 0; y < 72; ++y) {
    for (int x = 0; x < 72; ++x)
      sparse.at<int32_t>(y, x) = (y / 36) * 2 + x / 36;
  }
  EXPECT_EQ(WireframeLineWidth(sparse, 3), 3);
  EXPECT_EQ(WireframeLineWidth(cv::Mat(9, 9, CV_32S, cv::Scalar(-1)), 3), 3);
}

TEST(ImageCompose, AnaglyphTakesRedFromTheLeftEye) {
  const cv::Mat left = Noise(1), right = Noise(2);
  const cv::Mat color = Anaglyph(left, right, AnaglyphType::kColor);
  const cv::Mat gray = Anaglyph(left, right, AnaglyphType::kGray);
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) {
      const cv::Vec3b l = left.at<cv::Vec3b>(y, x),
                      r = right.at<cv::Vec3b>(y, x);
      EXPECT_EQ(color.at<cv::Vec3b>(y, x), cv::Vec3b(r[0], r[1], l[2]));
      const cv::Vec3b g = gray.at<cv::Vec3b>(y, x);
      EXPECT_EQ(g[0], g[1]);
      // Grey by luminance, 0.299 R + 0.587 G + 0.114 B.
      EXPECT_NEAR(g[2], 0.299 * l[2] + 0.587 * l[1] + 0.114 * l[0], 1.0);
      EXPECT_NEAR(g[0], 0.299 * r[2] + 0.587 * r[1] + 0.114 * r[0], 1.0);
    }
  }
}

TEST(ImageCompose, PairsSideBySideAndInterleaved) {
  const cv::Mat left = Noise(3), right = Noise(4);
  const cv::Mat pair = SideBySide(left, right);
  ASSERT_EQ(pair.size(), cv::Size(10, 6));
  EXPECT_EQ(cv::norm(pair.colRange(0, 5), left, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(pair.colRange(5, 10), right, cv::NORM_INF), 0);
  const cv::Mat rows = RowInterleaved(left, right);
  ASSERT_EQ(rows.size(), left.size());
  for (int y = 0; y < rows.rows; ++y) {
    const cv::Mat& source = y % 2 == 0 ? left : right;
    EXPECT_EQ(cv::norm(rows.row(y), source.row(y), cv::NORM_INF), 0) << y;
  }
}

}  // namespace
}  // namespace bayon
