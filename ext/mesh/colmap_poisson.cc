// SPDX-License-Identifier: BSD-3-Clause
//
// Stock `colmap poisson_mesher` behind meshing.h, for comparison.
#include "ext/colmap/colmap_cli.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/mesh/meshing.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

TriangleMesh ColmapPoissonMesh(const PointCloud& cloud,
                               const ColmapPoissonOptions& options,
                               int num_threads) {
  options.Check();
  if (!cloud.HasNormals()) {
    ThrowInputError(
        "colmap_poisson needs point normals and the cloud has none");
  }
  std::string folder = options.work_path;
  const bool temporary = folder.empty();
  if (temporary) {
    folder =
        (fs::temp_directory_path() / ("bayon-colmap-poisson" + TempSuffix()))
            .string();
  }
  fs::create_directories(folder);
  struct Remove {
    std::string path;
    bool active;
    ~Remove() {
      std::error_code ignored;
      if (active) fs::remove_all(path, ignored);
    }
  } remove{folder, temporary};

  const std::string input = folder + "/fused.ply";
  const std::string output = folder + "/meshed-poisson.ply";
  WriteColmapFusedPly(cloud, input, "bayon mesh --method colmap_poisson");

  ColmapCall call;
  call.command = "poisson_mesher";
  call.options = {
      {"--input_path", input},
      {"--output_path", output},
      {"--PoissonMeshing.depth", std::to_string(options.depth)},
      {"--PoissonMeshing.point_weight", std::to_string(options.point_weight)},
      {"--PoissonMeshing.trim", std::to_string(options.trim)},
      {"--PoissonMeshing.num_threads", std::to_string(num_threads)}};
  call.expected_outputs = {output};
  ColmapRunOptions run_options;
  run_options.log_path = folder + "/colmap.log";
  const ColmapResult result = RunColmap(call, run_options);
  if (!result.success) {
    throw RunFailure(
        StrCat("colmap poisson_mesher failed: ",
               result.message,
               temporary ? "" : " (log: " + result.log_path + ")"));
  }
  TriangleMesh mesh = ReadPly(output);
  // COLMAP's mesher writes colours only; keep positions and faces.
  mesh.vertices.colors.clear();
  mesh.vertices.attributes.clear();
  return mesh;
}

}  // namespace bayon
