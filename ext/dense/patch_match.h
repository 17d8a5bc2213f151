// SPDX-License-Identifier: BSD-3-Clause
//
// A depth and a normal for every pixel of a master image, by propagating
// plane hypotheses between neighbouring pixels (PatchMatch stereo: Bleyer,
// Rhemann and Rother 2011; Galliani, Lasinger and Schindler 2015, whose
// red-black sweep this follows; Schönberger et al. 2016).
//
// The images are first resampled into pinhole cameras at a working scale
// (PinholeView): distortion and the image frame removed, so that a plane
// maps between two images by a homography. Every pixel starts from a random
// plane in the master's depth range (and, where a sparse point lies, from
// that point's depth), or from the plane found at the coarser level where
// that matches better (num_levels: the same done first at half the size,
// recursively). Then, in alternate half-sweeps over the pixels of a
// checkerboard's two colours, each pixel takes the best of
//   - the planes of eight neighbours of the other colour (at one and at
//     five pixels along the rows and columns; of those the best-matched
//     num_propagation_candidates), and
//   - perturbations of its own plane (depth and normal, shrinking with each
//     iteration).
// A plane is scored by normalised cross-correlation of the master's window
// (every window_step-th pixel within window_radius) with its homographic
// image in each source view; the score is the mean of 1 - NCC over the
// best `best_views` views, so that a view in which the point is hidden or
// lit otherwise does not decide. The pixels of one colour are independent,
// so each half-sweep runs in parallel over rows; random numbers come from
// the pixel and the iteration, so the result does not depend on the threads.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/option_registry.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace bayon {

// One image resampled into a pinhole camera: K = [f 0 cx; 0 f cy; 0 0 1]
// in the working pixels (pixel (i, j) covers [i, i+1) x [j, j+1)).
struct PinholeView {
  cv::Mat gray;   // CV_32F
  cv::Mat color;  // CV_8UC3 (BGR) or empty
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Rigid3d cam_from_world;
  int width() const { return gray.cols; }
  int height() const { return gray.rows; }
};

// Resamples `gray` (and `color`, if not empty) of an image with `camera`
// (and `frame`) into a pinhole camera `downscale` times smaller: the focal
// length is the camera's mean, the principal point the camera's, divided by
// `downscale`.
PinholeView MakePinholeView(const Camera& camera,
                            const ImageFrame* frame,
                            const Rigid3d& cam_from_world,
                            const cv::Mat& gray,
                            const cv::Mat& color,
                            int downscale);

struct PatchMatchOptions {
  // The correlation window: every window_step-th pixel within
  // window_radius of the centre, working pixels.
  int window_radius = 4;
  int window_step = 2;
  // Red-black iterations (each: both colours once), at every level.
  int num_iterations = 4;
  // Coarse to fine: levels of halved size (1: the working size alone);
  // each level's planes start the next finer one.
  int num_levels = 2;
  // Of the eight neighbours' planes, those of the best-matched this many
  // are scored at a pixel (ranked by their cost at their own pixels).
  int num_propagation_candidates = 4;
  // The score is the mean cost (1 - NCC) of the best this many views.
  int best_views = 2;
  // Master windows with a smaller standard deviation of their grey values
  // are not matched (no texture).
  double min_texture = 1.0;
  // Random normals lie within this angle of the master ray.
  double max_normal_angle_deg = 70;
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

// A master's depth map: per working pixel the depth (z in the master's
// camera; 0 where none), the normal (master camera frame, facing it) and
// the cost (1 - NCC over the best views, 0..2; 2 where none).
struct DepthMap {
  int width = 0, height = 0;
  std::vector<float> depth;
  std::vector<Eigen::Vector3f> normal;
  std::vector<float> cost;
  size_t index(int x, int y) const {
    return static_cast<size_t>(y) * width + x;
  }
};

// Sparse points to start from: the object point, seen in the master.
struct DepthSeed {
  Eigen::Vector2d xy;  // working pixels
  double depth = 0;
};

// The depth map of `master` against `sources` (at most 32), with depths in
// [min_depth, max_depth].
DepthMap EstimateDepthMap(const PinholeView& master,
                          const std::vector<const PinholeView*>& sources,
                          double min_depth,
                          double max_depth,
                          const std::vector<DepthSeed>& seeds,
                          const PatchMatchOptions& options,
                          int num_threads);

// The cost (1 - NCC) of the plane with `depth` and `normal` (master camera
// frame) at pixel (x, y) of `master` in each source: 2 where the window
// leaves the source or the plane is seen edge-on; NaN for a flat master
// window. For tests and diagnostics.
std::vector<float> PlaneCosts(const PinholeView& master,
                              const std::vector<const PinholeView*>& sources,
                              int x,
                              int y,
                              float depth,
                              const Eigen::Vector3f& normal,
                              const PatchMatchOptions& options);

}  // namespace bayon
