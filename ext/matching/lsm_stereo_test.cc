// SPDX-License-Identifier: BSD-3-Clause
//
// Least-squares matching against the correlation peak on real stereo pairs
// with true disparity (../shared/data/stereo-gt: Middlebury 2003 cones and
// teddy, rectified, quarter size; truth value = 4 x disparity, 0 unknown),
// for the Moravec points of the left image:
//   correlation  the integer NCC peak along the same row (15 x 15 windows,
//                disparities 0..63) and a parabola through it and its two
//                neighbours;
//   LSM          least-squares matching (15 x 15, affine + radiometry,
//                unconstrained, so y may move too) from the parabola's
//                position, with refine_keypoints' options and blunder checks
//                (convergence, sigma0, correlation, precision, shift,
//                back-matching).
// Two sets of points:
//   unoccluded   truth known at the point and confirmed by the right
//                view's truth at the conjugate (within 1 pixel): errors
//                beyond 1 pixel are blunders, and the share of LSM's
//                blunders that its checks catch is reported;
//   valid truth  besides, truth known over the whole window and planar
//                there (a plane fits it to 0.15 pixel, what the quarter-
//                pixel quantisation leaves): the window sees one surface,
//                which both methods assume, and the plane's value at the
//                point is the truth (free of the quantisation). The RMS
//                errors are compared on the points where neither blundered.
#include "ext/features/moravec.h"
#include "ext/image/image_io.h"
#include "ext/matching/keypoint_refinement.h"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/stereo_gt_testing.h"
#include "tests/testing.h"

namespace bayon {
namespace {

constexpr int kRadius = 7;  // 15 x 15 windows for both methods
constexpr int kMaxDisparity = 63;
constexpr double kBlunderPx = 1.0;
// Left and right truth must agree this well, pixels; else occluded.
constexpr double kMaxTruthDisagreementPx = 1.0;
// Largest RMS deviation of the window's truth from a plane, pixels.
constexpr double kMaxPlaneResidualPx = 0.15;

// Zero-mean, unit-norm window of side 2 kRadius + 1 around pixel (col, row);
// false where it leaves the image or is flat.
bool NormalizedWindow(const cv::Mat& image,
                      int col,
                      int row,
                      std::vector<double>* window) {
  if (col < kRadius || row < kRadius || col + kRadius >= image.cols ||
      row + kRadius >= image.rows) {
    return false;
  }
  window->clear();
  double sum = 0;
  for (int v = -kRadius; v <= kRadius; ++v) {
    for (int u = -kRadius; u <= kRadius; ++u) {
      window->push_back(image.at<float>(row + v, col + u));
      sum += window->back();
    }
  }
  const double mean = sum / window->size();
  double norm = 0;
  for (double& value : *window) {
    value -= mean;
    norm += value * value;
  }
  if (norm < 1e-6) return false;
  for (double& value : *window) value /= std::sqrt(norm);
  return true;
}

// Disparity along the row by the NCC peak and a parabola through it; false
// where the peak is at the end of the range or a window leaves the image.
bool ParabolaDisparity(const testing::StereoPair& pair,
                       int col,
                       int row,
                       double* disparity) {
  std::vector<double> left, right;
  if (!NormalizedWindow(pair.left, col, row, &left)) return false;
  std::vector<double> ncc(kMaxDisparity + 1, -2.0);
  int best = -1;
  for (int d = 0; d <= kMaxDisparity; ++d) {
    if (!NormalizedWindow(pair.right, col - d, row, &right)) continue;
    double r = 0;
    for (size_t k = 0; k < left.size(); ++k) r += left[k] * right[k];
    ncc[d] = r;
    if (best < 0 || r > ncc[best]) best = d;
  }
  if (best <= 0 || best >= kMaxDisparity || ncc[best - 1] < -1 ||
      ncc[best + 1] < -1) {
    return false;
  }
  const double a = ncc[best - 1], b = ncc[best], c = ncc[best + 1];
  const double curvature = a - 2 * b + c;
  if (!(curvature < 0)) return false;
  *disparity = best + 0.5 * (a - c) / curvature;
  return true;
}

struct PointResult {
  double truth = 0;         // at the pixel (quarter pixels)
  bool planar = false;      // valid truth (header comment)
  double planar_truth = 0;  // the plane's value
  double parabola = 0;
  double lsm = 0;             // LSM's solution, accepted or not
  bool lsm_accepted = false;  // passed the blunder checks
};

struct SceneResult {
  int num_points = 0;    // Moravec points
  int num_unknown = 0;   // no truth at the point
  int num_occluded = 0;  // left and right truth disagree
  int num_no_peak = 0;   // no correlation peak inside the range
  std::vector<PointResult> points;
};

SceneResult EvaluateScene(const std::string& scene) {
  const testing::StereoPair pair = testing::ReadStereoPair(scene);
  MoravecOptions moravec;
  moravec.max_num_features = 2000;
  moravec.border_px = kRadius + 3;
  const KeypointRefinementOptions options;
  const cv::Mat left = SmoothForMatching(pair.left, options);
  const cv::Mat right = SmoothForMatching(pair.right, options);
  SceneResult result;
  for (const InterestPoint& point : DetectMoravecPoints(pair.left, moravec)) {
    ++result.num_points;
    const int col = static_cast<int>(std::floor(point.xy.x()));
    const int row = static_cast<int>(std::floor(point.xy.y()));
    const int value = pair.left_truth.at<uint8_t>(row, col);
    if (value == 0) {
      ++result.num_unknown;
      continue;
    }
    PointResult p;
    p.truth = value / 4.0;
    const int right_col = static_cast<int>(std::lround(col - p.truth));
    const int right_value =
        right_col >= 0 ? pair.right_truth.at<uint8_t>(row, right_col) : 0;
    if (right_value == 0 ||
        std::abs(right_value / 4.0 - p.truth) > kMaxTruthDisagreementPx) {
      ++result.num_occluded;
      continue;
    }
    if (!ParabolaDisparity(pair, col, row, &p.parabola)) {
      ++result.num_no_peak;
      continue;
    }
    p.planar = testing::PlanarTruth(pair.left_truth,
                                    col,
                                    row,
                                    kRadius,
                                    kMaxPlaneResidualPx,
                                    &p.planar_truth);
    const Eigen::Vector2d left_xy(col + 0.5, row + 0.5);
    const ObservationRefinement lsm =
        RefineObservation(left,
                          left_xy,
                          right,
                          left_xy - Eigen::Vector2d(p.parabola, 0),
                          Eigen::Matrix2d::Identity(),
                          options);
    p.lsm = left_xy.x() - lsm.matched_xy.x();
    p.lsm_accepted = lsm.outcome == ObservationOutcome::kRefined;
    result.points.push_back(p);
  }
  return result;
}

double Rms(const std::vector<double>& errors) {
  double sum = 0;
  for (double e : errors) sum += e * e;
  return errors.empty() ? 0.0 : std::sqrt(sum / errors.size());
}

double Share(int part, int whole) {
  return whole > 0 ? 100.0 * part / whole : 0.0;
}

struct Precision {
  int num_points = 0;  // valid truth
  int num_clean = 0;   // neither method blundered
  double parabola_rms = 0, lsm_rms = 0;
  int num_accepted = 0;  // of the clean ones, LSM accepted
  double parabola_rms_accepted = 0, lsm_rms_accepted = 0;
};

Precision ComputePrecision(const SceneResult& scene) {
  Precision f;
  std::vector<double> parabola, lsm, parabola_accepted, lsm_accepted;
  for (const PointResult& p : scene.points) {
    if (!p.planar) continue;
    ++f.num_points;
    const double e_parabola = p.parabola - p.planar_truth;
    const double e_lsm = p.lsm - p.planar_truth;
    if (!(std::abs(e_parabola) <= kBlunderPx &&
          std::abs(e_lsm) <= kBlunderPx)) {
      continue;
    }
    parabola.push_back(e_parabola);
    lsm.push_back(e_lsm);
    if (p.lsm_accepted) {
      parabola_accepted.push_back(e_parabola);
      lsm_accepted.push_back(e_lsm);
    }
  }
  f.num_clean = static_cast<int>(parabola.size());
  f.parabola_rms = Rms(parabola);
  f.lsm_rms = Rms(lsm);
  f.num_accepted = static_cast<int>(parabola_accepted.size());
  f.parabola_rms_accepted = Rms(parabola_accepted);
  f.lsm_rms_accepted = Rms(lsm_accepted);
  return f;
}

struct Blunders {
  int num_points = 0;  // unoccluded
  int num_parabola = 0, num_lsm = 0;
  int num_lsm_caught = 0;       // LSM blunders its checks rejected
  int num_parabola_caught = 0;  // parabola blunders LSM rejected
  int num_lsm_good = 0;
  int num_good_rejected = 0;  // LSM within 1 pixel, rejected anyway
};

Blunders ComputeBlunders(const SceneResult& scene) {
  Blunders b;
  for (const PointResult& p : scene.points) {
    ++b.num_points;
    const bool parabola = std::abs(p.parabola - p.truth) > kBlunderPx;
    const bool lsm = !(std::abs(p.lsm - p.truth) <= kBlunderPx);
    b.num_parabola += parabola;
    b.num_parabola_caught += parabola && !p.lsm_accepted;
    b.num_lsm += lsm;
    b.num_lsm_caught += lsm && !p.lsm_accepted;
    b.num_lsm_good += !lsm;
    b.num_good_rejected += !lsm && !p.lsm_accepted;
  }
  return b;
}

void Print(const std::string& scene,
           const SceneResult& r,
           const Precision& f,
           const Blunders& b) {
  std::printf(
      "\n%s: %d Moravec points: %d without truth, %d occluded, %d without a "
      "correlation peak in 0..%d; %d unoccluded, %d of them with valid "
      "(planar) truth\n",
      scene.c_str(),
      r.num_points,
      r.num_unknown,
      r.num_occluded,
      r.num_no_peak,
      kMaxDisparity,
      b.num_points,
      f.num_points);
  std::printf(
      "%-40s %7s %10s\n", "disparity error, valid truth", "points", "RMS px");
  std::printf("%-40s %7d %10.4f\n",
              "NCC peak + parabola (neither blundered)",
              f.num_clean,
              f.parabola_rms);
  std::printf(
      "%-40s %7d %10.4f\n", "LSM (the same points)", f.num_clean, f.lsm_rms);
  std::printf("%-40s %7d %10.4f\n",
              "NCC peak + parabola (LSM accepted)",
              f.num_accepted,
              f.parabola_rms_accepted);
  std::printf("%-40s %7d %10.4f\n",
              "LSM (accepted)",
              f.num_accepted,
              f.lsm_rms_accepted);
  std::printf(
      "blunders (> %.1f px) of %d unoccluded points: parabola %d, LSM %d; "
      "LSM's checks caught %d of LSM's (%.1f %%) and %d of the parabola's "
      "(%.1f %%), and rejected %d of %d good LSM results (%.1f %%)\n",
      kBlunderPx,
      b.num_points,
      b.num_parabola,
      b.num_lsm,
      b.num_lsm_caught,
      Share(b.num_lsm_caught, b.num_lsm),
      b.num_parabola_caught,
      Share(b.num_parabola_caught, b.num_parabola),
      b.num_good_rejected,
      b.num_lsm_good,
      Share(b.num_good_rejected, b.num_lsm_good));
  std::fflush(stdout);
}

void CheckScene(const std::string& scene) {
  const SceneResult result = EvaluateScene(scene);
  const Precision precision = ComputePrecision(result);
  const Blunders blunders = ComputeBlunders(result);
  Print(scene, result, precision, blunders);
  // Enough points for the RMS to mean something.
  ASSERT_GT(precision.num_clean, 250);
  ASSERT_GT(precision.num_accepted, 250);
  EXPECT_LT(precision.lsm_rms, precision.parabola_rms);
  EXPECT_LT(precision.lsm_rms_accepted, precision.parabola_rms_accepted);
  // The checks catch most of LSM's blunders, and keep most good results.
  ASSERT_GT(blunders.num_lsm, 20);
  EXPECT_GT(Share(blunders.num_lsm_caught, blunders.num_lsm), 70.0);
  EXPECT_LT(Share(blunders.num_good_rejected, blunders.num_lsm_good), 25.0);
}

TEST(LsmStereo, ConesLsmBeatsTheParabolaAgainstTrueDisparity) {
  BAYON_REQUIRE_DATA("stereo-gt/cones/disp2.png");
  CheckScene("cones");
}

TEST(LsmStereo, TeddyLsmBeatsTheParabolaAgainstTrueDisparity) {
  BAYON_REQUIRE_DATA("stereo-gt/teddy/disp2.png");
  CheckScene("teddy");
}

}  // namespace
}  // namespace bayon
