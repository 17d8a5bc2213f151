// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon synth_cloud`, `bayon edit` and `bayon mesh` end to end: a synthetic
// dense cloud with known surface and blunders, edited and meshed through the
// command line, the outputs read back and judged against the truth; and bad
// input refused with one line, nothing written.
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/file_util.h"
#include "ext/core/mesh_geometry.h"
#include "ext/eval/mesh_distance.h"
#include "ext/mesh/mesh_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A small tower cloud (and its true surface) shared by the tests of one
// build.
std::string TowerCloud() {
  return testing::SharedFixture("edit_mesh_tower", [](const std::string& dir) {
    const testing::CommandResult result =
        testing::RunBayon({"synth_cloud",
                           "--shape",
                           "box_tower",
                           "--num_points",
                           "30000",
                           "--output_path",
                           dir + "/points.ply",
                           "--truth_path",
                           dir + "/surface.ply"});
    ASSERT_EQ(result.exit_code, 0) << result.output;
  });
}

size_t CountBlunders(const PointCloud& cloud) {
  const PointAttribute* flags = cloud.FindAttribute("blunder");
  EXPECT_NE(flags, nullptr);
  size_t count = 0;
  for (double f : flags->values) count += f != 0;
  return count;
}

// Runs bayon, expects exit code 2 with one line naming `expected`, the
// inputs unchanged and none of `outputs` created.
void ExpectRefusedWithoutOutput(const std::vector<std::string>& args,
                                const std::string& expected,
                                const std::string& input,
                                const std::vector<std::string>& outputs) {
  const auto before = testing::HashTree(input);
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("error: "), std::string::npos)
      << result.output;
  EXPECT_NE(result.LastLine().find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.output;
  EXPECT_EQ(testing::HashTree(input), before);
  for (const std::string& output : outputs) {
    EXPECT_FALSE(fs::exists(output)) << output << " was written";
  }
}

TEST(EditCommand, RemovesTheBlundersOfASyntheticTower) {
  const std::string fixture = TowerCloud();
  const std::string ws = testing::TempDir("edit_tower");
  fs::create_directories(ws + "/dense");
  fs::copy_file(fixture + "/points.ply", ws + "/dense/points.ply");
  const testing::CommandResult result =
      testing::RunBayon({"edit",
                         "--input_path",
                         ws + "/dense/points.ply",
                         "--output_path",
                         ws + "/dense/points_edited.ply",
                         "--removed_path",
                         ws + "/dense/removed.ply",
                         "--report_path",
                         ws + "/dense/edit.json"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("iteration 2:"), std::string::npos);
  EXPECT_TRUE(fs::exists(ws + "/logs/edit.log"));
  EXPECT_TRUE(fs::exists(ws + "/logs/edit.options"));

  const PointCloud input = ReadPointCloudPly(ws + "/dense/points.ply");
  const PointCloud edited = ReadPointCloudPly(ws + "/dense/points_edited.ply");
  const PointCloud removed = ReadPointCloudPly(ws + "/dense/removed.ply");
  EXPECT_EQ(edited.size() + removed.size(), input.size());
  const size_t blunders = CountBlunders(input);
  EXPECT_EQ(blunders, 600u);                        // 2 % of 30000
  EXPECT_LE(CountBlunders(edited), blunders / 20);  // >= 95 % removed
  const size_t good_removed = removed.size() - CountBlunders(removed);
  EXPECT_LT(good_removed, (input.size() - blunders) / 100);
  // Sigmas and flags travel with the kept points; the removed carry why.
  EXPECT_NE(edited.FindAttribute("sx"), nullptr);
  ASSERT_NE(removed.FindAttribute("edit_reason"), nullptr);
  EXPECT_EQ(removed.FindAttribute("edit_reason")->values[0], 1.0);

  std::ifstream report_file(ws + "/dense/edit.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report["num_removed"].get<size_t>(), removed.size());
  EXPECT_TRUE(report["used_point_precision"].get<bool>());
  EXPECT_GE(report["iterations"].size(), 2u);

  // PCL's statistical outlier removal through the same command.
  const testing::CommandResult statistical =
      testing::RunBayon({"edit",
                         "--input_path",
                         ws + "/dense/points.ply",
                         "--output_path",
                         ws + "/dense/statistical.ply",
                         "--method",
                         "statistical"});
  ASSERT_EQ(statistical.exit_code, 0) << statistical.output;
  EXPECT_NE(statistical.output.find("statistical outlier"), std::string::npos);
}

TEST(EditCommand, BadInput) {
  const std::string dir = testing::TempDir("edit_bad");
  const std::string out = dir + "/out.ply";

  // An empty cloud.
  WritePointCloudPly(PointCloud(), dir + "/empty.ply");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/empty.ply", "--output_path", out},
      "empty.ply: the cloud has no points",
      dir + "/empty.ply",
      {out});

  // All points on one line.
  PointCloud line;
  for (int i = 0; i < 200; ++i) line.positions.emplace_back(i, 0.5 * i, 1);
  WritePointCloudPly(line, dir + "/line.ply");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/line.ply", "--output_path", out},
      "line.ply: all 200 points lie on one line",
      dir + "/line.ply",
      {out});

  // A NaN coordinate (ASCII, as another program might write it).
  WriteFileAtomically(dir + "/nan.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\n"
                      "property float x\nproperty float y\nproperty float z\n"
                      "end_header\n0 0 0\n1 nan 0\n0 1 0\n");
  ExpectRefusedWithoutOutput(
      {"edit", "--input_path", dir + "/nan.ply", "--output_path", out},
      "nan.ply: point 1 has a coordinate that is not a finite number",
      dir + "/nan.ply",
      {out});

  // A bad option value and a bad method name.
  ExpectRefusedWithoutOutput({"edit",
                              "--input_path",
                              dir + "/line.ply",
                              "--output_path",
                              out,
                              "--num_iterations",
                              "0"},
                             "surface_fit.num_iterations must be in [1, 20] "
                             "(got 0)",
                             dir + "/line.ply",
                             {out});
  ExpectRefusedWithoutOutput({"edit",
                              "--input_path",
                              dir + "/line.ply",
                              "--output_path",
                              out,
                              "--method",
                              "median"},
                             "median",
                             dir + "/line.ply",
                             {out});
}

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file);
}

TEST(MeshCommand, CylinderMeshOfTheEditedTower) {
  const std::string fixture = TowerCloud();
  const std::string ws = testing::TempDir("mesh_tower");
  fs::create_directories(ws + "/dense");
  fs::create_directories(ws + "/mesh");
  const testing::CommandResult edit =
      testing::RunBayon({"edit",
                         "--input_path",
                         fixture + "/points.ply",
                         "--output_path",
                         ws + "/dense/points_edited.ply"});
  ASSERT_EQ(edit.exit_code, 0) << edit.output;
  const testing::CommandResult mesh =
      testing::RunBayon({"mesh",
                         "--input_path",
                         ws + "/dense/points_edited.ply",
                         "--output_path",
                         ws + "/mesh/mesh.ply",
                         "--method",
                         "cylinder",
                         "--report_path",
                         ws + "/mesh/report.json"});
  ASSERT_EQ(mesh.exit_code, 0) << mesh.output;
  EXPECT_TRUE(fs::exists(ws + "/logs/mesh.log"));
  const nlohmann::json report = ReadJson(ws + "/mesh/report.json");
  // Closed around the axis: open only at top and bottom, manifold.
  EXPECT_EQ(report["num_boundary_loops"].get<int>(), 2) << mesh.output;
  EXPECT_EQ(report["num_non_manifold_edges"].get<int>(), 0);
  EXPECT_EQ(report["num_non_manifold_vertices"].get<int>(), 0);
  EXPECT_EQ(report["num_components"].get<int>(), 1);
  EXPECT_GT(report["cylinder"]["num_seam_faces"].get<int>(), 20);

  // Within the noise of the true surface both ways (sigma 2 mm per axis).
  const TriangleMesh result = ReadMesh(ws + "/mesh/mesh.ply");
  const TriangleMesh truth = ReadMesh(fixture + "/surface.ply");
  MeshComparisonOptions compare;
  compare.num_samples = 30000;
  const MeshComparison c = CompareMeshes(result, truth, compare);
  EXPECT_LT(c.mesh_to_truth.rms, 0.003);
  EXPECT_LT(c.truth_to_mesh.rms, 0.003);

  // The same mesh as OBJ and OFF.
  for (const char* ext : {"obj", "off"}) {
    const std::string path = ws + "/mesh/mesh." + ext;
    const testing::CommandResult other =
        testing::RunBayon({"mesh",
                           "--input_path",
                           ws + "/dense/points_edited.ply",
                           "--output_path",
                           path});
    ASSERT_EQ(other.exit_code, 0) << other.output;
    EXPECT_EQ(ReadMesh(path).NumFaces(), result.NumFaces()) << ext;
  }
}

// A torus with true normals (and one without), shared by the tests of one
// build.
std::string TorusCloud() {
  return testing::SharedFixture("edit_mesh_torus", [](const std::string& dir) {
    for (const char* normals : {"1", "0"}) {
      const testing::CommandResult result = testing::RunBayon(
          {"synth_cloud",
           "--shape",
           "torus",
           "--num_points",
           "8000",
           "--blunder_fraction",
           "0",
           "--with_normals",
           normals,
           "--output_path",
           dir + (normals[0] == '1' ? "/normals.ply" : "/plain.ply"),
           "--truth_path",
           dir + "/surface" + normals + ".ply"});
      ASSERT_EQ(result.exit_code, 0) << result.output;
    }
  });
}

TEST(MeshCommand, ThreeDimensionalMethodsAndColmapPoisson) {
  const std::string fixture = TorusCloud();
  const std::string dir = testing::TempDir("mesh_torus");
  const TriangleMesh truth = ReadMesh(fixture + "/surface1.ply");
  const std::vector<std::vector<std::string>> runs = {
      {"advancing_front"},
      {"greedy_projection"},
      {"poisson", "--poisson.depth", "6"},
      // --colmap_trim: a flag's earlier name, still accepted.
      {"colmap_poisson", "--colmap_poisson.depth", "6", "--colmap_trim", "0"}};
  for (const std::vector<std::string>& run : runs) {
    const std::string out = dir + "/" + run[0] + ".ply";
    std::vector<std::string> args = {"mesh",
                                     "--input_path",
                                     fixture + "/normals.ply",
                                     "--output_path",
                                     out,
                                     "--method"};
    args.insert(args.end(), run.begin(), run.end());
    const testing::CommandResult result = testing::RunBayon(args);
    ASSERT_EQ(result.exit_code, 0) << result.output;
    const TriangleMesh mesh = ReadMesh(out);
    const MeshTopology t = ComputeMeshTopology(mesh);
    EXPECT_TRUE(t.IsManifold()) << run[0];
    MeshComparisonOptions compare;
    compare.num_samples = 20000;
    const MeshComparison c = CompareMeshes(mesh, truth, compare);
    // The Poissons smooth a little at depth 6; the interpolating methods
    // carry the 2 mm noise.
    EXPECT_LT(c.mesh_to_truth.rms, 0.006) << run[0];
    if (run[0] != "greedy_projection") {
      EXPECT_LT(c.truth_to_mesh.rms, 0.006) << run[0];
    }
  }
  // Normals estimated where the cloud has none.
  const testing::CommandResult estimated =
      testing::RunBayon({"mesh",
                         "--input_path",
                         fixture + "/plain.ply",
                         "--output_path",
                         dir + "/estimated.ply",
                         "--method",
                         "poisson",
                         "--poisson.depth",
                         "6"});
  ASSERT_EQ(estimated.exit_code, 0) << estimated.output;
  EXPECT_NE(estimated.output.find("normals estimated with PCL"),
            std::string::npos);
  EXPECT_TRUE(ComputeMeshTopology(ReadMesh(dir + "/estimated.ply")).IsClosed());
}

TEST(MeshCommand, BadInput) {
  const std::string fixture = TorusCloud();
  const std::string dir = testing::TempDir("mesh_bad");
  const std::string out = dir + "/mesh.ply";
  WritePointCloudPly(PointCloud(), dir + "/empty.ply");
  ExpectRefusedWithoutOutput(
      {"mesh", "--input_path", dir + "/empty.ply", "--output_path", out},
      "empty.ply: the cloud has no points",
      dir + "/empty.ply",
      {out});
  PointCloud line;
  for (int i = 0; i < 100; ++i) line.positions.emplace_back(0, 0, 0.1 * i);
  WritePointCloudPly(line, dir + "/line.ply");
  for (const char* method : {"cylinder", "advancing_front", "poisson"}) {
    ExpectRefusedWithoutOutput({"mesh",
                                "--input_path",
                                dir + "/line.ply",
                                "--output_path",
                                out,
                                "--method",
                                method},
                               "line.ply: all 100 points lie on one line",
                               dir + "/line.ply",
                               {out});
  }
  WriteFileAtomically(dir + "/nan.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\n"
                      "property double x\nproperty double y\n"
                      "property double z\nend_header\n0 0 0\n1 0 0\n"
                      "0 1 -nan\n");
  ExpectRefusedWithoutOutput(
      {"mesh", "--input_path", dir + "/nan.ply", "--output_path", out},
      "nan.ply: point 2 has a coordinate that is not a finite number",
      dir + "/nan.ply",
      {out});
  // A nested option is named as registered, whichever name was given.
  const std::string plain = fixture + "/plain.ply";
  ExpectRefusedWithoutOutput(
      {"mesh",
       "--input_path",
       plain,
       "--output_path",
       out,
       "--cone_angle_deg",
       "85"},
      "cylinder.cone_angle_deg must be in [0, 80) (got 85)",
      plain,
      {out});
  ExpectRefusedWithoutOutput({"mesh",
                              "--input_path",
                              plain,
                              "--output_path",
                              out,
                              "--cylinder.axis_direction",
                              "0,1"},
                             "--cylinder.axis_direction: '0,1' is not three "
                             "numbers x,y,z",
                             plain,
                             {out});
  // Poisson on a cloud without normals, estimation turned off.
  ExpectRefusedWithoutOutput({"mesh",
                              "--input_path",
                              fixture + "/plain.ply",
                              "--output_path",
                              out,
                              "--method",
                              "poisson",
                              "--estimate_normals",
                              "0"},
                             "plain.ply: poisson needs point normals and the "
                             "cloud has none",
                             fixture + "/plain.ply",
                             {out});
  // delaunay_graph_cut: its rays need the oriented model and the images
  // that saw each point; a cloud too sparse is refused, not meshed by the
  // cylinder instead.
  ExpectRefusedWithoutOutput({"mesh",
                              "--input_path",
                              fixture + "/plain.ply",
                              "--output_path",
                              out,
                              "--method",
                              "delaunay_graph_cut"},
                             "--method delaunay_graph_cut needs --sparse_path",
                             fixture + "/plain.ply",
                             {out});
  Scene model;
  Camera camera = Camera::Create(CameraModelId::kPinhole, 500, 600, 400);
  camera.camera_id = 1;
  model.cameras.Set(1, camera);
  Image image;
  image.image_id = 7;
  image.camera_id = 1;
  image.name = "a.png";
  model.images.Set(7, image);
  fs::create_directories(dir + "/sparse");
  WriteModel(model, dir + "/sparse", ModelFormat::kBinary);
  const std::vector<std::string> graph_cut = {
      "--method", "delaunay_graph_cut", "--sparse_path", dir + "/sparse"};
  std::vector<std::string> args = {
      "mesh", "--input_path", fixture + "/plain.ply", "--output_path", out};
  args.insert(args.end(), graph_cut.begin(), graph_cut.end());
  ExpectRefusedWithoutOutput(args,
                             "plain.ply: delaunay_graph_cut needs the images "
                             "that saw each point",
                             fixture + "/plain.ply",
                             {out});
  PointCloud sparse;
  for (int i = 0; i < 50; ++i) {
    sparse.positions.emplace_back(std::cos(i), std::sin(i), 0.01 * i);
  }
  sparse.AddAttribute("master_id", PlyScalarType::kInt, 7);
  WritePointCloudPly(sparse, dir + "/sparse.ply");
  args = {"mesh", "--input_path", dir + "/sparse.ply", "--output_path", out};
  args.insert(args.end(), graph_cut.begin(), graph_cut.end());
  ExpectRefusedWithoutOutput(
      args,
      "delaunay_graph_cut: 50 points are too sparse to close a surface",
      dir + "/sparse.ply",
      {out});
  // configs/ring.ini's Poisson likewise, and neither falls back to the
  // cylinder.
  ExpectRefusedWithoutOutput({"mesh",
                              "--input_path",
                              dir + "/sparse.ply",
                              "--output_path",
                              out,
                              "--method",
                              "poisson",
                              "--depth",
                              "10"},
                             "poisson: 50 points are too sparse to close a "
                             "surface",
                             dir + "/sparse.ply",
                             {out});
  ExpectRefusedWithoutOutput({"mesh",
                              "--input_path",
                              fixture + "/plain.ply",
                              "--output_path",
                              dir + "/mesh.stl"},
                             "unknown mesh format",
                             fixture + "/plain.ply",
                             {dir + "/mesh.stl"});
}

}  // namespace
}  // namespace bayon
