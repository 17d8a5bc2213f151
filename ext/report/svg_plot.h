// SPDX-License-Identifier: BSD-3-Clause
//
// Small charts as standalone SVG elements (<svg ...>...</svg>, well-formed
// XML, no scripts, no external fonts or ids), for reports that must open
// from the file system: histograms, bar charts (stacked, vertical or
// horizontal), a plan view of camera stations with their viewing directions
// over a point cloud, and an image frame with points and vectors in pixel
// coordinates. Axes carry "nice" ticks (1, 2 or 5 times a power of ten).
//
// Sizes are SVG user units (CSS pixels); the elements carry a viewBox, so a
// page may scale them. Colours are CSS colour strings.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

// The frame every chart shares.
struct ChartOptions {
  int width_px = 480;
  int height_px = 280;
  std::string title;    // above the plot
  std::string x_label;  // below the x axis
  std::string y_label;  // beside the y axis (rotated)
  std::string note;     // small text in the plot's upper right corner
};

// Points drawn as dots of one colour.
struct PointSeries {
  std::string name;  // legend entry; empty: none
  std::vector<Eigen::Vector2d> points;
  std::string color = "#888888";
  double radius_px = 1.2;
  double opacity = 1.0;
};

// Tick positions covering [lo, hi]: multiples of 1, 2 or 5 times a power of
// ten, about `target` of them, the first <= lo and the last >= hi.
std::vector<double> NiceTicks(double lo, double hi, int target);

// A number as a tick label with as many decimals as `step` needs.
std::string TickLabel(double value, double step);

struct HistogramOptions {
  ChartOptions chart;
  int num_bins = 40;
  // The range of the bins; min >= max: from the values (their 0.5 and 99.5
  // percentiles, so that a few blunders do not squeeze the rest into one
  // bin). Values outside are counted in the note, not drawn.
  double min = 0;
  double max = 0;
  // The automatic range symmetric about zero (residuals).
  bool symmetric = false;
  // Overlays the normal density with the values' mean and standard
  // deviation (scaled to counts per bin).
  bool show_normal = false;
  std::string color = "#4c78a8";
};

std::string SvgHistogram(const std::vector<double>& values,
                         const HistogramOptions& options);

// One bar: a value per series (stacked in series order).
struct Bar {
  std::string label;
  std::vector<double> values;
  std::string color;    // overrides the series colour (one series only)
  std::string tooltip;  // <title> of the bar; empty: label and value
};

struct BarSeries {
  std::string name;  // legend entry (shown when there are two or more)
  std::string color = "#4c78a8";
};

struct BarChartOptions {
  ChartOptions chart;
  // Horizontal bars with the labels on the left (long labels, few bars);
  // vertical bars with the labels below, rotated when they do not fit.
  // Horizontal charts with chart.height_px <= 0 get 20 px per bar.
  bool horizontal = false;
  std::vector<BarSeries> series = {BarSeries()};
  // Writes each bar's total at its end with this many decimals; < 0: not.
  int value_decimals = -1;
  std::string value_unit;  // appended to the written totals
};

std::string SvgBarChart(const std::vector<Bar>& bars,
                        const BarChartOptions& options);

// A camera station in a view: its centre, its unit viewing direction
// projected into the view's plane (length <= 1: a camera looking across the
// view gets a shorter arrow), and its name.
struct ViewCamera {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  Eigen::Vector2d direction = Eigen::Vector2d::Zero();
  std::string label;
};

struct StationViewOptions {
  ChartOptions chart;
  // Length of an unforeshortened viewing direction arrow as a fraction of
  // the drawing's extent.
  double arrow_fraction = 0.08;
  // The drawing covers every camera and the points between these per-axis
  // quantiles (0.01: the 1st and 99th percentiles), so that a few stray
  // points do not shrink the rest; points outside are left out and counted
  // in the note.
  double point_quantile = 0.01;
  // Labels only every k-th camera when there are more than this many; 0:
  // no labels.
  int max_labels = 40;
  std::string camera_color = "#d62728";
};

// Equal scale in both axes, x to the right and y up; chart.height_px <= 0
// fits the height to the drawing (200 px to chart.width_px). The points are
// drawn first (grey), then the cameras: a dot, an arrow along the viewing
// direction and the name, placed away from the cameras' centroid.
std::string SvgStationView(const PointSeries& points,
                           const std::vector<ViewCamera>& cameras,
                           const StationViewOptions& options);

// A vector from `from` to `to`, in the frame's pixel coordinates.
struct FrameArrow {
  Eigen::Vector2d from = Eigen::Vector2d::Zero();
  Eigen::Vector2d to = Eigen::Vector2d::Zero();
};

struct ImageFrameOptions {
  int width_px = 160;  // the height follows the image's aspect ratio
  std::string title;   // above the frame (the image's name)
  std::string note;    // below the frame (e.g. the number of points)
  std::string arrow_color = "#d62728";
};

// An image frame of `image_size` pixels (x right, y down, as image
// coordinates), with the series' points and the arrows drawn inside it.
std::string SvgImageFrame(const Eigen::Vector2d& image_size,
                          const std::vector<PointSeries>& series,
                          const std::vector<FrameArrow>& arrows,
                          const ImageFrameOptions& options);

}  // namespace bayon
