// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/keypoint_refinement.h"

#include "ext/colmap/database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/random.h"
#include "ext/synth/texture_patches.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <glog/logging.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <random>

#include "tests/testing.h"

namespace bayon {
namespace {

namespace fs = std::filesystem;

constexpr int kImageSize = 200;

// Three views of one random texture: view 0 is the texture itself, views 1
// and 2 affine copies with other radiometry, x_i = q0_i + M_i (s - p0) for
// the texture point s.
struct SyntheticViews {
  std::vector<TexturePairTruth> truths;
  std::vector<cv::Mat> images;

  Eigen::Vector2d ToView(int view, const Eigen::Vector2d& s) const {
    const TexturePairTruth& t = truths[view];
    return t.search_xy + t.shape * (s - t.template_xy);
  }
  Eigen::Vector2d ToTexture(int view, const Eigen::Vector2d& x) const {
    const TexturePairTruth& t = truths[view];
    return t.template_xy + t.shape.inverse() * (x - t.search_xy);
  }
};

SyntheticViews MakeViews(double noise_sigma) {
  WaveTextureOptions texture_options;
  texture_options.seed = 11;
  const WaveTexture texture(texture_options);
  SyntheticViews views;
  views.truths.resize(3);
  for (TexturePairTruth& truth : views.truths) {
    truth.template_xy = truth.search_xy = Eigen::Vector2d(100, 100);
  }
  views.truths[1].search_xy = Eigen::Vector2d(103.3, 97.6);
  views.truths[1].shape << 1.1, 0.08, -0.05, 0.95;
  views.truths[1].r0 = 10;
  views.truths[1].r1 = 0.9;
  // A quarter turn and a scale change: what the keypoint frames supply.
  views.truths[2].search_xy = Eigen::Vector2d(98.2, 101.7);
  views.truths[2].shape =
      0.9 * Eigen::Rotation2Dd(0.5 * M_PI + 0.05).toRotationMatrix();
  views.truths[2].r0 = -5;
  views.truths[2].r1 = 1.1;
  views.images.push_back(RenderTemplateImage(texture, kImageSize, kImageSize));
  for (int view = 1; view < 3; ++view) {
    views.images.push_back(
        RenderSearchImage(texture, views.truths[view], kImageSize, kImageSize));
  }
  for (int view = 0; view < 3; ++view) {
    AddGaussianNoise(noise_sigma, 100 + view, &views.images[view]);
  }
  return views;
}

// Keypoints of texture points in a view: true position plus up to
// +-max_error_px, with 6-column frames of scale 2 (and a few degrees of
// orientation error) carried into the view.
FeatureKeypoints MakeKeypoints(const SyntheticViews& views,
                               int view,
                               const std::vector<Eigen::Vector2d>& points,
                               double max_error_px,
                               uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> error(-max_error_px, max_error_px);
  std::uniform_real_distribution<double> angle(-0.07, 0.07);
  FeatureKeypoints keypoints(points.size(), 6);
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector2d xy =
        views.ToView(view, points[k]) + RandomVector<2>(error, rng);
    const Eigen::Matrix2d frame =
        views.truths[view].shape * 2.0 *
        Eigen::Rotation2Dd(angle(rng)).toRotationMatrix();
    keypoints.row(k) << xy.x(), xy.y(), frame(0, 0), frame(0, 1), frame(1, 0),
        frame(1, 1);
  }
  return keypoints.cast<float>();
}

std::vector<Eigen::Vector2d> GridPoints() {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      points.emplace_back(60.5 + 20 * i, 60.5 + 20 * j);
    }
  }
  return points;
}

FeatureMatches IdentityMatches(int n) {
  FeatureMatches matches(n, 2);
  for (int i = 0; i < n; ++i) matches.row(i) << i, i;
  return matches;
}

TEST(KeypointRefinement, TracksAreTheConnectedComponentsOfTheMatches) {
  // Pair (1, 2): 0-0, 1-1; pair (2, 3): 0-5; pair (1, 3): 1-7.
  // Components: {1:0, 2:0, 3:5}, {1:1, 2:1, 3:7}.
  FeatureMatches m12(2, 2), m23(1, 2), m13(1, 2);
  m12 << 0, 0, 1, 1;
  m23 << 0, 5;
  m13 << 1, 7;
  const auto tracks = BuildKeypointTracks({{PairIdFromImageIds(1, 2), m12},
                                           {PairIdFromImageIds(2, 3), m23},
                                           {PairIdFromImageIds(1, 3), m13}});
  ASSERT_EQ(tracks.size(), 2u);
  const KeypointTrack first = {{1, 0}, {2, 0}, {3, 5}};
  const KeypointTrack second = {{1, 1}, {2, 1}, {3, 7}};
  EXPECT_EQ(tracks[0], first);
  EXPECT_EQ(tracks[1], second);
  EXPECT_TRUE(BuildKeypointTracks({}).empty());
}

TEST(KeypointRefinement, ShapeRatioFromTheKeypointFrames) {
  FeatureKeypoints six(1, 6), other(1, 6);
  six << 10, 20, 2, 0, 0, 2;     // scale 2, upright
  other << 30, 40, 0, -3, 3, 0;  // scale 3, a quarter turn
  Eigen::Matrix2d expected;
  expected << 0, -1.5, 1.5, 0;
  EXPECT_LT((KeypointShapeRatio(six, 0, other, 0) - expected).norm(), 1e-12);
  // Scale and orientation (4 columns) give the same frame.
  FeatureKeypoints four(1, 4);
  four << 30, 40, 3, static_cast<float>(0.5 * M_PI);
  EXPECT_LT((KeypointShapeRatio(six, 0, four, 0) - expected).norm(), 1e-6);
  // No frame (2 columns) or a degenerate one: identity.
  FeatureKeypoints two(1, 2);
  two << 1, 2;
  EXPECT_LT(
      (KeypointShapeRatio(two, 0, six, 0) - 2 * Eigen::Matrix2d::Identity())
          .norm(),
      1e-12);
  EXPECT_TRUE(KeypointShapeRatio(two, 0, two, 0).isIdentity(1e-12));
  FeatureKeypoints flat(1, 6);
  flat << 0, 0, 0, 0, 0, 0;
  EXPECT_TRUE(KeypointShapeRatio(flat, 0, six, 0).isIdentity(1e-12));
}

TEST(KeypointRefinement, ObservationConvergesToTheConjugateOfTheReference) {
  const SyntheticViews views = MakeViews(1.0);
  KeypointRefinementOptions options;
  const Eigen::Vector2d reference_xy(90.3, 105.8);  // view 0 = texture
  const Eigen::Vector2d truth = views.ToView(1, reference_xy);
  const Eigen::Vector2d start = truth + Eigen::Vector2d(0.9, -0.7);
  const ObservationRefinement result =
      RefineObservation(views.images[0],
                        reference_xy,
                        views.images[1],
                        start,
                        Eigen::Matrix2d::Identity(),
                        options);
  ASSERT_EQ(result.outcome, ObservationOutcome::kRefined)
      << ObservationOutcomeName(result.outcome);
  EXPECT_LT((result.refined_xy - truth).norm(), 0.05);
  EXPECT_EQ(result.original_xy, start);
  EXPECT_LT(result.backmatch_px, 0.05);
  EXPECT_GT(result.correlation, 0.95);
  EXPECT_LT(result.sigma_xy.maxCoeff(), 0.05);
}

TEST(KeypointRefinement, WrongConjugatesAndFlatPatchesAreRejected) {
  const SyntheticViews views = MakeViews(1.0);
  KeypointRefinementOptions options;
  // A keypoint 25 pixels from the true conjugate: another texture.
  const Eigen::Vector2d reference_xy(80.5, 80.5);
  const Eigen::Vector2d wrong =
      views.ToView(1, reference_xy) + Eigen::Vector2d(25, 0);
  const ObservationRefinement blunder =
      RefineObservation(views.images[0],
                        reference_xy,
                        views.images[1],
                        wrong,
                        Eigen::Matrix2d::Identity(),
                        options);
  EXPECT_TRUE(IsRejection(blunder.outcome))
      << ObservationOutcomeName(blunder.outcome);
  EXPECT_EQ(blunder.refined_xy, wrong);

  cv::Mat flat(kImageSize, kImageSize, CV_32F, cv::Scalar(100));
  const ObservationRefinement flat_result =
      RefineObservation(flat,
                        reference_xy,
                        views.images[1],
                        views.ToView(1, reference_xy),
                        Eigen::Matrix2d::Identity(),
                        options);
  EXPECT_EQ(flat_result.outcome, ObservationOutcome::kFlatPatch);
  // A patch off the image.
  const ObservationRefinement outside =
      RefineObservation(views.images[0],
                        Eigen::Vector2d(3.5, 100.5),
                        views.images[1],
                        Eigen::Vector2d(3.5, 100.5),
                        Eigen::Matrix2d::Identity(),
                        options);
  EXPECT_EQ(outside.outcome, ObservationOutcome::kOutsideImage);
}

TEST(KeypointRefinement, TrackObservationsBecomeConjugateToTheReference) {
  const SyntheticViews views = MakeViews(1.0);
  const std::vector<Eigen::Vector2d> points = GridPoints();
  std::map<image_t, RefinementImage> images;
  for (int view = 0; view < 3; ++view) {
    images[view + 1].gray = views.images[view];
    images[view + 1].keypoints =
        MakeKeypoints(views, view, points, 1.0, 7 + view);
  }
  KeypointRefinementOptions options;
  options.num_threads = 1;
  int num_refined = 0;
  double max_error = 0, max_error_before = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const point2D_t idx = static_cast<point2D_t>(k);
    const KeypointTrack track = {{1, idx}, {2, idx}, {3, idx}};
    const auto results = RefineTrack(track, images, options);
    ASSERT_EQ(results.size(), 3u);
    int reference = -1;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(results[i].observation, track[i]);
      if (results[i].outcome == ObservationOutcome::kReference) reference = i;
    }
    ASSERT_GE(reference, 0);
    EXPECT_EQ(results[reference].refined_xy, results[reference].original_xy);
    // Where the reference keypoint is on the texture, and so where the
    // others must be.
    const Eigen::Vector2d s =
        views.ToTexture(reference, results[reference].original_xy);
    for (int i = 0; i < 3; ++i) {
      if (i == reference) continue;
      const Eigen::Vector2d truth = views.ToView(i, s);
      max_error_before =
          std::max(max_error_before, (results[i].original_xy - truth).norm());
      if (results[i].outcome != ObservationOutcome::kRefined) continue;
      ++num_refined;
      max_error = std::max(max_error, (results[i].refined_xy - truth).norm());
    }
  }
  // 25 tracks of 3: 50 observations to refine, nearly all succeed.
  EXPECT_GE(num_refined, 45);
  EXPECT_GT(max_error_before, 0.5);
  EXPECT_LT(max_error, 0.08);

  // Tracks that are too long are left alone.
  options.max_track_length = 2;
  for (const ObservationRefinement& result :
       RefineTrack({{1, 0}, {2, 0}, {3, 0}}, images, options)) {
    EXPECT_EQ(result.outcome, ObservationOutcome::kLongTrack);
    EXPECT_EQ(result.refined_xy, result.original_xy);
  }
}

// A COLMAP database of the three views with noisy keypoints, descriptors,
// matches (pairs 1-2, 2-3, and one wrong match in 1-3) and their verified
// geometries; the images as 8-bit PNG files.
struct SyntheticDatabase {
  std::string dir, database_path, image_path;
  SyntheticViews views;
  std::vector<Eigen::Vector2d> points;
};

SyntheticDatabase MakeDatabase(const std::string& name) {
  SyntheticDatabase data;
  data.dir = testing::TempDir(name);
  data.database_path = data.dir + "/database.db";
  data.image_path = data.dir + "/images";
  fs::create_directories(data.image_path);
  data.views = MakeViews(0.5);
  data.points = GridPoints();
  Database database(data.database_path, Database::Mode::kCreate);
  const camera_t camera_id = database.WriteCamera(Camera::Create(
      CameraModelId::kSimplePinhole, 200, kImageSize, kImageSize));
  const int n = static_cast<int>(data.points.size());
  for (int view = 0; view < 3; ++view) {
    const std::string name = StrCat("view", view, ".png");
    cv::Mat bytes;
    data.views.images[view].convertTo(bytes, CV_8U);
    CHECK(cv::imwrite(data.image_path + "/" + name, bytes));
    const image_t image_id = database.WriteImage(
        DatabaseImage{kInvalidImageId, name, camera_id, {}, {}});
    database.WriteKeypoints(
        image_id, MakeKeypoints(data.views, view, data.points, 1.0, 20 + view));
    FeatureDescriptors descriptors(n, 128);
    descriptors.setConstant(static_cast<uint8_t>(view));
    database.WriteDescriptors(image_id, descriptors);
  }
  FeatureMatches wrong(1, 2);
  wrong << 0, 1;
  for (const auto& [id1, id2, matches] :
       {std::make_tuple(1, 2, IdentityMatches(n)),
        std::make_tuple(2, 3, IdentityMatches(n)),
        std::make_tuple(1, 3, wrong)}) {
    database.WriteMatches(id1, id2, matches);
    TwoViewGeometry geometry;
    geometry.config = TwoViewConfig::kUncalibrated;
    geometry.inlier_matches = matches;
    database.WriteTwoViewGeometry(id1, id2, geometry);
  }
  return data;
}

TEST(KeypointRefinement, WritesARefinedCopyOfTheDatabase) {
  const SyntheticDatabase data = MakeDatabase("refine_keypoints_db");
  const uint64_t input_hash = FileHash(data.database_path);
  const std::string output_path = data.dir + "/refined.db";
  KeypointRefinementOptions options;
  options.num_threads = 2;
  const KeypointRefinementSummary summary = RefineDatabaseKeypoints(
      data.database_path, data.image_path, output_path, false, options);
  EXPECT_EQ(FileHash(data.database_path), input_hash);
  EXPECT_EQ(summary.match_source, "two_view_geometries");
  EXPECT_EQ(summary.num_pairs, 3);
  // The wrong match 1:0 - 3:1 joins tracks 0 and 1 into one of 6
  // observations (two in views 1 and 3): 24 tracks.
  EXPECT_EQ(summary.num_tracks, 24);
  EXPECT_EQ(summary.num_observations, 75);
  EXPECT_EQ(summary.num_reference, 24);
  EXPECT_GE(summary.num_refined, 45);
  EXPECT_GE(summary.num_rejected, 3);  // the wrong point's three at least
  EXPECT_EQ(summary.num_refined + summary.num_rejected + summary.num_reference,
            summary.num_observations);
  ASSERT_EQ(summary.images.size(), 3u);
  EXPECT_EQ(summary.images[0].num_keypoints, 25);
  EXPECT_GT(summary.median_shift_px, 0.2);

  Database input(data.database_path, Database::Mode::kReadOnly);
  Database output(output_path, Database::Mode::kReadOnly);
  EXPECT_EQ(output.UserVersion(), input.UserVersion());
  // Everything but the keypoint positions is as it was.
  for (image_t image_id = 1; image_id <= 3; ++image_id) {
    const FeatureKeypoints before = input.ReadKeypoints(image_id);
    const FeatureKeypoints after = output.ReadKeypoints(image_id);
    ASSERT_EQ(after.rows(), before.rows());
    ASSERT_EQ(after.cols(), 6);
    EXPECT_EQ(after.rightCols<4>(), before.rightCols<4>());
    EXPECT_EQ(output.ReadDescriptors(image_id),
              input.ReadDescriptors(image_id));
  }
  EXPECT_EQ(output.ReadAllMatches().size(), 3u);
  EXPECT_EQ(output.ReadMatches(1, 2), input.ReadMatches(1, 2));
  EXPECT_EQ(output.ReadTwoViewGeometry(2, 3).inlier_matches,
            input.ReadTwoViewGeometry(2, 3).inlier_matches);

  // The refined tracks agree: the texture positions of a clean track's
  // three keypoints (points 2..24), up to 0.8 px apart before, coincide to a
  // tenth of a pixel after, in every track but those with a rejected
  // observation beyond the wrong point's three (which keeps its error).
  double spread_before = 0;
  int num_agreeing = 0;
  for (int k = 2; k < 25; ++k) {
    std::vector<Eigen::Vector2d> before, after;
    for (int view = 0; view < 3; ++view) {
      before.push_back(data.views.ToTexture(
          view, KeypointXY(input.ReadKeypoints(view + 1), k)));
      after.push_back(data.views.ToTexture(
          view, KeypointXY(output.ReadKeypoints(view + 1), k)));
    }
    double track_after = 0;
    for (int a = 0; a < 3; ++a) {
      for (int b = a + 1; b < 3; ++b) {
        spread_before = std::max(spread_before, (before[a] - before[b]).norm());
        track_after = std::max(track_after, (after[a] - after[b]).norm());
      }
    }
    num_agreeing += track_after < 0.1;
  }
  EXPECT_GT(spread_before, 0.8);
  EXPECT_GE(num_agreeing, 23 - (summary.num_rejected - 3));
  // ... and most of them to a few hundredths of a pixel.
  EXPECT_LT(summary.num_rejected, 10);
}

TEST(KeypointRefinement, RefusesBadInputAndLeavesTheInputUnchanged) {
  const SyntheticDatabase data = MakeDatabase("refine_keypoints_bad");
  const uint64_t input_hash = FileHash(data.database_path);
  KeypointRefinementOptions options;
  const auto expect_error = [&](const std::string& database_path,
                                const std::string& image_path,
                                const std::string& output_path,
                                const std::string& named) {
    try {
      RefineDatabaseKeypoints(
          database_path, image_path, output_path, false, options);
      ADD_FAILURE() << "no error for " << named;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(named), std::string::npos)
          << error.what();
    }
    EXPECT_EQ(FileHash(data.database_path), input_hash);
  };
  // The output exists.
  const std::string existing = data.dir + "/existing.db";
  std::ofstream(existing) << "mine";
  expect_error(data.database_path, data.image_path, existing, existing);
  EXPECT_EQ(ReadFileToString(existing), "mine");
  // The output is the input.
  expect_error(data.database_path,
               data.image_path,
               data.database_path,
               data.database_path);
  // Not a COLMAP database.
  const std::string text = data.dir + "/notes.db";
  std::ofstream(text) << "not a database\n";
  expect_error(text, data.image_path, data.dir + "/out1.db", text);
  EXPECT_FALSE(fs::exists(data.dir + "/out1.db"));
  // An image missing.
  fs::remove(data.image_path + "/view2.png");
  expect_error(
      data.database_path, data.image_path, data.dir + "/out2.db", "view2.png");
  EXPECT_FALSE(fs::exists(data.dir + "/out2.db"));
  // Options.
  options.max_sigma0 = 0;
  expect_error(
      data.database_path, data.image_path, data.dir + "/out3.db", "max_sigma0");
}

}  // namespace
}  // namespace bayon
