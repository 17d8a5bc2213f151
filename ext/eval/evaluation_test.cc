// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/evaluation.h"

#include "ext/colmap/model_io.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"
#include "ext/synth/points_scene.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A truth folder (gt/sparse) holding a ring of cameras around points.
fs::path TruthFolder(const std::string& name) {
  const fs::path gt = fs::path(testing::TempDir(name)) / "gt";
  fs::create_directories(gt / "sparse");
  PointsSceneOptions options;
  options.num_points = 60;
  Scene truth = SynthesizePointsScene(options).scene;
  ConvertSceneCamerasToColmap(&truth);
  WriteModel(truth, (gt / "sparse").string(), ModelFormat::kBinary);
  return gt;
}

// What RunEvaluation printed, and its report.
struct Printed {
  std::string tables;
  nlohmann::ordered_json report;
};

Printed Evaluate(const EvaluationOptions& options) {
  std::FILE* tables = std::tmpfile();
  Printed printed;
  try {
    printed.report = RunEvaluation(options, tables);
  } catch (...) {
    std::fclose(tables);
    throw;
  }
  std::rewind(tables);
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), tables)) > 0) {
    printed.tables.append(buffer, n);
  }
  std::fclose(tables);
  return printed;
}

std::string CheckMessage(const EvaluationOptions& options) {
  try {
    options.Check();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Evaluation, ChecksRefuseWhatCannotBeEvaluated) {
  EvaluationOptions options;
  EXPECT_NE(CheckMessage(options).find("ground_truth_path is required"),
            std::string::npos);
  options.ground_truth_path = "gt";
  EXPECT_NE(CheckMessage(options).find("nothing to evaluate"),
            std::string::npos);
  options.edit_input_path = "before.ply";
  options.mesh_path = "mesh.ply";
  EXPECT_NE(CheckMessage(options).find("needs the edited cloud"),
            std::string::npos);
  options = EvaluationOptions();
  options.image_names = {"a.png"};
  EXPECT_NE(CheckMessage(options).find("image_names needs image_path"),
            std::string::npos);
  options.image_path = "photographs";
  EXPECT_NE(CheckMessage(options).find("needs the textured model"),
            std::string::npos);
  options = EvaluationOptions();
  options.silhouette_image_path = "photographs";
  options.mesh_path = "mesh.ply";
  EXPECT_NE(CheckMessage(options).find("needs the mesh"), std::string::npos);
}

TEST(Evaluation, AModelAgainstItselfHasNoErrorAndTheReportSaysSo) {
  const fs::path gt = TruthFolder("evaluation_itself");
  EvaluationOptions options;
  options.ground_truth_path = gt.string();
  options.input_path = (gt / "sparse").string();
  options.label = "itself";
  const Printed printed = Evaluate(options);
  EXPECT_NE(printed.tables.find("itself"), std::string::npos);
  EXPECT_EQ(printed.report["ground_truth_path"], gt.string());
  const auto& sparse = printed.report["sparse"];
  EXPECT_EQ(sparse["num_registered"], 16);
  EXPECT_EQ(sparse["num_truth_images"], 16);
  EXPECT_LT(sparse["center_max"].get<double>(), 1e-9);
  EXPECT_LT(sparse["rotation_max_deg"].get<double>(), 1e-6);
  EXPECT_EQ(sparse["images"].size(), 16u);
  // No surface.ply in this truth: no tie-point distances, no calibration.
  EXPECT_FALSE(printed.report.contains("points3D_to_surface_m"));
  EXPECT_FALSE(printed.report.contains("calibration"));
}

TEST(Evaluation, WhatTheTruthLacksIsRefusedBeforeAnythingIsEvaluated) {
  const fs::path gt = TruthFolder("evaluation_lacks");
  const fs::path cloud = gt.parent_path() / "cloud.ply";
  std::ofstream(cloud) << "not read: refused first\n";
  EvaluationOptions options;
  options.ground_truth_path = gt.string();
  options.input_path = (gt / "sparse").string();
  options.cloud_path = cloud.string();
  std::FILE* tables = std::tmpfile();
  try {
    RunEvaluation(options, tables);
    ADD_FAILURE() << "a cloud without a true surface was evaluated";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no surface.ply"), std::string::npos)
        << e.what();
  }
  // The sparse table was not printed: the check came before the work.
  EXPECT_EQ(std::ftell(tables), 0);
  std::fclose(tables);

  options.cloud_path.clear();
  options.textured_mesh_path = cloud.string();
  EXPECT_THROW(Evaluate(options), InputError);
}

TEST(Evaluation, AGroundTruthThatIsNotAFolderIsRefused) {
  const fs::path dir(testing::TempDir("evaluation_not_a_folder"));
  std::ofstream(dir / "truth.txt") << "x\n";
  EvaluationOptions options;
  options.ground_truth_path = (dir / "truth.txt").string();
  options.input_path = dir.string();
  try {
    Evaluate(options);
    ADD_FAILURE() << "a file was taken for the truth";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a folder"), std::string::npos);
  }
}

}  // namespace
}  // namespace bayon
