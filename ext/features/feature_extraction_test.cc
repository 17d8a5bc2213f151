// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/feature_extraction.h"

#include "ext/colmap/control_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_features.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

cv::Mat Texture(int width, int height, unsigned seed) {
  cv::Mat image(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.2);
  return image;
}

// A database with three images: 8-bit grey, 16-bit grey and 8-bit colour
// versions of the same texture.
std::string MakeWorkspace(const std::string& name) {
  const std::string dir = testing::TempDir(name);
  fs::create_directories(dir + "/images");
  const cv::Mat texture = Texture(160, 120, 11);
  cv::Mat gray8, gray16, color;
  texture.convertTo(gray8, CV_8U);
  gray8.convertTo(gray16, CV_16U, 257.0);
  cv::cvtColor(gray8, color, cv::COLOR_GRAY2BGR);
  WriteImage(dir + "/images/a.png", gray8);
  WriteImage(dir + "/images/b.png", gray16);
  WriteImage(dir + "/images/c.png", color);
  Database database(dir + "/database.db", Database::Mode::kCreate);
  const camera_t camera_id = database.WriteCamera(
      Camera::Create(CameraModelId::kSimpleRadial, 200, 160, 120));
  for (const char* image_name : {"a.png", "b.png", "c.png"}) {
    DatabaseImage image;
    image.name = image_name;
    image.camera_id = camera_id;
    database.WriteImage(image);
  }
  return dir;
}

FeatureExtractionOptions SmallOptions() {
  FeatureExtractionOptions options;
  options.moravec.max_num_features = 100;
  options.num_threads = 2;
  return options;
}

TEST(FeatureExtraction, WritesKeypointsAndInterestForAnyDepth) {
  const std::string dir = MakeWorkspace("features_depths");
  const FeatureExtractionSummary summary =
      ExtractFeatures(dir + "/database.db", dir + "/images", SmallOptions());
  EXPECT_EQ(summary.num_extracted, 3);
  EXPECT_EQ(summary.num_skipped, 0);
  Database database(dir + "/database.db", Database::Mode::kReadOnly);
  const FeatureKeypoints a = database.ReadKeypoints(1);
  ASSERT_GT(a.rows(), 50);
  EXPECT_EQ(a.cols(), 6);
  // The same picture in 16 bits and in colour gives the same points.
  EXPECT_EQ(database.ReadKeypoints(2), a);
  EXPECT_EQ(database.ReadKeypoints(3), a);
  const auto interest = ReadKeypointInterest(&database, 1);
  ASSERT_TRUE(interest.has_value());
  EXPECT_EQ(interest->detector, "moravec");
  EXPECT_EQ(interest->interest.size(), static_cast<size_t>(a.rows()));
  EXPECT_GE(interest->interest.back(), SmallOptions().moravec.min_interest);
  EXPECT_FALSE(database.ExistsDescriptors(1));
}

TEST(FeatureExtraction, SiftAndBothGiveEveryKeypointADescriptor) {
  const std::string dir = MakeWorkspace("features_sift");
  const std::string db = dir + "/database.db";
  FeatureExtractionOptions options = SmallOptions();
  ExtractFeatures(db, dir + "/images", options);
  FeatureKeypoints moravec;
  {
    Database database(db, Database::Mode::kReadOnly);
    moravec = database.ReadKeypoints(1);
  }
  options.overwrite = true;
  options.detector = FeatureDetector::kSift;
  const FeatureExtractionSummary sift =
      ExtractFeatures(db, dir + "/images", options);
  EXPECT_EQ(sift.num_sift, sift.num_features);
  int num_sift = 0;
  {
    Database database(db, Database::Mode::kReadOnly);
    const FeatureKeypoints keypoints = database.ReadKeypoints(1);
    num_sift = static_cast<int>(keypoints.rows());
    ASSERT_GT(num_sift, 20);
    EXPECT_EQ(database.ReadDescriptors(1).rows(), num_sift);
    const auto interest = ReadKeypointInterest(&database, 1);
    ASSERT_TRUE(interest.has_value());
    EXPECT_EQ(interest->detector, "sift");
    ASSERT_EQ(interest->interest.size(), static_cast<size_t>(num_sift));
    for (float value : interest->interest) EXPECT_TRUE(std::isnan(value));
  }
  // Both: the Moravec points as before, then the SIFT keypoints.
  options.detector = FeatureDetector::kBoth;
  ExtractFeatures(db, dir + "/images", options);
  Database database(db, Database::Mode::kReadOnly);
  const FeatureKeypoints keypoints = database.ReadKeypoints(1);
  const int num_moravec = static_cast<int>(moravec.rows());
  ASSERT_EQ(keypoints.rows(), num_moravec + num_sift);
  EXPECT_EQ(keypoints.topRows(num_moravec), moravec);
  EXPECT_EQ(database.ReadDescriptors(1).rows(), keypoints.rows());
  const auto interest = ReadKeypointInterest(&database, 1);
  ASSERT_TRUE(interest.has_value());
  EXPECT_EQ(interest->detector, "both");
  for (int i = 0; i < keypoints.rows(); ++i) {
    EXPECT_EQ(std::isfinite(interest->interest[i]), i < num_moravec) << i;
  }
  // Back to Moravec alone: the descriptors go with the old keypoints.
  options.detector = FeatureDetector::kMoravec;
  ExtractFeatures(db, dir + "/images", options);
  EXPECT_FALSE(database.ExistsDescriptors(1));
}

TEST(FeatureExtraction, KeepsKeypointsUnlessOverwriteThenDropsTheirMatches) {
  const std::string dir = MakeWorkspace("features_overwrite");
  const std::string db = dir + "/database.db";
  FeatureExtractionOptions options = SmallOptions();
  ExtractFeatures(db, dir + "/images", options);
  {
    Database database(db, Database::Mode::kReadWrite);
    FeatureMatches matches(2, 2);
    matches << 0, 1, 2, 3;
    database.WriteMatches(1, 2, matches);
    database.WriteMatches(2, 3, matches);
  }
  options.moravec.max_num_features = 20;
  const FeatureExtractionSummary kept =
      ExtractFeatures(db, dir + "/images", options);
  EXPECT_EQ(kept.num_skipped, 3);
  {
    Database database(db, Database::Mode::kReadOnly);
    EXPECT_GT(database.ReadKeypoints(1).rows(), 20);
    EXPECT_EQ(database.NumMatchedPairs(), 2);
  }
  options.overwrite = true;
  const FeatureExtractionSummary replaced =
      ExtractFeatures(db, dir + "/images", options);
  EXPECT_EQ(replaced.num_extracted, 3);
  EXPECT_EQ(replaced.num_pairs_invalidated, 2);
  Database database(db, Database::Mode::kReadOnly);
  EXPECT_EQ(database.ReadKeypoints(1).rows(), 20);
  EXPECT_EQ(database.NumMatchedPairs(), 0);
}

// Coded targets join the keypoints after the detector's, with no interest
// value and their names in bayon_keypoint_targets; a run without them
// leaves no record behind.
TEST(FeatureExtraction, AppendsCodedTargetsAsNamedKeypoints) {
  const std::string dir = MakeWorkspace("features_targets");
  const std::string db = dir + "/database.db";
  const std::string targets = dir + "/targets.txt";
  WriteImageMeasurements(targets,
                         {{"CT4", "a.png", {20.25, 30.5}, 0.03},
                          {"CT7", "a.png", {100.0, 90.75}, 0.05},
                          {"CT4", "c.png", {21.0, 31.0}, 0.04}});
  FeatureExtractionOptions options = SmallOptions();
  options.targets_path = targets;
  const FeatureExtractionSummary summary =
      ExtractFeatures(db, dir + "/images", options);
  EXPECT_EQ(summary.num_targets, 3);
  {
    Database database(db, Database::Mode::kReadOnly);
    const FeatureKeypoints a = database.ReadKeypoints(1);
    const int n = static_cast<int>(a.rows());
    const std::vector<KeypointTarget> found =
        ReadKeypointTargets(&database, 1, n);
    ASSERT_EQ(found.size(), 2u);
    EXPECT_EQ(found[0].name, "CT4");
    EXPECT_EQ(found[0].point2D_idx, static_cast<uint32_t>(n - 2));
    EXPECT_FLOAT_EQ(a(n - 2, 0), 20.25f);
    EXPECT_FLOAT_EQ(a(n - 2, 1), 30.5f);
    EXPECT_EQ(found[1].name, "CT7");
    EXPECT_FLOAT_EQ(found[1].sigma_px, 0.05f);
    const auto interest = ReadKeypointInterest(&database, 1);
    ASSERT_TRUE(interest.has_value());
    EXPECT_TRUE(std::isnan(interest->interest[n - 1]));
    EXPECT_TRUE(std::isfinite(interest->interest[n - 3]));
    EXPECT_TRUE(ReadKeypointTargets(&database, 2, 1000).empty());
    EXPECT_EQ(ReadKeypointTargets(&database, 3, 1000).size(), 0u)
        << "a record of another keypoint count is stale";
  }
  options.targets_path.clear();
  options.overwrite = true;
  ExtractFeatures(db, dir + "/images", options);
  Database database(db, Database::Mode::kReadOnly);
  EXPECT_TRUE(
      ReadKeypointTargets(
          &database, 1, static_cast<int>(database.ReadKeypoints(1).rows()))
          .empty());

  // A target in a photograph the database does not have: another
  // project's file, refused before any work.
  WriteImageMeasurements(targets, {{"CT4", "z.png", {20, 30}, 0.03}});
  options.targets_path = targets;
  const auto before = testing::HashTree(db);
  try {
    ExtractFeatures(db, dir + "/images", options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("z.png"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("targets.txt"), std::string::npos);
  }
  EXPECT_EQ(testing::HashTree(db), before);
}

TEST(FeatureExtraction, RefusesBadInputBeforeWriting) {
  const std::string dir = MakeWorkspace("features_bad");
  const std::string db = dir + "/database.db";
  fs::remove(dir + "/images/b.png");
  const auto before = testing::HashTree(db);
  try {
    ExtractFeatures(db, dir + "/images", SmallOptions());
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("b.png"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("missing on disk"),
              std::string::npos);
  }
  EXPECT_EQ(testing::HashTree(db), before);

  const std::string empty = dir + "/empty.db";
  { Database database(empty, Database::Mode::kCreate); }
  try {
    ExtractFeatures(empty, dir + "/images", SmallOptions());
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("no images"), std::string::npos);
  }
  // An image whose size is not its camera's.
  WriteImage(dir + "/images/b.png", cv::Mat(50, 60, CV_8U, cv::Scalar(3)));
  EXPECT_THROW(ExtractFeatures(db, dir + "/images", SmallOptions()),
               InputError);
  EXPECT_EQ(testing::HashTree(db), before);
}

}  // namespace
}  // namespace bayon
