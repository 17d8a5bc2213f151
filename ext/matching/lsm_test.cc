// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/lsm.h"

#include "ext/core/errors.h"
#include "ext/synth/texture_patches.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace bayon {
namespace {

constexpr int kImageSize = 41;
const Eigen::Vector2d kTemplateXY(20.5, 20.5);

TexturePairTruth MakeTruth(double angle_deg,
                           double scale_x,
                           double scale_y,
                           double shear,
                           const Eigen::Vector2d& fraction,
                           double r0,
                           double r1) {
  TexturePairTruth truth;
  truth.template_xy = kTemplateXY;
  truth.search_xy = kTemplateXY + fraction;
  const double a = angle_deg * M_PI / 180;
  Eigen::Matrix2d rotation;
  rotation << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  Eigen::Matrix2d stretch;
  stretch << scale_x, shear, 0, scale_y;
  truth.shape = rotation * stretch;
  truth.r0 = r0;
  truth.r1 = r1;
  return truth;
}

// The Cramer-Rao bound of the eight parameters for Gaussian noise of
// sigma_f in the template and sigma_g in the search image: the Fisher
// information of the model f = r0 + r1 g(M w + q0) at the truth, with the
// exact gradients of the texture, and the noise of both images referred to
// the template, sigma^2 = sigma_f^2 + r1^2 sigma_g^2.
LsmMatrix CramerRaoBound(const WaveTexture& texture,
                         const TexturePairTruth& truth,
                         int radius,
                         double sigma_f,
                         double sigma_g) {
  LsmMatrix information = LsmMatrix::Zero();
  const Eigen::Matrix2d inverse_transpose = truth.shape.inverse().transpose();
  for (int v = -radius; v <= radius; ++v) {
    for (int u = -radius; u <= radius; ++u) {
      const Eigen::Vector2d p = truth.template_xy + Eigen::Vector2d(u, v);
      const double g = (texture.Value(p) - truth.r0) / truth.r1;
      // r1 * grad g(q) = M^-T grad s(p).
      const Eigen::Vector2d rg = inverse_transpose * texture.Gradient(p);
      LsmVector row;
      row << rg.x(), rg.y(), rg.x() * u, rg.x() * v, rg.y() * u, rg.y() * v,
          1.0, g;
      information += row * row.transpose();
    }
  }
  const double sigma_sq =
      sigma_f * sigma_f + truth.r1 * truth.r1 * sigma_g * sigma_g;
  return sigma_sq * information.inverse();
}

struct TrialStatistics {
  int num_trials = 0;
  int num_converged = 0;
  Eigen::Vector2d mean_error = Eigen::Vector2d::Zero();
  Eigen::Vector2d rms_error = Eigen::Vector2d::Zero();
  Eigen::Vector2d rms_reported = Eigen::Vector2d::Zero();
  double max_error = 0;
};

TrialStatistics RunTrials(const WaveTextureOptions& texture_options,
                          const TexturePairTruth& truth,
                          double sigma,
                          int num_trials,
                          const LsmOptions& options) {
  const WaveTexture texture(texture_options);
  const cv::Mat clean_template =
      RenderTemplateImage(texture, kImageSize, kImageSize);
  const cv::Mat clean_search =
      RenderSearchImage(texture, truth, kImageSize, kImageSize);
  // Approximation: half a pixel off, upright, no radiometric correction.
  const LsmParameters approximation =
      LsmParameters::At(truth.search_xy + Eigen::Vector2d(0.5, -0.4));
  TrialStatistics stats;
  stats.num_trials = num_trials;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Vector2d sum_sq = Eigen::Vector2d::Zero();
  Eigen::Vector2d reported_sq = Eigen::Vector2d::Zero();
  for (int trial = 0; trial < num_trials; ++trial) {
    cv::Mat f = clean_template.clone();
    cv::Mat g = clean_search.clone();
    AddGaussianNoise(sigma, 1000 + 2 * trial, &f);
    AddGaussianNoise(sigma, 1001 + 2 * trial, &g);
    const LsmMatch match = MatchLsm(f, kTemplateXY, g, approximation, options);
    if (!match.ok()) continue;
    ++stats.num_converged;
    const Eigen::Vector2d error = match.xy - truth.search_xy;
    sum += error;
    sum_sq += error.cwiseAbs2();
    reported_sq += match.sigma_xy.cwiseAbs2();
    stats.max_error = std::max(stats.max_error, error.norm());
  }
  const double n = std::max(1, stats.num_converged);
  stats.mean_error = sum / n;
  stats.rms_error = (sum_sq / n).cwiseSqrt();
  stats.rms_reported = (reported_sq / n).cwiseSqrt();
  return stats;
}

struct PrecisionCase {
  const char* name;
  Interpolation interpolation;
  uint32_t seed;
  TexturePairTruth truth;
};

// The figure: empirical error within 1.2 x of the Cramer-Rao bound
// and unbiased; the reported standard deviations agree with the empirical
// ones within 20 %.
TEST(Lsm, ReachesTheCramerRaoBoundUnbiasedWithHonestSigmas) {
  const double sigma = 6.0;  // grey values, both images
  const int num_trials = 300;
  const PrecisionCase cases[] = {
      {"affine, bicubic",
       Interpolation::kBicubic,
       3,
       MakeTruth(12, 1.1, 0.93, 0.06, {0.37, -0.23}, 15, 0.8)},
      {"affine, bilinear",
       Interpolation::kBilinear,
       5,
       MakeTruth(-7, 0.95, 1.05, -0.04, {-0.41, 0.18}, -10, 1.25)},
  };
  for (const PrecisionCase& test : cases) {
    SCOPED_TRACE(test.name);
    WaveTextureOptions texture;
    texture.seed = test.seed;
    texture.min_wavelength_px = 8;
    LsmOptions options;
    options.interpolation = test.interpolation;
    const TrialStatistics stats =
        RunTrials(texture, test.truth, sigma, num_trials, options);
    const LsmMatrix crb = CramerRaoBound(
        WaveTexture(texture), test.truth, options.patch_radius, sigma, sigma);
    const Eigen::Vector2d bound(std::sqrt(crb(kLsmA0, kLsmA0)),
                                std::sqrt(crb(kLsmB0, kLsmB0)));
    std::printf(
        "%-18s converged %d/%d  CRB (%.4f, %.4f)  empirical RMS (%.4f, "
        "%.4f)  ratio (%.2f, %.2f)  mean (%+.4f, %+.4f)  reported (%.4f, "
        "%.4f)\n",
        test.name,
        stats.num_converged,
        stats.num_trials,
        bound.x(),
        bound.y(),
        stats.rms_error.x(),
        stats.rms_error.y(),
        stats.rms_error.x() / bound.x(),
        stats.rms_error.y() / bound.y(),
        stats.mean_error.x(),
        stats.mean_error.y(),
        stats.rms_reported.x(),
        stats.rms_reported.y());
    EXPECT_EQ(stats.num_converged, num_trials);
    for (int axis = 0; axis < 2; ++axis) {
      EXPECT_LE(stats.rms_error[axis], 1.2 * bound[axis]) << axis;
      // Unbiased: the mean error is within three standard errors of zero.
      EXPECT_LE(std::abs(stats.mean_error[axis]),
                3 * stats.rms_error[axis] / std::sqrt(num_trials))
          << axis;
      EXPECT_NEAR(stats.rms_reported[axis] / stats.rms_error[axis], 1.0, 0.2)
          << axis;
    }
  }
}

TEST(Lsm, RecoversAffineAndRadiometryExactlyWithoutNoise) {
  WaveTextureOptions texture_options;
  texture_options.seed = 11;
  const WaveTexture texture(texture_options);
  const TexturePairTruth truth =
      MakeTruth(15, 1.15, 0.9, 0.08, {1.3, -0.8}, 20, 0.7);
  const cv::Mat f = RenderTemplateImage(texture, kImageSize, kImageSize);
  const cv::Mat g = RenderSearchImage(texture, truth, kImageSize, kImageSize);
  LsmOptions options;
  options.interpolation = Interpolation::kBicubic;
  const LsmMatch match =
      MatchLsm(f,
               kTemplateXY,
               g,
               LsmParameters::At(kTemplateXY + Eigen::Vector2d(1, -1)),
               options);
  ASSERT_TRUE(match.ok()) << LsmStatusName(match.status);
  EXPECT_NEAR((match.xy - truth.search_xy).norm(), 0, 0.01);
  EXPECT_LT((match.params.Shape() - truth.shape).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_NEAR(match.params.r1, truth.r1, 0.01);
  EXPECT_NEAR(match.params.r0, truth.r0, 2.0);
  EXPECT_GT(match.correlation, 0.999);
  EXPECT_LT(match.iterations, 15);
  for (bool held : match.held) EXPECT_FALSE(held);
}

TEST(Lsm, HoldsTheShiftAlongAStraightEdge) {
  // Grey values change only across a diagonal edge: the shift along it is
  // not determinable and must be held, not estimated from the noise.
  auto edge = [](double x, double y) {
    return 100 + 60 * std::tanh(((x - 20.5) + (y - 20.5)) / 2.5);
  };
  cv::Mat f(kImageSize, kImageSize, CV_32F), g(kImageSize, kImageSize, CV_32F);
  for (int r = 0; r < kImageSize; ++r) {
    for (int c = 0; c < kImageSize; ++c) {
      f.at<float>(r, c) = static_cast<float>(edge(c + 0.5, r + 0.5));
      g.at<float>(r, c) = static_cast<float>(edge(c + 0.5 - 0.3, r + 0.5));
    }
  }
  AddGaussianNoise(1.0, 7, &f);
  AddGaussianNoise(1.0, 8, &g);
  LsmOptions options;
  const LsmMatch match =
      MatchLsm(f, kTemplateXY, g, LsmParameters::At(kTemplateXY), options);
  EXPECT_EQ(match.status, LsmStatus::kShiftUndetermined);
  EXPECT_TRUE(match.held[kLsmA0] != match.held[kLsmB0]);
  EXPECT_TRUE(std::isinf(match.sigma_xy.x()) || std::isinf(match.sigma_xy.y()));
  // Across the edge the position is still right: the edge moved 0.3 px in
  // x, i.e. 0.3 / sqrt(2) px along its normal.
  const Eigen::Vector2d normal(std::sqrt(0.5), std::sqrt(0.5));
  EXPECT_NEAR((match.xy - kTemplateXY).dot(normal), 0.3 * std::sqrt(0.5), 0.02);
}

TEST(Lsm, ReportsFlatPatchesAndPatchesOffTheImage) {
  cv::Mat flat(kImageSize, kImageSize, CV_32F, cv::Scalar(80));
  AddGaussianNoise(0.5, 3, &flat);
  WaveTextureOptions texture_options;
  const WaveTexture texture(texture_options);
  const cv::Mat textured = RenderTemplateImage(texture, kImageSize, kImageSize);
  LsmOptions options;
  EXPECT_EQ(
      MatchLsm(
          flat, kTemplateXY, textured, LsmParameters::At(kTemplateXY), options)
          .status,
      LsmStatus::kFlatPatch);
  // The template off its image.
  EXPECT_EQ(MatchLsm(textured,
                     Eigen::Vector2d(3.5, 20.5),
                     textured,
                     LsmParameters::At(kTemplateXY),
                     options)
                .status,
            LsmStatus::kOutsideImage);
  // The search patch off its image.
  EXPECT_EQ(MatchLsm(textured,
                     kTemplateXY,
                     textured,
                     LsmParameters::At(Eigen::Vector2d(38.5, 20.5)),
                     options)
                .status,
            LsmStatus::kOutsideImage);
  // A search patch of something else: diverges or fits badly, never a
  // confident match.
  WaveTextureOptions other_options;
  other_options.seed = 99;
  const cv::Mat other =
      RenderTemplateImage(WaveTexture(other_options), kImageSize, kImageSize);
  const LsmMatch wrong = MatchLsm(
      textured, kTemplateXY, other, LsmParameters::At(kTemplateXY), options);
  EXPECT_TRUE(!wrong.ok() || wrong.correlation < 0.7)
      << LsmStatusName(wrong.status) << " r = " << wrong.correlation;
}

TEST(Lsm, NormalEquationsMatchFiniteDifferences) {
  // A'l must be minus half the gradient of l'l with respect to the
  // parameters. Where the interpolation and its gradient are exact (bicubic
  // on a quadratic image, bilinear on a plane) central differences of l'l
  // must agree.
  for (Interpolation interpolation :
       {Interpolation::kBilinear, Interpolation::kBicubic}) {
    const double curvature =
        interpolation == Interpolation::kBicubic ? 1.0 : 0.0;
    auto image = [&](double x, double y) {
      return 40 + 3 * x - 2 * y +
             curvature * (0.2 * x * x - 0.15 * x * y + 0.1 * y * y);
    };
    cv::Mat f(kImageSize, kImageSize, CV_32F);
    cv::Mat g(kImageSize, kImageSize, CV_32F);
    for (int r = 0; r < kImageSize; ++r) {
      for (int c = 0; c < kImageSize; ++c) {
        f.at<float>(r, c) = static_cast<float>(image(c + 0.5, r + 0.5));
        g.at<float>(r, c) =
            static_cast<float>(0.9 * image(c + 0.8, r + 0.3) + 5);
      }
    }
    LsmTemplate patch;
    ASSERT_TRUE(ExtractLsmTemplate(f, kTemplateXY, 5, interpolation, &patch));
    LsmParameters params = LsmParameters::At(
        kTemplateXY + Eigen::Vector2d(0.4, -0.3),
        (Eigen::Matrix2d() << 1.05, 0.03, -0.02, 0.97).finished());
    params.r0 = 3;
    params.r1 = 1.1;
    LsmNormalEquations equations;
    ASSERT_TRUE(
        BuildLsmNormalEquations(patch, g, params, interpolation, &equations));
    // The correlation alone is the same number (to float rounding: the
    // bilinear correlation samples values alone, in another order).
    double correlation = 0;
    ASSERT_TRUE(LsmCorrelation(patch, g, params, interpolation, &correlation));
    EXPECT_NEAR(correlation, equations.Correlation(), 1e-6);
    for (int j = 0; j < kNumLsmParams; ++j) {
      // Steps large enough for the float precision of the grey values.
      const double step =
          j == kLsmA0 || j == kLsmB0 || j == kLsmR0 ? 1e-2 : 1e-3;
      LsmVector delta = LsmVector::Zero();
      delta[j] = step;
      LsmParameters plus = params, minus = params;
      plus.Add(delta);
      minus.Add(-delta);
      LsmNormalEquations ep, em;
      ASSERT_TRUE(BuildLsmNormalEquations(patch, g, plus, interpolation, &ep));
      ASSERT_TRUE(BuildLsmNormalEquations(patch, g, minus, interpolation, &em));
      const double numeric = -(ep.residual_sq - em.residual_sq) / (4 * step);
      EXPECT_NEAR(
          equations.rhs[j], numeric, 2e-3 * std::max(10.0, std::abs(numeric)))
          << LsmParamName(j) << " " << InterpolationName(interpolation);
    }
  }
}

TEST(Lsm, NormalEquationsAreTheDesignMatrixSquared) {
  // N = A'A and rhs = A'l with A's rows (gx, gy, gx u, gx v, gy u, gy v, 1,
  // g) sampled one at a time, for a sheared patch in the middle of a noise
  // image and one whose corner is half a pixel from where the bilinear
  // footprint ends (the bicubic one is out there), with both
  // interpolations.
  cv::Mat f(kImageSize, kImageSize, CV_32F), g(kImageSize, kImageSize, CV_32F);
  cv::randu(f, 0, 255);
  cv::randu(g, 0, 255);
  const int radius = 4;
  LsmTemplate patch;
  ASSERT_TRUE(ExtractLsmTemplate(
      f, kTemplateXY, radius, Interpolation::kBilinear, &patch));
  const Eigen::Matrix2d shape =
      (Eigen::Matrix2d() << 1.1, 0.2, -0.15, 0.9).finished();
  for (Interpolation interpolation :
       {Interpolation::kBilinear, Interpolation::kBicubic}) {
    for (const Eigen::Vector2d& centre :
         {Eigen::Vector2d(20.3, 19.6), Eigen::Vector2d(7.2, 30.2)}) {
      LsmParameters params = LsmParameters::At(centre, shape);
      params.r0 = 4;
      params.r1 = 0.8;
      LsmNormalEquations equations;
      if (!BuildLsmNormalEquations(
              patch, g, params, interpolation, &equations)) {
        // Only the bicubic footprint leaves the image at the border.
        EXPECT_EQ(interpolation, Interpolation::kBicubic);
        continue;
      }
      LsmMatrix N = LsmMatrix::Zero();
      LsmVector rhs = LsmVector::Zero();
      int k = 0;
      for (int v = -radius; v <= radius; ++v) {
        for (int u = -radius; u <= radius; ++u, ++k) {
          const Eigen::Vector2d xy = params.affine * Eigen::Vector3d(u, v, 1);
          ImageSample sample;
          ASSERT_TRUE(SampleImage(g, xy.x(), xy.y(), interpolation, &sample));
          const double gx = params.r1 * sample.dx, gy = params.r1 * sample.dy;
          LsmVector row;
          row << gx, gy, gx * u, gx * v, gy * u, gy * v, 1, sample.value;
          N += row * row.transpose();
          rhs += row * (patch.values[k] - params.r0 - params.r1 * sample.value);
        }
      }
      EXPECT_LT((equations.N - N).norm(), 1e-9 * N.norm())
          << InterpolationName(interpolation) << " at " << centre.transpose();
      EXPECT_LT((equations.rhs - rhs).norm(), 1e-9 * rhs.norm())
          << InterpolationName(interpolation) << " at " << centre.transpose();
    }
  }
}

TEST(Lsm, RadiometricFitIsTheEquationsRebuiltAtTheRegression) {
  // The search patch is the template's texture at another contrast and
  // brightness plus noise, in grey values about 128 as MPGC's high-passed
  // images are: the fit gives the regression of f on g, and the equations
  // it turns are those built afresh at the fitted values.
  cv::Mat f(kImageSize, kImageSize, CV_32F),
      noise(kImageSize, kImageSize, CV_32F);
  cv::randu(f, 118, 138);
  cv::randn(noise, 0, 2);
  const cv::Mat g = 0.6 * f + 51.2 + noise;
  const int radius = 4;
  LsmTemplate patch;
  ASSERT_TRUE(ExtractLsmTemplate(
      f, kTemplateXY, radius, Interpolation::kBilinear, &patch));
  const Eigen::Matrix2d shape =
      (Eigen::Matrix2d() << 1.02, 0.01, -0.02, 0.99).finished();
  LsmParameters params = LsmParameters::At(kTemplateXY, shape);
  params.r0 = 4;
  params.r1 = 0.8;
  LsmNormalEquations turned;
  ASSERT_TRUE(BuildLsmNormalEquations(
      patch, g, params, Interpolation::kBilinear, &turned));
  const double n = turned.num_observations;
  const double slope = (turned.sum_fg - turned.sum_f * turned.sum_g / n) /
                       (turned.sum_gg - turned.sum_g * turned.sum_g / n);
  ASSERT_TRUE(FitLsmRadiometry(0.05, &params, &turned));
  EXPECT_NEAR(params.r1, slope, 1e-12);
  EXPECT_NEAR(params.r0, (turned.sum_f - slope * turned.sum_g) / n, 1e-9);
  // Near 1 / 0.6 at this shape (the resampling smooths g a little).
  EXPECT_GT(params.r1, 1.2);
  EXPECT_LT(params.r1, 1.8);
  LsmNormalEquations rebuilt;
  ASSERT_TRUE(BuildLsmNormalEquations(
      patch, g, params, Interpolation::kBilinear, &rebuilt));
  EXPECT_LT((turned.N - rebuilt.N).norm(), 1e-9 * rebuilt.N.norm());
  EXPECT_LT((turned.rhs - rebuilt.rhs).norm(), 1e-9 * rebuilt.N.norm());
  EXPECT_NEAR(
      turned.residual_sq, rebuilt.residual_sq, 1e-9 * rebuilt.residual_sq);
  // At the regression the residuals have no mean and no part along g.
  EXPECT_NEAR(
      rebuilt.rhs[kLsmR0], 0, 1e-7 * std::sqrt(rebuilt.N(kLsmR0, kLsmR0)));
  EXPECT_NEAR(
      rebuilt.rhs[kLsmR1], 0, 1e-7 * std::sqrt(rebuilt.N(kLsmR1, kLsmR1)));
  // A search patch unrelated to the template keeps the least contrast given.
  cv::Mat other(kImageSize, kImageSize, CV_32F);
  cv::randu(other, 118, 138);
  LsmParameters unrelated = LsmParameters::At(kTemplateXY);
  LsmNormalEquations equations;
  ASSERT_TRUE(BuildLsmNormalEquations(
      patch, other, unrelated, Interpolation::kBilinear, &equations));
  ASSERT_TRUE(FitLsmRadiometry(0.5, &unrelated, &equations));
  EXPECT_EQ(unrelated.r1, 0.5);
}

TEST(Lsm, OneTemplateAgainstSeveralSearchPatches) {
  // One template, three search images with different shapes, radiometry
  // and one search patch off its image: each solution is independent, the
  // bad one is flagged and does not disturb the others.
  WaveTextureOptions texture_options;
  texture_options.seed = 21;
  const WaveTexture texture(texture_options);
  cv::Mat f = RenderTemplateImage(texture, kImageSize, kImageSize);
  AddGaussianNoise(1.0, 30, &f);
  const TexturePairTruth truths[] = {
      MakeTruth(5, 1.05, 0.95, 0.02, {0.3, 0.2}, 5, 0.9),
      MakeTruth(-10, 0.9, 1.1, -0.05, {-0.6, 0.4}, -8, 1.2),
      MakeTruth(0, 1.0, 1.0, 0.0, {0.1, -0.7}, 0, 1.0),
  };
  std::vector<cv::Mat> images;
  for (int i = 0; i < 3; ++i) {
    images.push_back(
        RenderSearchImage(texture, truths[i], kImageSize, kImageSize));
    AddGaussianNoise(1.0, 31 + i, &images.back());
  }
  LsmOptions options;
  LsmTemplate patch;
  ASSERT_TRUE(ExtractLsmTemplate(
      f, kTemplateXY, options.patch_radius, options.interpolation, &patch));
  std::vector<LsmSearch> searches;
  for (int i = 0; i < 3; ++i) {
    searches.push_back(
        {&images[i],
         LsmParameters::At(truths[i].search_xy + Eigen::Vector2d(0.4, -0.3))});
  }
  searches.push_back(
      {&images[0], LsmParameters::At(Eigen::Vector2d(3.5, 3.5))});
  const std::vector<LsmMatch> matches = MatchLsmMulti(patch, searches, options);
  ASSERT_EQ(matches.size(), 4u);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(matches[i].ok())
        << i << " " << LsmStatusName(matches[i].status);
    EXPECT_LT((matches[i].xy - truths[i].search_xy).norm(), 0.05) << i;
    EXPECT_LT((matches[i].xy - truths[i].search_xy).norm(),
              4 * matches[i].sigma_xy.norm() + 0.005)
        << i;
    // Bilinear resampling smooths the search patch's shortest waves, so r1
    // comes out a few per cent high.
    EXPECT_NEAR(matches[i].params.r1, truths[i].r1, 0.06) << i;
  }
  EXPECT_EQ(matches[3].status, LsmStatus::kOutsideImage);
}

// Random blocks 2 pixels wide, each pixel the average of the scene over
// the pixel's area (8 x 8 sub-samples) with the scene moved by `shift`:
// what a camera records of sharp edges, g(x) = f(x + shift).
cv::Mat RenderBlocks(int size, const Eigen::Vector2d& shift) {
  constexpr int kBlock = 2, kSubsamples = 8;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> grey(40, 200);
  const int num_blocks = size / kBlock + 4;
  std::vector<double> blocks(num_blocks * num_blocks);
  for (double& value : blocks) value = grey(rng);
  cv::Mat image(size, size, CV_32F);
  for (int row = 0; row < size; ++row) {
    for (int col = 0; col < size; ++col) {
      double sum = 0;
      for (int a = 0; a < kSubsamples; ++a) {
        for (int b = 0; b < kSubsamples; ++b) {
          const double x = col + (a + 0.5) / kSubsamples + shift.x();
          const double y = row + (b + 0.5) / kSubsamples + shift.y();
          const int i = static_cast<int>(std::floor(x / kBlock)) + 2;
          const int j = static_cast<int>(std::floor(y / kBlock)) + 2;
          sum += blocks[j * num_blocks + i];
        }
      }
      image.at<float>(row, col) = sum / (kSubsamples * kSubsamples);
    }
  }
  return image;
}

TEST(Lsm, StepControlConvergesWherePlainGaussNewtonOscillates) {
  // Edges a pixel wide: the smooth gradients are about half the slope of
  // the interpolated surface, the full Gauss-Newton step overshoots by
  // about 2x and the iteration oscillates around the solution.
  const Eigen::Vector2d shift(0.37, 0.21);
  const cv::Mat f = RenderBlocks(120, Eigen::Vector2d::Zero());
  const cv::Mat g = RenderBlocks(120, shift);
  int num_converged[2] = {0, 0};
  double sum_sq = 0;
  int num_points = 0;
  for (int step_control = 0; step_control < 2; ++step_control) {
    LsmOptions options;
    options.step_control = step_control == 1;
    for (int y = 20; y < 100; y += 6) {
      for (int x = 20; x < 100; x += 6) {
        const Eigen::Vector2d p(x + 0.5, y + 0.5);
        const LsmMatch match =
            MatchLsm(f,
                     p,
                     g,
                     LsmParameters::At(p + Eigen::Vector2d(0.4, -0.5)),
                     options);
        num_points += step_control;
        if (!match.ok()) continue;
        ++num_converged[step_control];
        if (step_control) sum_sq += (match.xy - (p - shift)).squaredNorm();
      }
    }
  }
  // 14 x 14 = 196 points.
  ASSERT_EQ(num_points, 196);
  EXPECT_LT(num_converged[0], num_points / 2);
  EXPECT_GE(num_converged[1], num_points * 95 / 100);
  EXPECT_LT(std::sqrt(sum_sq / num_converged[1]), 0.1);
}

TEST(Lsm, OptionsAreChecked) {
  LsmOptions options;
  options.patch_radius = 1;
  EXPECT_THROW(options.Check(), InputError);
  options = LsmOptions();
  options.min_shape_scale = 1.5;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace bayon
