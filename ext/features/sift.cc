// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/sift.h"

#include "ext/core/errors.h"

#include <glog/logging.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace bayon {

void SiftOptions::Register(OptionRegistry* r) {
  r->Add("max_num_features",
         &max_num_features,
         "At most this many keypoints per image, the strongest");
  r->Add("contrast_threshold",
         &contrast_threshold,
         "Smallest DoG contrast kept (OpenCV's units)");
  r->Add("edge_threshold",
         &edge_threshold,
         "Largest ratio of principal curvatures kept");
  r->Add("max_image_size",
         &max_image_size,
         "Longer images are reduced to this first (0 = never)");
}

void SiftOptions::Check() const {
  CheckOption(
      max_num_features >= 1, "max_num_features", ">= 1", max_num_features);
  CheckOption(num_octave_layers >= 1 && num_octave_layers <= 8,
              "num_octave_layers",
              "in [1, 8]",
              num_octave_layers);
  CheckOption(contrast_threshold > 0 && contrast_threshold < 1,
              "contrast_threshold",
              "in (0, 1)",
              contrast_threshold);
  CheckOption(edge_threshold >= 1, "edge_threshold", ">= 1", edge_threshold);
  CheckOption(max_image_size == 0 || max_image_size >= 64,
              "max_image_size",
              "0 (never reduce) or >= 64",
              max_image_size);
}

namespace {

// OpenCV's SIFT works on 8-bit images (its float path expects 0..1).
struct DetectionImage {
  cv::Mat gray8;
  double factor = 1;  // full-image pixels per detection pixel
};

DetectionImage MakeDetectionImage(const cv::Mat& gray,
                                  const SiftOptions& options) {
  DetectionImage image;
  const int long_side = std::max(gray.cols, gray.rows);
  cv::Mat reduced = gray;
  if (options.max_image_size > 0 && long_side > options.max_image_size) {
    image.factor = static_cast<double>(long_side) / options.max_image_size;
    cv::resize(
        gray,
        reduced,
        cv::Size(static_cast<int>(std::lround(gray.cols / image.factor)),
                 static_cast<int>(std::lround(gray.rows / image.factor))),
        0,
        0,
        cv::INTER_AREA);
    image.factor = static_cast<double>(gray.cols) / reduced.cols;
  }
  reduced.convertTo(image.gray8, CV_8U);
  return image;
}

cv::Ptr<cv::SIFT> MakeSift(const SiftOptions& options, int max_num_features) {
  return cv::SIFT::create(max_num_features,
                          options.num_octave_layers,
                          options.contrast_threshold,
                          options.edge_threshold);
}

// OpenCV's descriptors (unit L2 norm after clipping, times 512) to
// RootSIFT as uint8: L1-normalise, square root (unit L2 norm), times 512.
FeatureDescriptors RootSiftBytes(const cv::Mat& descriptors) {
  FeatureDescriptors bytes(descriptors.rows, 128);
  for (int i = 0; i < descriptors.rows; ++i) {
    const float* row = descriptors.ptr<float>(i);
    double l1 = 0;
    for (int k = 0; k < 128; ++k) l1 += std::abs(row[k]);
    for (int k = 0; k < 128; ++k) {
      const double root = l1 > 0 ? std::sqrt(std::abs(row[k]) / l1) : 0.0;
      bytes(i, k) =
          static_cast<uint8_t>(std::min(255.0, std::round(512.0 * root)));
    }
  }
  return bytes;
}

}  // namespace

SiftFeatures DetectSiftFeatures(const cv::Mat& gray,
                                const SiftOptions& options) {
  options.Check();
  const DetectionImage image = MakeDetectionImage(gray, options);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  MakeSift(options, options.max_num_features)
      ->detectAndCompute(image.gray8, cv::noArray(), keypoints, descriptors);
  // OpenCV may return one point with several orientations as several rows;
  // strongest first, then by position so that the order is reproducible.
  std::vector<int> order(keypoints.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return keypoints[a].response > keypoints[b].response;
  });
  if (static_cast<int>(order.size()) > options.max_num_features) {
    order.resize(options.max_num_features);
  }

  SiftFeatures features;
  features.keypoints.resize(order.size(), 6);
  cv::Mat kept(static_cast<int>(order.size()), 128, CV_32F);
  for (size_t r = 0; r < order.size(); ++r) {
    const cv::KeyPoint& point = keypoints[order[r]];
    // OpenCV's pixel centres are whole numbers; COLMAP's are at +0.5.
    const double x = (point.pt.x + 0.5) * image.factor;
    const double y = (point.pt.y + 0.5) * image.factor;
    const double scale = 0.5 * point.size * image.factor;
    const double angle = point.angle * M_PI / 180.0;
    features.keypoints.row(r) << static_cast<float>(x), static_cast<float>(y),
        static_cast<float>(scale * std::cos(angle)),
        static_cast<float>(-scale * std::sin(angle)),
        static_cast<float>(scale * std::sin(angle)),
        static_cast<float>(scale * std::cos(angle));
    features.response.push_back(point.response);
    descriptors.row(order[r]).copyTo(kept.row(static_cast<int>(r)));
  }
  features.descriptors = RootSiftBytes(kept);
  return features;
}

FeatureDescriptors ComputeUprightSiftDescriptors(
    const cv::Mat& gray,
    const std::vector<Eigen::Vector2d>& xy,
    const SiftOptions& options) {
  options.Check();
  const DetectionImage image = MakeDetectionImage(gray, options);
  // Octave 0, layer 0 (the packed octave field 0): the base level of the
  // pyramid, blurred to sigma 1.6; OpenCV's size is twice the sigma.
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(xy.size());
  for (const Eigen::Vector2d& p : xy) {
    keypoints.emplace_back(static_cast<float>(p.x() / image.factor - 0.5),
                           static_cast<float>(p.y() / image.factor - 0.5),
                           3.2f,
                           0.f);
  }
  const size_t num_points = keypoints.size();
  cv::Mat descriptors;
  MakeSift(options, 0)
      ->detectAndCompute(image.gray8,
                         cv::noArray(),
                         keypoints,
                         descriptors,
                         /*useProvidedKeypoints=*/true);
  CHECK_EQ(keypoints.size(), num_points);
  return RootSiftBytes(descriptors);
}

}  // namespace bayon
