// SPDX-License-Identifier: BSD-3-Clause
//
// Interior orientation of a scanned film frame without fiducial marks, the
// paper's section 3.1: "virtual fiducials" are the corners of the image
// frame, found by intersecting the straight lines of adjacent, mutually
// perpendicular frame edges; they define the image's own coordinate system.
//
// The frame edge is the boundary between the uniform film border (the
// unexposed film around the photograph, dark on a positive) and the
// photograph. The frame is assumed upright in the scan, its edges within
// `max_rotation_deg` of the scan's axes: the frame's top edge (+y in image
// millimetres) is the one nearest the top of the scan.
//
// 1. Edge points. Along every scan row (left and right edges) and column
//    (top and bottom edges), from the outer edge of the scan inwards: the
//    border level is the median of the line's first pixels, and the first
//    pixel that differs from it by more than the threshold (min_contrast, or
//    noise_factor times the border's robust noise, whichever is larger)
//    marks the transition. The pixel c where the profile passes half-way
//    from the border to the photograph puts the edge within half a pixel of
//    c's outer boundary; a window of 2 * edge_half_width_px + 2 pixels is
//    centred there. In it the edge position is the first moment of the
//    gradient: with the border level b (median of the pixels before the
//    window) and the photograph's level p_j (a straight line through the
//    four pixels after the window, extrapolated, so that the scene's own
//    gradient across the edge does not shift it),
//      e = x_end - sum_j (v_j - b) / (p_j - b),
//    the number of pixels' worth of border in the window. For a
//    pixel-integrated step blurred by any symmetric point spread function
//    that fits in the window it is exact, whatever the edge's position
//    within its pixel (no bias with the sub-pixel phase, unlike a parabola
//    through the gradient maximum). Intensities are made linear first (sRGB
//    decoded), since scene and border mix linearly in a pixel that the edge
//    crosses; for the same reason each colour channel is measured on its
//    own, only where the window and the level pixels are not clipped (a
//    bright sky often saturates blue and green but not red), and the
//    channels' positions are averaged with weights (p - b)^2.
// 2. Lines. Each edge's points are fitted with across = m * along + q
//    (x = m y + q for the left and right edges, y = m x + q for top and
//    bottom), residuals along the scan lines in pixels: least median of
//    squares over random point pairs, sigma = 1.4826 (1 + 5 / (n - 2))
//    sqrt(min median r^2), points beyond outlier_threshold sigma rejected,
//    then least squares on the rest, iterated (sigma from the residuals of
//    the kept points) until the kept set stays the same. Once the corners
//    are known, points within corner_margin_px of a corner (where the
//    window meets the other edge) are dropped and the lines fitted again.
// 3. Corners: adjacent lines intersected, the angle at each corner
//    reported and checked against 90 degrees.
// 4. The image frame (ImageFrame, ext/core/image_frame.h): pixel =
//    pixel_from_frame * (x_mm, y_mm, 1), image coordinates with x right,
//    y up, origin at the frame centre, the nominal corners at (+-w/2,
//    +-h/2) for a w x h mm frame. How the scale is determined:
//    - no scan resolution given (scan_resolution_um = 0): from the nominal
//      frame size. Four corners: the affine transformation (6 parameters,
//      scale in x and y, shear) by least squares from the four nominal
//      corners to the measured ones. Three edges (two corners along one
//      side): the similarity (square pixels) that maps the nominal side
//      onto it exactly.
//    - scan resolution given: the scale is fixed at 1 / resolution, and
//      rotation and shift are fitted to the corners by least squares
//      (four corners, or two along one side), or (two adjacent edges, one
//      corner: the paper's minimum) taken from the corner and the mean
//      direction of its two edges. The measured side lengths then serve as
//      a check on the frame size.
//    The frame's rotation in the scan is atan2(-a21, a11) of
//    pixel_from_frame, positive counter-clockwise as seen on the film
//    (the convention of `bayon synth`'s gt/interior.json).
//
// A frame that cannot be measured is reported with the reason: no border
// or no edge points on a side, fewer than three edges (two adjacent ones
// with a scan resolution), a residual RMS above max_rms_px, corners not
// perpendicular within tolerance, pixels not square within tolerance (the
// affine case) or a frame size that disagrees with the scan resolution.
#pragma once

#include "ext/core/image_frame.h"
#include "ext/core/option_registry.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

struct VirtualFiducialOptions {
  // Nominal size of the exposed frame (the film gate), mm; 36 x 24 for
  // 35 mm film in landscape. The nominal corners are at (+-w/2, +-h/2).
  double frame_width_mm = 36.0;
  double frame_height_mm = 24.0;
  // The scanner's pixel size in micrometres (e.g. 21 um for the paper's
  // Agfa Horizon scans). 0: unknown, the scale comes from the nominal frame
  // size (an affine transformation); > 0: the scale is fixed by it and the
  // frame size becomes a check (see the header comment).
  double scan_resolution_um = 0.0;
  // Decode the sRGB tone curve before measuring (8- and 16-bit scans are
  // usually so encoded); off: the values are taken as linear.
  bool decode_srgb = true;
  // 8- and 16-bit values at or above this fraction of the top of their
  // range count as clipped (MakeLinearScan()); below 1 because noise added
  // after the clipping scatters clipped values just under the top.
  double clip_level = 0.98;
  // How far into the scan each edge is searched, as a fraction of the scan's
  // width (left, right) or height (top, bottom).
  double search_fraction = 0.25;
  // A scan line must start with at least this many border pixels before
  // the transition's window; lines that start in the photograph are skipped.
  int min_border_px = 3;
  // Pixels at the start of each line that give its border level.
  int border_probe_px = 4;
  // The transition: the first pixel that differs from the border level by
  // more than max(min_contrast, noise_factor * border noise), in linear
  // intensity (0..1). Lower values find edges next to dark scene parts but
  // admit grain and dust.
  double min_contrast = 0.01;
  double noise_factor = 6.0;
  // A side whose outer pixels vary more than this (robust standard
  // deviation, linear intensity) has no uniform film border: the photograph
  // or something else fills the scan there.
  double max_border_noise = 0.03;
  // The window in which the edge position is measured reaches at least
  // this many pixels and a half to both sides of the edge: it must hold the
  // edge's blur (1 for a Gaussian blur up to sigma 0.5 px, 2 up to about
  // 0.8 px), while every pixel more lets the scene's texture in.
  int edge_half_width_px = 1;
  // Line fitting: random pairs for the least median of squares, and the
  // rejection threshold in robust standard deviations.
  int num_samples = 500;
  double outlier_threshold = 3.0;
  // Floor of the robust scale, pixels, so that nearly exact edges do not
  // reject points for their rounding.
  double min_sigma_px = 0.05;
  // Edge points closer than this to a corner are not used in the final
  // fit, pixels.
  double corner_margin_px = 8.0;
  // An edge is accepted with at least this many kept points, at least this
  // share of its points kept, and a residual RMS of at most max_rms_px.
  int min_edge_points = 30;
  double min_inlier_ratio = 0.5;
  double max_rms_px = 0.5;
  // Largest rotation of the frame edges against the scan's axes, degrees.
  double max_rotation_deg = 10.0;
  // Largest deviation of a corner angle from 90 degrees.
  double max_corner_angle_deviation_deg = 0.5;
  // Affine case: largest residual of a measured corner against the fitted
  // transformation (opposite edges not parallel), pixels, and the largest
  // relative difference of the x and y pixel sizes.
  double max_corner_residual_px = 1.0;
  double max_pixel_aspect_deviation = 0.02;
  // Scan resolution given: largest difference of a measured side length
  // from the nominal frame size, mm.
  double max_frame_size_deviation_mm = 0.5;
  uint32_t seed = 1;
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value and rule
};

// The four sides of the frame, in the order of their table in the results.
enum class FrameSide { kLeft = 0, kTop = 1, kRight = 2, kBottom = 3 };
const char* FrameSideName(FrameSide side);

// A robust straight-line fit across = m * along + q (header comment, 2.).
struct EdgeLineFit {
  bool success = false;
  std::string reason;  // when not
  double slope = 0;    // m
  double offset = 0;   // q
  int num_points = 0;
  int num_inliers = 0;
  double sigma_px = 0;  // robust scale of the least median of squares
  double rms_px = 0;    // of the kept points
  double max_px = 0;
  std::vector<bool> inliers;  // per point
};
EdgeLineFit FitEdgeLine(const std::vector<Eigen::Vector2d>& along_across,
                        const VirtualFiducialOptions& options);

struct FrameEdge {
  FrameSide side = FrameSide::kLeft;
  bool found = false;
  std::string reason;  // when not found
  // x = slope * y + offset (left, right) or y = slope * x + offset (top,
  // bottom), COLMAP pixel coordinates.
  double slope = 0;
  double offset = 0;
  int num_lines = 0;  // scan lines searched
  // Lines not measured because the edge window was clipped in every
  // channel.
  int num_saturated_lines = 0;
  int num_points = 0;    // edge points measured (final fit)
  int num_inliers = 0;   // kept by the robust fit
  int num_rejected = 0;  // num_points - num_inliers
  double rms_px = 0;     // residuals of the kept points along the scan lines
  double max_px = 0;
  double border_level = 0;  // median linear intensity of the border
  double border_noise = 0;  // its robust standard deviation
  // The line as a x + b y + c = 0 with (a, b) a unit vector.
  Eigen::Vector3d Line() const;
};

struct VirtualFiducialResult {
  bool success = false;
  std::string reason;              // when not
  std::array<FrameEdge, 4> edges;  // indexed by FrameSide
  int num_edges = 0;               // found
  // Corners in the order (-x, +y) (+x, +y) (+x, -y) (-x, -y) of the image
  // coordinates, i.e. upper left, upper right, lower right, lower left (the
  // order of `bayon synth`'s frame_corners_px); valid where both adjacent
  // edges were found.
  std::array<Eigen::Vector2d, 4> corners_px;
  std::array<bool, 4> has_corner = {false, false, false, false};
  std::array<double, 4> corner_angles_deg = {0, 0, 0, 0};
  int num_corners = 0;
  double max_corner_angle_deviation_deg = 0;
  // How pixel_from_frame was determined: "affine, nominal frame size",
  // "similarity, nominal frame width", "scan resolution", ...
  std::string scale_source;
  ImageFrame frame;
  double rotation_deg = 0;
  // Largest distance of a measured corner from the fitted frame's.
  double max_corner_residual_px = 0;
  // Pixel size of the fitted frame along its x and y axes, micrometres.
  Eigen::Vector2d pixel_size_um = Eigen::Vector2d::Zero();
  // Measured side lengths (top, bottom, left, right; 0 where a side's two
  // corners are not both known), mm, in the fitted frame's scale.
  std::array<double, 4> side_lengths_mm = {0, 0, 0, 0};
  // Over the kept edge points of the found edges, pixels.
  double rms_px = 0;
  double max_px = 0;
  int num_points = 0;
  int num_rejected = 0;
};

// A scan as the measurement sees it: each colour channel (one for a grey
// scan; alpha dropped) as CV_32F linear intensity in [0, 1], and for each a
// CV_8U mask of its clipped pixels (255 where an 8- or 16-bit value is at
// or above clip_level of its range: no longer a linear mix of what the
// pixel saw).
struct LinearScan {
  std::vector<cv::Mat> channels;
  std::vector<cv::Mat> clipped;
  int width() const { return channels.empty() ? 0 : channels[0].cols; }
  int height() const { return channels.empty() ? 0 : channels[0].rows; }
};

// 8- and 16-bit values scaled to [0, 1] and (decode_srgb) decoded from
// sRGB; floating-point values taken as they are (never clipped). Throws
// InputError for an empty image or an unsupported depth or channel count.
LinearScan MakeLinearScan(const cv::Mat& image,
                          bool decode_srgb,
                          double clip_level = 0.98);

// Finds the frame in a scan.
VirtualFiducialResult FindVirtualFiducials(
    const LinearScan& scan, const VirtualFiducialOptions& options);

}  // namespace bayon
