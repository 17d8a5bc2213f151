// SPDX-License-Identifier: BSD-3-Clause
//
// Two-dimensional steps of `bayon render`: the 8-bit tone curve, hidden-line
// wireframes from a triangle-id buffer, and stereo pairs composed for
// red-cyan glasses, side-by-side viewers and row-interleaved (polarised)
// displays. Images are OpenCV BGR.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace bayon {

// CV_32FC3 colours (1 = white) to CV_8UC3: clamped to [0, 1], rounded.
cv::Mat ToneMap8(const cv::Mat& color);

// Hidden-line wireframe of a triangle-id buffer (CV_32S, -1 = background)
// rendered at `scale` times the output size: a pixel lies on a line where
// its triangle differs from its right or lower neighbour's, i.e. on a
// visible edge or the silhouette; lines are widened to `line_width` fine
// pixels (1 to scale) and box-filtered down by `scale`, so they come out
// line_width / scale output pixels wide and anti-aliased. Returns the line
// coverage, CV_32F in [0, 1], at the output size.
cv::Mat WireframeCoverage(const cv::Mat& triangle_id,
                          int scale,
                          int line_width);

// The line width (in pixels of the fine buffer, 1 to scale) that keeps a
// wireframe legible: one output pixel where the visible triangles' edges
// are at least 6 output pixels long, thinner in proportion where the mesh
// is denser on screen, so that dense meshes show grey tones instead of a
// black patch. Edge length from the mean visible triangle area A in output
// pixels, as for an equilateral triangle: sqrt(4 A / sqrt(3)).
int WireframeLineWidth(const cv::Mat& triangle_id, int scale);

// `background` (CV_32FC3, or an empty Mat for white) with lines of colour
// `line_bgr` painted at `coverage`.
cv::Mat PaintLines(const cv::Mat& coverage,
                   const cv::Mat& background,
                   const Eigen::Vector3f& line_bgr);

enum class AnaglyphType {
  kColor,  // red from the left image's red, green and blue from the right's
  kGray,   // red from the left image's grey, green and blue the right's grey
};

// Red-cyan anaglyph (red filter over the left eye) of two CV_8UC3 images of
// the same size.
cv::Mat Anaglyph(const cv::Mat& left, const cv::Mat& right, AnaglyphType type);

// Left image beside the right one (twice the width).
cv::Mat SideBySide(const cv::Mat& left, const cv::Mat& right);

// Rows 0, 2, 4, ... from the left image, rows 1, 3, ... from the right.
cv::Mat RowInterleaved(const cv::Mat& left, const cv::Mat& right);

}  // namespace bayon
