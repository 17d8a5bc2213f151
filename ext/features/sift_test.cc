// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/sift.h"

#include "ext/core/errors.h"
#include "ext/matching/descriptor_matcher.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace bayon {
namespace {

// Blobs of many sizes and contrasts on a smooth background: structure at
// every scale, as SIFT needs.
cv::Mat Blobs(int width, int height, unsigned seed) {
  cv::Mat image(height, width, CV_32F, cv::Scalar(128));
  cv::RNG rng(seed);
  for (int k = 0; k < 400; ++k) {
    const cv::Point center(rng.uniform(0, width), rng.uniform(0, height));
    const int radius = rng.uniform(2, 14);
    cv::ellipse(image,
                center,
                cv::Size(radius, rng.uniform(2, 14)),
                rng.uniform(0.0, 180.0),
                0,
                360,
                cv::Scalar(rng.uniform(0.0, 255.0)),
                cv::FILLED,
                cv::LINE_AA);
  }
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.0);
  return image;
}

// COLMAP pixel coordinates through a 2 x 3 affine map of OpenCV's pixel
// coordinates (whole numbers at pixel centres).
Eigen::Vector2d Warp(const cv::Mat& affine, const Eigen::Vector2d& xy) {
  const double x = xy.x() - 0.5, y = xy.y() - 0.5;
  return Eigen::Vector2d(
      affine.at<double>(0, 0) * x + affine.at<double>(0, 1) * y +
          affine.at<double>(0, 2) + 0.5,
      affine.at<double>(1, 0) * x + affine.at<double>(1, 1) * y +
          affine.at<double>(1, 2) + 0.5);
}

TEST(Sift, FindsAndMatchesTheSamePointsUnderRotationAndScale) {
  const cv::Mat image1 = Blobs(480, 360, 3);
  // Turned by 35 deg and reduced to 0.7 about the centre.
  const cv::Mat affine =
      cv::getRotationMatrix2D(cv::Point2f(240, 180), 35.0, 0.7);
  cv::Mat image2;
  cv::warpAffine(image1,
                 image2,
                 affine,
                 image1.size(),
                 cv::INTER_LINEAR,
                 cv::BORDER_CONSTANT,
                 cv::Scalar(128));
  const SiftOptions options;
  const SiftFeatures features1 = DetectSiftFeatures(image1, options);
  const SiftFeatures features2 = DetectSiftFeatures(image2, options);
  ASSERT_GT(features1.keypoints.rows(), 200);
  ASSERT_EQ(features1.keypoints.cols(), 6);
  ASSERT_EQ(features1.descriptors.rows(), features1.keypoints.rows());
  ASSERT_EQ(features1.descriptors.cols(), 128);
  // Strongest first.
  EXPECT_TRUE(
      std::is_sorted(features1.response.rbegin(), features1.response.rend()));
  // RootSIFT as COLMAP stores it: unit L2 norm times 512.
  for (int i = 0; i < features1.descriptors.rows(); i += 17) {
    const double norm = features1.descriptors.row(i).cast<double>().norm();
    EXPECT_NEAR(norm, 512, 4) << "row " << i;
  }

  const std::vector<DescriptorMatch> matches =
      MatchDescriptors(ToUnitDescriptors(features1.descriptors),
                       ToUnitDescriptors(features2.descriptors),
                       DescriptorMatchingOptions());
  ASSERT_GT(matches.size(), 100u);
  int num_correct = 0;
  std::vector<double> scale_ratios;
  for (const DescriptorMatch& match : matches) {
    const Eigen::Vector2d predicted =
        Warp(affine, KeypointXY(features1.keypoints, match.idx1));
    if ((predicted - KeypointXY(features2.keypoints, match.idx2)).norm() <
        1.5) {
      ++num_correct;
      scale_ratios.push_back(KeypointScale(features2.keypoints, match.idx2) /
                             KeypointScale(features1.keypoints, match.idx1));
    }
  }
  EXPECT_GT(num_correct, 0.95 * matches.size())
      << num_correct << " of " << matches.size();
  // The keypoints' scales follow the image's.
  std::nth_element(scale_ratios.begin(),
                   scale_ratios.begin() + scale_ratios.size() / 2,
                   scale_ratios.end());
  EXPECT_NEAR(scale_ratios[scale_ratios.size() / 2], 0.7, 0.05);
}

TEST(Sift, ReducedImagesGiveFullImageCoordinates) {
  const cv::Mat image = Blobs(600, 400, 5);
  cv::Mat half;
  cv::resize(image, half, cv::Size(300, 200), 0, 0, cv::INTER_AREA);
  SiftOptions options;
  options.max_image_size = 300;
  const SiftFeatures reduced = DetectSiftFeatures(image, options);
  options.max_image_size = 0;
  const SiftFeatures direct = DetectSiftFeatures(half, options);
  ASSERT_GT(direct.keypoints.rows(), 50);
  ASSERT_EQ(reduced.keypoints.rows(), direct.keypoints.rows());
  for (int i = 0; i < direct.keypoints.rows(); ++i) {
    EXPECT_NEAR(reduced.keypoints(i, 0), 2 * direct.keypoints(i, 0), 1e-3);
    EXPECT_NEAR(reduced.keypoints(i, 1), 2 * direct.keypoints(i, 1), 1e-3);
    EXPECT_NEAR(KeypointScale(reduced.keypoints, i),
                2 * KeypointScale(direct.keypoints, i),
                1e-3);
  }
  EXPECT_EQ(reduced.descriptors, direct.descriptors);
}

TEST(Sift, UprightDescriptorsOfGivenPointsFollowTheImage) {
  const cv::Mat image1 = Blobs(300, 240, 9);
  // Shifted by whole pixels: the same windows at other coordinates.
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 7, 0, 1, -5);
  cv::Mat image2;
  cv::warpAffine(image1, image2, shift, image1.size());
  std::vector<Eigen::Vector2d> xy1, xy2;
  for (int y = 40; y < 200; y += 20) {
    for (int x = 40; x < 260; x += 20) {
      xy1.emplace_back(x + 0.5, y + 0.5);
      xy2.emplace_back(x + 7.5, y - 4.5);
    }
  }
  const SiftOptions options;
  const FeatureDescriptors d1 =
      ComputeUprightSiftDescriptors(image1, xy1, options);
  const FeatureDescriptors d2 =
      ComputeUprightSiftDescriptors(image2, xy2, options);
  ASSERT_EQ(d1.rows(), static_cast<int>(xy1.size()));
  const std::vector<DescriptorMatch> matches =
      MatchDescriptors(ToUnitDescriptors(d1),
                       ToUnitDescriptors(d2),
                       DescriptorMatchingOptions());
  int num_right = 0;
  for (const DescriptorMatch& match : matches) {
    num_right += match.idx1 == match.idx2;
  }
  EXPECT_GT(num_right, 0.9 * xy1.size());
  EXPECT_EQ(num_right, static_cast<int>(matches.size()));
}

TEST(Sift, RefusesBadOptions) {
  SiftOptions options;
  options.max_num_features = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = SiftOptions();
  options.contrast_threshold = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = SiftOptions();
  options.max_image_size = 10;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
