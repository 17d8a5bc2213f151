// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/render/model_formats.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>

namespace bayon {
namespace internal {

std::string VrmlText(const TriangleMesh& mesh,
                     const Wedges& wedges,
                     const std::string& png_name) {
  std::string out;
  out.reserve(48 * (mesh.NumVertices() + wedges.uv.size()) +
              64 * mesh.NumFaces());
  out += "#VRML V2.0 utf8\n# written by bayon\n";
  // No Material node: VRML then draws the texture unlit, the photographs'
  // own light, as the paper's models were shown.
  out +=
      "Shape {\n  appearance Appearance {\n    texture ImageTexture { url \"";
  out += png_name;
  out += "\" repeatS FALSE repeatT FALSE }\n  }\n";
  out += "  geometry IndexedFaceSet {\n    solid FALSE\n    ccw TRUE\n";
  out += "    coord Coordinate {\n      point [\n";
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    Append(&out, "        %.12g %.12g %.12g,\n", p.x(), p.y(), p.z());
  }
  out += "      ]\n    }\n    texCoord TextureCoordinate {\n      point [\n";
  for (const Eigen::Vector2f& uv : wedges.uv) {
    Append(&out, "        %.9g %.9g,\n", double(uv.x()), double(uv.y()));
  }
  out += "      ]\n    }\n    coordIndex [\n";
  for (const Eigen::Vector3i& v : mesh.faces) {
    Append(&out, "      %d, %d, %d, -1,\n", v[0], v[1], v[2]);
  }
  out += "    ]\n    texCoordIndex [\n";
  for (const Eigen::Vector3i& t : wedges.faces) {
    Append(&out, "      %d, %d, %d, -1,\n", t[0], t[1], t[2]);
  }
  out += "    ]\n  }\n}\n";
  return out;
}

// VRML 2.0 as WriteTexturedModel writes it: one IndexedFaceSet with
// Coordinate, TextureCoordinate, coordIndex, texCoordIndex and an
// ImageTexture. A tokenizer, not a full VRML parser: DEF/USE, PROTOs,
// transforms and several shapes are not understood.
TexturedModel ReadVrml(const std::string& path) {
  const std::string text = ReadFileToString(path);
  if (text.rfind("#VRML V2.0", 0) != 0) {
    ThrowInputError(path, ": not a VRML 2.0 file (no '#VRML V2.0' header)");
  }
  std::vector<std::string> tokens;
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (std::isspace(static_cast<unsigned char>(c)) || c == ',') {
      ++i;
    } else if (c == '"') {
      const size_t end = text.find('"', i + 1);
      if (end == std::string::npos) {
        ThrowInputError(path, ": unterminated string");
      }
      tokens.push_back(text.substr(i, end - i + 1));
      i = end + 1;
    } else if (c == '[' || c == ']' || c == '{' || c == '}') {
      tokens.emplace_back(1, c);
      ++i;
    } else {
      size_t end = i;
      while (end < text.size() &&
             !std::isspace(static_cast<unsigned char>(text[end])) &&
             // memchr, not strchr: strchr finds a NUL byte (the string's
             // end), and a token that ends before it starts never advances.
             std::memchr(",[]{}#\"", text[end], 7) == nullptr) {
        ++end;
      }
      tokens.push_back(text.substr(i, end - i));
      i = end;
    }
  }
  // The numbers in the bracketed list after `field` inside `node`.
  auto numbers_after = [&](const std::string& node, const std::string& field) {
    std::vector<double> values;
    size_t i = 0;
    if (!node.empty()) {
      while (i < tokens.size() && tokens[i] != node) ++i;
    }
    while (i < tokens.size() && tokens[i] != field) ++i;
    if (i + 1 >= tokens.size() || tokens[i + 1] != "[") {
      ThrowInputError(path, ": no '", field, " [ ... ]' list found");
    }
    for (i += 2; i < tokens.size() && tokens[i] != "]"; ++i) {
      char* end = nullptr;
      const double value = std::strtod(tokens[i].c_str(), &end);
      if (*end != '\0' || !std::isfinite(value)) {
        ThrowInputError(
            path, ": '", tokens[i], "' in ", field, " is no number");
      }
      values.push_back(value);
    }
    if (i >= tokens.size())
      ThrowInputError(path, ": ", field, " list not closed");
    return values;
  };
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  const std::vector<double> points = numbers_after("Coordinate", "point");
  if (points.size() % 3 != 0) {
    ThrowInputError(path, ": Coordinate point count is not a multiple of 3");
  }
  for (size_t i = 0; i < points.size(); i += 3) {
    mesh.vertices.positions.emplace_back(
        points[i], points[i + 1], points[i + 2]);
  }
  // Polygons end with -1 (the last one may omit it).
  auto polygons = [&](const std::vector<double>& indices, size_t count) {
    std::vector<std::vector<int>> result(1);
    for (double value : indices) {
      if (value == -1) {
        result.emplace_back();
        continue;
      }
      // Checked as a double: converting one beyond int's range first is
      // undefined (found by fuzzing).
      if (!(value >= 0 && value < static_cast<double>(count)) ||
          value != std::floor(value)) {
        ThrowInputError(
            path, ": index ", value, " out of range (", count, " records)");
      }
      result.back().push_back(static_cast<int>(value));
    }
    if (result.back().empty()) result.pop_back();
    return result;
  };
  const auto coord_polygons =
      polygons(numbers_after("", "coordIndex"), mesh.NumVertices());
  const bool textured =
      std::find(tokens.begin(), tokens.end(), "texCoordIndex") != tokens.end();
  std::vector<std::vector<int>> uv_polygons;
  std::vector<Eigen::Vector2f> uvs;
  if (textured) {
    const std::vector<double> uv_values =
        numbers_after("TextureCoordinate", "point");
    if (uv_values.size() % 2 != 0) {
      ThrowInputError(path, ": TextureCoordinate count is not even");
    }
    for (size_t i = 0; i < uv_values.size(); i += 2) {
      uvs.emplace_back(float(uv_values[i]), float(uv_values[i + 1]));
    }
    uv_polygons = polygons(numbers_after("", "texCoordIndex"), uvs.size());
    if (uv_polygons.size() != coord_polygons.size()) {
      ThrowInputError(path, ": coordIndex and texCoordIndex differ in length");
    }
  }
  for (size_t p = 0; p < coord_polygons.size(); ++p) {
    const std::vector<int>& polygon = coord_polygons[p];
    if (polygon.size() < 3)
      ThrowInputError(path, ": polygon ", p, " too small");
    if (textured && uv_polygons[p].size() != polygon.size()) {
      ThrowInputError(path, ": polygon ", p, ": texCoordIndex differs");
    }
    for (size_t k = 1; k + 1 < polygon.size(); ++k) {
      mesh.faces.emplace_back(polygon[0], polygon[k], polygon[k + 1]);
      if (textured) {
        const std::vector<int>& t = uv_polygons[p];
        mesh.face_texcoords.push_back({uvs[t[0]], uvs[t[k]], uvs[t[k + 1]]});
      }
    }
  }
  if (mesh.faces.empty()) ThrowInputError(path, ": VRML file has no faces");
  if (textured) {
    const auto url = std::find(tokens.begin(), tokens.end(), "url");
    if (url == tokens.end() || url + 1 == tokens.end()) {
      ThrowInputError(path,
                      ": has texture coordinates but no ImageTexture url");
    }
    std::string name = *(url + 1);
    if (name == "[" && url + 2 != tokens.end()) name = *(url + 2);
    if (name.size() < 2 || name.front() != '"') {
      ThrowInputError(path, ": ImageTexture url is not a string");
    }
    name = name.substr(1, name.size() - 2);
    model.atlas = ReadAtlasFile(path, ResolveBeside(path, name));
  }
  mesh.Check(path);
  return model;
}

}  // namespace internal
}  // namespace bayon
