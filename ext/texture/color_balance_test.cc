// SPDX-License-Identifier: BSD-3-Clause
#include "ext/texture/color_balance.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <iostream>
#include <random>

namespace bayon {
namespace {

// Faces of random true colours seen by random subsets of photographs, each
// photograph with its own gain and offset per channel; `outliers`: share of
// observations replaced by an unrelated colour (an occlusion the mesh
// misses).
struct Overlaps {
  std::vector<std::vector<FaceColor>> faces;
  std::vector<GainOffset> exposure;  // the photographs' true ones
};

Overlaps MakeOverlaps(int num_images,
                      double outliers,
                      uint32_t seed,
                      float noise = 0.0f) {
  std::mt19937 random(seed);
  std::normal_distribution<float> gaussian(0.0f, noise > 0 ? noise : 1.0f);
  std::uniform_real_distribution<float> colour(20, 200), gain(0.7f, 1.2f),
      offset(-15, 15), unit(0, 1);
  Overlaps o;
  o.exposure.resize(num_images);
  for (GainOffset& e : o.exposure) {
    for (int c = 0; c < 3; ++c) {
      e.gain[c] = gain(random);
      e.offset[c] = offset(random);
    }
  }
  for (int f = 0; f < 3000; ++f) {
    const Eigen::Vector3f truth(colour(random), colour(random), colour(random));
    // Three to five consecutive photographs, as around a ring.
    const int first = static_cast<int>(unit(random) * num_images);
    const int count = 3 + f % 3;
    std::vector<FaceColor> seen;
    for (int i = 0; i < count; ++i) {
      const int j = (first + i) % num_images;
      FaceColor c;
      c.image = j;
      c.color = o.exposure[j].gain.cwiseProduct(truth) + o.exposure[j].offset;
      if (noise > 0) {
        c.color += Eigen::Vector3f(
            gaussian(random), gaussian(random), gaussian(random));
      }
      if (unit(random) < outliers) {
        c.color = Eigen::Vector3f(colour(random), colour(random), 30);
      }
      seen.push_back(c);
    }
    o.faces.push_back(seen);
  }
  return o;
}

// After the corrections every photograph's colour of a face is the same
// affine function of the truth: the largest spread of the corrected
// colours over photographs, for a grey ramp.
double CorrectedSpread(const Overlaps& o,
                       const std::vector<GainOffset>& corrections) {
  double spread = 0;
  for (float truth = 20; truth <= 200; truth += 30) {
    for (int c = 0; c < 3; ++c) {
      double lo = 1e9, hi = -1e9;
      for (size_t j = 0; j < o.exposure.size(); ++j) {
        const double seen =
            o.exposure[j].gain[c] * truth + o.exposure[j].offset[c];
        const double corrected =
            corrections[j].gain[c] * seen + corrections[j].offset[c];
        lo = std::min(lo, corrected);
        hi = std::max(hi, corrected);
      }
      spread = std::max(spread, hi - lo);
    }
  }
  return spread;
}

TEST(BalanceExposures, MakesThePhotographsAgreeAndKeepsTheirMean) {
  const Overlaps o = MakeOverlaps(12, 0.0, 1);
  ColorBalanceReport report;
  const std::vector<GainOffset> corrections =
      BalanceExposures(o.faces, 12, ColorBalanceOptions(), &report);
  ASSERT_EQ(corrections.size(), 12u);
  EXPECT_EQ(report.num_faces, 3000);
  EXPECT_GT(report.sigma_before, 5.0);
  // Exact colours: what remains is the prior's pull to gain 1 and offset 0
  // (about 1 % of the corrections).
  EXPECT_LT(report.sigma_after, 0.5);
  EXPECT_LT(CorrectedSpread(o, corrections), 4.0);
  // The gauge: the mean gain is 1 and the mean offset 0 in every channel.
  Eigen::Vector3f mean_gain = Eigen::Vector3f::Zero(),
                  mean_offset = Eigen::Vector3f::Zero();
  for (const GainOffset& c : corrections) {
    mean_gain += c.gain / 12.0f;
    mean_offset += c.offset / 12.0f;
  }
  EXPECT_NEAR(mean_gain.maxCoeff(), 1.0, 1e-4);
  EXPECT_NEAR(mean_gain.minCoeff(), 1.0, 1e-4);
  EXPECT_LT(mean_offset.cwiseAbs().maxCoeff(), 1e-3);
}

TEST(BalanceExposures, OcclusionsDoNotPullTheSolution) {
  const Overlaps o = MakeOverlaps(12, 0.15, 2);
  const std::vector<GainOffset> corrections =
      BalanceExposures(o.faces, 12, ColorBalanceOptions());
  // A sixth of the observations unrelated: the photographs still agree to
  // about a grey level over the whole range (least squares alone: several).
  const double robust = CorrectedSpread(o, corrections);
  EXPECT_LT(robust, 4.0);
  ColorBalanceOptions least_squares;
  least_squares.huber_k = 1e6;
  const double plain =
      CorrectedSpread(o, BalanceExposures(o.faces, 12, least_squares));
  EXPECT_GT(plain, 2.0 * robust);
  std::cout << "largest spread of the corrected photographs: " << robust
            << " grey levels (least squares alone: " << plain << ")\n";
}

// Mean gain of photographs [first, last) in channel 0.
double MeanGain(const std::vector<GainOffset>& corrections,
                int first,
                int last) {
  double sum = 0;
  for (int j = first; j < last; ++j) sum += corrections[j].gain.x();
  return sum / (last - first);
}

// With noise in the colours, the overlaps' cost shrinks with the gains: a
// photograph without overlaps, or a second group of photographs, must not
// take up what one mean over all would let the others give away.
TEST(BalanceExposures, APhotographWithoutOverlapIsLeftAlone) {
  const Overlaps o = MakeOverlaps(6, 0.0, 3, 2.0f);
  ColorBalanceReport report;
  const std::vector<GainOffset> corrections =
      BalanceExposures(o.faces, 7, ColorBalanceOptions(), &report);
  ASSERT_EQ(corrections.size(), 7u);
  EXPECT_EQ(report.num_groups, 1);
  EXPECT_EQ(corrections[6].gain, Eigen::Vector3f::Ones());
  EXPECT_EQ(corrections[6].offset, Eigen::Vector3f::Zero());
  EXPECT_NEAR(MeanGain(corrections, 0, 6), 1.0, 1e-4);
  EXPECT_LT(CorrectedSpread(o, corrections), 3.0);

  // Two groups that share no face: each keeps its own mean gain 1.
  Overlaps second = MakeOverlaps(6, 0.0, 4, 2.0f);
  std::vector<std::vector<FaceColor>> both = o.faces;
  for (std::vector<FaceColor> face : second.faces) {
    for (FaceColor& c : face) c.image += 6;
    both.push_back(face);
  }
  const std::vector<GainOffset> two =
      BalanceExposures(both, 12, ColorBalanceOptions(), &report);
  EXPECT_EQ(report.num_groups, 2);
  EXPECT_NEAR(MeanGain(two, 0, 6), 1.0, 1e-4);
  EXPECT_NEAR(MeanGain(two, 6, 12), 1.0, 1e-4);
  EXPECT_THROW(BalanceExposures(both, 6, ColorBalanceOptions()), InputError);

  // Clipped samples do not count: a face seen clipped in one of its two
  // photographs has one usable colour.
  std::vector<std::vector<FaceColor>> clipped = {
      {{0, Eigen::Vector3f(255, 100, 100)}, {1, Eigen::Vector3f(90, 90, 90)}}};
  BalanceExposures(clipped, 2, ColorBalanceOptions(), &report);
  EXPECT_EQ(report.num_faces, 0);
}

// A strip of 2n triangles along x, the left half in chart 0 (grey level
// 100) and the right half in chart 1 (grey level 140).
TEST(LevelSeams, LevelsAChartBorder) {
  const int n = 8;
  TriangleMesh mesh;
  for (int i = 0; i <= n; ++i) {
    mesh.vertices.positions.emplace_back(i, 0, 0);
    mesh.vertices.positions.emplace_back(i, 1, 0);
  }
  std::vector<int> chart;
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i, b = a + 1, c = a + 2, d = a + 3;
    mesh.faces.emplace_back(a, c, d);
    mesh.faces.emplace_back(a, d, b);
    chart.push_back(i < n / 2 ? 0 : 1);
    chart.push_back(i < n / 2 ? 0 : 1);
  }
  std::vector<TwoFaceEdge> edges;
  for (int i = 0; i < n; ++i) {
    edges.push_back({2 * i, 2 * i + 3, 2 * i, 2 * i + 1});  // diagonal
    if (i + 1 < n) edges.push_back({2 * i + 2, 2 * i + 3, 2 * i, 2 * i + 3});
  }
  const FaceColorAt color_at =
      [&](int face, const Eigen::Vector3d&, Eigen::Vector3f* color) {
        *color = Eigen::Vector3f::Constant(chart[face] == 0 ? 100.0f : 140.0f);
        return true;
      };
  SeamLevelingReport report;
  const auto adjustment =
      LevelSeams(mesh, chart, edges, color_at, SeamLevelingOptions(), &report);
  EXPECT_EQ(report.num_seam_edges, 1);
  EXPECT_EQ(report.num_unknowns, 2 * (n + 1) + 2);  // the border twice
  EXPECT_NEAR(report.difference_before, 40.0, 1e-4);
  EXPECT_LT(report.difference_after, 1.0);
  // Half the step on each side of the border; a chart with no other
  // border moves as a whole (the smoothness carries the step across it).
  const int left = 2 * (n / 2) - 2, right = 2 * (n / 2);
  EXPECT_NEAR(adjustment[left][1].x(), 20.0, 1.0);  // vertex on the border
  EXPECT_NEAR(adjustment[right][0].x(), -20.0, 1.0);
  EXPECT_NEAR(adjustment[0][0].x(), 20.0, 1.0);
  EXPECT_NEAR(adjustment[2 * n - 1][1].x(), -20.0, 1.0);
  // Faces in no chart are left unchanged.
  chart[0] = -1;
  const auto partial =
      LevelSeams(mesh, chart, edges, color_at, SeamLevelingOptions());
  EXPECT_EQ(partial[0][0], Eigen::Vector3f::Zero());
}

}  // namespace
}  // namespace bayon
