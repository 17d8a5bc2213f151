// SPDX-License-Identifier: BSD-3-Clause
//
// bayon refine_keypoints end to end (issue 5): a stock COLMAP database of
// the real temple ring (SIFT from `colmap feature_extractor`,
// `exhaustive_matcher`: the tests' one COLMAP run of it, temple_fixture.h),
// refined by least-squares matching; stock `colmap
// mapper` on both databases, judged with `bayon evaluate` against the
// calibrated cameras (`bayon import_ground_truth`). Bad input: one line,
// exit code 2, the input unchanged.
#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/temple_fixture.h"
#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

void RunBayonOk(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

void RunColmapOk(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunColmap(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadFileToString(path));
}

struct MapperResult {
  int num_registered = 0;
  double mean_reprojection_error_px = 0;
  double center_rms = 0;
  double rotation_rms_deg = 0;
};

// Stock `colmap mapper` on a copy of `database_path` with its camera held
// fixed; the largest model, evaluated against the truth.
MapperResult MapAndEvaluate(const std::string& database_path,
                            const std::string& truth_path,
                            const std::string& dir) {
  const std::string images = testing::DataPath("temple-ring");
  const std::string copy = dir + "/database.db";
  fs::create_directories(dir + "/sparse");
  CopyDatabaseForColmap(database_path, copy);
  // The database's camera is the calibration compare_colmap gave COLMAP
  // (the one bayon's pipeline was given): held fixed, as there.
  RunColmapOk({"mapper",
               "--database_path",
               copy,
               "--image_path",
               images,
               "--output_path",
               dir + "/sparse",
               "--Mapper.ba_refine_focal_length",
               "0",
               "--Mapper.ba_refine_principal_point",
               "0",
               "--Mapper.ba_refine_extra_params",
               "0"});
  std::string best;
  size_t best_size = 0;
  for (const auto& entry : fs::directory_iterator(dir + "/sparse")) {
    const size_t size = ReadModel(entry.path().string()).images.size();
    if (size > best_size) {
      best_size = size;
      best = entry.path().string();
    }
  }
  MapperResult result;
  if (best.empty()) {
    ADD_FAILURE() << "colmap mapper made no model in " << dir;
    return result;
  }
  // The mean of the points' errors, as colmap model_analyzer prints it.
  result.mean_reprojection_error_px =
      ReadModel(best).Stats().mean_reprojection_error_px;
  RunBayonOk({"evaluate",
              "--input_path",
              best,
              "--ground_truth_path",
              truth_path,
              "--output_path",
              dir + "/evaluate.json"});
  const nlohmann::json sparse = ReadJson(dir + "/evaluate.json")["sparse"];
  result.num_registered = sparse["num_registered"];
  result.center_rms = sparse["center_rms"];
  result.rotation_rms_deg = sparse["rotation_rms_deg"];
  return result;
}

TEST(RefineKeypoints, TempleMapsWithLowerReprojectionErrorAndNoWorsePoses) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string stock_db = testing::TempleColmapFixture().database;
  const std::string truth = testing::TempleConfigFixture().truth;
  const std::string dir = testing::TempDir("refine_keypoints_temple");
  const std::string refined_db = dir + "/refined.db";
  const uint64_t stock_hash = FileHash(stock_db);
  RunBayonOk({"refine_keypoints",
              "--database_path",
              stock_db,
              "--image_path",
              testing::DataPath("temple-ring"),
              "--output_path",
              refined_db,
              "--report_path",
              dir + "/refine.json"});
  EXPECT_EQ(FileHash(stock_db), stock_hash);

  const nlohmann::json report = ReadJson(dir + "/refine.json");
  const int64_t num_refined = report["num_refined"];
  const int64_t num_candidates = report["num_observations"].get<int64_t>() -
                                 report["num_reference"].get<int64_t>();
  std::printf(
      "refine_keypoints: %lld of %lld observations refined, median "
      "shift %.3f px\n",
      static_cast<long long>(num_refined),
      static_cast<long long>(num_candidates),
      report["median_shift_px"].get<double>());
  EXPECT_GT(num_refined, num_candidates / 2);
  // SIFT on 640 x 480 images is good to a few tenths of a pixel.
  EXPECT_GT(report["median_shift_px"].get<double>(), 0.05);
  EXPECT_LT(report["median_shift_px"].get<double>(), 1.0);

  // Everything but the keypoint positions is the stock database's.
  {
    Database stock(stock_db, Database::Mode::kReadOnly);
    Database refined(refined_db, Database::Mode::kReadOnly);
    EXPECT_EQ(refined.UserVersion(), stock.UserVersion());
    EXPECT_EQ(refined.NumKeypoints(), stock.NumKeypoints());
    EXPECT_EQ(refined.NumInlierMatches(), stock.NumInlierMatches());
    EXPECT_EQ(refined.NumMatches(), stock.NumMatches());
    int num_moved = 0;
    for (const DatabaseImage& image : stock.ReadAllImages()) {
      const FeatureKeypoints a = stock.ReadKeypoints(image.image_id);
      const FeatureKeypoints b = refined.ReadKeypoints(image.image_id);
      ASSERT_EQ(a.rows(), b.rows());
      ASSERT_EQ(a.cols(), b.cols());
      EXPECT_EQ(a.rightCols(a.cols() - 2), b.rightCols(b.cols() - 2));
      EXPECT_EQ(stock.ReadDescriptors(image.image_id),
                refined.ReadDescriptors(image.image_id));
      for (int i = 0; i < a.rows(); ++i) num_moved += a.row(i) != b.row(i);
    }
    // A refined keypoint may move by less than float precision.
    EXPECT_LE(num_moved, num_refined);
    EXPECT_GE(num_moved, 0.99 * num_refined);
  }

  const MapperResult stock = MapAndEvaluate(stock_db, truth, dir + "/stock");
  const MapperResult refined =
      MapAndEvaluate(refined_db, truth, dir + "/refined");
  std::printf(
      "%-10s %10s %10s %12s %10s\n%-10s %10d %10.4f %12.6g %10.4f\n"
      "%-10s %10d %10.4f %12.6g %10.4f\n",
      "database",
      "registered",
      "reproj px",
      "centre RMS",
      "rot deg",
      "stock",
      stock.num_registered,
      stock.mean_reprojection_error_px,
      stock.center_rms,
      stock.rotation_rms_deg,
      "refined",
      refined.num_registered,
      refined.mean_reprojection_error_px,
      refined.center_rms,
      refined.rotation_rms_deg);
  ASSERT_GE(stock.num_registered, 10);
  EXPECT_GE(refined.num_registered, stock.num_registered);
  EXPECT_LT(refined.mean_reprojection_error_px,
            0.97 * stock.mean_reprojection_error_px);
  // Not worse, within 1 % (the mapper's own rounding between runs).
  EXPECT_LE(refined.center_rms, 1.01 * stock.center_rms);
  EXPECT_LE(refined.rotation_rms_deg, 1.01 * stock.rotation_rms_deg);
}

TEST(RefineKeypoints, BadInputIsOneLineExitTwoAndTheInputUnchanged) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string stock_db = testing::TempleColmapFixture().database;
  const std::string images = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("refine_keypoints_bad");
  const uint64_t stock_hash = FileHash(stock_db);
  const auto expect_refused = [&](const std::vector<std::string>& args,
                                  const std::string& named) {
    std::vector<std::string> argv = {"refine_keypoints"};
    argv.insert(argv.end(), args.begin(), args.end());
    const testing::CommandResult result = testing::RunBayon(argv);
    EXPECT_EQ(result.exit_code, 2) << result.output;
    EXPECT_NE(result.LastLine().find(named), std::string::npos)
        << result.output;
    EXPECT_EQ(FileHash(stock_db), stock_hash);
  };

  // The output exists already.
  const std::string existing = dir + "/existing.db";
  std::ofstream(existing) << "keep me";
  expect_refused({"--database_path",
                  stock_db,
                  "--image_path",
                  images,
                  "--output_path",
                  existing},
                 existing);
  EXPECT_EQ(ReadFileToString(existing), "keep me");

  // The input is not a COLMAP database.
  const std::string text = dir + "/notes.db";
  std::ofstream(text) << "not a database\n";
  const uint64_t text_hash = FileHash(text);
  expect_refused({"--database_path",
                  text,
                  "--image_path",
                  images,
                  "--output_path",
                  dir + "/out1.db"},
                 text);
  EXPECT_EQ(FileHash(text), text_hash);
  EXPECT_FALSE(fs::exists(dir + "/out1.db"));
  EXPECT_FALSE(fs::exists(dir + "/logs"));

  // An image missing: the folder holds all but templeSR0007.png.
  const std::string partial = dir + "/images";
  fs::create_directories(partial);
  for (const auto& entry : fs::directory_iterator(images)) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() == ".png" && name != "templeSR0007.png") {
      fs::copy_file(entry.path(), partial + "/" + name);
    }
  }
  expect_refused({"--database_path",
                  stock_db,
                  "--image_path",
                  partial,
                  "--output_path",
                  dir + "/out2.db"},
                 "templeSR0007.png");
  EXPECT_FALSE(fs::exists(dir + "/out2.db"));

  // --overwrite 1 replaces an existing output.
  RunBayonOk({"refine_keypoints",
              "--database_path",
              stock_db,
              "--image_path",
              images,
              "--output_path",
              existing,
              "--overwrite",
              "1"});
  EXPECT_EQ(FileHash(stock_db), stock_hash);
  Database replaced(existing, Database::Mode::kReadOnly);
  EXPECT_GT(replaced.NumKeypoints(), 0);
}

}  // namespace
}  // namespace bayon
