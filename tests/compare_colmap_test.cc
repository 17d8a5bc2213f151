// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon compare_colmap` end to end on the temple ring (16 x 640x480, real
// photographs with Middlebury's calibration as truth): the workspace
// `bayon pipeline` makes of it, then stock COLMAP beside it through the
// command (the tests' one stock COLMAP run of the temple,
// TempleColmapFixture in temple_fixture.h); the table's figures within the
// ranges the benchmark measured, the workspace's own database and model
// untouched, a second run reusing COLMAP's model, and bad input refused before
// COLMAP runs.
#include "ext/colmap/model_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "tests/temple_fixture.h"
#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

using Json = nlohmann::ordered_json;

Json ReadJson(const std::string& path) {
  return Json::parse(ReadFileToString(path));
}

TEST(CompareColmap, TempleRingSideBySide) {
  BAYON_REQUIRE_DATA("temple-ring");
  const testing::TempleColmap fixture = testing::TempleColmapFixture();
  const std::string& ws = fixture.workspace;
  const std::string& output = fixture.output;
  std::cout << output;

  const Json c = ReadJson(ws + "/colmap/comparison.json");
  for (const char* key :
       {"image_path", "num_images", "bayon", "colmap", "agreement", "truth"}) {
    EXPECT_TRUE(c.contains(key)) << key;
  }
  EXPECT_EQ(c["num_images"], 16);
  EXPECT_EQ(c["image_path"], testing::DataPath("temple-ring"));
  EXPECT_EQ(c["colmap_reused"], false);
  for (const char* program : {"bayon", "colmap"}) {
    for (const char* key : {"model_path",
                            "registered",
                            "points3D",
                            "observations",
                            "mean_track_length",
                            "mean_reprojection_error_px",
                            "rms_reprojection_error_px",
                            "sigma0_px",
                            "adjustment_sigma0",
                            "stage_seconds",
                            "total_seconds"}) {
      EXPECT_TRUE(c[program].contains(key)) << program << "." << key;
    }
  }
  const Json& b = c["bayon"];
  const Json& m = c["colmap"];
  // A fair comparison: the calibrated camera bayon's import was given
  // (pipeline.json) is given to COLMAP too, and held fixed in its mapper.
  const Json pipeline = ReadJson(ws + "/pipeline.json");
  std::string given;
  for (const Json& stage : pipeline["stages"]) {
    if (stage["name"] != "import") continue;
    const Json& words = stage["command"];
    for (size_t i = 0; i + 1 < words.size(); ++i) {
      if (words[i] == "--camera_params") given = words[i + 1];
    }
  }
  ASSERT_FALSE(given.empty());
  ASSERT_TRUE(c["camera_given_to_colmap"].is_object());
  EXPECT_EQ(c["camera_given_to_colmap"]["params"], given);
  EXPECT_EQ(c["camera_given_to_colmap"]["model"], "PINHOLE");
  const std::string mapper_command =
      ReadJson(ws + "/colmap/colmap.json")["stages"][2]["command"];
  for (const char* fixed : {"--Mapper.ba_refine_focal_length 0",
                            "--Mapper.ba_refine_principal_point 0",
                            "--Mapper.ba_refine_extra_params 0"}) {
    EXPECT_NE(mapper_command.find(fixed), std::string::npos) << mapper_command;
  }
  ASSERT_EQ(m["cameras"].size(), 1u);
  EXPECT_EQ(m["cameras"][0]["model"], "PINHOLE");
  // bayon registers the whole ring; COLMAP 13 of 16 in the benchmark.
  EXPECT_EQ(b["registered"], 16);
  EXPECT_GE(m["registered"].get<int>(), 10);
  for (const Json* model : {&b, &m}) {
    const Json& s = *model;
    EXPECT_GT(s["points3D"].get<int>(), 100);
    EXPECT_GE(s["observations"].get<int>(), 2 * s["points3D"].get<int>());
    EXPECT_GE(s["mean_track_length"].get<double>(), 2.0);
    EXPECT_GT(s["mean_reprojection_error_px"].get<double>(), 0.0);
    EXPECT_LT(s["mean_reprojection_error_px"].get<double>(), 2.0);
    EXPECT_GE(s["rms_reprojection_error_px"].get<double>(),
              s["mean_reprojection_error_px"].get<double>());
    // sigma0 = RMS sqrt(n / (2n - u)) (RMS over n 2D residuals): above
    // RMS / sqrt(2), below RMS sqrt(2) where tracks are 2 or longer
    // (u <= 1.5 n + the images' and cameras' few).
    EXPECT_GT(s["sigma0_px"].get<double>(),
              s["rms_reprojection_error_px"].get<double>() / std::sqrt(2.0));
    EXPECT_LT(s["sigma0_px"].get<double>(),
              1.6 * s["rms_reprojection_error_px"].get<double>());
  }
  // The mean reprojection error as `bayon adjust` reported it.
  const Json adjustment =
      ReadJson(ws + "/sparse/adjusted/adjustment.json")["statistics"];
  EXPECT_NEAR(b["mean_reprojection_error_px"].get<double>(),
              adjustment["mean_reprojection_error_px"].get<double>(),
              1e-6);
  EXPECT_EQ(b["adjustment_sigma0"], adjustment["sigma0_px"]);
  EXPECT_TRUE(m["adjustment_sigma0"].is_null());

  // Runtimes: bayon's sparse stages from pipeline.json (dense left out),
  // COLMAP's three measured.
  EXPECT_TRUE(b["stage_seconds"].contains("features"));
  EXPECT_TRUE(b["stage_seconds"].contains("adjust"));
  EXPECT_FALSE(b["stage_seconds"].contains("dense"));
  double sum = 0;
  for (const auto& [name, seconds] : b["stage_seconds"].items()) {
    sum += seconds.get<double>();
  }
  EXPECT_NEAR(b["total_seconds"].get<double>(), sum, 1e-9);
  sum = 0;
  for (const char* stage :
       {"feature_extractor", "exhaustive_matcher", "mapper"}) {
    ASSERT_TRUE(m["stage_seconds"].contains(stage)) << stage;
    EXPECT_GT(m["stage_seconds"][stage].get<double>(), 0.0) << stage;
    sum += m["stage_seconds"][stage].get<double>();
    EXPECT_TRUE(fs::exists(ws + "/colmap/" + stage + ".log")) << stage;
  }
  EXPECT_NEAR(m["total_seconds"].get<double>(), sum, 1e-9);

  // The two models agree where the truth says both are right: COLMAP's
  // centres within a few per cent of the ring's radius of bayon's
  // (benchmark: bayon 0.21 %, COLMAP 0.56 % from the truth).
  const Json& a = c["agreement"];
  EXPECT_EQ(a["num_common"], m["registered"]);
  EXPECT_LT(a["center_rms_percent"].get<double>(), 3.0);
  EXPECT_LE(a["center_rms"].get<double>(), a["center_max"].get<double>());
  EXPECT_LT(a["rotation_rms_deg"].get<double>(), 3.0);

  const Json& t = c["truth"];
  ASSERT_TRUE(t.is_object());
  EXPECT_EQ(t["bayon"]["registered"], 16);
  EXPECT_EQ(t["colmap"]["registered"], m["registered"]);
  EXPECT_LT(t["bayon"]["center_rms_percent"].get<double>(), 1.0);
  EXPECT_LT(t["bayon"]["rotation_rms_deg"].get<double>(), 0.5);
  EXPECT_LT(t["colmap"]["center_rms_percent"].get<double>(), 3.0);
  EXPECT_LT(t["colmap"]["rotation_rms_deg"].get<double>(), 3.0);

  // The table: printed and written.
  const std::string table = ReadFileToString(ws + "/colmap/comparison.txt");
  for (const char* row : {"registered images",
                          "16/16",
                          "mean reprojection error [px]",
                          "sigma0 [px]",
                          "time mapper [s]",
                          "against the truth",
                          "agreement of the cameras",
                          "given to COLMAP too and held fixed"}) {
    EXPECT_NE(table.find(row), std::string::npos) << row;
  }
  EXPECT_NE(output.find(table.substr(0, table.find('\n'))), std::string::npos);
  EXPECT_NE(output.find("compare_colmap: bayon 16/16"), std::string::npos);
  EXPECT_TRUE(fs::exists(ws + "/logs/compare_colmap.log"));
}

TEST(CompareColmap, LeavesTheWorkspaceDatabaseAndModelAlone) {
  BAYON_REQUIRE_DATA("temple-ring");
  const testing::TempleColmap fixture = testing::TempleColmapFixture();
  const std::string& ws = fixture.workspace;
  EXPECT_EQ(fixture.database_digest, testing::TreeDigest(ws + "/database.db"));
  EXPECT_EQ(fixture.adjusted_digest,
            testing::TreeDigest(ws + "/sparse/adjusted"));
  // COLMAP worked on its own database.
  EXPECT_TRUE(fs::exists(ws + "/colmap/database.db"));
  const Json record = ReadJson(ws + "/colmap/colmap.json");
  EXPECT_TRUE(fs::is_directory(ws + "/colmap/" +
                               record["model_path"].get<std::string>()));
}

TEST(CompareColmap, SecondRunReusesColmapsModel) {
  BAYON_REQUIRE_DATA("temple-ring");
  const testing::TempleColmap fixture = testing::TempleColmapFixture();
  const std::string dir = testing::TempDir("compare_colmap_reuse");
  testing::CopyTree(fixture.workspace, dir + "/ws");
  const std::string ws = dir + "/ws";
  const auto colmap_before = testing::HashTree(ws + "/colmap/sparse");
  const uint64_t colmap_db = FileHash(ws + "/colmap/database.db");
  const uint64_t record = FileHash(ws + "/colmap/colmap.json");
  const Json first = ReadJson(ws + "/colmap/comparison.json");

  // A stage the pipeline skipped as up to date: its time is its stamp's,
  // that of the run that made its output.
  fs::create_directories(ws + "/pipeline");
  WriteFileAtomically(ws + "/pipeline/features.done",
                      R"({"command": [], "seconds": 123.5})");

  const auto start = std::chrono::steady_clock::now();
  const testing::CommandResult result = testing::RunBayon(
      {"compare_colmap", "--workspace_path", ws, "--num_threads", "2"});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("reusing"), std::string::npos) << result.output;
  EXPECT_EQ(testing::HashTree(ws + "/colmap/sparse"), colmap_before);
  EXPECT_EQ(FileHash(ws + "/colmap/database.db"), colmap_db);
  EXPECT_EQ(FileHash(ws + "/colmap/colmap.json"), record);
  // Well below what COLMAP took the first time.
  EXPECT_LT(seconds, first["colmap"]["total_seconds"].get<double>());

  const Json second = ReadJson(ws + "/colmap/comparison.json");
  EXPECT_EQ(second["colmap_reused"], true);
  EXPECT_EQ(second["colmap"]["registered"], first["colmap"]["registered"]);
  EXPECT_EQ(second["colmap"]["stage_seconds"],
            first["colmap"]["stage_seconds"]);
  EXPECT_EQ(second["agreement"], first["agreement"]);
  EXPECT_EQ(second["bayon"]["stage_seconds"]["features"], 123.5);
  EXPECT_EQ(second["bayon"]["stage_seconds"]["adjust"],
            first["bayon"]["stage_seconds"]["adjust"]);
  // No truth given this time.
  EXPECT_TRUE(second["truth"].is_null());
}

// A workspace with a one-image bayon model (enough to get past that check)
// and an image folder.
std::string TinyWorkspace(const std::string& name) {
  const std::string ws = testing::TempDir(name);
  Scene model;
  Camera camera = Camera::Create(CameraModelId::kPinhole, 100, 64, 48);
  camera.camera_id = 1;
  model.cameras.Set(1, camera);
  Image image;
  image.image_id = 1;
  image.name = "a.png";
  image.camera_id = 1;
  model.images.Set(1, image);
  fs::create_directories(ws + "/sparse/adjusted");
  WriteModel(model, ws + "/sparse/adjusted", ModelFormat::kText);
  fs::create_directories(ws + "/images");
  return ws;
}

TEST(CompareColmap, MapperRegisteringNothingStillWritesTheComparison) {
  // Three photographs of unrelated blocky noise: SIFT finds features, no
  // pair matches, and the mapper gives up ("failed to create sparse
  // model", exit 1).
  const std::string ws = TinyWorkspace("compare_colmap_nothing");
  uint32_t state = 1;
  for (int i = 0; i < 3; ++i) {
    const int width = 320, height = 240;
    std::vector<uint8_t> blocks((width / 8) * (height / 8));
    for (uint8_t& value : blocks) {
      state = state * 1664525u + 1013904223u;
      value = static_cast<uint8_t>(state >> 24);
    }
    std::string pgm = "P5\n320 240\n255\n";
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        pgm += static_cast<char>(blocks[(y / 8) * (width / 8) + x / 8]);
      }
    }
    WriteFileAtomically(ws + "/images/noise" + std::to_string(i) + ".pgm", pgm);
  }
  const testing::CommandResult result = testing::RunBayon(
      {"compare_colmap", "--workspace_path", ws, "--num_threads", "2"});
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.LastLine().find("mapper made no model"), std::string::npos)
      << result.output;
  const Json c = ReadJson(ws + "/colmap/comparison.json");
  EXPECT_EQ(c["num_images"], 3);
  EXPECT_EQ(c["colmap"]["registered"], 0);
  EXPECT_TRUE(c["colmap"]["model_path"].is_null());
  EXPECT_TRUE(c["colmap"]["mean_reprojection_error_px"].is_null());
  EXPECT_TRUE(c["colmap"]["stage_seconds"].contains("mapper"));
  EXPECT_EQ(c["agreement"]["num_common"], 0);
  EXPECT_TRUE(c["agreement"]["center_rms"].is_null());
  // No model to reuse: colmap.json does not mark the run as finished.
  EXPECT_TRUE(ReadJson(ws + "/colmap/colmap.json")["model_path"].is_null());
}

TEST(CompareColmap, RefusesBadInputBeforeRunningColmap) {
  // No workspace.
  const std::string missing = testing::TempDir("compare_colmap_bad") + "/no";
  testing::CommandResult result =
      testing::RunBayon({"compare_colmap", "--workspace_path", missing});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(missing), std::string::npos)
      << result.output;

  // A workspace without bayon's model.
  const std::string empty = testing::TempDir("compare_colmap_empty");
  result = testing::RunBayon({"compare_colmap", "--workspace_path", empty});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("pipeline"), std::string::npos)
      << result.output;
  EXPECT_NE(result.LastLine().find("sparse/adjusted"), std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(empty + "/colmap"));

  // An image folder without images.
  const std::string ws = TinyWorkspace("compare_colmap_tiny");
  result = testing::RunBayon({"compare_colmap", "--workspace_path", ws});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(ws + "/images"), std::string::npos)
      << result.output;

  // An unreadable truth (a folder without a model).
  WriteFileAtomically(ws + "/images/a.png", "not decoded here");
  const std::string truth = testing::TempDir("compare_colmap_no_truth");
  result = testing::RunBayon(
      {"compare_colmap", "--workspace_path", ws, "--ground_truth_path", truth});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(truth), std::string::npos) << result.output;

  // Unknown choices.
  result = testing::RunBayon(
      {"compare_colmap", "--workspace_path", ws, "--matching", "vocab_tree"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  result = testing::RunBayon({"compare_colmap",
                              "--workspace_path",
                              ws,
                              "--camera_model",
                              "BROWN_BEYER"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("camera_model must be a COLMAP model"),
            std::string::npos)
      << result.output;
  // A calibration with the wrong number of parameters for its model.
  result = testing::RunBayon({"compare_colmap",
                              "--workspace_path",
                              ws,
                              "--camera_model",
                              "PINHOLE",
                              "--camera_params",
                              "500,320,240"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("camera_params: 3 values"),
            std::string::npos)
      << result.output;

  // Nothing was run or written.
  EXPECT_FALSE(fs::exists(ws + "/colmap"));
}

}  // namespace
}  // namespace bayon
