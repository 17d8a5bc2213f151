// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/ply_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace bayon {
namespace {

TriangleMesh Tetrahedron() {
  TriangleMesh mesh;
  PointCloud& v = mesh.vertices;
  v.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1.0 / 3.0}};
  v.normals = {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  v.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {10, 20, 30}};
  v.AddAttribute("sx", PlyScalarType::kFloat, 0.001);
  v.AddAttribute("num_images", PlyScalarType::kUChar, 5);
  v.attributes[0].values[2] = 0.125;
  mesh.faces = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    mesh.face_texcoords.push_back({Eigen::Vector2f(0, 0),
                                   Eigen::Vector2f(0.5f, 0),
                                   Eigen::Vector2f(0, 0.25f * f)});
  }
  return mesh;
}

TEST(PlyIo, MeshRoundTripInBinaryAndAscii) {
  const std::string dir = testing::TempDir("ply_io");
  const TriangleMesh mesh = Tetrahedron();
  for (bool binary : {true, false}) {
    PlyWriteOptions options;
    options.binary = binary;
    const std::string path = dir + (binary ? "/bin.ply" : "/ascii.ply");
    WriteMeshPly(mesh, path, options);
    const TriangleMesh back = ReadMeshPly(path);
    ASSERT_EQ(back.NumVertices(), 4u);
    ASSERT_EQ(back.faces, mesh.faces);
    EXPECT_EQ(back.vertices.positions, mesh.vertices.positions);
    EXPECT_EQ(back.vertices.colors, mesh.vertices.colors);
    ASSERT_EQ(back.vertices.attributes.size(), 2u);
    EXPECT_EQ(back.vertices.attributes[1].name, "num_images");
    EXPECT_EQ(back.vertices.attributes[1].values[3], 5);
    EXPECT_FLOAT_EQ(back.vertices.attributes[0].values[2], 0.125f);
    ASSERT_TRUE(back.HasTexcoords());
    EXPECT_EQ(back.face_texcoords[3][2], Eigen::Vector2f(0, 0.75f));
  }
}

TEST(PlyIo, ReadsBigEndianFloatCloudsAndPolygons) {
  const std::string dir = testing::TempDir("ply_io_be");
  std::string data =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar "
      "int vertex_index\nend_header\n";
  auto put_float = [&](float value) {
    uint32_t bits;
    std::memcpy(&bits, &value, 4);
    for (int shift = 24; shift >= 0; shift -= 8)
      data += static_cast<char>(bits >> shift);
  };
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f})
    put_float(v);
  data += static_cast<char>(4);
  for (int idx : {0, 1, 2, 3}) {
    for (int shift = 24; shift >= 0; shift -= 8)
      data += static_cast<char>(idx >> shift);
  }
  WriteFileAtomically(dir + "/quad.ply", data);
  const TriangleMesh mesh = ReadMeshPly(dir + "/quad.ply");
  EXPECT_EQ(mesh.NumFaces(), 2u);  // the quad as a fan of two triangles
  EXPECT_EQ(mesh.vertices.positions[2], Eigen::Vector3d(1, 1, 0));
}

TEST(PlyIo, RefusesBrokenFiles) {
  const std::string dir = testing::TempDir("ply_io_bad");
  WriteMeshPly(Tetrahedron(), dir + "/good.ply");
  const std::string good = ReadFileToString(dir + "/good.ply");
  WriteFileAtomically(dir + "/truncated.ply", good.substr(0, good.size() - 10));
  WriteFileAtomically(dir + "/text.ply", "hello\n");
  WriteFileAtomically(
      dir + "/nan.ply",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n1 nan 2\n");
  WriteFileAtomically(
      dir + "/bad_face.ply",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n0 0 0\n3 0 1 2\n");
  // Found by fuzz_ply: records without properties, 2^43 of them.
  WriteFileAtomically(
      dir + "/empty_records.ply",
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement junk 9000000000000\n"
      "end_header\n0 0 0\n");
  for (const char* name : {"truncated.ply",
                           "text.ply",
                           "nan.ply",
                           "bad_face.ply",
                           "empty_records.ply"}) {
    try {
      ReadPly(dir + "/" + name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(name), std::string::npos)
          << error.what();
    }
  }
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}};
  WritePointCloudPly(cloud, dir + "/cloud.ply");
  EXPECT_THROW(ReadMeshPly(dir + "/cloud.ply"), InputError);
  EXPECT_EQ(ReadPointCloudPly(dir + "/cloud.ply").size(), 1u);
}

TEST(PlyIo, FusedVisibilityRoundTripAndBrokenFiles) {
  const std::string dir = testing::TempDir("ply_io_vis");
  const TriangleMesh mesh = Tetrahedron();
  const std::vector<std::vector<uint32_t>> visibility = {
      {0, 3}, {}, {7}, {1, 2, 4}};
  WriteColmapFusedPly(mesh.vertices, dir + "/fused.ply", "test", &visibility);
  EXPECT_EQ(ReadColmapVisibility(dir + "/fused.ply.vis"), visibility);
  // A count beyond the file, a short record and bytes after the last one.
  const std::string good = ReadFileToString(dir + "/fused.ply.vis");
  for (const auto& [name, bytes] :
       {std::pair{std::string("count.vis"),
                  std::string("\xff\xff\xff\xff\0\0\0\0", 8)},
        std::pair{std::string("short.vis"), good.substr(0, good.size() - 2)},
        std::pair{std::string("long.vis"), good + std::string(4, '\0')}}) {
    WriteFileAtomically(dir + "/" + name, bytes);
    EXPECT_THROW(ReadColmapVisibility(dir + "/" + name), InputError) << name;
  }
  EXPECT_THROW(ReadColmapVisibility(dir + "/missing.vis"), InputError);
}

}  // namespace
}  // namespace bayon
