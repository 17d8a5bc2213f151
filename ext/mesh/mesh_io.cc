// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/mesh_io.h"

#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/mesh/openmesh_types.h"

#include <glog/logging.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
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

// A whole token as a number: false for "1x", "", "nan", "inf".
bool ParseFinite(const std::string& token, double* value) {
  char* end = nullptr;
  *value = std::strtod(token.c_str(), &end);
  return !token.empty() && *end == '\0' && std::isfinite(*value);
}

bool ParseCount(const std::string& token, long long* value) {
  if (token.empty() || token.size() > 15 ||
      token.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  *value = std::stoll(token);
  return true;
}

// ASCII OFF, read by bayon rather than OpenMesh, whose reader trusts the
// file: fuzzing made it reserve gigabytes for a forged header's counts, read
// the first vertex as the counts when they stood on the keyword's line, and
// push corners for a face of 10^30 corners until memory ran out. The keyword
// [ST][C][N]OFF says what a vertex line holds after x y z: a normal (N), a
// colour (C: 3 or 4 numbers, in 0..1 or 0..255), texture coordinates (ST,
// skipped). A face line is "n i1 .. in" and an optional colour (skipped);
// polygons are cut into fans. 4OFF, nOFF and binary OFF are refused.
TriangleMesh ReadMeshOff(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInputError(path, ": cannot open the mesh");
  long long number = 0;
  std::vector<std::string> tokens;
  // The next line with content, comments removed, split into tokens.
  auto next_record = [&]() {
    tokens.clear();
    for (std::string line; std::getline(in, line);) {
      ++number;
      std::istringstream fields(line.substr(0, line.find('#')));
      for (std::string token; fields >> token;) tokens.push_back(token);
      if (!tokens.empty()) return true;
    }
    return false;
  };
  if (!next_record()) ThrowInputError(path, ": empty, no OFF header");
  const std::string keyword = tokens[0];
  const size_t off = keyword.size() >= 3 ? keyword.size() - 3 : 0;
  if (keyword.compare(off, std::string::npos, "OFF") != 0) {
    ThrowInputError(path, ": not an OFF mesh (no OFF header)");
  }
  std::string prefix = keyword.substr(0, off);
  const bool has_texture = prefix.rfind("ST", 0) == 0;
  if (has_texture) prefix.erase(0, 2);
  const bool has_color = !prefix.empty() && prefix[0] == 'C';
  if (has_color) prefix.erase(0, 1);
  const bool has_normal = !prefix.empty() && prefix[0] == 'N';
  if (has_normal) prefix.erase(0, 1);
  if (!prefix.empty()) {
    ThrowInputError(
        path, ": ", keyword, " is not supported (ASCII [ST][C][N]OFF in 3D)");
  }
  if (tokens.size() > 1 && tokens[1] == "BINARY") {
    ThrowInputError(path,
                    ": binary OFF is not supported (use ASCII OFF or PLY)");
  }
  // The counts: on the keyword's line or the next.
  size_t first = 1;
  if (tokens.size() == 1) {
    if (!next_record()) {
      ThrowInputError(path, ": no vertex and face counts after ", keyword);
    }
    first = 0;
  }
  long long num_vertices = 0;
  long long num_faces = 0;
  long long num_edges = 0;
  const size_t num_counts = tokens.size() - first;
  if (num_counts < 2 || num_counts > 3 ||
      !ParseCount(tokens[first], &num_vertices) ||
      !ParseCount(tokens[first + 1], &num_faces) ||
      (num_counts == 3 && !ParseCount(tokens[first + 2], &num_edges))) {
    ThrowInputError(
        path, ":", number, ": the counts must be two or three whole numbers");
  }
  // Every vertex has three numbers and every face at least four, each
  // followed by a separator: counts beyond that are forged or damaged.
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
  TriangleMesh mesh;
  PointCloud& vertices = mesh.vertices;
  const size_t fixed = 3 + (has_normal ? 3 : 0) + (has_texture ? 2 : 0);
  for (long long v = 0; v < num_vertices; ++v) {
    if (!next_record()) {
      ThrowInputError(
          path, ": the file ends after ", v, " of ", num_vertices, " vertices");
    }
    const size_t color_size = tokens.size() - std::min(tokens.size(), fixed);
    if (tokens.size() < fixed ||
        (has_color ? color_size != 3 && color_size != 4 : color_size != 0)) {
      ThrowInputError(path,
                      ":",
                      number,
                      ": ",
                      tokens.size(),
                      " numbers for a vertex of ",
                      keyword);
    }
    std::vector<double> values(tokens.size());
    for (size_t k = 0; k < tokens.size(); ++k) {
      if (!ParseFinite(tokens[k], &values[k])) {
        ThrowInputError(
            path, ":", number, ": '", tokens[k], "' is not a number");
      }
    }
    vertices.positions.emplace_back(values[0], values[1], values[2]);
    if (has_normal) {
      vertices.normals.emplace_back(values[3], values[4], values[5]);
    }
    if (has_color) {
      const size_t at = 3 + (has_normal ? 3 : 0);
      const double* rgb = &values[at];
      // Geomview's rule: integers are bytes, reals are fractions.
      bool fractions = false;
      for (size_t k = at; k < at + 3; ++k) {
        fractions |= tokens[k].find_first_of(".eE") != std::string::npos;
      }
      Eigen::Matrix<uint8_t, 3, 1> color;
      for (int k = 0; k < 3; ++k) {
        const double level = fractions ? rgb[k] * 255 : rgb[k];
        if (!(level >= 0 && level <= 255)) {
          ThrowInputError(path,
                          ":",
                          number,
                          ": colour ",
                          rgb[k],
                          " outside 0..1 and 0..255");
        }
        color[k] = static_cast<uint8_t>(std::lround(level));
      }
      vertices.colors.push_back(color);
    }
  }
  for (long long f = 0; f < num_faces; ++f) {
    if (!next_record()) {
      ThrowInputError(
          path, ": the file ends after ", f, " of ", num_faces, " faces");
    }
    long long corners = 0;
    if (!ParseCount(tokens[0], &corners) || corners < 3 ||
        static_cast<size_t>(corners) >= tokens.size() ||
        tokens.size() - 1 - corners > 4) {
      ThrowInputError(path,
                      ":",
                      number,
                      ": a face is its corner count (3 or more), the "
                      "corners and at most a colour");
    }
    std::vector<int> face(corners);
    for (long long k = 0; k < corners; ++k) {
      long long index = 0;
      if (!ParseCount(tokens[k + 1], &index) || index >= num_vertices) {
        ThrowInputError(path,
                        ":",
                        number,
                        ": corner '",
                        tokens[k + 1],
                        "' is not one of the ",
                        num_vertices,
                        " vertices");
      }
      face[k] = static_cast<int>(index);
    }
    for (long long k = 1; k + 1 < corners; ++k) {
      mesh.faces.emplace_back(face[0], face[k], face[k + 1]);
    }
  }
  if (mesh.faces.empty()) ThrowInputError(path, ": the mesh has no faces");
  mesh.Check(path);
  return mesh;
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
    // "v x y z r g b", or OpenMesh's own "vc r g b": OpenMesh scales a
    // colour by 255 into a byte, which for a value outside 0..1 (a file
    // written with 0..255) is undefined.
    if (keyword == "v" || keyword == "vc") {
      const int first_colour = keyword == "v" ? 3 : 0;
      if (keyword == "v") ++num_vertices;
      double values[6];
      int n = 0;
      while (n < first_colour + 3 && tokens >> values[n]) ++n;
      for (int i = first_colour; n == first_colour + 3 && i < n; ++i) {
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
  if (ext == ".off") return ReadMeshOff(path);
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
