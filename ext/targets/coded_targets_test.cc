// SPDX-License-Identifier: BSD-3-Clause
#include "ext/targets/coded_targets.h"

#include "ext/core/errors.h"

#include <Eigen/Geometry>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "tests/testing.h"

namespace bayon {
namespace {

using ::testing::HasSubstr;

constexpr int kSupersampling = 4;
constexpr int kCellPx = 32;  // of the marker's drawing

// The printed marker with a white margin of one cell, kCellPx per cell.
cv::Mat MarkerDrawing(const std::string& dictionary, int code) {
  const cv::Mat pattern = CodedTargetPattern(dictionary, code);
  cv::Mat drawing(pattern.rows + 2, pattern.cols + 2, CV_8U, cv::Scalar(255));
  pattern.copyTo(drawing(cv::Rect(1, 1, pattern.cols, pattern.rows)));
  cv::resize(drawing, drawing, cv::Size(), kCellPx, kCellPx, cv::INTER_NEAREST);
  return drawing;
}

// A marker seen by a camera: side_px long on average, tilted by tilt_deg,
// turned by any angle, at `where` (COLMAP pixels). Rendered at
// kSupersampling times the size and averaged down (the pixels integrate the
// light), on a grey background. Returns the true centre.
Eigen::Vector2d RenderMarker(const cv::Mat& drawing,
                             double side_px,
                             double tilt_deg,
                             double turn_deg,
                             double azimuth_deg,
                             const Eigen::Vector2d& where,
                             cv::Mat* photo) {
  const double s = kSupersampling;
  // The drawing in a plane: its centre at the origin, in cells.
  const double cells = drawing.cols / static_cast<double>(kCellPx);
  const double centre_cv = (drawing.cols - 1) / 2.0;  // OpenCV coordinates
  Eigen::Matrix3d to_plane;
  to_plane << 1.0 / kCellPx, 0, -centre_cv / kCellPx,  //
      0, 1.0 / kCellPx, -centre_cv / kCellPx,          //
      0, 0, 1;
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(turn_deg * M_PI / 180, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(tilt_deg * M_PI / 180,
                         Eigen::Vector3d(std::cos(azimuth_deg * M_PI / 180),
                                         std::sin(azimuth_deg * M_PI / 180),
                                         0)))
          .toRotationMatrix();
  // The marker's printed side (cells - 2 of the drawing's) at distance z
  // and focal f spans side_px.
  const double f = 1000 * s, z = 20.0;
  const double scale = side_px * s * z / f / (cells - 2);
  Eigen::Matrix3d pose;
  pose.col(0) = scale * R.col(0);
  pose.col(1) = scale * R.col(1);
  pose.col(2) = Eigen::Vector3d(0, 0, z);
  Eigen::Matrix3d K;
  // where (COLMAP, photo) -> OpenCV coordinates of the supersampled photo.
  K << f, 0, where.x() * s - 0.5, 0, f, where.y() * s - 0.5, 0, 0, 1;
  const Eigen::Matrix3d H = K * pose * to_plane;
  cv::Mat H_cv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) H_cv.at<double>(r, c) = H(r, c);
  }
  cv::Mat big;
  cv::warpPerspective(
      drawing,
      big,
      H_cv,
      cv::Size(photo->cols * kSupersampling, photo->rows * kSupersampling),
      cv::INTER_LINEAR,
      cv::BORDER_CONSTANT,
      cv::Scalar(128));
  cv::Mat small;
  cv::resize(big, small, photo->size(), 0, 0, cv::INTER_AREA);
  // Only where the marker is: the rest of the photograph stays.
  cv::Mat mask;
  cv::warpPerspective(cv::Mat(drawing.size(), CV_8U, cv::Scalar(255)),
                      mask,
                      H_cv,
                      big.size(),
                      cv::INTER_NEAREST);
  cv::resize(mask, mask, photo->size(), 0, 0, cv::INTER_AREA);
  small.copyTo(*photo, mask > 0);
  const Eigen::Vector3d centre = H * Eigen::Vector3d(centre_cv, centre_cv, 1);
  return (centre.hnormalized().array() + 0.5) / s;
}

void AddNoise(double sigma, uint32_t seed, cv::Mat* photo) {
  cv::Mat noise(photo->size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat sum;
  photo->convertTo(sum, CV_32F);
  sum += noise;
  sum.convertTo(*photo, CV_8U);  // rounds and saturates
}

// Measured against the truth: markers of 24 to 60 px, tilted up to 60
// degrees, turned anyhow, under noise of 2 grey values. Every one is found
// with its code, the centres lie within 0.1 px RMS (the bound) and
// the stated standard deviations do not understate the errors.
TEST(CodedTargets, FindsEveryMarkerWithItsCodeAndCentreToATenthPixel) {
  const CodedTargetOptions options;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  double error_sq = 0, stated_sq = 0, worst = 0;
  int num_markers = 0;
  for (int photo_index = 0; photo_index < 10; ++photo_index) {
    cv::Mat photo(480, 640, CV_8U, cv::Scalar(128));
    std::map<int, Eigen::Vector2d> truth;
    for (int slot = 0; slot < 4; ++slot) {
      const int code = photo_index * 4 + slot;
      const Eigen::Vector2d where(
          160 + 320 * (slot % 2) + 40 * (uniform(random) - 0.5),
          120 + 240 * (slot / 2) + 40 * (uniform(random) - 0.5));
      truth[code] = RenderMarker(MarkerDrawing(options.dictionary, code),
                                 24 + 36 * uniform(random),
                                 60 * uniform(random),
                                 360 * uniform(random),
                                 360 * uniform(random),
                                 where,
                                 &photo);
    }
    AddNoise(2.0, photo_index + 1, &photo);
    CodedTargetReport report;
    const std::vector<CodedTarget> targets =
        DetectCodedTargets(photo, options, "photo.png", &report);
    ASSERT_EQ(targets.size(), truth.size())
        << "photograph " << photo_index << ": " << report.num_decoded
        << " decoded, refused: "
        << (report.refused.empty() ? "" : report.refused[0]);
    for (const CodedTarget& target : targets) {
      ASSERT_TRUE(truth.count(target.code)) << target.name;
      EXPECT_EQ(target.name, "CT" + std::to_string(target.code));
      const double error = (target.centre - truth.at(target.code)).norm();
      error_sq += error * error;
      stated_sq += target.covariance.trace();
      worst = std::max(worst, error);
      ++num_markers;
    }
  }
  const double rms = std::sqrt(error_sq / num_markers);
  const double stated = std::sqrt(stated_sq / num_markers);
  RecordProperty("centre_rms_px", std::to_string(rms));
  RecordProperty("stated_rms_px", std::to_string(stated));
  std::cout << num_markers << " markers: centre error RMS " << rms
            << " px, worst " << worst << " px; stated " << stated << " px\n";
  // Measured: 0.013 px, stated 0.052 px. The scatter of the edge points
  // alone states 0.032 px here, but on the rendered 1800 x 1200 tower only
  // a quarter of the true error (0.010 px against 0.038 px): there the
  // errors are the edge locator's own, shared along a side. The stated
  // sigma therefore carries edge_bias_px, and errs on the safe side on
  // these ideal markers; it must not understate the error, nor be so
  // large that a bundle would throw the targets' precision away.
  EXPECT_LT(rms, 0.1);
  EXPECT_LT(rms / stated, 1.5);
  EXPECT_LT(stated, 0.1);
}

TEST(CodedTargets, ACodeSeenTwiceNamesThePhotograph) {
  const CodedTargetOptions options;
  cv::Mat photo(480, 640, CV_8U, cv::Scalar(128));
  const cv::Mat drawing = MarkerDrawing(options.dictionary, 3);
  RenderMarker(drawing, 40, 10, 0, 0, Eigen::Vector2d(160, 240), &photo);
  RenderMarker(drawing, 40, 10, 30, 90, Eigen::Vector2d(480, 240), &photo);
  try {
    DetectCodedTargets(photo, options, "IMG_0042.JPG", nullptr);
    FAIL() << "a code seen twice was accepted";
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("IMG_0042.JPG"));
    EXPECT_THAT(error.what(), HasSubstr("CT3 is seen twice"));
  }
}

// A side covered in part: the occluder's edge points are left out of the
// side's line, so that the target is measured from the rest about as
// precisely as the uncovered one. (Were more than half of a side covered,
// the target would be left out, with its reason.)
TEST(CodedTargets, APartlyCoveredSideDoesNotMoveTheCentre) {
  const CodedTargetOptions options;
  // A twig across the side, and a dark blot of two sizes on its edge.
  for (int occluder = 0; occluder < 3; ++occluder) {
    cv::Mat photo(480, 640, CV_8U, cv::Scalar(128));
    // Codes 5 and 6 side by side, alike.
    const auto render = [&](int code, double x) {
      return RenderMarker(MarkerDrawing(options.dictionary, code),
                          60,
                          10,
                          5,
                          0,
                          Eigen::Vector2d(x, 240),
                          &photo);
    };
    const Eigen::Vector2d truth5 = render(5, 160);
    const Eigen::Vector2d truth6 = render(6, 480);
    if (occluder == 0) {
      cv::line(photo, cv::Point(150, 195), cv::Point(166, 220), 0, 2);
    } else {
      cv::circle(photo, cv::Point(165, 209), 2 * occluder, 0, cv::FILLED);
    }
    CodedTargetReport report;
    const std::vector<CodedTarget> targets =
        DetectCodedTargets(photo, options, "photo.png", &report);
    std::map<std::string, Eigen::Vector2d> centre;
    for (const CodedTarget& target : targets) {
      centre[target.name] = target.centre;
    }
    ASSERT_TRUE(centre.count("CT6"));
    EXPECT_LT((centre["CT6"] - truth6).norm(), 0.1);
    // Measured: 0.0034, 0.0027 and 0.0023 px from the truth; with every
    // edge point in the lines, 0.0076 px, refused ("side 1 is not
    // straight") and 0.057 px.
    ASSERT_TRUE(centre.count("CT5"))
        << occluder << ": "
        << (report.refused.empty() ? "not decoded" : report.refused[0]);
    EXPECT_LT((centre["CT5"] - truth5).norm(), 0.02) << occluder;
  }
}

TEST(CodedTargets, RefusesBadOptionsAndImages) {
  CodedTargetOptions options;
  options.dictionary = "aruco_3x3";
  try {
    options.Check();
    FAIL();
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("aruco_4x4_50, aruco_5x5_100"));
  }
  options = CodedTargetOptions();
  options.min_side_px = 4;
  EXPECT_THROW(options.Check(), InputError);
  options = CodedTargetOptions();
  const cv::Mat floating(10, 10, CV_32F, cv::Scalar(0));
  EXPECT_THROW(DetectCodedTargets(floating, options, "x.tif", nullptr),
               InputError);
  EXPECT_THROW(CodedTargetPattern("aruco_4x4_50", 50), InputError);
  EXPECT_EQ(ParseCodedTargetCodes("0-3,9"), std::vector<int>({0, 1, 2, 3, 9}));
  EXPECT_THROW(ParseCodedTargetCodes("4-2"), InputError);
  EXPECT_THROW(ParseCodedTargetCodes("a"), InputError);
  EXPECT_EQ(CodedTargetDictionarySize("apriltag_36h11"), 587);
}

// The sheet: every code once, its black cells as the dictionary draws
// them, and too many for the page refused.
TEST(CodedTargets, PrintsASheetOfTheCodes) {
  const std::string dir = testing::TempDir("coded_target_sheet");
  const CodedTargetOptions options;
  const std::vector<int> codes = {0, 1, 7, 49};
  WriteCodedTargetSheet(options, codes, 40, dir + "/sheet.svg");
  std::ifstream in(dir + "/sheet.svg");
  std::stringstream text;
  text << in.rdbuf();
  const std::string svg = text.str();
  int black_cells = 0;
  for (int code : codes) {
    EXPECT_THAT(svg, HasSubstr("<g id=\"CT" + std::to_string(code) + "\""));
    const cv::Mat pattern = CodedTargetPattern(options.dictionary, code);
    black_cells += pattern.total() - cv::countNonZero(pattern);
  }
  int rects = -1;  // the page's white rectangle
  for (size_t at = svg.find("<rect"); at != std::string::npos;
       at = svg.find("<rect", at + 1)) {
    ++rects;
  }
  EXPECT_EQ(rects, black_cells);
  std::vector<int> many(50);
  for (int i = 0; i < 50; ++i) many[i] = i;
  try {
    WriteCodedTargetSheet(options, many, 60, dir + "/too_many.svg");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr("do not fit on an A4 page"));
  }
}

}  // namespace
}  // namespace bayon
