// SPDX-License-Identifier: BSD-3-Clause
//
// Coded targets: square markers whose black-and-white cells spell a code
// that names them (ArUco, Garrido-Jurado et al. 2014; AprilTag 36h11, Olson
// 2011). OpenCV's aruco module finds and decodes them (its corners
// unrefined); bayon then measures each to a photogrammetric precision, with
// a covariance.
//
// The measurement. A marker's outer edge, the step from its white margin
// to its black border, is four straight lines in the photograph. Each side
// is measured at points about a pixel apart along it, from the corners that
// OpenCV gives: at each, the position across the side where the grey value
// falls from white to black (the centroid of the top of the directional
// derivative's slope, sampled a quarter pixel apart). A straight line is
// fitted to each side's points by least squares. The corners are where
// neighbouring lines meet, and the target's point is where the diagonals meet:
// the image of the marker's centre under any perspective (a plane's projection
// keeps lines and their incidences, not midpoints). Its covariance follows from
// the lines' by propagation (each line's offset and angle, from the scatter of
// its points about it).
//
// A side whose points do not lie on a line (sigma above max_line_sigma_px:
// an occluder, a curled sheet, a marker at the frame) is no measurement,
// and the target is left out, counted in the report; so is a decoding that
// shows no such edges (OpenCV's error correction reads codes into masonry
// now and then).
//
// Measured (targets_coded_targets_test, 40 markers of 24 to 60 px tilted
// up to 60 degrees, noise 2 grey values): centres within 0.013 px RMS of
// the truth, where the diagonals of OpenCV's own sub-pixel corners give
// 0.097 px.
//
// Coordinates are COLMAP's: the centre of the upper-left pixel is
// (0.5, 0.5).
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <string>
#include <vector>

namespace bayon {

struct CodedTargetOptions {
  // aruco_4x4_50, aruco_5x5_100, aruco_6x6_250 or apriltag_36h11.
  std::string dictionary = "aruco_4x4_50";
  // A target's name is this prefix and its code number: CT0, CT1, ...
  // (bayon synth names its disc targets T01, T02, ...).
  std::string name_prefix = "CT";
  // Markers whose sides are shorter are not looked for, pixels.
  int min_side_px = 16;
  // How far across a side its edge is looked for, either way, pixels (at
  // most a cell of the marker).
  double edge_search_px = 3;
  // A side whose points scatter more about their line is no measurement.
  double max_line_sigma_px = 0.5;
  // The standard deviation of a side's line that its points' scatter does
  // not show, pixels: the edge locator's own error (the pixel grid's phase,
  // the tails of the edges a cell away), shared by the points of a side,
  // so it does not average down along it. Added in quadrature to each
  // line's offset. 0.04 px: on the rendered tower the centres are 0.038 px
  // (radial RMS) from the truth at 3 x 3 samples per pixel and 0.056 px at
  // 8 x 8, where the scatter alone states about 0.01 px.
  double edge_bias_px = 0.04;
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

struct CodedTarget {
  int code = -1;
  std::string name;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  // pixels^2
  // The outer corners, in the marker's order (its upper left first, then
  // clockwise as printed).
  std::array<Eigen::Vector2d, 4> corners;
  // The scatter of each side's edge points about its line, pixels.
  std::array<double, 4> line_sigma_px{};
};

struct CodedTargetReport {
  int num_decoded = 0;               // markers OpenCV found and decoded
  int num_measured = 0;              // of those, measured here
  std::vector<std::string> refused;  // why the others were not, one line each
};

// The dictionary's number of codes and cells per side (the code without
// its border); InputError listing the choices for an unknown name.
int CodedTargetDictionarySize(const std::string& dictionary);
int CodedTargetCells(const std::string& dictionary);

// The targets in a photograph (8-bit, one or three channels). A code seen
// twice is an InputError naming `what` (the photograph): two targets may
// not share a name.
std::vector<CodedTarget> DetectCodedTargets(const cv::Mat& image,
                                            const CodedTargetOptions& options,
                                            const std::string& what,
                                            CodedTargetReport* report);

// "0-11", "3,5,8" or both mixed ("0-3,9"): the codes of a sheet;
// InputError naming the item that is neither a code nor a range a-b.
std::vector<int> ParseCodedTargetCodes(const std::string& text);

// The marker of `code` as printed: (cells + 2) x (cells + 2) values, 0 for
// black and 255 for white, the black border included.
cv::Mat CodedTargetPattern(const std::string& dictionary, int code);

// A printable sheet (SVG, A4 portrait, sizes in millimetres) of the given
// codes, each marker side_mm wide with a white margin of one cell and its
// name below; written atomically. InputError where a code is not in the
// dictionary or the markers do not fit on the page.
void WriteCodedTargetSheet(const CodedTargetOptions& options,
                           const std::vector<int>& codes,
                           double side_mm,
                           const std::string& path);

}  // namespace bayon
