// SPDX-License-Identifier: BSD-3-Clause
//
// The rectified stereo pairs with true disparity of ../shared/data/stereo-gt
// (Middlebury 2003 cones and teddy, quarter size; truth value = 4 x
// disparity, 0 unknown) for the tests that judge sub-pixel matching on them
// (lsm_stereo_test, dense's mpgc_stereo_test).
#pragma once

#include "ext/image/image_io.h"

#include <Eigen/Cholesky>
#include <opencv2/core.hpp>

#include <cmath>
#include <string>

#include "tests/testing.h"

namespace bayon {
namespace testing {

struct StereoPair {
  cv::Mat left, right;              // CV_32F grey
  cv::Mat left_truth, right_truth;  // CV_8U, 4 x disparity, 0 unknown
};

inline StereoPair ReadStereoPair(const std::string& scene) {
  const std::string dir = DataPath("stereo-gt/" + scene);
  StereoPair pair;
  pair.left = ReadImageGrayFloat(dir + "/im2.png");
  pair.right = ReadImageGrayFloat(dir + "/im6.png");
  pair.left_truth = ReadImage(dir + "/disp2.png", ImageReadMode::kGray);
  pair.right_truth = ReadImage(dir + "/disp6.png", ImageReadMode::kGray);
  return pair;
}

// The truth over the (2 radius + 1)^2 window around pixel (col, row) as a
// plane d = p0 + p1 u + p2 v: false where a value is unknown or the plane
// misses them by more than max_residual_px RMS (the window then sees more
// than one surface); else the plane's value at the point, free of the
// truth's quarter-pixel quantisation.
inline bool PlanarTruth(const cv::Mat& truth,
                        int col,
                        int row,
                        int radius,
                        double max_residual_px,
                        double* disparity) {
  if (col < radius || row < radius || col + radius >= truth.cols ||
      row + radius >= truth.rows) {
    return false;
  }
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double sum_sq = 0;
  int n = 0;
  for (int v = -radius; v <= radius; ++v) {
    for (int u = -radius; u <= radius; ++u) {
      const int value = truth.at<uint8_t>(row + v, col + u);
      if (value == 0) return false;
      const double d = value / 4.0;
      const Eigen::Vector3d a(1, u, v);
      normal += a * a.transpose();
      rhs += a * d;
      sum_sq += d * d;
      ++n;
    }
  }
  const Eigen::Vector3d plane = normal.ldlt().solve(rhs);
  const double residual_sq = std::max(0.0, sum_sq - rhs.dot(plane));
  if (std::sqrt(residual_sq / (n - 3)) > max_residual_px) return false;
  *disparity = plane[0];
  return true;
}

}  // namespace testing
}  // namespace bayon
