// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/virtual_fiducials.h"

#include "ext/core/errors.h"
#include "ext/core/robust_estimator.h"
#include "ext/core/statistics.h"

#include <Eigen/Dense>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>

namespace bayon {

void VirtualFiducialOptions::Register(OptionRegistry* r) {
  r->Add(
      "frame_width_mm", &frame_width_mm, "Nominal frame width (film gate), mm");
  r->Add("frame_height_mm", &frame_height_mm, "Nominal frame height, mm");
  r->Add("scan_resolution_um",
         &scan_resolution_um,
         "Scanner pixel size, um: fixes the scale (the frame size "
         "is then a check); 0: scale from the nominal frame size "
         "(affine)");
  r->Add("decode_srgb",
         &decode_srgb,
         "1: decode the sRGB curve before measuring; 0: values are "
         "linear");
  r->Add("search_fraction",
         &search_fraction,
         "How far into the scan each edge is searched (fraction of "
         "its width or height)");
  r->Add("min_contrast",
         &min_contrast,
         "Smallest step from the border to the photograph (linear "
         "intensity, 0..1)");
  r->Add("edge_half_width_px",
         &edge_half_width_px,
         "Half width of the edge window, pixels (covers the blur)");
  r->Add("min_edge_points",
         &min_edge_points,
         "Fewest points on an accepted edge line");
  r->Add("corner_margin_px",
         &corner_margin_px,
         "Edge points this close to a corner are left out, pixels");
  r->Add("max_rms_px",
         &max_rms_px,
         "Largest residual RMS of an accepted edge, pixels");
  r->Add("max_rotation_deg",
         &max_rotation_deg,
         "Largest rotation of the frame in the scan, degrees");
  r->Add("max_corner_angle_deviation_deg",
         &max_corner_angle_deviation_deg,
         "Largest deviation of a corner angle from 90 degrees");
  r->Add("max_pixel_aspect_deviation",
         &max_pixel_aspect_deviation,
         "Without a scan resolution: largest relative difference of "
         "the x and y pixel sizes");
  r->Add("max_frame_size_deviation_mm",
         &max_frame_size_deviation_mm,
         "With a scan resolution: largest difference of a measured "
         "side from the nominal frame size, mm");
}

void VirtualFiducialOptions::Check() const {
  CheckOption(frame_width_mm > 0,
              "VirtualFiducialOptions.frame_width_mm",
              "> 0",
              frame_width_mm);
  CheckOption(frame_height_mm > 0,
              "VirtualFiducialOptions.frame_height_mm",
              "> 0",
              frame_height_mm);
  CheckOption(scan_resolution_um >= 0,
              "VirtualFiducialOptions.scan_resolution_um",
              ">= 0 (0: unknown)",
              scan_resolution_um);
  CheckOption(clip_level > 0 && clip_level <= 1,
              "VirtualFiducialOptions.clip_level",
              "in (0, 1]",
              clip_level);
  CheckOption(search_fraction > 0 && search_fraction <= 0.5,
              "VirtualFiducialOptions.search_fraction",
              "in (0, 0.5]",
              search_fraction);
  CheckOption(min_border_px >= 1,
              "VirtualFiducialOptions.min_border_px",
              ">= 1",
              min_border_px);
  CheckOption(border_probe_px >= 1,
              "VirtualFiducialOptions.border_probe_px",
              ">= 1",
              border_probe_px);
  CheckOption(min_contrast > 0 && min_contrast < 1,
              "VirtualFiducialOptions.min_contrast",
              "in (0, 1)",
              min_contrast);
  CheckOption(noise_factor >= 0,
              "VirtualFiducialOptions.noise_factor",
              ">= 0",
              noise_factor);
  CheckOption(max_border_noise > 0,
              "VirtualFiducialOptions.max_border_noise",
              "> 0",
              max_border_noise);
  CheckOption(edge_half_width_px >= 1 && edge_half_width_px <= 10,
              "VirtualFiducialOptions.edge_half_width_px",
              "in [1, 10]",
              edge_half_width_px);
  CheckOption(num_samples >= 1,
              "VirtualFiducialOptions.num_samples",
              ">= 1",
              num_samples);
  CheckOption(outlier_threshold > 0,
              "VirtualFiducialOptions.outlier_threshold",
              "> 0",
              outlier_threshold);
  CheckOption(min_sigma_px > 0,
              "VirtualFiducialOptions.min_sigma_px",
              "> 0",
              min_sigma_px);
  CheckOption(corner_margin_px >= 0,
              "VirtualFiducialOptions.corner_margin_px",
              ">= 0",
              corner_margin_px);
  CheckOption(min_edge_points >= 3,
              "VirtualFiducialOptions.min_edge_points",
              ">= 3",
              min_edge_points);
  CheckOption(min_inlier_ratio > 0 && min_inlier_ratio <= 1,
              "VirtualFiducialOptions.min_inlier_ratio",
              "in (0, 1]",
              min_inlier_ratio);
  CheckOption(
      max_rms_px > 0, "VirtualFiducialOptions.max_rms_px", "> 0", max_rms_px);
  CheckOption(max_rotation_deg > 0 && max_rotation_deg < 45,
              "VirtualFiducialOptions.max_rotation_deg",
              "in (0, 45)",
              max_rotation_deg);
  CheckOption(max_corner_angle_deviation_deg > 0,
              "VirtualFiducialOptions.max_corner_angle_deviation_deg",
              "> 0",
              max_corner_angle_deviation_deg);
  CheckOption(max_corner_residual_px > 0,
              "VirtualFiducialOptions.max_corner_residual_px",
              "> 0",
              max_corner_residual_px);
  CheckOption(max_pixel_aspect_deviation > 0,
              "VirtualFiducialOptions.max_pixel_aspect_deviation",
              "> 0",
              max_pixel_aspect_deviation);
  CheckOption(max_frame_size_deviation_mm > 0,
              "VirtualFiducialOptions.max_frame_size_deviation_mm",
              "> 0",
              max_frame_size_deviation_mm);
}

const char* FrameSideName(FrameSide side) {
  switch (side) {
    case FrameSide::kLeft:
      return "left";
    case FrameSide::kTop:
      return "top";
    case FrameSide::kRight:
      return "right";
    case FrameSide::kBottom:
      return "bottom";
  }
  return "?";
}

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

bool IsVertical(FrameSide side) {
  return side == FrameSide::kLeft || side == FrameSide::kRight;
}

// Median and robust standard deviation (1.4826 MAD).
std::pair<double, double> MedianAndSigma(const std::vector<double>& values) {
  const double median = Median(values);
  std::vector<double> deviations(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    deviations[i] = std::abs(values[i] - median);
  }
  return {median, 1.4826 * Median(std::move(deviations))};
}

double SrgbToLinear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// Least squares across = m * along + q over the flagged points.
bool FitLine(const std::vector<Eigen::Vector2d>& points,
             const std::vector<bool>& use,
             double* slope,
             double* offset) {
  double n = 0, sa = 0, sc = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!use[i]) continue;
    n += 1;
    sa += points[i].x();
    sc += points[i].y();
  }
  if (n < 2) return false;
  const double ma = sa / n, mc = sc / n;
  double saa = 0, sac = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!use[i]) continue;
    const double da = points[i].x() - ma;
    saa += da * da;
    sac += da * (points[i].y() - mc);
  }
  if (saa <= 0) return false;
  *slope = sac / saa;
  *offset = mc - *slope * ma;
  return true;
}

// Where a line of intensities (index 0 at the scan's outer edge) crosses
// from the border into the photograph, in pixels from its start.
struct EdgeCrossing {
  double position = 0;
  double contrast = 0;  // photograph minus border level
};

// Lines whose window or photograph level touch a saturated pixel (a
// clipped value, which does not mix linearly) are not measured.
std::optional<EdgeCrossing> MeasureCrossing(
    const std::vector<double>& v,
    const std::vector<uint8_t>& saturated,
    double probe_level,
    double threshold,
    const VirtualFiducialOptions& options,
    bool* clipped) {
  const int length = static_cast<int>(v.size());
  const int w = options.edge_half_width_px;
  auto median = [&](int begin, int end) {
    return Median(std::vector<double>(v.begin() + begin, v.begin() + end));
  };
  // The first pixel off the border level.
  int k0 = -1;
  for (int j = 0; j < length; ++j) {
    if (std::abs(v[j] - probe_level) > threshold) {
      k0 = j;
      break;
    }
  }
  if (k0 - 1 < options.min_border_px || k0 + w + 4 > length) {
    return std::nullopt;
  }
  // Provisional levels, and the pixel c where the profile passes half-way:
  // the edge lies within half a pixel of c's outer boundary.
  const double border0 = median(std::max(0, k0 - 17), k0 - 1);
  const double contrast0 = median(k0 + w + 1, k0 + w + 4) - border0;
  if (std::abs(contrast0) <= threshold) return std::nullopt;
  int c = -1;
  for (int j = k0; j <= k0 + w + 1; ++j) {
    if ((v[j] - border0) / contrast0 >= 0.5) {
      c = j;
      break;
    }
  }
  if (c < 0) return std::nullopt;
  // The window [lo, hi] reaches w + 1/2 pixels or more to both sides of the
  // edge; the levels are measured just outside it.
  const int lo = c - w - 1, hi = c + w;
  if (lo < options.min_border_px || hi + 5 > length) return std::nullopt;
  for (int j = lo; j <= hi + 4; ++j) {
    if (saturated[j]) {
      *clipped = true;
      return std::nullopt;
    }
  }
  const double border = median(std::max(0, lo - 16), lo);
  const double contrast = median(hi + 1, hi + 4) - border;
  if (std::abs(contrast) <= threshold) return std::nullopt;
  // The photograph's level across the window: a straight line through the
  // four pixels after it, so that the scene's own gradient across the edge
  // does not shift it.
  double mean_j = 0, mean_v = 0;
  for (int j = hi + 1; j <= hi + 4; ++j) {
    mean_j += j / 4.0;
    mean_v += v[j] / 4.0;
  }
  double sjj = 0, sjv = 0;
  for (int j = hi + 1; j <= hi + 4; ++j) {
    sjj += (j - mean_j) * (j - mean_j);
    sjv += (j - mean_j) * (v[j] - mean_v);
  }
  const double slope = sjv / sjj;
  // Border pixels' worth in the window (the gradient's first moment).
  double covered = 0;
  for (int j = lo; j <= hi; ++j) {
    const double level = mean_v + slope * (j - mean_j) - border;
    if (std::abs(level) <= threshold) return std::nullopt;
    covered += (v[j] - border) / level;
  }
  const double position = (hi + 1) - covered;
  if (position < lo || position > hi + 1) return std::nullopt;
  return EdgeCrossing{position, contrast};
}

// The points along one side's scan lines, with the border statistics.
struct SideScan {
  std::vector<Eigen::Vector2d> points;  // (along, across)
  int num_lines = 0;
  int num_saturated_lines = 0;
  double border_level = 0;  // mean over the channels used
  double border_noise = 0;
  std::string reason;  // why there are no points
};

SideScan ScanSide(const LinearScan& image,
                  FrameSide side,
                  const VirtualFiducialOptions& options) {
  const int width = image.width(), height = image.height();
  const bool vertical = IsVertical(side);
  const int num_lines = vertical ? height : width;
  const int across_size = vertical ? width : height;
  const int length = static_cast<int>(options.search_fraction * across_size);
  const int w = options.edge_half_width_px;
  SideScan scan;
  scan.num_lines = num_lines;
  // The smallest line: the border (probe and min_border_px before the
  // window), the window and the photograph's level after it.
  if (length <
      std::max(options.border_probe_px, options.min_border_px) + 2 * w + 6) {
    scan.reason = StrCat(
        "the scan is too small to search (", length, " pixels per line)");
    return scan;
  }
  // Element j of scan line `line` of a matrix, counted from this side.
  auto at = [&](const cv::Mat& mat, int line, int j) -> const uint8_t* {
    switch (side) {
      case FrameSide::kLeft:
        return mat.ptr(line, j);
      case FrameSide::kRight:
        return mat.ptr(line, width - 1 - j);
      case FrameSide::kTop:
        return mat.ptr(j, line);
      case FrameSide::kBottom:
        return mat.ptr(height - 1 - j, line);
    }
    return nullptr;
  };
  auto value = [&](int channel, int line, int j) -> double {
    return *reinterpret_cast<const float*>(
        at(image.channels[channel], line, j));
  };

  // The border of each channel: the outermost pixels of every line. A
  // channel whose border is not uniform is not used on this side.
  const int num_channels = static_cast<int>(image.channels.size());
  std::vector<double> thresholds(num_channels, -1);
  std::vector<int> used;
  double worst_noise = 0;
  for (int c = 0; c < num_channels; ++c) {
    std::vector<double> probe;
    probe.reserve(static_cast<size_t>(num_lines) * options.border_probe_px);
    for (int line = 0; line < num_lines; ++line) {
      for (int j = 0; j < options.border_probe_px; ++j) {
        probe.push_back(value(c, line, j));
      }
    }
    const auto [level, noise] = MedianAndSigma(probe);
    worst_noise = std::max(worst_noise, noise);
    if (noise > options.max_border_noise) continue;
    thresholds[c] =
        std::max(options.min_contrast, options.noise_factor * noise);
    scan.border_level += level;
    scan.border_noise += noise;
    used.push_back(c);
  }
  if (used.empty()) {
    scan.reason = StrCat("no uniform film border (its outer pixels vary by ",
                         worst_noise,
                         ", more than max_border_noise ",
                         options.max_border_noise,
                         ")");
    return scan;
  }
  scan.border_level /= used.size();
  scan.border_noise /= used.size();

  // Each line in each channel whose window is not clipped; the channels'
  // positions averaged with weights contrast^2 (their signal to noise).
  std::vector<double> line_values(length);
  std::vector<uint8_t> line_clipped(length);
  std::vector<Eigen::Vector2d> points[2];  // brighter, darker than the border
  for (int line = 0; line < num_lines; ++line) {
    double sum = 0, sum_weights = 0;
    int sign = 0;
    bool clipped = false, mixed_polarity = false;
    for (int c : used) {
      for (int j = 0; j < length; ++j) {
        line_values[j] = value(c, line, j);
        line_clipped[j] = *at(image.clipped[c], line, j);
      }
      const double probe_level = Median(std::vector<double>(
          line_values.begin(), line_values.begin() + options.border_probe_px));
      const std::optional<EdgeCrossing> crossing =
          MeasureCrossing(line_values,
                          line_clipped,
                          probe_level,
                          thresholds[c],
                          options,
                          &clipped);
      if (!crossing) continue;
      const int channel_sign = crossing->contrast > 0 ? 1 : -1;
      if (sign != 0 && channel_sign != sign) mixed_polarity = true;
      sign = channel_sign;
      const double weight = crossing->contrast * crossing->contrast;
      sum += weight * crossing->position;
      sum_weights += weight;
    }
    if (sum_weights == 0 || mixed_polarity) {
      scan.num_saturated_lines += clipped && sum_weights == 0;
      continue;
    }
    const double d = sum / sum_weights;
    double across = d;
    if (side == FrameSide::kRight) across = width - d;
    if (side == FrameSide::kBottom) across = height - d;
    points[sign > 0 ? 0 : 1].emplace_back(line + 0.5, across);
  }
  // The photograph is brighter than the border on most lines (a positive)
  // or darker (a negative): lines of the other polarity are not edges.
  scan.points = points[0].size() >= points[1].size() ? points[0] : points[1];
  if (scan.points.empty()) {
    scan.reason = StrCat(
        "no edge points (no unclipped transition from the "
        "border, level ",
        scan.border_level,
        ", by more than ",
        std::max(options.min_contrast,
                 options.noise_factor * scan.border_noise),
        " within ",
        length,
        " pixels)");
  }
  return scan;
}

// The fit of `points` as frame edge `side`, with the acceptance rules.
void FitSide(const std::vector<Eigen::Vector2d>& points,
             const VirtualFiducialOptions& options,
             FrameEdge* edge) {
  VirtualFiducialOptions fit_options = options;
  fit_options.seed = options.seed + 7919u * static_cast<uint32_t>(edge->side);
  const EdgeLineFit fit = FitEdgeLine(points, fit_options);
  edge->num_points = fit.num_points;
  edge->num_inliers = fit.num_inliers;
  edge->num_rejected = fit.num_points - fit.num_inliers;
  edge->slope = fit.slope;
  edge->offset = fit.offset;
  edge->rms_px = fit.rms_px;
  edge->max_px = fit.max_px;
  edge->found = false;
  if (!fit.success) {
    edge->reason = fit.reason;
    return;
  }
  const double rotation = std::atan(std::abs(fit.slope)) * kRadToDeg;
  if (rotation > options.max_rotation_deg) {
    edge->reason = StrCat("the line is turned by ",
                          rotation,
                          " deg against the scan axis (max_rotation_deg ",
                          options.max_rotation_deg,
                          ")");
    return;
  }
  if (fit.rms_px > options.max_rms_px) {
    edge->reason = StrCat("residual RMS ",
                          fit.rms_px,
                          " px exceeds max_rms_px ",
                          options.max_rms_px);
    return;
  }
  edge->found = true;
  edge->reason.clear();
}

// Corner k (upper left, upper right, lower right, lower left) lies on
// these sides.
constexpr FrameSide kCornerVertical[4] = {
    FrameSide::kLeft, FrameSide::kRight, FrameSide::kRight, FrameSide::kLeft};
constexpr FrameSide kCornerHorizontal[4] = {
    FrameSide::kTop, FrameSide::kTop, FrameSide::kBottom, FrameSide::kBottom};
const char* const kCornerNames[4] = {
    "upper left", "upper right", "lower right", "lower left"};

// Unit direction of an edge pointing away from corner k along it.
Eigen::Vector2d AwayFromCorner(const FrameEdge& edge, int k) {
  Eigen::Vector2d direction = IsVertical(edge.side)
                                  ? Eigen::Vector2d(edge.slope, 1.0)
                                  : Eigen::Vector2d(1.0, edge.slope);
  direction.normalize();
  const bool top = k == 0 || k == 1;
  const bool left = k == 0 || k == 3;
  if (IsVertical(edge.side) ? !top : !left) direction = -direction;
  return direction;
}

void ComputeCorners(VirtualFiducialResult* result) {
  result->num_corners = 0;
  result->max_corner_angle_deviation_deg = 0;
  for (int k = 0; k < 4; ++k) {
    const FrameEdge& v = result->edges[static_cast<int>(kCornerVertical[k])];
    const FrameEdge& h = result->edges[static_cast<int>(kCornerHorizontal[k])];
    result->has_corner[k] = v.found && h.found;
    if (!result->has_corner[k]) continue;
    const Eigen::Vector3d corner = v.Line().cross(h.Line());
    result->corners_px[k] = corner.head<2>() / corner.z();
    const double cosine =
        std::clamp(AwayFromCorner(v, k).dot(AwayFromCorner(h, k)), -1.0, 1.0);
    result->corner_angles_deg[k] = std::acos(cosine) * kRadToDeg;
    result->max_corner_angle_deviation_deg =
        std::max(result->max_corner_angle_deviation_deg,
                 std::abs(result->corner_angles_deg[k] - 90.0));
    ++result->num_corners;
  }
}

// pixel = [a b; b -a] * xy + t (square pixels, y flipped: the form of every
// ImageFrame without shear) fitted to point pairs by least squares; with
// `scale` > 0 the norm of (a, b) is held at it (Procrustes: the rotation
// of the free fit, that scale).
Eigen::Matrix<double, 2, 3> FitConformal(const std::vector<Eigen::Vector2d>& mm,
                                         const std::vector<Eigen::Vector2d>& px,
                                         double scale) {
  Eigen::Vector2d mean_mm = Eigen::Vector2d::Zero();
  Eigen::Vector2d mean_px = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < mm.size(); ++i) {
    mean_mm += mm[i];
    mean_px += px[i];
  }
  mean_mm /= mm.size();
  mean_px /= mm.size();
  double sum_a = 0, sum_b = 0, sum_squares = 0;
  for (size_t i = 0; i < mm.size(); ++i) {
    const Eigen::Vector2d x = mm[i] - mean_mm, p = px[i] - mean_px;
    sum_a += p.x() * x.x() - p.y() * x.y();
    sum_b += p.x() * x.y() + p.y() * x.x();
    sum_squares += x.squaredNorm();
  }
  double a = sum_a / sum_squares, b = sum_b / sum_squares;
  if (scale > 0) {
    const double norm = std::hypot(a, b);
    a *= scale / norm;
    b *= scale / norm;
  }
  Eigen::Matrix<double, 2, 3> pixel_from_frame;
  pixel_from_frame.leftCols<2>() << a, b, b, -a;
  pixel_from_frame.col(2) = mean_px - pixel_from_frame.leftCols<2>() * mean_mm;
  return pixel_from_frame;
}

// The general affine transformation by least squares (>= 3 pairs).
Eigen::Matrix<double, 2, 3> FitAffine(const std::vector<Eigen::Vector2d>& mm,
                                      const std::vector<Eigen::Vector2d>& px) {
  Eigen::MatrixXd design(mm.size(), 3);
  Eigen::MatrixXd rhs(mm.size(), 2);
  for (size_t i = 0; i < mm.size(); ++i) {
    design.row(i) << mm[i].x(), mm[i].y(), 1.0;
    rhs.row(i) = px[i].transpose();
  }
  const Eigen::MatrixXd solution = design.colPivHouseholderQr().solve(rhs);
  return solution.transpose();
}

// Sets result->frame from the corners (and, with one corner, the edge
// directions); false with result->reason when the found edges do not
// determine it.
bool FitFrame(const VirtualFiducialOptions& options,
              VirtualFiducialResult* result) {
  const double w = options.frame_width_mm, h = options.frame_height_mm;
  const Eigen::Vector2d nominal[4] = {{-0.5 * w, 0.5 * h},
                                      {0.5 * w, 0.5 * h},
                                      {0.5 * w, -0.5 * h},
                                      {-0.5 * w, -0.5 * h}};
  std::vector<Eigen::Vector2d> mm, px;
  for (int k = 0; k < 4; ++k) {
    if (!result->has_corner[k]) continue;
    mm.push_back(nominal[k]);
    px.push_back(result->corners_px[k]);
  }
  const bool known_scale = options.scan_resolution_um > 0;
  const double scale = known_scale ? 1000.0 / options.scan_resolution_um : 0;
  if (result->num_corners == 4) {
    if (known_scale) {
      result->frame.pixel_from_frame = FitConformal(mm, px, scale);
      result->scale_source =
          "scan resolution, rotation and shift from 4 "
          "corners";
    } else {
      result->frame.pixel_from_frame = FitAffine(mm, px);
      result->scale_source = "affine from 4 corners, nominal frame size";
    }
  } else if (result->num_corners == 2) {
    result->frame.pixel_from_frame = FitConformal(mm, px, scale);
    result->scale_source =
        known_scale ? "scan resolution, rotation and shift from 2 corners"
                    : "similarity from 2 corners, nominal side length";
  } else if (result->num_corners == 1 && known_scale) {
    // The frame's x axis in pixels, (a, b), from every found edge: a top or
    // bottom edge y = m x + q runs along (1, m), a side edge x = m y + q
    // along the y axis (b, -a) ~ (m, 1) * -1, i.e. (a, b) ~ (1, -m).
    Eigen::Vector2d axis = Eigen::Vector2d::Zero();
    for (const FrameEdge& edge : result->edges) {
      if (!edge.found) continue;
      const Eigen::Vector2d along = IsVertical(edge.side)
                                        ? Eigen::Vector2d(1.0, -edge.slope)
                                        : Eigen::Vector2d(1.0, edge.slope);
      axis += along.normalized();
    }
    axis = scale * axis.normalized();
    Eigen::Matrix<double, 2, 3>& a = result->frame.pixel_from_frame;
    a.leftCols<2>() << axis.x(), axis.y(), axis.y(), -axis.x();
    a.col(2) = px[0] - a.leftCols<2>() * mm[0];
    result->scale_source =
        "scan resolution, 1 corner and the directions of its edges";
  } else {
    std::string missing;
    for (const FrameEdge& edge : result->edges) {
      if (edge.found) continue;
      missing += StrCat(missing.empty() ? "" : "; ",
                        FrameSideName(edge.side),
                        ": ",
                        edge.reason);
    }
    result->reason = StrCat(
        result->num_edges == 0
            ? "no frame edges found"
            : StrCat("fewer than 3 frame edges (",
                     result->num_edges,
                     " found",
                     result->num_corners == 1 ? "; two adjacent edges suffice "
                                                "with --scan_resolution_um"
                                              : "",
                     ")"),
        " -- ",
        missing);
    return false;
  }
  return true;
}

// The checks of a fitted frame that guard against a silent wrong answer.
bool CheckFrame(const VirtualFiducialOptions& options,
                VirtualFiducialResult* result) {
  const ImageFrame& frame = result->frame;
  const auto& a = frame.pixel_from_frame;
  result->rotation_deg = std::atan2(-a(1, 0), a(0, 0)) * kRadToDeg;
  const double px_per_mm_x = a.col(0).norm(), px_per_mm_y = a.col(1).norm();
  result->pixel_size_um =
      Eigen::Vector2d(1000.0 / px_per_mm_x, 1000.0 / px_per_mm_y);
  const double w = options.frame_width_mm, h = options.frame_height_mm;
  const Eigen::Vector2d nominal[4] = {{-0.5 * w, 0.5 * h},
                                      {0.5 * w, 0.5 * h},
                                      {0.5 * w, -0.5 * h},
                                      {-0.5 * w, -0.5 * h}};
  result->max_corner_residual_px = 0;
  for (int k = 0; k < 4; ++k) {
    if (!result->has_corner[k]) continue;
    result->max_corner_residual_px = std::max(
        result->max_corner_residual_px,
        (frame.PixelFromFrame(nominal[k]) - result->corners_px[k]).norm());
  }
  // Top, bottom, left, right: between corners 0-1, 3-2, 0-3, 1-2.
  const int ends[4][2] = {{0, 1}, {3, 2}, {0, 3}, {1, 2}};
  const double nominal_length[4] = {w, w, h, h};
  const char* const side_names[4] = {"top", "bottom", "left", "right"};
  for (int s = 0; s < 4; ++s) {
    const int i = ends[s][0], j = ends[s][1];
    result->side_lengths_mm[s] =
        result->has_corner[i] && result->has_corner[j]
            ? (frame.FrameFromPixel(result->corners_px[i]) -
               frame.FrameFromPixel(result->corners_px[j]))
                  .norm()
            : 0.0;
  }

  if (result->max_corner_angle_deviation_deg >
      options.max_corner_angle_deviation_deg) {
    int worst = 0;
    for (int k = 0; k < 4; ++k) {
      if (result->has_corner[k] &&
          std::abs(result->corner_angles_deg[k] - 90) >=
              result->max_corner_angle_deviation_deg - 1e-12) {
        worst = k;
      }
    }
    result->reason = StrCat("the edges are not perpendicular: ",
                            result->corner_angles_deg[worst],
                            " deg at the ",
                            kCornerNames[worst],
                            " corner (max_corner_angle_deviation_deg ",
                            options.max_corner_angle_deviation_deg,
                            ")");
    return false;
  }
  if (std::abs(result->rotation_deg) > options.max_rotation_deg) {
    result->reason = StrCat("the frame is rotated by ",
                            result->rotation_deg,
                            " deg (max_rotation_deg ",
                            options.max_rotation_deg,
                            ")");
    return false;
  }
  // The affine fit to four corners has two degrees of freedom to spare:
  // its residual shows opposite edges that are not parallel. (With a scan
  // resolution the residual also holds the frame's difference from its
  // nominal size, which the size check below judges.)
  if (options.scan_resolution_um == 0 && result->num_corners == 4 &&
      result->max_corner_residual_px > options.max_corner_residual_px) {
    result->reason = StrCat("the corners do not form a parallelogram: ",
                            result->max_corner_residual_px,
                            " px off the fitted frame "
                            "(max_corner_residual_px ",
                            options.max_corner_residual_px,
                            ")");
    return false;
  }
  if (options.scan_resolution_um > 0) {
    for (int s = 0; s < 4; ++s) {
      if (result->side_lengths_mm[s] == 0) continue;
      const double deviation =
          std::abs(result->side_lengths_mm[s] - nominal_length[s]);
      if (deviation > options.max_frame_size_deviation_mm) {
        result->reason = StrCat("the ",
                                side_names[s],
                                " edge measures ",
                                result->side_lengths_mm[s],
                                " mm with ",
                                options.scan_resolution_um,
                                " um pixels, nominal ",
                                nominal_length[s],
                                " mm (max_frame_size_deviation_mm ",
                                options.max_frame_size_deviation_mm,
                                "): wrong --scan_resolution_um or frame size?");
        return false;
      }
    }
  } else {
    const double aspect = px_per_mm_x / px_per_mm_y;
    if (std::abs(aspect - 1) > options.max_pixel_aspect_deviation) {
      result->reason = StrCat("the pixels come out ",
                              result->pixel_size_um.x(),
                              " x ",
                              result->pixel_size_um.y(),
                              " um, not square within "
                              "max_pixel_aspect_deviation ",
                              options.max_pixel_aspect_deviation,
                              ": wrong --frame_width_mm/--frame_height_mm?");
      return false;
    }
  }
  return true;
}

// The line across = slope * along + offset through two edge points (the
// model is (slope, offset)), and every point's offset across from it.
class EdgeLineEstimator {
 public:
  using Model = Eigen::Vector2d;
  static constexpr int kMinNumSamples = 2;

  explicit EdgeLineEstimator(const std::vector<Eigen::Vector2d>& points)
      : points_(points) {}

  bool Estimate(const std::vector<int>& sample, Model* model) const {
    const Eigen::Vector2d& a = points_[sample[0]];
    const Eigen::Vector2d& b = points_[sample[1]];
    const double da = b.x() - a.x();
    if (std::abs(da) < 1e-9) return false;
    const double slope = (b.y() - a.y()) / da;
    *model = Model(slope, a.y() - slope * a.x());
    return true;
  }

  void Residuals(const Model& model, std::vector<double>* residuals) const {
    residuals->resize(points_.size());
    for (size_t k = 0; k < points_.size(); ++k) {
      (*residuals)[k] = points_[k].y() - model[0] * points_[k].x() - model[1];
    }
  }

 private:
  const std::vector<Eigen::Vector2d>& points_;
};

}  // namespace

Eigen::Vector3d FrameEdge::Line() const {
  const Eigen::Vector3d line = IsVertical(side)
                                   ? Eigen::Vector3d(1.0, -slope, -offset)
                                   : Eigen::Vector3d(-slope, 1.0, -offset);
  return line / line.head<2>().norm();
}

EdgeLineFit FitEdgeLine(const std::vector<Eigen::Vector2d>& along_across,
                        const VirtualFiducialOptions& options) {
  options.Check();
  EdgeLineFit fit;
  const std::vector<Eigen::Vector2d>& points = along_across;
  const int n = static_cast<int>(points.size());
  fit.num_points = n;
  fit.inliers.assign(n, false);
  if (n < options.min_edge_points) {
    fit.reason = StrCat("too few edge points (",
                        n,
                        " < min_edge_points ",
                        options.min_edge_points,
                        ")");
    return fit;
  }

  // Least median of squares over random pairs.
  UniformSampler sampler(n, options.seed);
  const LmedsReport<Eigen::Vector2d> lmeds = LeastMedianOfSquares(
      EdgeLineEstimator(points), options.num_samples, &sampler);
  if (!lmeds.success()) {
    fit.reason = "the edge points do not span a line";
    return fit;
  }
  fit.sigma_px = std::max(options.min_sigma_px,
                          1.4826 * (1.0 + 5.0 / (n - 2)) *
                              std::sqrt(lmeds.best().median_of_squares));

  // Rejection and least squares, iterated until the kept set is stable.
  double slope = lmeds.best().model[0], offset = lmeds.best().model[1];
  double sigma = fit.sigma_px;
  std::vector<bool> keep(n, false);
  for (int iteration = 0; iteration < 20; ++iteration) {
    std::vector<bool> next(n);
    for (int k = 0; k < n; ++k) {
      const double r = points[k].y() - slope * points[k].x() - offset;
      next[k] = std::abs(r) <= options.outlier_threshold * sigma;
    }
    if (next == keep) break;
    keep = next;
    if (!FitLine(points, keep, &slope, &offset)) break;
    double sum_squares = 0;
    int count = 0;
    for (int k = 0; k < n; ++k) {
      if (!keep[k]) continue;
      const double r = points[k].y() - slope * points[k].x() - offset;
      sum_squares += r * r;
      ++count;
    }
    sigma = std::max(options.min_sigma_px,
                     std::sqrt(sum_squares / std::max(1, count - 2)));
  }
  fit.slope = slope;
  fit.offset = offset;
  fit.inliers = keep;
  double sum_squares = 0;
  for (int k = 0; k < n; ++k) {
    if (!keep[k]) continue;
    const double r = points[k].y() - slope * points[k].x() - offset;
    sum_squares += r * r;
    fit.max_px = std::max(fit.max_px, std::abs(r));
    ++fit.num_inliers;
  }
  fit.rms_px =
      fit.num_inliers > 0 ? std::sqrt(sum_squares / fit.num_inliers) : 0.0;
  if (fit.num_inliers < options.min_edge_points) {
    fit.reason = StrCat("only ",
                        fit.num_inliers,
                        " of ",
                        n,
                        " edge points on a line (min_edge_points ",
                        options.min_edge_points,
                        ")");
    return fit;
  }
  if (fit.num_inliers < options.min_inlier_ratio * n) {
    fit.reason = StrCat("no straight edge: only ",
                        fit.num_inliers,
                        " of ",
                        n,
                        " edge points on a line (min_inlier_ratio ",
                        options.min_inlier_ratio,
                        ")");
    return fit;
  }
  fit.success = true;
  return fit;
}

LinearScan MakeLinearScan(const cv::Mat& image,
                          bool decode_srgb,
                          double clip_level) {
  const int channels = image.channels();
  const int depth = image.depth();
  if (image.empty()) ThrowInputError("an empty image");
  if (channels < 1 || channels > 4) {
    ThrowInputError("images with ", channels, " channels are not supported");
  }
  double unit = 1.0;
  if (depth == CV_8U) {
    unit = 1.0 / 255.0;
  } else if (depth == CV_16U) {
    unit = 1.0 / 65535.0;
  } else if (depth != CV_32F && depth != CV_64F) {
    ThrowInputError("image depth ",
                    depth,
                    " (OpenCV code) is not supported: 8 or 16 bit unsigned, "
                    "or floating point");
  }
  const bool integer = depth == CV_8U || depth == CV_16U;
  // Grey, grey + alpha: one channel; colour (+ alpha): three.
  const int num_colour = channels >= 3 ? 3 : 1;
  cv::Mat values;
  image.convertTo(values, CV_MAKETYPE(CV_64F, channels), unit);
  // sRGB decoding of 8-bit values by table.
  std::vector<double> table;
  if (decode_srgb && depth == CV_8U) {
    table.resize(256);
    for (int v = 0; v < 256; ++v) table[v] = SrgbToLinear(v / 255.0);
  }
  auto decode = [&](double v) {
    if (!decode_srgb || !integer) return v;
    if (!table.empty()) {
      return table[std::clamp(
          static_cast<int>(std::lround(v * 255.0)), 0, 255)];
    }
    return SrgbToLinear(v);
  };
  LinearScan scan;
  for (int c = 0; c < num_colour; ++c) {
    scan.channels.emplace_back(image.size(), CV_32F);
    scan.clipped.push_back(cv::Mat::zeros(image.size(), CV_8U));
  }
  for (int y = 0; y < image.rows; ++y) {
    const double* in = values.ptr<double>(y);
    for (int x = 0; x < image.cols; ++x) {
      const double* pixel = in + static_cast<size_t>(x) * channels;
      for (int c = 0; c < num_colour; ++c) {
        scan.channels[c].at<float>(y, x) = static_cast<float>(decode(pixel[c]));
        if (integer && pixel[c] >= clip_level)
          scan.clipped[c].at<uint8_t>(y, x) = 255;
      }
    }
  }
  return scan;
}

VirtualFiducialResult FindVirtualFiducials(
    const LinearScan& scan, const VirtualFiducialOptions& options) {
  options.Check();
  CHECK(!scan.channels.empty() && scan.clipped.size() == scan.channels.size())
      << "FindVirtualFiducials takes MakeLinearScan()";
  for (size_t c = 0; c < scan.channels.size(); ++c) {
    CHECK(scan.channels[c].type() == CV_32F &&
          scan.clipped[c].type() == CV_8U &&
          scan.channels[c].size() == scan.channels[0].size() &&
          scan.clipped[c].size() == scan.channels[0].size())
        << "FindVirtualFiducials takes MakeLinearScan()";
  }
  VirtualFiducialResult result;
  std::array<SideScan, 4> scans;
  for (int s = 0; s < 4; ++s) {
    FrameEdge& edge = result.edges[s];
    edge.side = static_cast<FrameSide>(s);
    scans[s] = ScanSide(scan, edge.side, options);
    edge.num_lines = scans[s].num_lines;
    edge.num_saturated_lines = scans[s].num_saturated_lines;
    edge.border_level = scans[s].border_level;
    edge.border_noise = scans[s].border_noise;
    edge.num_points = static_cast<int>(scans[s].points.size());
    if (!scans[s].reason.empty()) {
      edge.reason = scans[s].reason;
      continue;
    }
    FitSide(scans[s].points, options, &edge);
  }
  ComputeCorners(&result);

  // Again without the points near the corners, where the window reaches
  // the other edge.
  for (int s = 0; s < 4; ++s) {
    FrameEdge& edge = result.edges[s];
    if (!edge.found) continue;
    // The corners at the start and the end of this edge's along axis.
    int first = 0, last = 0;
    switch (edge.side) {
      case FrameSide::kLeft:
        first = 0, last = 3;
        break;
      case FrameSide::kRight:
        first = 1, last = 2;
        break;
      case FrameSide::kTop:
        first = 0, last = 1;
        break;
      case FrameSide::kBottom:
        first = 3, last = 2;
        break;
    }
    const int axis = IsVertical(edge.side) ? 1 : 0;
    double low = -std::numeric_limits<double>::infinity();
    double high = std::numeric_limits<double>::infinity();
    if (result.has_corner[first]) {
      low = result.corners_px[first][axis] + options.corner_margin_px;
    }
    if (result.has_corner[last]) {
      high = result.corners_px[last][axis] - options.corner_margin_px;
    }
    std::vector<Eigen::Vector2d> inner;
    for (const Eigen::Vector2d& point : scans[s].points) {
      if (point.x() >= low && point.x() <= high) inner.push_back(point);
    }
    FitSide(inner, options, &edge);
  }
  ComputeCorners(&result);

  for (FrameEdge& edge : result.edges) {
    if (!edge.found && edge.num_saturated_lines > 0) {
      edge.reason += StrCat(" (",
                            edge.num_saturated_lines,
                            " of ",
                            edge.num_lines,
                            " scan lines clipped in every channel at the "
                            "edge)");
    }
  }
  for (const FrameEdge& edge : result.edges) {
    if (!edge.found) continue;
    ++result.num_edges;
    result.num_points += edge.num_points;
    result.num_rejected += edge.num_rejected;
    result.rms_px += edge.rms_px * edge.rms_px * edge.num_inliers;
    result.max_px = std::max(result.max_px, edge.max_px);
  }
  const int num_inliers = result.num_points - result.num_rejected;
  result.rms_px =
      num_inliers > 0 ? std::sqrt(result.rms_px / num_inliers) : 0.0;
  if (!FitFrame(options, &result)) return result;
  if (!CheckFrame(options, &result)) return result;
  result.success = true;
  return result;
}

}  // namespace bayon
