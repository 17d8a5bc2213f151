// SPDX-License-Identifier: BSD-3-Clause
//
// Image pyramids for coarse-to-fine matching. Level 0 is the image itself;
// level l + 1 is level l smoothed by the binomial filter [1 3 3 1] / 8 in x
// and y and decimated by two, so that pixel c of level l + 1 is centred
// between pixels 2c and 2c + 1 of level l. In COLMAP pixel coordinates
// (pixel centres at +0.5) this makes the levels nest exactly:
//
//   xy_level = xy_full / 2^level
//
// (OpenCV's pyrDown centres level-(l + 1) pixels on even pixels and would
// shift the coordinates by half a pixel.)
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace bayon {

struct ImagePyramid {
  std::vector<cv::Mat> levels;  // CV_32F, one channel; levels[0] full size

  int num_levels() const { return static_cast<int>(levels.size()); }
  static double Scale(int level) { return 1.0 / (1 << level); }
  static Eigen::Vector2d LevelFromFull(const Eigen::Vector2d& xy, int level) {
    return xy * Scale(level);
  }
  static Eigen::Vector2d FullFromLevel(const Eigen::Vector2d& xy, int level) {
    return xy / Scale(level);
  }
};

// Level 0 and up to num_levels - 1 reduced levels; stops early where a level
// would be smaller than `min_size` pixels on its short side.
ImagePyramid BuildImagePyramid(const cv::Mat& gray,
                               int num_levels,
                               int min_size = 16);

// One reduction step (the filter above); odd sizes lose their last column
// or row.
cv::Mat DownsampleByTwo(const cv::Mat& gray);

}  // namespace bayon
