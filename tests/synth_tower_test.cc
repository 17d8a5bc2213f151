// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon synth --scene tower` end to end: a small workspace (600 x 400
// photographs, a coarse tower) with every truth file, read back with
// bayon's own readers, deterministic for a seed.
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/control_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::vector<std::string> SmallTowerArgs(const std::string& output,
                                        const std::string& seed) {
  return {"synth",
          "--scene",
          "tower",
          "--output_path",
          output,
          "--num_views",
          "4",
          "--image_width",
          "600",
          "--mesh_spacing_m",
          "0.08",
          "--texel_size_m",
          "0.02",
          "--supersampling",
          "2",
          "--seed",
          seed};
}

TEST(SynthTower, WritesACompleteWorkspace) {
  const std::string dir = testing::TempDir("synth_tower");
  const std::string ws = dir + "/ws";
  const testing::CommandResult result =
      testing::RunBayon(SmallTowerArgs(ws, "3"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* file : {"images/image_001.png",
                           "images/image_004.png",
                           "database.db",
                           "control/points.txt",
                           "control/observations.txt",
                           "control/distances.txt",
                           "gt/sparse/cameras.txt",
                           "gt/sparse/images.txt",
                           "gt/sparse/points3D.txt",
                           "gt/calibration.json",
                           "gt/interior.json",
                           "gt/surface.ply",
                           "gt/surface_texture.png",
                           "gt/ground.ply",
                           "gt/control/points.txt",
                           "gt/control/observations.txt",
                           "gt/control/distances.txt",
                           "gt/heldout/images.txt",
                           "gt/synth.json"}) {
    EXPECT_TRUE(fs::exists(ws + "/" + file)) << file;
  }
  // The database as `bayon import --single_camera 1` writes it, with the
  // true calibration beside the FULL_OPENCV camera.
  {
    Database database(ws + "/database.db", Database::Mode::kReadOnly);
    const std::vector<Camera> cameras = database.ReadAllCameras();
    ASSERT_EQ(cameras.size(), 1u);
    EXPECT_EQ(cameras[0].model_id, CameraModelId::kFullOpenCV);
    EXPECT_EQ(cameras[0].width, 600u);
    const std::vector<DatabaseImage> images = database.ReadAllImages();
    ASSERT_EQ(images.size(), 4u);
    EXPECT_EQ(images[0].image_id, 1u);
    EXPECT_EQ(images[0].name, "image_001.png");
    EXPECT_EQ(images[3].image_id, 4u);
    const auto calibration = ReadCalibration(&database, cameras[0].camera_id);
    ASSERT_TRUE(calibration);
    EXPECT_EQ(calibration->camera.model_id, CameraModelId::kBrownBeyer);
    EXPECT_TRUE(ReadInterior(&database, 4));
  }
  // Truth: the true camera with all ten additional parameters but K3.
  const std::vector<CalibrationEntry> calibration =
      ReadCalibrationJson(ws + "/gt/calibration.json");
  ASSERT_EQ(calibration.size(), 1u);
  const Camera& camera = calibration[0].camera;
  EXPECT_NEAR(camera.params[brown::kC], 35.0, 1e-12);
  for (int p : {brown::kDc,
                brown::kDx0,
                brown::kDy0,
                brown::kK1,
                brown::kK2,
                brown::kP1,
                brown::kP2,
                brown::kB1,
                brown::kB2}) {
    EXPECT_NE(camera.params[p], 0.0) << p;
  }
  const Scene truth = ReadModel(ws + "/gt/sparse");
  EXPECT_EQ(truth.images.size(), 4u);
  EXPECT_GT(truth.points3D.size(), 0u);
  const TriangleMesh surface = ReadMeshPly(ws + "/gt/surface.ply");
  EXPECT_TRUE(surface.HasTexcoords());
  EXPECT_GT(surface.NumFaces(), 10000u);
  // Control: >= 7 points plus the bar's two, the bar vertical.
  const auto points = ReadControlPoints(ws + "/gt/control/points.txt");
  EXPECT_GE(points.size(), 9u);
  const auto user_points = ReadControlPoints(ws + "/control/points.txt");
  EXPECT_GE(user_points.size(), 7u);
  EXPECT_GT(user_points[0].sigma.x(), 0.0);
  const auto distances = ReadDistances(ws + "/gt/control/distances.txt");
  ASSERT_EQ(distances.size(), 1u);
  EXPECT_TRUE(distances[0].vertical);
  EXPECT_NEAR(distances[0].distance_m, 1.5, 1e-12);
  const auto observations =
      ReadImageMeasurements(ws + "/gt/control/observations.txt");
  EXPECT_GT(observations.size(), 3u);
  const nlohmann::json synth =
      nlohmann::json::parse(ReadFileToString(ws + "/gt/synth.json"));
  EXPECT_EQ(synth["images"].size(), 4u);
  EXPECT_GT(synth["gsd_m"].get<double>(), 0.005);

  // Same seed, same photographs; another seed, others.
  const testing::CommandResult again =
      testing::RunBayon(SmallTowerArgs(dir + "/again", "3"));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(testing::HashTree(ws + "/images"),
            testing::HashTree(dir + "/again/images"));
  const testing::CommandResult other =
      testing::RunBayon(SmallTowerArgs(dir + "/other", "4"));
  ASSERT_EQ(other.exit_code, 0) << other.output;
  EXPECT_NE(testing::HashTree(ws + "/images"),
            testing::HashTree(dir + "/other/images"));
}

TEST(SynthTower, FilmScansAndJpeg) {
  const std::string dir = testing::TempDir("synth_tower_film");
  std::vector<std::string> args = SmallTowerArgs(dir + "/ws", "5");
  args[6] = "2";  // --num_views 2
  for (const char* extra : {"--film_scan", "1", "--jpeg_quality", "90"}) {
    args.push_back(extra);
  }
  const testing::CommandResult result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const cv::Mat image = cv::imread(dir + "/ws/images/image_001.jpg");
  // The scan: (36 + 2 * 2) x (24 + 2 * 2) mm at 60 um.
  EXPECT_EQ(image.cols, 667);
  EXPECT_EQ(image.rows, 467);
  const nlohmann::json interior =
      nlohmann::json::parse(ReadFileToString(dir + "/ws/gt/interior.json"));
  ASSERT_EQ(interior["images"].size(), 2u);
  EXPECT_EQ(interior["images"][0]["frame_corners_px"].size(), 4u);
}

TEST(SynthTower, RefusesBadOptions) {
  const std::string dir = testing::TempDir("synth_tower_bad");
  std::vector<std::string> args = SmallTowerArgs(dir + "/ws", "1");
  args[6] = "1";  // --num_views 1
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("num_views"), std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(dir + "/ws"));
}

}  // namespace
}  // namespace bayon
