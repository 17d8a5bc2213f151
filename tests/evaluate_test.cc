// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon evaluate` end to end on a small synthetic tower: the truth judged
// against itself is perfect, a noisy cloud sampled from the true surface has
// its noise as accuracy and reaches the visible surface, a degraded texture
// scores lower than the true one, and bad input is one line with exit 2.
#include "ext/colmap/ply_io.h"
#include "ext/image/image_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string Tower() {
  return testing::SharedFixture("evaluate_tower",
                                [](const std::string& dir) {
                                  const testing::CommandResult result =
                                      testing::RunBayon({"synth",
                                                         "--scene",
                                                         "tower",
                                                         "--output_path",
                                                         dir + "/ws",
                                                         "--num_views",
                                                         "6",
                                                         "--image_width",
                                                         "480",
                                                         "--mesh_spacing_m",
                                                         "0.08",
                                                         "--texel_size_m",
                                                         "0.02",
                                                         "--supersampling",
                                                         "1",
                                                         "--seed",
                                                         "5"});
                                  ASSERT_EQ(result.exit_code, 0)
                                      << result.output;
                                }) +
         "/ws";
}

nlohmann::json Evaluate(const std::vector<std::string>& args,
                        const std::string& json_path) {
  std::vector<std::string> argv = {"evaluate", "--output_path", json_path};
  argv.insert(argv.end(), args.begin(), args.end());
  const testing::CommandResult result = testing::RunBayon(argv);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  std::cout << result.output;
  std::ifstream in(json_path);
  return nlohmann::json::parse(in);
}

TEST(Evaluate, TheTruthAgainstItselfIsPerfect) {
  const std::string ws = Tower();
  const std::string dir = testing::TempDir("evaluate_truth");
  const nlohmann::json report = Evaluate({"--ground_truth_path",
                                          ws + "/gt",
                                          "--input_path",
                                          ws + "/gt/sparse",
                                          "--calibration_path",
                                          ws + "/gt/calibration.json",
                                          "--mesh_path",
                                          ws + "/gt/surface.ply",
                                          "--textured_mesh_path",
                                          ws + "/gt/surface.ply",
                                          "--num_samples",
                                          "40000"},
                                         dir + "/report.json");
  EXPECT_EQ(report["sparse"]["num_registered"], 6);
  EXPECT_LT(report["sparse"]["center_rms"].get<double>(), 1e-9);
  for (const auto& p : report["calibration"][0]["parameters"]) {
    EXPECT_NEAR(p["error"].get<double>(), 0.0, 1e-12) << p["name"];
  }
  // The targets sit on the surface.
  EXPECT_LT(report["points3D_to_surface_m"]["max"].get<double>(), 0.01);
  EXPECT_LT(report["mesh"]["accuracy_m"]["max"].get<double>(), 1e-9);
  EXPECT_EQ(report["mesh"]["completeness_fraction"].get<double>(), 1.0);
  EXPECT_GT(report["mesh"]["num_visible_true_samples"].get<int>(), 5000);
  EXPECT_EQ(report["texture"]["views"].size(), 4u);
  EXPECT_GT(report["texture"]["mean_psnr_db"].get<double>(), 60.0);
  EXPECT_GT(report["texture"]["mean_ssim"].get<double>(), 0.999);
}

TEST(Evaluate, NoisyCloudAndDegradedTexture) {
  const std::string ws = Tower();
  const std::string dir = testing::TempDir("evaluate_products");
  const testing::CommandResult cloud =
      testing::RunBayon({"synth_cloud",
                         "--shape",
                         "mesh",
                         "--input_path",
                         ws + "/gt/surface.ply",
                         "--output_path",
                         dir + "/cloud.ply",
                         "--num_points",
                         "300000",
                         "--sigma_m",
                         "0.004",
                         "--sigma_spread",
                         "0",
                         "--blunder_fraction",
                         "0"});
  ASSERT_EQ(cloud.exit_code, 0) << cloud.output;

  // The true surface with its texture blurred: detail lost, seams none.
  TriangleMesh surface = ReadMeshPly(ws + "/gt/surface.ply");
  cv::Mat texture = ReadImage(PlyTextureFile(ws + "/gt/surface.ply"));
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 3.0);
  WriteImage(dir + "/blurred.png", texture);
  PlyWriteOptions ply;
  ply.comment = "TextureFile blurred.png";
  WriteMeshPly(surface, dir + "/blurred.ply", ply);

  const auto before = testing::HashTree(ws);
  const nlohmann::json report = Evaluate({"--ground_truth_path",
                                          ws + "/gt",
                                          "--cloud_path",
                                          dir + "/cloud.ply",
                                          "--textured_mesh_path",
                                          dir + "/blurred.ply",
                                          "--num_samples",
                                          "40000",
                                          "--completeness_threshold_m",
                                          "0.03",
                                          "--render_path",
                                          dir + "/renders"},
                                         dir + "/report.json");
  EXPECT_EQ(testing::HashTree(ws), before);
  const auto& c = report["cloud"];
  EXPECT_NEAR(c["accuracy_m"]["rms"].get<double>(), 0.004, 0.0006);
  EXPECT_GT(c["completeness_fraction"].get<double>(), 0.97);
  EXPECT_GT(c["accuracy_gsd"]["rms"].get<double>(), 0.0);
  // The tower's walls and tops (the cloud covers the whole surface).
  size_t by_orientation = 0;
  for (const char* part : {"walls", "tops", "undersides"}) {
    const auto& o = c["completeness_by_orientation"][part];
    by_orientation += o["num_visible_true_samples"].get<size_t>();
    if (std::string(part) != "undersides") {
      EXPECT_GT(o["completeness_fraction"].get<double>(), 0.95) << part;
    }
  }
  EXPECT_EQ(by_orientation, c["num_visible_true_samples"].get<size_t>());
  const double psnr = report["texture"]["mean_psnr_db"];
  const double ssim = report["texture"]["mean_ssim"];
  EXPECT_LT(psnr, 45.0);
  EXPECT_GT(psnr, 15.0);
  EXPECT_LT(ssim, 0.98);
  EXPECT_TRUE(fs::exists(dir + "/renders/model_heldout_01.png"));
  EXPECT_TRUE(fs::exists(dir + "/renders/truth_heldout_01.png"));
}

TEST(Evaluate, BadInput) {
  const std::string ws = Tower();
  const std::string dir = testing::TempDir("evaluate_bad");
  auto expect_bad = [&](const std::vector<std::string>& args,
                        const std::string& says) {
    std::vector<std::string> argv = {"evaluate"};
    argv.insert(argv.end(), args.begin(), args.end());
    const testing::CommandResult result = testing::RunBayon(argv);
    EXPECT_EQ(result.exit_code, 2) << result.output;
    EXPECT_NE(result.LastLine().find(says), std::string::npos)
        << result.LastLine();
  };
  expect_bad({"--ground_truth_path", ws + "/gt"}, "nothing to evaluate");
  expect_bad({"--ground_truth_path",
              dir + "/missing",
              "--input_path",
              ws + "/gt/sparse"},
             "not a folder");
  // A cloud far from the tower.
  PointCloud far;
  far.positions.push_back(Eigen::Vector3d(100, 100, 100));
  WritePointCloudPly(far, dir + "/far.ply");
  expect_bad(
      {"--ground_truth_path", ws + "/gt", "--cloud_path", dir + "/far.ply"},
      "evaluation region");
  // Texture coordinates without a texture file.
  TriangleMesh surface = ReadMeshPly(ws + "/gt/surface.ply");
  WriteMeshPly(surface, dir + "/untextured.ply");
  expect_bad({"--ground_truth_path",
              ws + "/gt",
              "--textured_mesh_path",
              dir + "/untextured.ply"},
             "TextureFile");
}

}  // namespace
}  // namespace bayon
