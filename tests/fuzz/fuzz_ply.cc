// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_ply: a PLY file, ASCII or binary of either byte order, read as a
// point cloud (with normals, colours and any other scalar properties as
// attributes), as a mesh (faces, texcoords) and for its texture file name.
// A cloud that reads and passes Check() is written and read back, and must
// keep its size and its attributes.
#include "ext/colmap/ply_io.h"
#include "ext/core/point_cloud.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tests/fuzz/fuzz_util.h"

namespace {

// Aborts (a finding) unless the cloud read back has the written layout.
void CheckRoundTrip(const bayon::PointCloud& cloud) {
  const std::string path = bayon::fuzz::FreshPath("roundtrip.ply");
  bayon::WritePointCloudPly(cloud, path);
  const bayon::PointCloud again = bayon::ReadPointCloudPly(path);
  if (again.size() != cloud.size() ||
      again.HasNormals() != cloud.HasNormals() ||
      again.HasColors() != cloud.HasColors() ||
      again.attributes.size() != cloud.attributes.size()) {
    std::fprintf(stderr,
                 "fuzz_ply: a cloud of %zu points did not survive a write "
                 "and read\n",
                 cloud.size());
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  const std::string path = fuzz::FreshPath("input.ply");
  fuzz::WriteFile(path, std::string(reinterpret_cast<const char*>(data), size));
  fuzz::Expect([&] {
    const PointCloud cloud = ReadPointCloudPly(path);
    cloud.Check(path);
    CheckRoundTrip(cloud);
  });
  fuzz::Expect([&] { ReadPly(path).Check(path); });
  fuzz::Expect([&] { ReadMeshPly(path).Check(path); });
  fuzz::Expect([&] { PlyTextureFile(path); });
  return 0;
}
