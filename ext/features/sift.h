// SPDX-License-Identifier: BSD-3-Clause
//
// SIFT keypoints and descriptors (Lowe 2004, "Distinctive image features
// from scale-invariant keypoints", IJCV), by OpenCV's implementation, in the
// form COLMAP stores and matches them.
//
// Why beside Moravec: the paper's points are matched by correlation of
// small upright windows, which holds while neighbouring photographs differ
// by little. Across wide baselines, in-plane rotations other than quarter
// turns, changes of scale and changes of light, a correlation window no
// longer looks like its conjugate; SIFT's descriptors (gradient histograms
// over a scale- and rotation-normalised support) still do.
//
// Conventions, as colmap-interop.md 1.3 states them:
// - positions in COLMAP pixel coordinates (pixel centres at +0.5) of the
//   full image, also when the image was reduced for detection;
// - scale in full-image pixels (the keypoint's Gaussian sigma) and
//   orientation in radians, stored in COLMAP's affine form;
// - descriptors L1-root normalised (RootSIFT, Arandjelovic and Zisserman
//   2012: unit L2 norm), times 512, rounded and clamped to 0..255, so that
//   COLMAP's matchers read them as they read their own.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/option_registry.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace bayon {

struct SiftOptions {
  // At most this many keypoints per image, the strongest (COLMAP's 8192).
  int max_num_features = 8192;
  // Scale levels per octave of the difference-of-Gaussians pyramid.
  int num_octave_layers = 3;
  // Smallest DoG extremum kept, in OpenCV's units: 0.04 is a contrast of
  // 0.5 * 0.04 / num_octave_layers = 0.0067 on the 0..1 grey scale, which is
  // COLMAP's peak_threshold.
  double contrast_threshold = 0.04;
  // Extrema whose principal curvatures differ by more than this ratio lie
  // on edges and are dropped (Lowe's r = 10).
  double edge_threshold = 10;
  // Images whose long side exceeds this are reduced before detection, as
  // COLMAP's max_image_size; 0 = never.
  int max_image_size = 3200;
  // The fields `bayon features` offers.
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

struct SiftFeatures {
  // COLMAP keypoints, N x 6: x, y and the affine shape
  // (s cos a, -s sin a, s sin a, s cos a) of scale s and orientation a.
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;  // N x 128, RootSIFT as uint8
  std::vector<float> response;     // |DoG| at the extremum
};

// Keypoints and descriptors of a grey image (CV_32F on the 0..255 scale, as
// ReadImageGrayFloat gives it), the strongest first.
SiftFeatures DetectSiftFeatures(const cv::Mat& gray,
                                const SiftOptions& options);

// SIFT descriptors of given points (COLMAP pixel coordinates), upright and
// at the pyramid's base scale (sigma 1.6 px): for points found by another
// operator, so that every keypoint of an image has a descriptor row, as
// COLMAP's matchers need.
FeatureDescriptors ComputeUprightSiftDescriptors(
    const cv::Mat& gray,
    const std::vector<Eigen::Vector2d>& xy,
    const SiftOptions& options);

}  // namespace bayon
