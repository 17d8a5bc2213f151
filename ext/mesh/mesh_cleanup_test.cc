// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/mesh_cleanup.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/mesh_geometry.h"
#include "ext/mesh/mesh_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace bayon {
namespace {

// An n x n grid of unit squares in the plane z = 0, two triangles each,
// counter-clockwise seen from +z.
TriangleMesh Grid(int n, double offset_x = 0) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.vertices.positions.emplace_back(offset_x + i, j, 0);
    }
  }
  const int base = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = base + j * (n + 1) + i;
      mesh.faces.emplace_back(a, a + 1, a + n + 2);
      mesh.faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  }
  return mesh;
}

TEST(MeshCleanup, MergesDuplicatesAndOrientsFaces) {
  TriangleMesh mesh = Grid(6);
  mesh.vertices.normals.assign(mesh.NumVertices(), Eigen::Vector3f::UnitZ());
  // A copy of vertex 8 used by one face, a repeated face, a face with a
  // repeated vertex, and a flipped face.
  mesh.vertices.positions.push_back(mesh.vertices.positions[8]);
  mesh.vertices.normals.push_back(Eigen::Vector3f::UnitZ());
  const int copy = static_cast<int>(mesh.NumVertices()) - 1;
  for (Eigen::Vector3i& f : mesh.faces) {
    if (f(0) == 8) {
      f(0) = copy;
      break;
    }
  }
  mesh.faces.push_back(mesh.faces[3]);
  mesh.faces.emplace_back(1, 1, 2);
  std::swap(mesh.faces[10](1), mesh.faces[10](2));
  MeshCleanupReport report;
  const TriangleMesh clean = CleanupMesh(mesh, MeshCleanupOptions(), &report);
  EXPECT_EQ(report.num_merged_vertices, 1u);
  EXPECT_EQ(report.num_duplicate_faces, 1u);
  EXPECT_EQ(report.num_repeated_vertex_faces, 1u);
  EXPECT_EQ(report.num_flipped_faces, 1u);
  EXPECT_EQ(clean.NumFaces(), 72u);
  EXPECT_EQ(clean.NumVertices(), 49u);
  const MeshTopology t = ComputeMeshTopology(clean);
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_EQ(t.num_boundary_loops, 1u);
  for (size_t f = 0; f < clean.NumFaces(); ++f) {
    EXPECT_GT(FaceNormal(clean, f).z(), 0.99);
  }
  ASSERT_TRUE(clean.vertices.HasNormals());
}

TEST(MeshCleanup, NonManifoldDegenerateAndSmallParts) {
  TriangleMesh mesh = Grid(8);
  const int n = static_cast<int>(mesh.NumVertices());
  // A fin: a third face on an inner edge (0-10 runs across the first
  // square's diagonal).
  mesh.vertices.positions.emplace_back(0.5, 0.5, 1);
  mesh.faces.emplace_back(0, 10, n);
  // A needle: a zero-area face hanging off the border.
  mesh.vertices.positions.emplace_back(4, -1, 0);
  mesh.vertices.positions.emplace_back(4, -1 + 1e-9, 0);
  mesh.faces.emplace_back(4, n + 2, n + 1);
  // A small far-away piece of 2 faces.
  TriangleMesh small = Grid(1, 100);
  for (Eigen::Vector3i f : small.faces) {
    mesh.faces.push_back(f.array() + static_cast<int>(mesh.NumVertices()));
  }
  mesh.vertices.positions.insert(mesh.vertices.positions.end(),
                                 small.vertices.positions.begin(),
                                 small.vertices.positions.end());
  MeshCleanupReport report;
  const TriangleMesh clean = CleanupMesh(mesh, MeshCleanupOptions(), &report);
  EXPECT_EQ(report.num_non_manifold_faces, 1u);
  EXPECT_EQ(report.num_degenerate_faces, 1u);
  EXPECT_EQ(report.num_small_components, 1u);
  EXPECT_EQ(report.num_small_component_faces, 2u);
  const MeshTopology t = ComputeMeshTopology(clean);
  EXPECT_TRUE(t.IsManifold());
  EXPECT_EQ(t.num_faces, 128u);
  EXPECT_EQ(t.num_degenerate_faces, 0u);
  EXPECT_EQ(t.num_components, 1u);
}

// Grid(n) without the squares (i, j) for which `cut` is true.
template <typename Cut>
TriangleMesh GridWithHoles(int n, Cut cut) {
  TriangleMesh mesh = Grid(n);
  std::vector<Eigen::Vector3i> kept;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const int square = static_cast<int>(f / 2);
    if (!cut(square % n, square / n)) kept.push_back(mesh.faces[f]);
  }
  mesh.faces = kept;
  return mesh;
}

// `mesh` through CleanupMesh with holes of up to `max_hole_edges` filled.
TriangleMesh CleanupFillingHoles(const TriangleMesh& mesh,
                                 int max_hole_edges,
                                 MeshCleanupReport* report) {
  MeshCleanupOptions options;
  options.max_hole_edges = max_hole_edges;
  return CleanupMesh(mesh, options, report);
}

TEST(MeshCleanup, FillsSmallHolesOnly) {
  // Two holes: one square (2 faces) and a 3 x 3 block (18 faces).
  const TriangleMesh mesh = GridWithHoles(10, [](int i, int j) {
    const bool small_hole = i == 2 && j == 2;
    const bool large_hole = i >= 5 && i <= 7 && j >= 5 && j <= 7;
    return small_hole || large_hole;
  });
  EXPECT_EQ(ComputeMeshTopology(mesh).num_boundary_loops, 3u);
  MeshCleanupReport report;
  const TriangleMesh clean = CleanupFillingHoles(mesh, 6, &report);
  EXPECT_EQ(report.num_holes_filled, 1u);
  EXPECT_EQ(report.num_fill_faces, 2u);
  const MeshTopology t = ComputeMeshTopology(clean);
  EXPECT_EQ(t.num_boundary_loops, 2u);  // the border and the large hole
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_NEAR(t.area, 100 - 9, 1e-9);
}

TEST(MeshCleanup, FillsAHoleWholeEarByEar) {
  // A 3 x 3 block: a loop of 12 edges, whose minimum-area triangulation
  // is added an ear of the boundary at a time (OpenMesh never relinks), and
  // all of its 10 triangles go in.
  const TriangleMesh mesh = GridWithHoles(
      10, [](int i, int j) { return i >= 4 && i <= 6 && j >= 4 && j <= 6; });
  MeshCleanupReport report;
  const TriangleMesh clean = CleanupFillingHoles(mesh, 12, &report);
  EXPECT_EQ(report.num_holes_filled, 1u);
  EXPECT_EQ(report.num_fill_faces, 10u);
  const MeshTopology t = ComputeMeshTopology(clean);
  EXPECT_TRUE(t.IsManifold());
  EXPECT_EQ(t.num_boundary_loops, 1u);  // the border
  EXPECT_EQ(t.num_inconsistent_edges, 0u);
  EXPECT_NEAR(t.area, 100, 1e-9);
}

TEST(MeshIo, PlyObjOffRoundTrip) {
  const std::string dir = ::testing::TempDir() + "/bayon_mesh_io";
  std::filesystem::create_directories(dir);
  TriangleMesh mesh = Grid(3);
  mesh.vertices.positions[5].z() = 0.123456789012;
  for (const std::string ext : {".ply", ".obj", ".off", ".OBJ"}) {
    const std::string path = dir + "/mesh" + ext;
    WriteMesh(mesh, path);
    const TriangleMesh back = ReadMesh(path);
    ASSERT_EQ(back.NumFaces(), mesh.NumFaces()) << ext;
    ASSERT_EQ(back.NumVertices(), mesh.NumVertices()) << ext;
    // OpenMesh's OBJ and OFF exporters go through single precision.
    EXPECT_NEAR(back.vertices.positions[5].z(),
                0.123456789012,
                ext == ".ply" ? 1e-15 : 1e-7)
        << ext;
    EXPECT_EQ(back.faces[4], mesh.faces[4]) << ext;
  }
  EXPECT_THROW(WriteMesh(mesh, dir + "/mesh.stl"), InputError);
  WriteFileAtomically(dir + "/broken.off", "OFF\n3 1\n0 0 0\n");
  EXPECT_THROW(ReadMesh(dir + "/broken.off"), InputError);
  // Found by fuzzing: OpenMesh reserved gigabytes for this header.
  WriteFileAtomically(dir + "/tab.off", "OFF\v4 2 0\n0 0 0\n1 0 0\n");
  EXPECT_THROW(ReadMesh(dir + "/tab.off"), InputError);
  WriteFileAtomically(dir + "/glued.off", "OFF0=3\n");
  EXPECT_THROW(ReadMesh(dir + "/glued.off"), InputError);
  // Counts on the keyword's line, comments, a quad (two triangles), colours
  // as fractions or bytes; a face of 10^30 corners is refused.
  const std::string triangle = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  WriteFileAtomically(dir + "/one_line.off", "OFF 3 1 0\n" + triangle);
  EXPECT_EQ(ReadMesh(dir + "/one_line.off").NumFaces(), 1u);
  WriteFileAtomically(dir + "/quad.off",
                      "COFF\n4 1 0\n0 0 0 1.0 0 0\n1 0 0 0 1 0\n"
                      "1 1 0 0 0 255\n0 1 0 0 0 128 255\n4 0 1 2 3\n");
  const TriangleMesh quad = ReadMesh(dir + "/quad.off");
  ASSERT_EQ(quad.NumFaces(), 2u);
  ASSERT_EQ(quad.vertices.colors.size(), 4u);
  EXPECT_EQ(quad.vertices.colors[0].x(), 255);
  EXPECT_EQ(quad.vertices.colors[1].y(), 1);  // an integer: a byte
  EXPECT_EQ(quad.vertices.colors[3].z(), 128);
  WriteFileAtomically(dir + "/valence.off",
                      "OFF\n3 1 0\n" + triangle.substr(0, 18) +
                          "1000000000000000000000000000000 0 1 2\n");
  EXPECT_THROW(ReadMesh(dir + "/valence.off"), InputError);
  WriteFileAtomically(dir + "/comment.off", "OFF # a\n3 1 0\n" + triangle);
  EXPECT_EQ(ReadMesh(dir + "/comment.off").NumFaces(), 1u);
  EXPECT_FALSE(IsMeshFormatSupported("a.xyz"));
}

// OpenMesh's OBJ reader aborts on a face without vertex indices (found by
// fuzzing): such files, faces naming vertices that are not there and
// colours beyond 0..1 (undefined in its conversion) are refused first; negative
// (relative) indices and v/vt/vn corners are read.
TEST(MeshIo, ObjFacesAreCheckedBeforeOpenMeshReadsThem) {
  const std::string dir = ::testing::TempDir() + "/bayon_mesh_obj";
  std::filesystem::create_directories(dir);
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
  const std::vector<std::pair<std::string, bool>> faces = {
      {"f 1 2 3\n", true},
      {"f -3/1 -2/1 -1/1\n", true},
      {"f 1//1 2//1 3//1\n", true},
      {"f /1 /1 /1\n", false},
      {"f 1 2 4\n", false},
      {"f 0 1 2\n", false},
      {"f 1 2\n", false},
      {"f 1x 2 3\n", false},
      {"v 0 0 1 0.5 1 0\nf 1 2 4\n", true},
      {"v 0 0 1 52 21.5 13\nf 1 2 4\n", false},
  };
  for (const auto& [face, good] : faces) {
    const std::string path = dir + "/mesh.obj";
    WriteFileAtomically(path, vertices + face);
    if (good) {
      EXPECT_EQ(ReadMesh(path).NumFaces(), 1u) << face;
    } else {
      EXPECT_THROW(ReadMesh(path), InputError) << face;
    }
  }
}

}  // namespace
}  // namespace bayon
