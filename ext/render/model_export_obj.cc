// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/render/model_formats.h"

#include <cctype>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace bayon {
namespace internal {

std::string ObjText(const TriangleMesh& mesh,
                    const Wedges& wedges,
                    const std::string& mtl_name) {
  std::string out;
  out.reserve(64 * (mesh.NumVertices() + wedges.uv.size() + mesh.NumFaces()));
  out += "# written by bayon\n";
  out += "mtllib " + mtl_name + "\n";
  // 12 significant digits: sub-millimetre for coordinates up to 1e6 m.
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    Append(&out, "v %.12g %.12g %.12g\n", p.x(), p.y(), p.z());
  }
  // 9 digits: every float texture coordinate reads back exactly.
  for (const Eigen::Vector2f& uv : wedges.uv) {
    Append(&out, "vt %.9g %.9g\n", double(uv.x()), double(uv.y()));
  }
  out += "usemtl atlas\n";
  for (size_t f = 0; f < mesh.NumFaces(); ++f) {
    const Eigen::Vector3i& v = mesh.faces[f];
    const Eigen::Vector3i& t = wedges.faces[f];
    Append(&out,
           "f %d/%d %d/%d %d/%d\n",
           v[0] + 1,
           t[0] + 1,
           v[1] + 1,
           t[1] + 1,
           v[2] + 1,
           t[2] + 1);
  }
  return out;
}

std::string MtlText(const std::string& png_name) {
  // Unlit look in most viewers: full diffuse from the map, no specular.
  return "# written by bayon\nnewmtl atlas\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\n"
         "d 1\nillum 1\nmap_Kd " +
         png_name + "\n";
}

namespace {

std::string Trim(const std::string& text) {
  size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin])))
    ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1])))
    --end;
  return text.substr(begin, end - begin);
}

// The map_Kd of each material in an MTL file. Options before the file name
// (-s 1 1 1, -clamp on, ...) are skipped: the name is the last word.
std::map<std::string, std::string> ReadMtlMaps(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInputError(path, ": cannot open the material library");
  std::map<std::string, std::string> maps;
  std::string line, material;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "newmtl") {
      material = Trim(line.substr(line.find("newmtl") + 6));
    } else if (keyword == "map_Kd") {
      std::string rest = Trim(line.substr(line.find("map_Kd") + 6));
      if (!rest.empty() && rest[0] == '-') {
        rest = rest.substr(rest.find_last_of(" \t") + 1);
      }
      if (!rest.empty()) maps[material] = rest;
    }
  }
  return maps;
}

// One OBJ vertex reference "v", "v/vt", "v//vn" or "v/vt/vn"; negative
// indices count back from the last one read. Returns 0-based indices, -1
// for an absent texture coordinate.
void ParseObjCorner(const std::string& token,
                    size_t num_positions,
                    size_t num_texcoords,
                    const std::string& where,
                    int* position,
                    int* texcoord) {
  auto resolve = [&](const std::string& text, size_t count) {
    char* end = nullptr;
    const long value = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || value == 0) {
      ThrowInputError(where, ": bad face corner '", token, "'");
    }
    const long index = value > 0 ? value - 1 : long(count) + value;
    if (index < 0 || index >= long(count)) {
      ThrowInputError(where,
                      ": face corner '",
                      token,
                      "' refers to a missing record (",
                      count,
                      " read so far)");
    }
    return static_cast<int>(index);
  };
  const size_t slash = token.find('/');
  *position = resolve(token.substr(0, slash), num_positions);
  *texcoord = -1;
  if (slash == std::string::npos) return;
  const size_t slash2 = token.find('/', slash + 1);
  const std::string vt = token.substr(slash + 1, slash2 - slash - 1);
  if (!vt.empty()) *texcoord = resolve(vt, num_texcoords);
}

}  // namespace

TexturedModel ReadObj(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInputError(path, ": cannot open the OBJ file");
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  std::vector<Eigen::Vector2f> texcoords;
  std::vector<Eigen::Vector3i> face_texcoord_indices;
  std::vector<std::string> libraries;
  std::set<std::string> used_materials;
  std::string material;
  bool all_colored = true;
  size_t faces_with_uv = 0, faces_without_uv = 0;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string where = StrCat(path, ":", line_number);
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword[0] == '#') continue;
    if (keyword == "v") {
      std::vector<double> values;
      double value;
      while (words >> value) values.push_back(value);
      if (values.size() != 3 && values.size() != 4 && values.size() != 6 &&
          values.size() != 7) {
        ThrowInputError(where, ": a vertex needs x y z (got '", line, "')");
      }
      mesh.vertices.positions.emplace_back(values[0], values[1], values[2]);
      if (values.size() >= 6) {
        // "v x y z r g b" (colours in [0, 1]), a common extension.
        Eigen::Matrix<uint8_t, 3, 1> color;
        for (int c = 0; c < 3; ++c) {
          color[c] = static_cast<uint8_t>(std::lround(
              255 * std::clamp(values[values.size() - 3 + c], 0.0, 1.0)));
        }
        mesh.vertices.colors.push_back(color);
      } else {
        all_colored = false;
      }
    } else if (keyword == "vt") {
      float u, v;
      if (!(words >> u >> v)) {
        ThrowInputError(where, ": a texture coordinate needs u v");
      }
      texcoords.emplace_back(u, v);
    } else if (keyword == "f") {
      std::vector<int> positions, uvs;
      std::string token;
      while (words >> token) {
        int position, texcoord;
        ParseObjCorner(token,
                       mesh.vertices.positions.size(),
                       texcoords.size(),
                       where,
                       &position,
                       &texcoord);
        positions.push_back(position);
        uvs.push_back(texcoord);
      }
      if (positions.size() < 3) {
        ThrowInputError(where, ": a face needs at least three corners");
      }
      const long num_missing = std::count(uvs.begin(), uvs.end(), -1);
      const bool has_uv = num_missing == 0;
      if (num_missing > 0 && num_missing < long(uvs.size())) {
        ThrowInputError(where,
                        ": some corners have texture coordinates, others "
                        "not");
      }
      // Polygons as fans around their first corner.
      for (size_t k = 1; k + 1 < positions.size(); ++k) {
        mesh.faces.emplace_back(positions[0], positions[k], positions[k + 1]);
        if (has_uv) {
          face_texcoord_indices.emplace_back(uvs[0], uvs[k], uvs[k + 1]);
          ++faces_with_uv;
        } else {
          ++faces_without_uv;
        }
      }
      used_materials.insert(material);
    } else if (keyword == "mtllib") {
      const std::string name = Trim(line.substr(line.find("mtllib") + 6));
      if (!name.empty()) libraries.push_back(ResolveBeside(path, name));
    } else if (keyword == "usemtl") {
      material = Trim(line.substr(line.find("usemtl") + 6));
    }
  }
  if (mesh.faces.empty()) ThrowInputError(path, ": OBJ file has no faces");
  if (!all_colored) mesh.vertices.colors.clear();
  if (faces_with_uv > 0 && faces_without_uv > 0) {
    ThrowInputError(path,
                    ": ",
                    faces_without_uv,
                    " of ",
                    mesh.NumFaces(),
                    " faces have no texture coordinates");
  }
  if (faces_with_uv > 0) {
    mesh.face_texcoords.resize(mesh.NumFaces());
    for (size_t f = 0; f < mesh.NumFaces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        mesh.face_texcoords[f][k] = texcoords[face_texcoord_indices[f][k]];
      }
    }
    std::map<std::string, std::string> maps;
    for (const std::string& library : libraries) {
      for (const auto& [name, file] : ReadMtlMaps(library)) {
        maps.emplace(name, ResolveBeside(library, file));
      }
    }
    std::set<std::string> images;
    for (const std::string& name : used_materials) {
      const auto it = maps.find(name);
      if (it != maps.end()) images.insert(it->second);
    }
    if (images.empty()) {
      ThrowInputError(path,
                      ": has texture coordinates but no material with a "
                      "map_Kd texture image");
    }
    if (images.size() > 1) {
      ThrowInputError(path,
                      ": its materials use ",
                      images.size(),
                      " texture images; one atlas is supported");
    }
    model.atlas = ReadAtlasFile(path, *images.begin());
  }
  mesh.Check(path);
  return model;
}

}  // namespace internal
}  // namespace bayon
