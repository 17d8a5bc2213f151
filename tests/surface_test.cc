// SPDX-License-Identifier: BSD-3-Clause
//
// The demo's surface on the temple ring (16 x 640x480 real photographs):
// the workspace `bayon pipeline` makes of it (tests/temple_fixture.h, dense
// points from depth maps at half size), meshed by configs/ring.ini's
// default, `mesh --method poisson --poisson.depth 10
// --cleanup.max_hole_edges 50`, and
// carried back into the photographs: its silhouette against the temple's
// (`evaluate --silhouette_image_path`). The full-size demo's figures are in
// docs/benchmarks.md (scripts/demo.sh temple).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/temple_fixture.h"
#include "tests/testing.h"

namespace bayon {
namespace {

TEST(Surface, TempleRingMeshCoversTheTempleInEveryPhotograph) {
  BAYON_REQUIRE_DATA("temple-ring");
  const testing::TempleSetup temple = testing::TempleConfigFixture();
  const std::string ws = testing::TemplePipelineWorkspace();
  const std::string dir = testing::TempDir("surface_temple");
  const testing::CommandResult mesh =
      testing::RunBayon({"mesh",
                         "--input_path",
                         ws + "/dense/points_edited.ply",
                         "--method",
                         "poisson",
                         "--poisson.depth",
                         "10",
                         "--cleanup.max_hole_edges",
                         "50",
                         "--output_path",
                         dir + "/mesh.ply",
                         "--report_path",
                         dir + "/mesh.json",
                         "--num_threads",
                         "2"});
  ASSERT_EQ(mesh.exit_code, 0) << mesh.output;
  // The options configs/ring.ini gives the pipeline.
  std::ifstream ring(testing::ConfigPath("ring.ini"));
  const std::string config((std::istreambuf_iterator<char>(ring)),
                           std::istreambuf_iterator<char>());
  std::string section = config.substr(config.find("[mesh]"));
  section = section.substr(0, section.find("\n["));
  for (const char* line : {"method = poisson\n",
                           "poisson.depth = 10\n",
                           "cleanup.max_hole_edges = 50\n"}) {
    EXPECT_NE(section.find(line), std::string::npos) << line;
  }
  const testing::CommandResult silhouettes =
      testing::RunBayon({"evaluate",
                         "--silhouette_image_path",
                         temple.images,
                         "--mesh_path",
                         dir + "/mesh.ply",
                         "--input_path",
                         ws + "/sparse/adjusted",
                         "--output_path",
                         dir + "/silhouettes.json"});
  ASSERT_EQ(silhouettes.exit_code, 0) << silhouettes.output;
  std::ifstream file(dir + "/silhouettes.json");
  const nlohmann::json report = nlohmann::json::parse(file);
  const nlohmann::json& s = report["silhouettes"];
  EXPECT_EQ(s["views"].size(), static_cast<size_t>(temple.num_images));
  std::ifstream mesh_file(dir + "/mesh.json");
  const nlohmann::json topology = nlohmann::json::parse(mesh_file);
  std::printf(
      "temple, fixture's dense points, poisson: mean IoU "
      "%.3f, worst %.3f (%s), best possible %.3f; %d boundary loops\n",
      s["mean_iou"].get<double>(),
      s["min_iou"].get<double>(),
      s["worst"].get<std::string>().c_str(),
      s["mean_best_iou"].get<double>(),
      topology["num_boundary_loops"].get<int>());
  // Measured 2026-12-05: mean 0.808, worst 0.748 (templeSR0002), best
  // possible 0.991, 18 boundary loops; the Delaunay graph cut gave 0.776
  // and 0.688 with 3,121 loops. At full size (scripts/demo.sh
  // temple) Poisson gives 0.866 and 0.790, where issue 30 asks 0.85 and
  // 0.75.
  EXPECT_GT(s["mean_iou"].get<double>(), 0.78);
  EXPECT_GT(s["min_iou"].get<double>(), 0.71);
  EXPECT_LT(topology["num_boundary_loops"].get<int>(), 50);
  EXPECT_GT(s["mean_best_iou"].get<double>(), 0.95);
}

// The rays from COLMAP's fused.ply.vis beside the cloud (every image that
// saw a point, not only its master), as stock COLMAP's fusion leaves them;
// a .vis of another cloud is refused in one line.
TEST(Surface, TempleGraphCutTakesTheRaysOfAFusedVis) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string ws = testing::TemplePipelineWorkspace();
  const std::string dir = testing::TempDir("surface_temple_vis");
  const std::vector<std::string> mesh = {"mesh",
                                         "--method",
                                         "delaunay_graph_cut",
                                         "--sparse_path",
                                         ws + "/sparse/adjusted",
                                         "--output_path",
                                         dir + "/mesh.ply",
                                         "--num_threads",
                                         "2",
                                         "--input_path"};
  std::vector<std::string> args = mesh;
  args.push_back(ws + "/dense/fused.ply");
  const testing::CommandResult fused = testing::RunBayon(args);
  ASSERT_EQ(fused.exit_code, 0) << fused.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/mesh.ply"));
  args = mesh;
  args.insert(args.end(),
              {ws + "/dense/points_edited.ply",
               "--visibility_path",
               ws + "/dense/fused.ply.vis",
               "--overwrite",
               "1"});
  const testing::CommandResult other = testing::RunBayon(args);
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_NE(other.output.find("but the cloud has"), std::string::npos)
      << other.output;
}

}  // namespace
}  // namespace bayon
