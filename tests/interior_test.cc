// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon interior` end to end (issue 5, item 1): virtual fiducials on the
// film scans of `bayon synth --scene tower --film_scan 1`, whose database
// carries the nominal camera and no image frames (--nominal_calibration 1),
// compared with the true frames in gt/interior.json: the corners within
// 0.3 px, the image coordinate systems within 0.01 mm over the frame. Then
// scans without a visible frame, kept rows, digital images and bad input.
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <map>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

constexpr int kNumViews = 4;

void RunOk(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

// Four film scans of 900 x 600 pixels across the frame (40 um), in a
// (36 + 4) x (24 + 4) mm scan; the database without the true frames.
std::string FilmScanFixture() {
  return testing::SharedFixture("interior_film_tower",
                                [](const std::string& dir) {
                                  RunOk({"synth",
                                         "--scene",
                                         "tower",
                                         "--output_path",
                                         dir + "/ws",
                                         "--num_views",
                                         std::to_string(kNumViews),
                                         "--image_width",
                                         "900",
                                         "--mesh_spacing_m",
                                         "0.08",
                                         "--texel_size_m",
                                         "0.02",
                                         "--supersampling",
                                         "3",
                                         "--film_scan",
                                         "1",
                                         "--nominal_calibration",
                                         "1",
                                         "--seed",
                                         "7"});
                                });
}

// A fresh copy of the fixture's workspace.
std::string CopyWorkspace(const std::string& name) {
  const std::string dir = testing::TempDir(name);
  testing::CopyTree(FilmScanFixture() + "/ws", dir + "/ws");
  return dir + "/ws";
}

struct TrueFrame {
  ImageFrame frame;
  std::array<Eigen::Vector2d, 4> corners_px;
  double rotation_deg = 0;
};

std::map<std::string, TrueFrame> ReadTruth(const std::string& ws) {
  const nlohmann::json json =
      nlohmann::json::parse(ReadFileToString(ws + "/gt/interior.json"));
  std::map<std::string, TrueFrame> truth;
  for (const nlohmann::json& image : json["images"]) {
    TrueFrame t;
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 3; ++c) {
        t.frame.pixel_from_frame(r, c) =
            image["pixel_from_frame"][r][c].get<double>();
      }
    }
    for (int k = 0; k < 4; ++k) {
      t.corners_px[k] =
          Eigen::Vector2d(image["frame_corners_px"][k][0].get<double>(),
                          image["frame_corners_px"][k][1].get<double>());
    }
    t.rotation_deg = image["rotation_deg"].get<double>();
    truth[image["name"].get<std::string>()] = t;
  }
  return truth;
}

std::map<std::string, InteriorRecord> ReadInteriorsByName(
    const std::string& database_path) {
  Database database(database_path, Database::Mode::kReadOnly);
  std::map<std::string, InteriorRecord> records;
  for (const auto& [image_id, record] : ReadAllInteriors(&database)) {
    records[database.ReadImage(image_id).name] = record;
  }
  return records;
}

TEST(Interior, VirtualFiducialsOnSyntheticFilmScans) {
  const std::string ws = CopyWorkspace("interior_film");
  // The blind database has no frames to start from.
  EXPECT_TRUE(ReadInteriorsByName(ws + "/database.db").empty());
  const testing::CommandResult result = testing::RunBayon({"interior",
                                                           "--database_path",
                                                           ws + "/database.db",
                                                           "--image_path",
                                                           ws + "/images",
                                                           "--film_scan",
                                                           "1"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find(StrCat(kNumViews, " film frames measured")),
            std::string::npos)
      << result.output;

  const std::map<std::string, TrueFrame> truth = ReadTruth(ws);
  const std::map<std::string, InteriorRecord> records =
      ReadInteriorsByName(ws + "/database.db");
  ASSERT_EQ(records.size(), static_cast<size_t>(kNumViews)) << result.output;
  const double w = 36, h = 24;
  const Eigen::Vector2d nominal[4] = {
      {-w / 2, h / 2}, {w / 2, h / 2}, {w / 2, -h / 2}, {-w / 2, -h / 2}};
  double max_corner = 0, sum_corner2 = 0, max_mm = 0, sum_mm2 = 0;
  int num_corners = 0, num_mm = 0;
  for (const auto& [name, record] : records) {
    ASSERT_TRUE(truth.count(name)) << name;
    const TrueFrame& t = truth.at(name);
    EXPECT_EQ(record.method, "virtual_fiducials");
    EXPECT_NEAR(record.frame_rotation_deg, t.rotation_deg, 0.01) << name;
    EXPECT_GT(record.rms_residual_px, 0);
    EXPECT_LT(record.rms_residual_px, 0.3) << name;
    // The corners the stored frame puts at the nominal corners.
    for (int k = 0; k < 4; ++k) {
      const double error =
          (record.frame.PixelFromFrame(nominal[k]) - t.corners_px[k]).norm();
      EXPECT_LT(error, 0.3) << name << " corner " << k;
      max_corner = std::max(max_corner, error);
      sum_corner2 += error * error;
      ++num_corners;
    }
    // Image coordinates of the same pixel, over the frame (11 x 11 grid).
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const Eigen::Vector2d mm(w * (i / 10.0 - 0.5), h * (j / 10.0 - 0.5));
        const Eigen::Vector2d pixel = t.frame.PixelFromFrame(mm);
        const double error = (record.frame.FrameFromPixel(pixel) - mm).norm();
        EXPECT_LT(error, 0.01) << name << " at " << mm.transpose() << " mm";
        max_mm = std::max(max_mm, error);
        sum_mm2 += error * error;
        ++num_mm;
      }
    }
  }
  std::cout << "virtual fiducials, " << records.size() << " scans: corners RMS "
            << std::sqrt(sum_corner2 / num_corners) << " px, max " << max_corner
            << " px; image coordinates RMS " << std::sqrt(sum_mm2 / num_mm)
            << " mm, max " << max_mm << " mm" << std::endl;

  // Again without --overwrite: every row is kept, and said so.
  const testing::CommandResult again = testing::RunBayon({"interior",
                                                          "--database_path",
                                                          ws + "/database.db",
                                                          "--image_path",
                                                          ws + "/images",
                                                          "--film_scan",
                                                          "1"});
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find(StrCat(kNumViews, " kept")), std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("--overwrite 1 replaces it"), std::string::npos)
      << again.output;
}

TEST(Interior, ScansWithoutAVisibleFrameFailPerImage) {
  const std::string ws = CopyWorkspace("interior_no_frame");
  const std::string first = ws + "/images/image_001.png";
  const std::string second = ws + "/images/image_002.png";
  const cv::Mat scan = cv::imread(first);
  ASSERT_FALSE(scan.empty());
  // image_001: the photograph fills the scan (its middle, enlarged).
  cv::Mat filled;
  cv::resize(scan(cv::Rect(
                 scan.cols / 4, scan.rows / 4, scan.cols / 2, scan.rows / 2)),
             filled,
             scan.size(),
             0,
             0,
             cv::INTER_LINEAR);
  ASSERT_TRUE(cv::imwrite(first, filled));
  // image_002: a uniform grey scan.
  ASSERT_TRUE(cv::imwrite(
      second, cv::Mat(scan.size(), scan.type(), cv::Scalar(70, 70, 70))));

  const testing::CommandResult result = testing::RunBayon({"interior",
                                                           "--database_path",
                                                           ws + "/database.db",
                                                           "--image_path",
                                                           ws + "/images",
                                                           "--film_scan",
                                                           "1"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("image_001.png: FAILED"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("image_002.png: FAILED"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("no frame edges found"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("2 failed"), std::string::npos) << result.output;
  const std::map<std::string, InteriorRecord> records =
      ReadInteriorsByName(ws + "/database.db");
  EXPECT_EQ(records.size(), static_cast<size_t>(kNumViews - 2));
  EXPECT_EQ(records.count("image_001.png"), 0u);
  EXPECT_EQ(records.count("image_002.png"), 0u);
  EXPECT_EQ(records.count("image_003.png"), 1u);

  // Nothing usable at all: exit code 1, and no rows.
  const std::string blank = CopyWorkspace("interior_blank");
  for (int i = 1; i <= kNumViews; ++i) {
    ASSERT_TRUE(
        cv::imwrite(blank + "/images/image_00" + std::to_string(i) + ".png",
                    cv::Mat(scan.size(), scan.type(), cv::Scalar(30, 30, 30))));
  }
  const testing::CommandResult none = testing::RunBayon({"interior",
                                                         "--database_path",
                                                         blank + "/database.db",
                                                         "--image_path",
                                                         blank + "/images",
                                                         "--film_scan",
                                                         "1"});
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_TRUE(ReadInteriorsByName(blank + "/database.db").empty());
}

TEST(Interior, DigitalFramesAndOverwrite) {
  const std::string ws = CopyWorkspace("interior_digital");
  RunOk({"interior",
         "--database_path",
         ws + "/database.db",
         "--image_path",
         ws + "/images",
         "--film_scan",
         "1"});
  // Digital frames replace the measured ones only with --overwrite 1.
  const std::vector<std::string> digital = {"interior",
                                            "--database_path",
                                            ws + "/database.db",
                                            "--image_path",
                                            ws + "/images",
                                            "--overwrite",
                                            "1"};
  const testing::CommandResult result = testing::RunBayon(digital);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  Database database(ws + "/database.db", Database::Mode::kReadOnly);
  const std::optional<CalibrationRecord> calibration =
      ReadCalibration(&database, 1);
  ASSERT_TRUE(calibration);
  const ImageFrame expected = calibration->camera.DefaultFrame();
  const auto records = ReadAllInteriors(&database);
  ASSERT_EQ(records.size(), static_cast<size_t>(kNumViews));
  for (const auto& [image_id, record] : records) {
    EXPECT_EQ(record.method, "digital");
    EXPECT_LT((record.frame.pixel_from_frame - expected.pixel_from_frame)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12);
  }
}

// Every file of a folder but the logs, which record the refused run.
std::map<std::string, uint64_t> HashWithoutLogs(const std::string& path) {
  std::map<std::string, uint64_t> hashes = testing::HashTree(path);
  for (auto it = hashes.begin(); it != hashes.end();) {
    it = it->first.rfind("logs/", 0) == 0 ? hashes.erase(it) : std::next(it);
  }
  return hashes;
}

TEST(Interior, BadInputChangesNothing) {
  const std::string ws = CopyWorkspace("interior_bad");
  const auto before = HashWithoutLogs(ws);
  // A missing image.
  fs::rename(ws + "/images/image_003.png", ws + "/image_003.png");
  testing::CommandResult result = testing::RunBayon({"interior",
                                                     "--database_path",
                                                     ws + "/database.db",
                                                     "--image_path",
                                                     ws + "/images",
                                                     "--film_scan",
                                                     "1"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("image_003.png"), std::string::npos)
      << result.output;
  fs::rename(ws + "/image_003.png", ws + "/images/image_003.png");
  // A bad option.
  result = testing::RunBayon({"interior",
                              "--database_path",
                              ws + "/database.db",
                              "--image_path",
                              ws + "/images",
                              "--film_scan",
                              "1",
                              "--frame_width_mm",
                              "0"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("frame_width_mm"), std::string::npos)
      << result.output;
  EXPECT_EQ(HashWithoutLogs(ws), before);

  // Film scans need a BROWN_BEYER camera: a database as `bayon import`
  // writes it with its default SIMPLE_RADIAL camera is refused.
  const std::string db = fs::path(ws).parent_path().string() + "/colmap.db";
  RunOk({"import", "--image_path", ws + "/images", "--database_path", db});
  const auto db_before = testing::HashTree(db);
  result = testing::RunBayon({"interior",
                              "--database_path",
                              db,
                              "--image_path",
                              ws + "/images",
                              "--film_scan",
                              "1"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("BROWN_BEYER"), std::string::npos)
      << result.output;
  EXPECT_EQ(testing::HashTree(db), db_before);
}

}  // namespace
}  // namespace bayon
