// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon pipeline` end to end on ../shared/data/temple-ring (a real ring of
// 16 photographs with calibrated cameras): every stage from the photographs
// to the report in one command, the orientation against the truth,
// a second run that finds everything up to date, a run killed with SIGKILL in
// the middle of `dense` that resumes without redoing the finished stages and
// gives the same result, and bad input stopped before any work.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

using testing::RunBayon;

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  EXPECT_TRUE(file.good()) << path;
  return file ? nlohmann::json::parse(file) : nlohmann::json();
}

std::map<std::string, std::string> Statuses(const std::string& workspace) {
  const nlohmann::json run = ReadJson(workspace + "/pipeline.json");
  std::map<std::string, std::string> statuses;
  for (const auto& stage : run["stages"]) {
    statuses[stage["name"]] = stage["status"];
  }
  return statuses;
}

// The temple's calibrated camera (the truth's PINHOLE fx, fy, cx, cy) and
// its pairs (all of them: 16 small images), on top of configs/ring.ini, with
// lighter renders; and the truth as a COLMAP model.
struct Temple {
  std::string images, truth, config;
};

Temple TempleFixture() {
  Temple temple;
  temple.images = testing::DataPath("temple-ring");
  const std::string dir =
      testing::SharedFixture("pipeline_temple", [&](const std::string& d) {
        const testing::CommandResult truth =
            RunBayon({"import_ground_truth",
                      "--format",
                      "middlebury",
                      "--input_path",
                      temple.images + "/templeSR_par.txt",
                      "--output_path",
                      d + "/truth"});
        ASSERT_EQ(truth.exit_code, 0) << truth.output;
        std::ifstream cameras(d + "/truth/cameras.txt");
        std::string line;
        while (std::getline(cameras, line) &&
               (line.empty() || line[0] == '#')) {
        }
        std::istringstream fields(line);
        std::string id, model, width, height;
        std::vector<double> params(4);
        fields >> id >> model >> width >> height >> params[0] >> params[1] >>
            params[2] >> params[3];
        ASSERT_EQ(model, "PINHOLE") << line;
        std::ofstream(d + "/temple.ini")
            << "[import]\ncamera_model = PINHOLE\ncamera_params = "
            << testing::CommaSeparated(params)
            << "\n[match]\npairing = exhaustive\n"
               "[adjust]\ndatum = free\nself_calibration = none\n"
               "[render]\nnum_views = 2\nsupersampling = 1\nwidth = 480\n"
               "height = 360\n";
      });
  temple.truth = dir + "/truth";
  temple.config = dir + "/temple.ini";
  return temple;
}

std::vector<std::string> PipelineArgs(const std::string& ws,
                                      const Temple& temple) {
  return {"pipeline",
          "--workspace_path",
          ws,
          "--image_path",
          temple.images,
          "--config",
          std::string(BAYON_SOURCE_DIR) + "/configs/ring.ini",
          "--config",
          temple.config,
          "--num_threads",
          "2"};
}

TEST(Pipeline, TempleEndToEndThenUpToDateThenResumesAfterKill) {
  BAYON_REQUIRE_DATA("temple-ring");
  const Temple temple = TempleFixture();
  const std::string ws = testing::TempDir("pipeline_temple") + "/ws";
  const auto images_before = testing::HashTree(temple.images);

  testing::CommandResult run = RunBayon(PipelineArgs(ws, temple));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const auto& [stage, status] : Statuses(ws)) {
    EXPECT_EQ(status, "ran") << stage;
  }
  for (const char* product : {"database.db",
                              "sparse/adjusted/adjustment.json",
                              "dense/points.ply",
                              "dense/points_edited.ply",
                              "mesh/mesh.ply",
                              "model/model.glb",
                              "model/model.obj",
                              "viewer/index.html",
                              "report.html"}) {
    EXPECT_TRUE(fs::exists(ws + "/" + product)) << product;
  }
  EXPECT_FALSE(fs::is_empty(ws + "/renders"));
  EXPECT_EQ(testing::HashTree(temple.images), images_before);
  const nlohmann::json json = ReadJson(ws + "/pipeline.json");
  EXPECT_EQ(json["stages"].size(), 15u) << json.dump(1);
  EXPECT_GT(json["total_seconds"].get<double>(), 0);

  // Every photograph oriented, as bayon's chain does stage by stage
  // (scripts/bench.sh chain: 0.207 %, 0.135 deg).
  const testing::CommandResult evaluation =
      RunBayon({"evaluate",
                "--ground_truth_path",
                temple.truth,
                "--input_path",
                ws + "/sparse/adjusted",
                "--output_path",
                ws + "/../evaluation.json"});
  ASSERT_EQ(evaluation.exit_code, 0) << evaluation.output;
  const nlohmann::json e = ReadJson(ws + "/../evaluation.json");
  EXPECT_EQ(e["sparse"]["num_registered"], 16);
  EXPECT_LT(e["sparse"]["center_rms_relative"].get<double>(), 0.004);
  EXPECT_LT(e["sparse"]["rotation_rms_deg"].get<double>(), 0.3);

  // Everything is up to date: nothing runs again.
  run = RunBayon(PipelineArgs(ws, temple));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const auto& [stage, status] : Statuses(ws)) {
    EXPECT_EQ(status, "skipped") << stage;
  }

  // Killed in the middle of dense (forced to run again from there), then run
  // again: the stages before dense are not redone, the ones from dense on
  // are, and the results are those of the uninterrupted run.
  const auto dense_before = testing::HashTree(ws + "/dense/points.ply");
  const auto mesh_before = testing::HashTree(ws + "/mesh/mesh.ply");
  std::string script = "\"" + testing::BayonBin() + "\"";
  for (const std::string& arg : PipelineArgs(ws, temple)) {
    script += " '" + arg + "'";
  }
  script += " --from_stage dense > '" + ws + "/../killed.log' 2>&1 & pid=$!; " +
            "n=0; while ! grep -q started '" + ws +
            "/logs/dense.log' 2>/dev/null; do sleep 0.2; n=$((n+1)); " +
            "[ $n -gt 600 ] && break; done; sleep 1; kill -9 $pid; wait $pid; "
            "exit 0";
  fs::remove(ws + "/logs/dense.log");
  const testing::CommandResult killed =
      testing::RunCommand({"/bin/sh", "-c", script});
  ASSERT_EQ(killed.exit_code, 0) << killed.output;
  EXPECT_FALSE(fs::exists(ws + "/pipeline/dense.done"))
      << "the killed dense stage must not look finished";

  run = RunBayon(PipelineArgs(ws, temple));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto statuses = Statuses(ws);
  for (const char* stage : {"import",
                            "features",
                            "match",
                            "relative",
                            "disparity",
                            "tiepoints",
                            "strip",
                            "adjust"}) {
    EXPECT_EQ(statuses.at(stage), "skipped") << stage;
  }
  for (const char* stage :
       {"dense", "edit", "mesh", "texture", "render", "viewer", "report"}) {
    EXPECT_EQ(statuses.at(stage), "ran") << stage;
  }
  EXPECT_EQ(testing::HashTree(ws + "/dense/points.ply"), dense_before);
  EXPECT_EQ(testing::HashTree(ws + "/mesh/mesh.ply"), mesh_before);
  for (const auto& entry : fs::directory_iterator(ws + "/dense")) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
        << "left behind: " << entry.path();
  }
}

TEST(Pipeline, BadInputIsRefusedBeforeAnyWork) {
  const std::string dir = testing::TempDir("pipeline_bad");
  fs::create_directories(dir + "/empty");
  testing::CommandResult run = RunBayon({"pipeline",
                                         "--workspace_path",
                                         dir + "/ws",
                                         "--image_path",
                                         dir + "/empty"});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("no images found"), std::string::npos)
      << run.LastLine();
  EXPECT_FALSE(fs::exists(dir + "/ws"));

  // Images for the config cases: two sizes from two cameras.
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string source = testing::DataPath("temple-ring");
  fs::create_directories(dir + "/images");
  std::vector<fs::path> names;
  for (const auto& entry : fs::directory_iterator(source)) {
    if (entry.path().extension() == ".png") names.push_back(entry.path());
  }
  std::sort(names.begin(), names.end());
  fs::copy_file(names[0], dir + "/images/" + names[0].filename().string());

  const std::string unknown_key = dir + "/unknown_key.ini";
  std::ofstream(unknown_key) << "[dense]\nnum_masterz = 5\n";
  run = RunBayon({"pipeline",
                  "--workspace_path",
                  dir + "/ws",
                  "--image_path",
                  dir + "/images",
                  "--config",
                  unknown_key});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("stage dense"), std::string::npos)
      << run.LastLine();
  EXPECT_NE(run.LastLine().find("num_masterz"), std::string::npos)
      << run.LastLine();
  EXPECT_FALSE(fs::exists(dir + "/ws"));

  const std::string unknown_stage = dir + "/unknown_stage.ini";
  std::ofstream(unknown_stage) << "[densify]\nnum_masters = 5\n";
  run = RunBayon({"pipeline",
                  "--workspace_path",
                  dir + "/ws",
                  "--image_path",
                  dir + "/images",
                  "--config",
                  unknown_stage});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("unknown section [densify]"), std::string::npos)
      << run.LastLine();
  EXPECT_FALSE(fs::exists(dir + "/ws"));

  const std::string bad_value = dir + "/bad_value.ini";
  std::ofstream(bad_value) << "[pipeline]\nsparse = metashape\n";
  run = RunBayon({"pipeline",
                  "--workspace_path",
                  dir + "/ws",
                  "--image_path",
                  dir + "/images",
                  "--config",
                  bad_value});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("colmap_mapper"), std::string::npos)
      << run.LastLine();

  // A second photograph of another size (another camera) with one camera
  // for all: refused by import, the first stage, before anything is written.
  const cv::Mat image = cv::imread(names[1].string());
  ASSERT_FALSE(image.empty());
  cv::Mat small;
  cv::resize(image, small, cv::Size(image.cols / 2, image.rows / 2));
  ASSERT_TRUE(cv::imwrite(dir + "/images/small.png", small));
  run = RunBayon({"pipeline",
                  "--workspace_path",
                  dir + "/ws",
                  "--image_path",
                  dir + "/images"});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("stage import"), std::string::npos)
      << run.LastLine();
  EXPECT_NE(run.LastLine().find("cannot share one camera"), std::string::npos)
      << run.LastLine();
  EXPECT_FALSE(fs::exists(dir + "/ws/database.db"));

  run = RunBayon({"pipeline",
                  "--workspace_path",
                  dir + "/ws",
                  "--image_path",
                  dir + "/images",
                  "--to_stage",
                  "meshing"});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("unknown stage 'meshing'"), std::string::npos)
      << run.LastLine();
}

}  // namespace
}  // namespace bayon
