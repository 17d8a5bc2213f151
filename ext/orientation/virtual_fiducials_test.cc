// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/virtual_fiducials.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <functional>
#include <iostream>
#include <random>

namespace bayon {
namespace {

// A synthetic film scan: a w x h mm photograph (a smooth texture of linear
// intensities 0.1 .. 0.6) placed by `frame` in a scan whose film border has
// the linear intensity `border`. Pixels the frame edge crosses are
// integrated exactly enough (16 x 16 samples), the result blurred by a
// Gaussian, sRGB-encoded to 8 bits with Gaussian noise, and decoded again
// by MakeLinearScan() as a scan file would be. Like a camera, the
// channels can be exposed differently and clip after the mixing.
struct ScanSpec {
  int width = 700;
  int height = 500;
  double pitch_mm = 0.06;
  double rotation_deg = 0.7;
  Eigen::Vector2d shift_mm = Eigen::Vector2d(0.31, -0.17);
  double frame_width_mm = 36;
  double frame_height_mm = 24;
  double shear = 0;  // x_scan = x + shear * y before the rotation
  double border = 0.003;
  double blur_sigma_px = 0.7;
  double noise_sigma = 1.0;  // 8-bit grey values
  // Linear gain of the blue, green and red channels before clipping.
  Eigen::Vector3d gain = Eigen::Vector3d::Ones();
  // Where it returns true the photograph is as dark as the border.
  std::function<bool(const Eigen::Vector2d& mm)> dark;
  bool fill = false;  // the photograph fills the scan: no border at all
  uint32_t seed = 5;

  ImageFrame Frame() const {
    const double a = rotation_deg * M_PI / 180;
    Eigen::Matrix2d rotation;
    rotation << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    Eigen::Matrix2d shear_matrix;
    shear_matrix << 1, shear, 0, 1;
    const Eigen::Matrix2d flip =
        Eigen::Vector2d(1 / pitch_mm, -1 / pitch_mm).asDiagonal();
    ImageFrame frame;
    frame.pixel_from_frame.leftCols<2>() = flip * rotation * shear_matrix;
    frame.pixel_from_frame.col(2) =
        flip * shift_mm + Eigen::Vector2d(0.5 * width, 0.5 * height);
    return frame;
  }

  std::array<Eigen::Vector2d, 4> Corners() const {
    const double w = frame_width_mm / 2, h = frame_height_mm / 2;
    const ImageFrame frame = Frame();
    return {frame.PixelFromFrame({-w, h}),
            frame.PixelFromFrame({w, h}),
            frame.PixelFromFrame({w, -h}),
            frame.PixelFromFrame({-w, -h})};
  }
};

double Texture(const Eigen::Vector2d& mm) {
  return 0.35 + 0.12 * std::sin(0.9 * mm.x() + 0.4 * mm.y()) +
         0.08 * std::cos(2.3 * mm.y() - 0.7 * mm.x()) +
         0.05 * std::sin(9.1 * mm.x()) * std::cos(7.3 * mm.y());
}

cv::Mat RenderScan(const ScanSpec& spec) {
  const ImageFrame frame = spec.Frame();
  const Eigen::Matrix2d frame_from_pixel =
      frame.pixel_from_frame.leftCols<2>().inverse();
  const Eigen::Vector2d origin = frame.pixel_from_frame.col(2);
  auto to_mm = [&](const Eigen::Vector2d& pixel) -> Eigen::Vector2d {
    return frame_from_pixel * (pixel - origin);
  };
  const double w = spec.frame_width_mm / 2, h = spec.frame_height_mm / 2;
  auto is_dark = [&](const Eigen::Vector2d& mm) {
    return static_cast<bool>(spec.dark) && spec.dark(mm);
  };
  auto sample = [&](const Eigen::Vector2d& pixel) {
    const Eigen::Vector2d mm = to_mm(pixel);
    if (!spec.fill && (std::abs(mm.x()) > w || std::abs(mm.y()) > h)) {
      return spec.border;
    }
    if (is_dark(mm)) return spec.border;
    return Texture(mm);
  };
  cv::Mat linear(spec.height, spec.width, CV_64F);
  constexpr int kSamples = 16;
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const Eigen::Vector2d center(x + 0.5, y + 0.5);
      const Eigen::Vector2d mm = to_mm(center);
      const double distance_px = std::min(std::abs(w - std::abs(mm.x())),
                                          std::abs(h - std::abs(mm.y()))) /
                                 spec.pitch_mm;
      // Pixels that a dark region's boundary crosses are integrated too.
      bool mixed = false;
      for (const Eigen::Vector2d& corner : {Eigen::Vector2d(x, y),
                                            Eigen::Vector2d(x + 1, y),
                                            Eigen::Vector2d(x, y + 1),
                                            Eigen::Vector2d(x + 1, y + 1)}) {
        mixed = mixed || is_dark(to_mm(corner)) != is_dark(mm);
      }
      double value = 0;
      if (distance_px > 2.0 && !mixed) {
        value = sample(center);
      } else {
        for (int j = 0; j < kSamples; ++j) {
          for (int i = 0; i < kSamples; ++i) {
            value += sample(Eigen::Vector2d(x + (i + 0.5) / kSamples,
                                            y + (j + 0.5) / kSamples));
          }
        }
        value /= kSamples * kSamples;
      }
      linear.at<double>(y, x) = value;
    }
  }
  if (spec.blur_sigma_px > 0) {
    cv::GaussianBlur(linear,
                     linear,
                     cv::Size(0, 0),
                     spec.blur_sigma_px,
                     spec.blur_sigma_px,
                     cv::BORDER_REPLICATE);
  }
  std::mt19937 rng(spec.seed);
  std::normal_distribution<double> noise(0, spec.noise_sigma);
  cv::Mat encoded(spec.height, spec.width, CV_8UC3);
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v =
            std::clamp(spec.gain[c] * linear.at<double>(y, x), 0.0, 1.0);
        const double srgb =
            v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
        encoded.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uint8_t>(
            255 * srgb + (spec.noise_sigma > 0 ? noise(rng) : 0.0));
      }
    }
  }
  return encoded;
}

VirtualFiducialResult Measure(const ScanSpec& spec,
                              VirtualFiducialOptions options = {}) {
  options.frame_width_mm = spec.frame_width_mm;
  options.frame_height_mm = spec.frame_height_mm;
  return FindVirtualFiducials(MakeLinearScan(RenderScan(spec), true), options);
}

// Largest distance between the image coordinates two frames give the same
// pixel, over the frame (a grid; the difference of two affine maps is
// largest at the frame's corners).
double MaxFrameDifferenceMm(const ImageFrame& estimate,
                            const ImageFrame& truth,
                            double width_mm,
                            double height_mm) {
  double worst = 0;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j) {
      const Eigen::Vector2d mm(width_mm * (i / 10.0 - 0.5),
                               height_mm * (j / 10.0 - 0.5));
      const Eigen::Vector2d pixel = truth.PixelFromFrame(mm);
      worst = std::max(worst, (estimate.FrameFromPixel(pixel) - mm).norm());
    }
  }
  return worst;
}

double MaxCornerError(const VirtualFiducialResult& result,
                      const ScanSpec& spec) {
  const auto truth = spec.Corners();
  double worst = 0;
  for (int k = 0; k < 4; ++k) {
    if (!result.has_corner[k]) continue;
    worst = std::max(worst, (result.corners_px[k] - truth[k]).norm());
  }
  return worst;
}

std::string Describe(const VirtualFiducialResult& result) {
  std::string text = result.reason;
  for (const FrameEdge& edge : result.edges) {
    text += StrCat("; ",
                   FrameSideName(edge.side),
                   edge.found ? " found " : " not found ",
                   edge.num_inliers,
                   "/",
                   edge.num_points,
                   " rms ",
                   edge.rms_px,
                   " ",
                   edge.reason);
  }
  return text;
}

TEST(VirtualFiducials, CornersAndFrameOfARotatedBlurredNoisyScan) {
  for (const double rotation : {0.7, -2.3, 0.0}) {
    ScanSpec spec;
    spec.rotation_deg = rotation;
    // Rotation 0: the edges parallel to the pixel grid, at a fractional
    // position, where a phase-dependent estimator would be biased.
    if (rotation == 0) spec.shift_mm = Eigen::Vector2d(0.0183, 0.0411);
    const VirtualFiducialResult result = Measure(spec);
    ASSERT_TRUE(result.success) << rotation << ": " << Describe(result);
    EXPECT_EQ(result.num_edges, 4);
    EXPECT_EQ(result.num_corners, 4);
    const double corner_error = MaxCornerError(result, spec);
    const double frame_error =
        MaxFrameDifferenceMm(result.frame, spec.Frame(), 36, 24);
    std::cout << "rotation " << rotation << " deg: corners within "
              << corner_error << " px, frame within " << frame_error
              << " mm, edge RMS " << result.rms_px << " px, "
              << result.num_points << " points, " << result.num_rejected
              << " rejected, measured rotation " << result.rotation_deg
              << " deg, max corner angle deviation "
              << result.max_corner_angle_deviation_deg << " deg\n";
    // (The rendering itself places an edge parallel to the pixel grid only
    // to 1/32 pixel.)
    EXPECT_LT(corner_error, 0.06);
    EXPECT_LT(frame_error, 0.003);
    EXPECT_NEAR(result.rotation_deg, rotation, 0.003);
    EXPECT_LT(result.max_corner_angle_deviation_deg, 0.01);
    EXPECT_NEAR(result.pixel_size_um.x(), 60.0, 0.01);
    EXPECT_NEAR(result.pixel_size_um.y(), 60.0, 0.01);
    // Texture and noise scatter the edge points by a fraction of a pixel.
    EXPECT_LT(result.rms_px, 0.2);
    // The convention of ImageFrame: x right, y up in the scan.
    EXPECT_GT(result.frame.pixel_from_frame(0, 0), 0);
    EXPECT_LT(result.frame.pixel_from_frame(1, 1), 0);
  }
}

TEST(VirtualFiducials, ScanResolutionFixesTheScaleAndChecksTheSize) {
  ScanSpec spec;
  spec.rotation_deg = 1.1;
  VirtualFiducialOptions options;
  options.scan_resolution_um = 60;
  const VirtualFiducialResult result = Measure(spec, options);
  ASSERT_TRUE(result.success) << Describe(result);
  EXPECT_NEAR(result.pixel_size_um.x(), 60.0, 1e-9);
  EXPECT_NEAR(result.pixel_size_um.y(), 60.0, 1e-9);
  EXPECT_NEAR(result.side_lengths_mm[0], 36, 0.01);
  EXPECT_NEAR(result.side_lengths_mm[2], 24, 0.01);
  EXPECT_LT(MaxFrameDifferenceMm(result.frame, spec.Frame(), 36, 24), 0.002);

  // A resolution that does not fit the frame: the size check says so.
  options.scan_resolution_um = 63;
  const VirtualFiducialResult wrong = Measure(spec, options);
  EXPECT_FALSE(wrong.success);
  EXPECT_NE(wrong.reason.find("scan_resolution_um"), std::string::npos)
      << wrong.reason;
}

TEST(VirtualFiducials, ThreeEdgesWhenThePhotographRunsOffTheScan) {
  ScanSpec spec;
  spec.height = 440;  // the frame's lower edge lies below the scan
  spec.shift_mm = Eigen::Vector2d(0.2, -1.6);
  spec.rotation_deg = 0.4;
  const VirtualFiducialResult result = Measure(spec);
  ASSERT_TRUE(result.success) << Describe(result);
  EXPECT_EQ(result.num_edges, 3);
  EXPECT_FALSE(result.edges[static_cast<int>(FrameSide::kBottom)].found);
  EXPECT_TRUE(result.has_corner[0] && result.has_corner[1]);
  EXPECT_FALSE(result.has_corner[2] || result.has_corner[3]);
  EXPECT_LT(MaxCornerError(result, spec), 0.05);
  // Square pixels and the nominal width give the scale.
  EXPECT_LT(MaxFrameDifferenceMm(result.frame, spec.Frame(), 36, 24), 0.005);
}

TEST(VirtualFiducials, TwoAdjacentEdgesNeedTheScanResolution) {
  ScanSpec spec;
  spec.width = 650;   // the right edge lies beyond the scan
  spec.height = 440;  // and the lower one
  spec.shift_mm = Eigen::Vector2d(1.8, -1.6);
  spec.rotation_deg = -0.6;
  const VirtualFiducialResult without = Measure(spec);
  EXPECT_FALSE(without.success);
  EXPECT_EQ(without.num_edges, 2);
  EXPECT_NE(without.reason.find("fewer than 3 frame edges"), std::string::npos)
      << without.reason;

  VirtualFiducialOptions options;
  options.scan_resolution_um = 60;
  const VirtualFiducialResult with = Measure(spec, options);
  ASSERT_TRUE(with.success) << Describe(with);
  EXPECT_EQ(with.num_corners, 1);
  EXPECT_LT(MaxCornerError(with, spec), 0.05);
  EXPECT_LT(MaxFrameDifferenceMm(with.frame, spec.Frame(), 36, 24), 0.01);
}

TEST(VirtualFiducials, DarkSceneAlongPartOfAnEdgeIsRejected) {
  ScanSpec spec;
  spec.rotation_deg = 0.9;
  // The lower 40 % of the left edge and a stretch of the top one are as
  // dark as the border; a dark blob inside the frame near the right edge
  // makes false edge points further in.
  spec.dark = [](const Eigen::Vector2d& mm) {
    return (mm.x() < -15 && mm.y() < -2) ||
           (mm.y() > 10 && mm.x() > -4 && mm.x() < 6) ||
           (mm.x() > 17.2 && mm.y() > -3 && mm.y() < 3);
  };
  const VirtualFiducialResult result = Measure(spec);
  ASSERT_TRUE(result.success) << Describe(result);
  EXPECT_EQ(result.num_edges, 4);
  EXPECT_GT(result.edges[static_cast<int>(FrameSide::kRight)].num_rejected, 20);
  EXPECT_LT(MaxCornerError(result, spec), 0.08);
  EXPECT_LT(MaxFrameDifferenceMm(result.frame, spec.Frame(), 36, 24), 0.003);
}

TEST(VirtualFiducials, ScansWithoutAFrameFailWithAReason) {
  // A uniform grey scan.
  const cv::Mat uniform(400, 600, CV_8UC1, cv::Scalar(90));
  const VirtualFiducialResult flat =
      FindVirtualFiducials(MakeLinearScan(uniform, true), {});
  EXPECT_FALSE(flat.success);
  EXPECT_EQ(flat.num_edges, 0);
  EXPECT_NE(flat.reason.find("no frame edges found"), std::string::npos)
      << flat.reason;

  // The photograph fills the scan: no border anywhere.
  ScanSpec spec;
  spec.fill = true;
  const VirtualFiducialResult filled = Measure(spec);
  EXPECT_FALSE(filled.success);
  EXPECT_LT(filled.num_edges, 3) << Describe(filled);
  EXPECT_NE(filled.reason.find("frame edges"), std::string::npos)
      << filled.reason;

  // All black.
  const cv::Mat black(400, 600, CV_8UC3, cv::Scalar(0, 0, 0));
  const VirtualFiducialResult dark =
      FindVirtualFiducials(MakeLinearScan(black, true), {});
  EXPECT_FALSE(dark.success);
  EXPECT_EQ(dark.num_edges, 0);

  // Too small to search.
  const cv::Mat tiny(8, 8, CV_8UC1, cv::Scalar(0));
  EXPECT_FALSE(FindVirtualFiducials(MakeLinearScan(tiny, true), {}).success);
}

TEST(VirtualFiducials, ShearedFrameIsNotPerpendicular) {
  ScanSpec spec;
  spec.shear = 0.03;  // 1.7 degrees
  const VirtualFiducialResult result = Measure(spec);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.num_corners, 4);
  EXPECT_NEAR(result.max_corner_angle_deviation_deg,
              std::atan(0.03) * 180 / M_PI,
              0.05);
  EXPECT_NE(result.reason.find("not perpendicular"), std::string::npos)
      << result.reason;
}

TEST(VirtualFiducials, WrongFrameSizeGivesNonSquarePixels) {
  ScanSpec spec;
  VirtualFiducialOptions options;
  const LinearScan scan = MakeLinearScan(RenderScan(spec), true);
  options.frame_height_mm = 26;  // the frame is 24 mm high
  const VirtualFiducialResult result = FindVirtualFiducials(scan, options);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.reason.find("not square"), std::string::npos)
      << result.reason;
}

TEST(VirtualFiducials, RobustLineFitRejectsBlunders) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.1);
  std::uniform_real_distribution<double> blunder(2, 30);
  std::vector<Eigen::Vector2d> points;
  int num_blunders = 0;
  for (int i = 0; i < 300; ++i) {
    const double along = i + 0.5;
    double across = 0.013 * along + 40.2 + noise(rng);
    if (i % 10 < 3) {  // 30 % blunders
      across += blunder(rng);
      ++num_blunders;
    }
    points.emplace_back(along, across);
  }
  VirtualFiducialOptions options;
  const EdgeLineFit fit = FitEdgeLine(points, options);
  ASSERT_TRUE(fit.success) << fit.reason;
  EXPECT_NEAR(fit.slope, 0.013, 1e-4);
  EXPECT_NEAR(fit.offset, 40.2, 0.05);
  EXPECT_NEAR(fit.rms_px, 0.1, 0.02);
  // Every blunder rejected, and of the good points only those beyond
  // 3 sigma (0.3 % of them expected, a few at most).
  int good_rejected = 0;
  for (int i = 0; i < 300; ++i) {
    if (i % 10 < 3) {
      EXPECT_FALSE(fit.inliers[i]) << i;
    } else {
      good_rejected += !fit.inliers[i];
    }
  }
  EXPECT_LE(good_rejected, 4);
  EXPECT_EQ(fit.num_points - fit.num_inliers, num_blunders + good_rejected);

  // Scatter: the robust scale follows it, and the residuals show that this
  // is no edge (FindVirtualFiducials rejects it by max_rms_px).
  std::uniform_real_distribution<double> scatter(0, 50);
  std::vector<Eigen::Vector2d> random;
  for (int i = 0; i < 300; ++i) random.emplace_back(i, scatter(rng));
  const EdgeLineFit none = FitEdgeLine(random, options);
  EXPECT_GT(none.rms_px, 20 * options.max_rms_px);

  // Too few points.
  random.resize(options.min_edge_points - 1);
  const EdgeLineFit few = FitEdgeLine(random, options);
  EXPECT_FALSE(few.success);
  EXPECT_NE(few.reason.find("too few edge points"), std::string::npos);
}

TEST(VirtualFiducials, ClippedChannelsAreLeftOut) {
  // Blue and green exposed 4 x: the photograph clips in them (texture 0.1 to
  // 0.6 times 4), and a pixel that the edge crosses is no longer the linear
  // mix of border and scene there; red is not clipped.
  ScanSpec spec;
  spec.rotation_deg = 0.8;
  spec.gain = Eigen::Vector3d(4, 4, 1);
  const LinearScan scan = MakeLinearScan(RenderScan(spec), true);
  const VirtualFiducialResult result = FindVirtualFiducials(scan, {});
  ASSERT_TRUE(result.success) << Describe(result);
  const double error = MaxCornerError(result, spec);
  EXPECT_LT(error, 0.06);
  // Without the masks the clipped channels pull every edge outwards.
  LinearScan unmasked = scan;
  for (cv::Mat& mask : unmasked.clipped)
    mask = cv::Mat::zeros(mask.size(), CV_8U);
  const VirtualFiducialResult biased = FindVirtualFiducials(unmasked, {});
  ASSERT_TRUE(biased.success) << Describe(biased);
  std::cout << "clipped blue and green: corners within " << error
            << " px; with them " << MaxCornerError(biased, spec) << " px\n";
  EXPECT_GT(MaxCornerError(biased, spec), 3 * error);

  // The photograph clipped in every channel (0.1 to 0.6 times 20), the
  // border not (0.06): no edge can be measured.
  spec.gain = Eigen::Vector3d(20, 20, 20);
  const VirtualFiducialResult white = Measure(spec);
  EXPECT_FALSE(white.success);
  EXPECT_EQ(white.num_edges, 0);
  for (const FrameEdge& edge : white.edges) {
    EXPECT_GT(edge.num_saturated_lines, 300) << FrameSideName(edge.side);
  }
  EXPECT_NE(white.reason.find("clipped in every channel"), std::string::npos)
      << white.reason;
}

TEST(VirtualFiducials, LinearScanDecodesAndFlagsClippedValues) {
  cv::Mat gray(1, 3, CV_8UC1);
  gray.at<uint8_t>(0, 0) = 0;
  gray.at<uint8_t>(0, 1) = 188;  // sRGB 188 is linear 0.5
  gray.at<uint8_t>(0, 2) = 255;
  const LinearScan linear = MakeLinearScan(gray, true);
  ASSERT_EQ(linear.channels.size(), 1u);
  EXPECT_FLOAT_EQ(linear.channels[0].at<float>(0, 0), 0.0f);
  EXPECT_NEAR(linear.channels[0].at<float>(0, 1), 0.5, 0.003);
  EXPECT_FLOAT_EQ(linear.channels[0].at<float>(0, 2), 1.0f);
  EXPECT_EQ(linear.clipped[0].at<uint8_t>(0, 1), 0);
  EXPECT_EQ(linear.clipped[0].at<uint8_t>(0, 2), 255);
  EXPECT_NEAR(MakeLinearScan(gray, false).channels[0].at<float>(0, 1),
              188 / 255.0,
              1e-6);
  // 250 of 255 is above the default clip level 0.98, 249 is not.
  gray.at<uint8_t>(0, 1) = 250;
  gray.at<uint8_t>(0, 2) = 249;
  const LinearScan near_top = MakeLinearScan(gray, true);
  EXPECT_EQ(near_top.clipped[0].at<uint8_t>(0, 1), 255);
  EXPECT_EQ(near_top.clipped[0].at<uint8_t>(0, 2), 0);
  EXPECT_EQ(MakeLinearScan(gray, true, 1.0).clipped[0].at<uint8_t>(0, 1), 0);
  // 16-bit BGRA: three colour channels, alpha dropped.
  cv::Mat colour(1, 1, CV_16UC4, cv::Scalar(65535, 0, 1000, 7));
  const LinearScan bgr = MakeLinearScan(colour, false);
  ASSERT_EQ(bgr.channels.size(), 3u);
  EXPECT_EQ(bgr.clipped[0].at<uint8_t>(0, 0), 255);
  EXPECT_EQ(bgr.clipped[2].at<uint8_t>(0, 0), 0);
  EXPECT_NEAR(bgr.channels[2].at<float>(0, 0), 1000 / 65535.0, 1e-7);
  // Floating point: as it is, never clipped.
  const LinearScan floating =
      MakeLinearScan(cv::Mat(2, 2, CV_32FC1, cv::Scalar(1.5)), true);
  EXPECT_FLOAT_EQ(floating.channels[0].at<float>(1, 1), 1.5f);
  EXPECT_EQ(cv::countNonZero(floating.clipped[0]), 0);
  EXPECT_THROW(MakeLinearScan(cv::Mat(2, 2, CV_16SC1), true), InputError);
  EXPECT_THROW(MakeLinearScan(cv::Mat(), true), InputError);
}

TEST(VirtualFiducials, OptionsAreChecked) {
  VirtualFiducialOptions options;
  options.frame_width_mm = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.search_fraction = 0.7;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.scan_resolution_um = -1;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
