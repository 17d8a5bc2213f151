// SPDX-License-Identifier: BSD-3-Clause
//
// The Moravec interest operator with grid thinning: the paper's step
// 3.2.1(a) (feature points for relative orientation) and 3.3(2) (dense
// points in the master images).
//
// Interest value (Moravec 1977, "Towards automatic visual obstacle
// avoidance", IJCAI): at pixel p, for each of the four directions
// d in {(1,0), (0,1), (1,1), (1,-1)}, the mean of (g(q + d) - g(q))^2 over the
// w x w window centred at p; the interest is the smallest of the four. It is
// large only where the grey values change in every direction (corners,
// blobs, texture), not along straight edges. Units: squared grey values on
// the 0..255 scale, whatever the image's bit depth (ReadImageGrayFloat).
//
// Grid thinning: the image is divided into square patches and only the
// strongest point of each patch is kept (if it passes the threshold and is
// also the maximum of its own w x w neighbourhood, so that two patches never
// keep the two sides of one corner), so that points spread evenly over the
// image instead of crowding into its most textured part.
//
// Positions are COLMAP pixel coordinates: the centre of pixel (col, row) is
// (col + 0.5, row + 0.5), whole pixels only. The operator finds a step
// corner within about half a window of it (its forward differences and
// window make it lean into the brighter side); that bias is the same in
// every image of the same orientation, and the matching stage refines the
// conjugate point to sub-pixel precision against the reference point anyway.
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace bayon {

struct MoravecOptions {
  // Side of the window over which the directional variances are averaged,
  // pixels, odd. Larger windows suppress noise but blur nearby corners.
  int window_size = 5;
  // Side of the thinning patches, pixels; one point per patch at most.
  // 0: chosen so that about max_num_features patches cover the image.
  int patch_size = 0;
  // Smallest interest value kept (mean squared grey-value difference in the
  // weakest direction, 0..255 scale). 4 = an RMS difference of 2 grey
  // levels, just above the noise of an 8-bit image.
  double min_interest = 4.0;
  // At most this many points per image, the strongest; 0 = no limit (then
  // patch_size must be given).
  int max_num_features = 4000;
  // Points closer than this to the image border are dropped, pixels: room
  // for the correlation windows of the matching stage.
  int border_px = 8;
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

struct InterestPoint {
  Eigen::Vector2f xy;  // COLMAP pixel coordinates (pixel centres at +0.5)
  float interest = 0;
};

// The Moravec interest image: CV_32F, same size as `gray` (one channel,
// CV_32F, 0..255). Pixels whose window leaves the image are 0.
cv::Mat MoravecInterest(const cv::Mat& gray, int window_size);

// The patch side that `options` implies for an image of this size.
int ThinningPatchSize(const MoravecOptions& options, int width, int height);

// Interest points of one grey image, thinned, strongest first.
std::vector<InterestPoint> DetectMoravecPoints(const cv::Mat& gray,
                                               const MoravecOptions& options);

}  // namespace bayon
