// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/mesh_io.h"

#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/mesh/openmesh_types.h"

#include <glog/logging.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return ext;
}

// OpenMesh reserves memory for the counts in an OFF header before it reads a
// vertex, so a damaged or forged header (a billion vertices in 50 bytes)
// would exhaust memory: the counts are checked against the file's size
// first. Every vertex has three numbers and every face at least four, each
// followed by a separator.
void CheckOffHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::string keyword;
  while (std::getline(in, line)) {
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    keyword = line.substr(start);
    break;
  }
  const size_t off = keyword.find("OFF");
  const bool prefix_ok =
      off != std::string::npos &&
      keyword.find_first_not_of("STCN4n") >= off;  // [ST][C][N][4][n]OFF
  if (!prefix_ok) ThrowInputError(path, ": not an OFF mesh (no OFF header)");
  if (keyword.find("BINARY") != std::string::npos) {
    ThrowInputError(path,
                    ": binary OFF is not supported (use ASCII OFF or PLY)");
  }
  // The counts (vertices, faces, edges) have the next line to themselves,
  // which is where OpenMesh reads them: "OFF0=3" made it reserve gigabytes
  // for counts it never read.
  std::string counts = keyword.substr(off + 3);
  if (counts.substr(0, counts.find('#')).find_first_not_of(" \t\r") ==
      std::string::npos) {
    counts.clear();
    while (std::getline(in, line)) {
      const size_t start = line.find_first_not_of(" \t\r");
      if (start == std::string::npos || line[start] == '#') continue;
      counts = line;
      break;
    }
  } else {
    // OpenMesh would skip them and take the first vertex for the counts.
    ThrowInputError(path,
                    ": the OFF counts must be on their own line after the "
                    "keyword line");
  }
  // A control character (a vertical tab after OFF) is refused too.
  const std::string header = keyword + "\n" + counts;
  if (std::any_of(header.begin(), header.end(), [](char c) {
        return std::iscntrl(static_cast<unsigned char>(c)) && c != '\t' &&
               c != '\r' && c != '\n';
      })) {
    ThrowInputError(path, ": a control character in the OFF header");
  }
  // Two or three whole numbers and nothing else (a comment aside).
  std::vector<long long> numbers;
  std::istringstream fields(counts.substr(0, counts.find('#')));
  for (std::string field; fields >> field;) {
    if (field.size() > 15 ||
        field.find_first_not_of("0123456789") != std::string::npos) {
      numbers.clear();
      break;
    }
    numbers.push_back(std::stoll(field));
  }
  if (numbers.size() < 2 || numbers.size() > 3) {
    ThrowInputError(path,
                    ": the OFF header's counts '",
                    counts,
                    "' are not two or three whole numbers");
  }
  const long long num_vertices = numbers[0];
  const long long num_faces = numbers[1];
  const long long file_size = static_cast<long long>(fs::file_size(path));
  if (num_vertices > file_size / 6 || num_faces > file_size / 8 ||
      num_vertices * 6 + num_faces * 8 > file_size) {
    ThrowInputError(path,
                    ": the OFF header's vertex and face counts (",
                    num_vertices,
                    ", ",
                    num_faces,
                    ") are more than its ",
                    file_size,
                    " bytes can hold");
  }
}

// OpenMesh's OBJ reader asserts (and so aborts the program) on a face that
// names no vertex, such as "f /1 /2 /3", and takes indices beyond the
// vertices read so far on trust. Every corner must start with its vertex
// index, counted from 1 or (negative) back from the last vertex, and every
// face must have three corners; vertex colours must be fractions.
void CheckObjFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  long long num_vertices = 0;
  for (long long number = 1; std::getline(in, line); ++number) {
    std::istringstream tokens(line);
    std::string keyword;
    if (!(tokens >> keyword)) continue;
    if (keyword == "v") {
      ++num_vertices;
      // x y z r g b: OpenMesh scales the colour by 255 into a byte, which
      // for a value outside 0..1 (a file written with 0..255) is undefined.
      double values[6];
      int n = 0;
      while (n < 6 && tokens >> values[n]) ++n;
      for (int i = 3; n == 6 && i < 6; ++i) {
        if (!(values[i] >= 0 && values[i] <= 1)) {
          ThrowInputError(path,
                          ":",
                          number,
                          ": vertex colour ",
                          values[i],
                          " outside 0..1");
        }
      }
      continue;
    }
    if (keyword != "f") continue;
    int corners = 0;
    for (std::string corner; tokens >> corner; ++corners) {
      const std::string index = corner.substr(0, corner.find('/'));
      size_t used = 0;
      long long value = 0;
      try {
        value = std::stoll(index, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != index.size() || value == 0 ||
          std::llabs(value) > num_vertices) {
        ThrowInputError(path,
                        ":",
                        number,
                        ": face corner '",
                        corner,
                        "' does not name one of the ",
                        num_vertices,
                        " vertices before it");
      }
    }
    if (corners < 3) {
      ThrowInputError(path,
                      ":",
                      number,
                      ": a face with ",
                      corners,
                      " corners (at least 3)");
    }
  }
}

}  // namespace

bool IsMeshFormatSupported(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".ply" || ext == ".obj" || ext == ".off";
}

void WriteMesh(const TriangleMesh& mesh, const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (!IsMeshFormatSupported(path)) {
    ThrowInputError(
        path, ": unknown mesh format '", ext, "' (use .ply, .obj or .off)");
  }
  if (ext == ".ply") {
    WriteMeshPly(mesh, path);
    return;
  }
  double largest = 0;
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    largest = std::max(largest, p.cwiseAbs().maxCoeff());
  }
  if (largest * 6e-8 > 1e-4) {
    LOG(WARNING) << path << ": coordinates up to " << largest << " lose about "
                 << largest * 6e-8 << " in OpenMesh's single-precision " << ext
                 << " export; .ply keeps full precision";
  }
  OmMesh om;
  const bool normals = mesh.vertices.HasNormals();
  const bool colors = mesh.vertices.HasColors();
  if (normals) om.request_vertex_normals();
  if (colors) om.request_vertex_colors();
  std::vector<OmMesh::VertexHandle> handles;
  handles.reserve(mesh.NumVertices());
  for (size_t i = 0; i < mesh.NumVertices(); ++i) {
    const Eigen::Vector3d& p = mesh.vertices.positions[i];
    const OmMesh::VertexHandle v =
        om.add_vertex(OmMesh::Point(p.x(), p.y(), p.z()));
    if (normals) {
      const Eigen::Vector3f& n = mesh.vertices.normals[i];
      om.set_normal(v, OmMesh::Normal(n.x(), n.y(), n.z()));
    }
    if (colors) {
      const auto& c = mesh.vertices.colors[i];
      om.set_color(v, OmMesh::Color(c(0), c(1), c(2)));
    }
    handles.push_back(v);
  }
  // OpenMesh's writers take any face list through its own structure, which
  // refuses non-manifold faces: write those meshes as PLY.
  const bool was_enabled = omerr().is_enabled();
  omerr().disable();
  size_t refused = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    refused +=
        !om.add_face(handles[f(0)], handles[f(1)], handles[f(2)]).is_valid();
  }
  if (was_enabled) omerr().enable();
  if (refused > 0) {
    ThrowInputError(path,
                    ": ",
                    refused,
                    " faces are non-manifold and cannot be written as ",
                    ext,
                    "; write .ply or clean the mesh first");
  }
  OpenMesh::IO::Options io_options;
  if (normals) io_options += OpenMesh::IO::Options::VertexNormal;
  if (colors) io_options += OpenMesh::IO::Options::VertexColor;
  // Full precision for the coordinates.
  RemoveStaleTemporaries(path);
  const std::string temp = path + TempSuffix() + ext;
  TempFileGuard guard(temp);
  if (!OpenMesh::IO::write_mesh(om, temp, io_options, 17)) {
    throw RunFailure(StrCat(path, ": OpenMesh could not write the mesh"));
  }
  std::error_code error;
  fs::rename(temp, path, error);
  if (error) {
    throw RunFailure(
        StrCat(path, ": cannot rename ", temp, ": ", error.message()));
  }
  guard.Keep();
}

TriangleMesh ReadMesh(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (!IsMeshFormatSupported(path)) {
    ThrowInputError(
        path, ": unknown mesh format '", ext, "' (use .ply, .obj or .off)");
  }
  if (ext == ".ply") return ReadMeshPly(path);
  CheckFileExists(path, "mesh");
  if (ext == ".off") CheckOffHeader(path);
  if (ext == ".obj") CheckObjFile(path);
  OmMesh om;
  om.request_vertex_normals();
  om.request_vertex_colors();
  OpenMesh::IO::Options io_options;
  io_options += OpenMesh::IO::Options::VertexNormal;
  io_options += OpenMesh::IO::Options::VertexColor;
  if (!OpenMesh::IO::read_mesh(om, path, io_options)) {
    ThrowInputError(path, ": not a readable ", ext, " mesh");
  }
  TriangleMesh mesh;
  for (OmMesh::VertexHandle v : om.vertices()) {
    const OmMesh::Point& p = om.point(v);
    mesh.vertices.positions.emplace_back(p[0], p[1], p[2]);
    if (io_options.vertex_has_normal()) {
      const OmMesh::Normal& n = om.normal(v);
      mesh.vertices.normals.emplace_back(n[0], n[1], n[2]);
    }
    if (io_options.vertex_has_color()) {
      const OmMesh::Color& c = om.color(v);
      mesh.vertices.colors.emplace_back(c[0], c[1], c[2]);
    }
  }
  for (OmMesh::FaceHandle f : om.faces()) {
    auto it = om.cfv_iter(f);
    const int a = (*it++).idx(), b = (*it++).idx(), c = (*it).idx();
    mesh.faces.emplace_back(a, b, c);
  }
  if (mesh.faces.empty()) ThrowInputError(path, ": the mesh has no faces");
  mesh.Check(path);
  return mesh;
}

}  // namespace bayon
