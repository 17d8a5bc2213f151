// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon pipeline` end to end on ../shared/data/temple-ring (a real ring of
// 16 photographs with calibrated cameras; an arc of 8 of them in the
// sanitizer lane, see temple_fixture.h): every stage from the photographs
// to the report in one command, the orientation against the truth,
// a second run that finds everything up to date, a run killed with SIGKILL in
// the middle of `dense` that resumes without redoing the finished stages and
// gives the same result, bad input stopped before any work, and a second
// run on one workspace stopped while the first holds it.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "tests/temple_fixture.h"
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

std::vector<std::string> PipelineArgs(const std::string& ws,
                                      const testing::TempleSetup& temple) {
  return testing::TemplePipelineCommand(
      temple, ws, {fs::path(ws).parent_path().string() + "/cylinder.ini"});
}

TEST(Pipeline, TempleEndToEndThenUpToDateThenResumesAfterKill) {
  BAYON_REQUIRE_DATA("temple-ring");
  const testing::TempleSetup temple = testing::TempleConfigFixture();
  const std::string ws = testing::TempDir("pipeline_temple") + "/ws";
  // The 2.5D Delaunay mesh is the same on every run; PCL's Poisson, which
  // the shared config asks for, differs with the threads' order.
  std::ofstream(fs::path(ws).parent_path().string() + "/cylinder.ini")
      << "[mesh]\nmethod = cylinder\n";
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
  EXPECT_EQ(json["stages"].size(), 16u) << json.dump(1);
  EXPECT_GT(json["total_seconds"].get<double>(), 0);

  // Every photograph oriented, as bayon's chain does stage by stage
  // (scripts/bench.sh chain: 0.207 %, 0.135 deg without self-calibration);
  // the sanitizer lane's arc of 8 stations as well.
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
  EXPECT_EQ(e["sparse"]["num_registered"], temple.num_images);
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
                            "targets",
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

// Runs the pipeline on dir/ws with `more` options and expects exit code 2
// with a last line naming each of `needles`, and no workspace made.
void ExpectRefused(const std::string& dir,
                   const std::string& images,
                   const std::vector<std::string>& more,
                   const std::vector<std::string>& needles) {
  std::vector<std::string> args = {
      "pipeline", "--workspace_path", dir + "/ws", "--image_path", images};
  args.insert(args.end(), more.begin(), more.end());
  const testing::CommandResult run = RunBayon(args);
  EXPECT_EQ(run.exit_code, 2) << run.output;
  for (const std::string& needle : needles) {
    EXPECT_NE(run.LastLine().find(needle), std::string::npos)
        << needle << " in: " << run.LastLine();
  }
  EXPECT_FALSE(fs::exists(dir + "/ws/database.db"));
}

TEST(Pipeline, BadInputIsRefusedBeforeAnyWork) {
  const std::string dir = testing::TempDir("pipeline_bad");
  fs::create_directories(dir + "/empty");
  ExpectRefused(dir, dir + "/empty", {}, {"no images found"});
  EXPECT_FALSE(fs::exists(dir + "/ws"));

  // One photograph for the config cases.
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string source = testing::DataPath("temple-ring");
  const std::string images = dir + "/images";
  fs::create_directories(images);
  std::vector<fs::path> names;
  for (const auto& entry : fs::directory_iterator(source)) {
    if (entry.path().extension() == ".png") names.push_back(entry.path());
  }
  std::sort(names.begin(), names.end());
  fs::copy_file(names[0], images + "/" + names[0].filename().string());

  // Configs with a misspelt key, an unknown stage, a value out of range.
  const std::vector<std::pair<std::string, std::vector<std::string>>> configs =
      {{"[dense]\nnum_masterz = 5\n", {"stage dense", "num_masterz"}},
       {"[densify]\nnum_masters = 5\n", {"unknown section [densify]"}},
       {"[pipeline]\nsparse = metashape\n", {"colmap_mapper"}}};
  for (size_t i = 0; i < configs.size(); ++i) {
    const std::string config = dir + "/bad" + std::to_string(i) + ".ini";
    std::ofstream(config) << configs[i].first;
    ExpectRefused(dir, images, {"--config", config}, configs[i].second);
    EXPECT_FALSE(fs::exists(dir + "/ws")) << configs[i].first;
  }
  ExpectRefused(
      dir, images, {"--to_stage", "meshing"}, {"unknown stage 'meshing'"});
  // One photograph: nothing to match, said before the first stage.
  ExpectRefused(dir, images, {}, {"one image", "two or more"});
  EXPECT_FALSE(fs::exists(dir + "/ws"));

  // A second photograph of another size (another camera) with one camera
  // for all: refused by import, the first stage, before anything is written.
  const cv::Mat image = cv::imread(names[1].string());
  ASSERT_FALSE(image.empty());
  cv::Mat small;
  cv::resize(image, small, cv::Size(image.cols / 2, image.rows / 2));
  ASSERT_TRUE(cv::imwrite(images + "/small.png", small));
  ExpectRefused(dir, images, {}, {"stage import", "cannot share one camera"});
}

// Two photographs of different objects: features and match run, and the
// first stage that needs an overlap says so in one line, exit code 2.
TEST(Pipeline, PhotographsThatDoNotOverlapAreNamed) {
  BAYON_REQUIRE_DATA("temple-ring");
  BAYON_REQUIRE_DATA("herz-jesu-P8");
  const std::string dir = testing::TempDir("pipeline_no_overlap");
  const std::string images = dir + "/images";
  fs::create_directories(images);
  fs::copy_file(testing::DataPath("temple-ring") + "/templeSR0001.png",
                images + "/temple.png");
  cv::Mat church =
      cv::imread(testing::DataPath("herz-jesu-P8") + "/images/0000.jpg");
  ASSERT_FALSE(church.empty());
  cv::resize(church, church, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  ASSERT_TRUE(cv::imwrite(images + "/church.png", church));
  const std::string config = dir + "/camera.ini";
  std::ofstream(config) << "[import]\ncamera_model = PINHOLE\n"
                           "camera_params = 1520.4,1525.9,302.82,247.37\n";
  const testing::CommandResult run = RunBayon({"pipeline",
                                               "--workspace_path",
                                               dir + "/ws",
                                               "--image_path",
                                               images,
                                               "--config",
                                               testing::ConfigPath("ring.ini"),
                                               "--config",
                                               config,
                                               "--num_threads",
                                               "2"});
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.LastLine().find("stage relative"), std::string::npos)
      << run.LastLine();
  EXPECT_NE(run.LastLine().find("overlap"), std::string::npos)
      << run.LastLine();
  EXPECT_FALSE(fs::exists(dir + "/ws/sparse"));
}

// One run per workspace: while another process holds the workspace's lock
// (a second `bayon pipeline` started beside the first), the run stops with
// one line before any stage; once the lock is released, it runs.
TEST(Pipeline, ASecondRunOnOneWorkspaceStopsWithOneLine) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = testing::TempDir("pipeline_locked");
  const std::string ws = dir + "/ws";
  fs::create_directories(ws + "/pipeline");
  const std::vector<std::string> args = {"pipeline",
                                         "--workspace_path",
                                         ws,
                                         "--image_path",
                                         testing::DataPath("temple-ring"),
                                         "--to_stage",
                                         "import"};
  {
    const FileLock first(ws + "/pipeline/lock", "the first run");
    const testing::CommandResult second = RunBayon(args);
    EXPECT_EQ(second.exit_code, 2) << second.output;
    EXPECT_NE(second.LastLine().find(StrCat(
                  "is in use by another process (pid ", ::getpid(), ")")),
              std::string::npos)
        << second.LastLine();
    EXPECT_FALSE(fs::exists(ws + "/database.db"));
  }
  const testing::CommandResult after = RunBayon(args);
  EXPECT_EQ(after.exit_code, 0) << after.output;
  EXPECT_TRUE(fs::exists(ws + "/database.db"));
}

}  // namespace
}  // namespace bayon
