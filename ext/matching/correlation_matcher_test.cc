// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/correlation_matcher.h"

#include "ext/features/moravec.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace bayon {
namespace {

cv::Mat Texture(int width, int height, unsigned seed) {
  cv::Mat fine(height, width, CV_32F), coarse(height / 8, width / 8, CV_32F);
  cv::RNG rng(seed);
  rng.fill(fine, cv::RNG::UNIFORM, 0, 255);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(fine, fine, cv::Size(0, 0), 1.3);
  cv::resize(coarse, coarse, fine.size(), 0, 0, cv::INTER_CUBIC);
  return 0.6 * fine + 0.4 * coarse;
}

struct Pair {
  cv::Mat image1, image2;
  // Truth in COLMAP pixel coordinates: p2 = A p1 + b.
  Eigen::Matrix2d A;
  Eigen::Vector2d b;
};

// Image 2 is image 1 scaled by `scale` and shifted by `shift` (OpenCV's
// integer pixel centres), then turned by `quarter_turns` clockwise.
Pair MakePair(double scale, Eigen::Vector2d shift, int quarter_turns) {
  Pair pair;
  pair.image1 = Texture(360, 270, 9);
  cv::Mat warp =
      (cv::Mat_<double>(2, 3) << scale, 0, shift.x(), 0, scale, shift.y());
  cv::Mat warped;
  cv::warpAffine(pair.image1,
                 warped,
                 warp,
                 pair.image1.size(),
                 cv::INTER_CUBIC,
                 cv::BORDER_REFLECT);
  // COLMAP coordinates are OpenCV's plus one half.
  Eigen::Matrix2d A = scale * Eigen::Matrix2d::Identity();
  Eigen::Vector2d b =
      shift + Eigen::Vector2d(0.5, 0.5) - A * Eigen::Vector2d(0.5, 0.5);
  const double w = pair.image1.cols, h = pair.image1.rows;
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  if (quarter_turns == 1) {
    cv::rotate(warped, pair.image2, cv::ROTATE_90_CLOCKWISE);
    R << 0, -1, 1, 0;  // (x, y) -> (h - y, x)
    t << h, 0;
  } else if (quarter_turns == 2) {
    cv::rotate(warped, pair.image2, cv::ROTATE_180);
    R << -1, 0, 0, -1;
    t << w, h;
  } else {
    pair.image2 = warped;
  }
  pair.A = R * A;
  pair.b = R * b + t;
  return pair;
}

ImagePatches Patches(const cv::Mat& image) {
  MoravecOptions moravec;
  moravec.max_num_features = 800;
  std::vector<Eigen::Vector2d> xy;
  for (const InterestPoint& p : DetectMoravecPoints(image, moravec)) {
    xy.push_back(p.xy.cast<double>());
  }
  return ExtractImagePatches(image, xy, PatchOptions());
}

void ExpectAccurateMatches(const Pair& pair, int quarter_turns) {
  const ImagePatches patches1 = Patches(pair.image1);
  const ImagePatches patches2 = Patches(pair.image2);
  CorrelationMatchingOptions options;
  const PairMatches result = MatchImagePatches(patches1, patches2, options);
  EXPECT_TRUE(result.mapping.found);
  EXPECT_EQ(result.mapping.quarter_turns, quarter_turns);
  const int n = static_cast<int>(result.matches.rows());
  EXPECT_GT(n, 200) << "of " << patches1.size() << " points";
  int wrong = 0;
  double sum2 = 0;
  int num_good = 0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d truth = pair.A * result.reference_xy1[k] + pair.b;
    const double error = (result.refined_xy2[k] - truth).norm();
    // The reference is the centre of the image-1 keypoint's pixel.
    EXPECT_LT(
        (result.reference_xy1[k] - patches1.xy[result.matches(k, 0)]).norm(),
        0.71);
    if (error > 1.0) {
      ++wrong;
    } else {
      sum2 += error * error;
      ++num_good;
    }
  }
  EXPECT_LE(wrong, n / 50) << wrong << " of " << n << " matches off by > 1 px";
  // Sub-pixel: bilinear texture, cubic resampling, parabola peak.
  EXPECT_LT(std::sqrt(sum2 / num_good), 0.15);
}

TEST(CorrelationMatcher, ShiftedImage) {
  ExpectAccurateMatches(MakePair(1.0, {23.4, -11.7}, 0), 0);
}

TEST(CorrelationMatcher, TurnedImagesAreFoundAndMatched) {
  ExpectAccurateMatches(MakePair(1.03, {-14.2, 6.6}, 2), 2);
  ExpectAccurateMatches(MakePair(0.98, {5.3, 9.1}, 1), 1);
}

TEST(CorrelationMatcher, UnrelatedImagesGiveNoGlobalMappingAndFewMatches) {
  // Smooth random textures correlate by chance; the global mapping must not
  // be fooled, and relaxation leaves only a few chance clusters (which the
  // relative orientation then finds inconsistent).
  for (unsigned seed : {1, 2, 3}) {
    const ImagePatches patches1 = Patches(Texture(360, 270, seed));
    const ImagePatches patches2 = Patches(Texture(360, 270, seed + 10));
    const PairMatches result =
        MatchImagePatches(patches1, patches2, CorrelationMatchingOptions());
    EXPECT_FALSE(result.mapping.found);
    EXPECT_LT(result.matches.rows(), patches1.size() / 10);
  }
}

// Keypoints of image 2 one pixel off their features (as Moravec points of
// two photographs are), on a fine texture: the keypoint windows alone
// correlate poorly, the shifted ones find the pairs, and the refinement the
// exact position.
TEST(CorrelationMatcher, CandidatesTolerateKeypointsOffByAPixel) {
  cv::Mat image1(270, 360, CV_32F);
  cv::RNG rng(12);
  rng.fill(image1, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image1, image1, cv::Size(0, 0), 1.0);
  // Image 2: image 1 shifted by whole pixels, so the truth is exact.
  const Eigen::Vector2d shift(7, -4);
  cv::Mat image2;
  const cv::Mat warp =
      (cv::Mat_<double>(2, 3) << 1, 0, shift.x(), 0, 1, shift.y());
  cv::warpAffine(image1,
                 image2,
                 warp,
                 image1.size(),
                 cv::INTER_NEAREST,
                 cv::BORDER_REFLECT);
  const ImagePatches patches1 = Patches(image1);
  std::vector<Eigen::Vector2d> xy2;
  for (int i = 0; i < patches1.size(); ++i) {
    const Eigen::Vector2d off(i % 2 == 0 ? 1.0 : -1.0, i % 3 == 0 ? 1.0 : 0.0);
    xy2.push_back(patches1.xy[i] + shift + off);
  }
  const ImagePatches patches2 =
      ExtractImagePatches(image2, xy2, PatchOptions());
  const auto true_candidates = [&](int max_shift) {
    CorrelationMatchingOptions options;
    options.max_keypoint_shift_px = max_shift;
    GlobalMapping mapping;
    mapping.affine.col(2) = shift;
    int count = 0;
    for (const MatchCandidate& c :
         FindCandidates(patches1, patches2, mapping, options)) {
      count += c.idx1 == c.idx2;
    }
    return count;
  };
  const int valid = patches1.NumValid();
  const int without = true_candidates(0), with = true_candidates(1);
  EXPECT_LT(without, valid / 2);
  EXPECT_GT(with, 0.8 * valid) << without << " without the shifts";
  const PairMatches result =
      MatchImagePatches(patches1, patches2, CorrelationMatchingOptions());
  int good = 0;
  for (int k = 0; k < result.matches.rows(); ++k) {
    const Eigen::Vector2d truth = result.reference_xy1[k] + shift;
    good += result.matches(k, 0) == result.matches(k, 1) &&
            (result.refined_xy2[k] - truth).norm() < 0.1;
  }
  EXPECT_GT(good, 0.8 * valid) << "of " << result.matches.rows();
}

TEST(CorrelationMatcher, RefinementFindsTheSubPixelShift) {
  const Pair pair = MakePair(1.0, {3.3, -2.6}, 0);
  const ImagePatches patches1 = Patches(pair.image1);
  // Image-2 "keypoints" one pixel off the truth: the refinement must move.
  std::vector<Eigen::Vector2d> xy2;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2d truth = pair.A * patches1.xy[i] + pair.b;
    xy2.push_back(truth.array().floor() + 0.5 + 1.0);
  }
  const ImagePatches patches2 =
      ExtractImagePatches(pair.image2, xy2, PatchOptions());
  int refined = 0;
  for (int i = 0; i < 40; ++i) {
    if (!patches1.valid[i] || !patches2.valid[i]) continue;
    Eigen::Vector2d xy;
    float ncc = 0;
    if (!RefineConjugatePoint(patches1, i, patches2, i, 0, 0.75, &xy, &ncc)) {
      continue;
    }
    ++refined;
    EXPECT_LT((xy - (pair.A * patches1.xy[i] + pair.b)).norm(), 0.2);
    EXPECT_GT(ncc, 0.9f);
  }
  EXPECT_GT(refined, 30);
}

}  // namespace
}  // namespace bayon
