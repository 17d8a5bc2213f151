// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/synth/cloud_scene.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunSynthCloud(int argc, char** argv) {
  std::string shape = "relief_cylinder";
  std::string input_path, cloud_path, output_path, truth_path;
  bool overwrite = false;
  NoisyCloudOptions options;
  ReliefCylinderOptions cylinder;
  BoxTowerOptions tower;
  TorusOptions torus;
  CommandLine command(
      "synth_cloud",
      "Write a synthetic dense cloud with known truth, for testing edit and "
      "mesh: points sampled from a built-in surface or from a mesh (e.g. a "
      "synthetic workspace's gt/surface.ply), with Gaussian noise, per-point "
      "sx, sy, sz, optional true normals, and blunders flagged in a "
      "`blunder` attribute. Or, with --cloud_path, blunders injected into an "
      "existing cloud (a dense matcher's, in the truth's frame) whose true "
      "surface is --shape mesh --input_path.");
  CLI::App& app = command.app();
  app.add_option("--shape", shape, "relief_cylinder, box_tower, torus, mesh")
      ->transform(
          CLI::IsMember({"relief_cylinder", "box_tower", "torus", "mesh"}));
  app.add_option("--input_path", input_path, "shape mesh: the surface (PLY)");
  app.add_option("--cloud_path",
                 cloud_path,
                 "Inject blunders into this cloud instead of sampling one "
                 "(needs --shape mesh)");
  app.add_option("--output_path", output_path, "Cloud to write (PLY)")
      ->required();
  app.add_option("--truth_path", truth_path, "Also write the true surface");
  command.AddOptions(&options);
  app.add_option("--relief_m",
                 cylinder.relief_m,
                 "relief_cylinder: relief amplitude, metres");
  app.add_option("--overwrite", overwrite, "Replace existing files");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckOutputPath(output_path, overwrite);
  if (!truth_path.empty()) CheckOutputPath(truth_path, overwrite);

  TriangleMesh surface;
  if (shape == "mesh") {
    if (input_path.empty()) {
      ThrowInputError("--input_path is required with --shape mesh");
    }
    CheckFileExists(input_path, "--input_path");
    surface = ReadMeshPly(input_path);
  } else if (shape == "relief_cylinder") {
    surface = MakeReliefCylinder(cylinder);
  } else if (shape == "box_tower") {
    surface = MakeBoxTower(tower);
  } else {
    surface = MakeTorus(torus);
  }
  PointCloud cloud;
  size_t num_blunders = 0;
  if (!cloud_path.empty()) {
    if (shape != "mesh") {
      ThrowInputError(
          "--cloud_path needs its true surface: --shape mesh "
          "--input_path SURFACE");
    }
    CheckFileExists(cloud_path, "--cloud_path");
    cloud = ReadPointCloudPly(cloud_path);
    num_blunders = InjectBlunders(surface, options, &cloud);
  } else {
    cloud = SampleNoisyCloud(surface, options);
    num_blunders = std::llround(options.blunder_fraction * cloud.size());
  }
  PlyWriteOptions write_options;
  write_options.comment = "bayon synth_cloud --shape " + shape;
  WritePointCloudPly(cloud, output_path, write_options);
  if (!truth_path.empty()) WriteMeshPly(surface, truth_path, write_options);
  command.PrintSummary(StrCat(shape,
                              ": ",
                              cloud.size(),
                              " points (",
                              num_blunders,
                              " blunders) -> ",
                              output_path));
  return 0;
}

}  // namespace bayon
