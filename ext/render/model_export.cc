// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/model_export.h"

#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// ---------------------------------------------------------------------------
// Wedges: a vertex together with one texture coordinate. Formats with a
// single index per corner (glTF) need one vertex per wedge; OBJ and VRML
// index positions and texture coordinates separately and list each wedge's
// texture coordinate once.

struct Wedges {
  std::vector<int> vertex;             // per wedge: the mesh vertex
  std::vector<Eigen::Vector2f> uv;     // per wedge
  std::vector<Eigen::Vector3i> faces;  // per face: wedge indices
};

Wedges SplitWedges(const TriangleMesh& mesh) {
  Wedges wedges;
  // The wedges of each vertex so far; a vertex rarely has more than a few.
  std::vector<std::vector<int>> of_vertex(mesh.NumVertices());
  wedges.faces.resize(mesh.NumFaces());
  for (size_t f = 0; f < mesh.NumFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      const Eigen::Vector2f& uv = mesh.face_texcoords[f][k];
      int found = -1;
      for (int w : of_vertex[v]) {
        if (wedges.uv[w] == uv) {
          found = w;
          break;
        }
      }
      if (found < 0) {
        found = static_cast<int>(wedges.vertex.size());
        wedges.vertex.push_back(v);
        wedges.uv.push_back(uv);
        of_vertex[v].push_back(found);
      }
      wedges.faces[f][k] = found;
    }
  }
  return wedges;
}

// Appends printf-formatted text (numbers in the C locale's format).
template <typename... Args>
void Append(std::string* out, const char* format, Args... args) {
  char buffer[160];
  const int n = std::snprintf(buffer, sizeof(buffer), format, args...);
  out->append(buffer, static_cast<size_t>(std::max(0, n)));
}

void CheckModel(const TexturedModel& model) {
  model.mesh.Check("textured model");
  if (model.mesh.faces.empty()) {
    ThrowInputError("textured model: the mesh has no faces");
  }
  if (!model.mesh.HasTexcoords()) {
    ThrowInputError("textured model: the mesh has no texture coordinates");
  }
  if (model.atlas.empty()) {
    ThrowInputError("textured model: the texture atlas is empty");
  }
  if (model.atlas.depth() != CV_8U ||
      (model.atlas.channels() != 3 && model.atlas.channels() != 1)) {
    ThrowInputError("textured model: the atlas must be 8-bit grey or BGR");
  }
}

// ---------------------------------------------------------------------------
// Writers.

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

void AppendBytes(std::string* bin, const void* data, size_t size) {
  bin->append(static_cast<const char*>(data), size);
}

void PadTo4(std::string* text, char pad) {
  while (text->size() % 4 != 0) text->push_back(pad);
}

std::string GlbBytes(const TriangleMesh& mesh,
                     const Wedges& wedges,
                     const std::string& png,
                     bool y_up,
                     const std::string& georeference_json) {
  // The binary chunk: positions, texture coordinates, indices, the PNG;
  // each view starts on a 4-byte boundary.
  std::string bin;
  const size_t num_wedges = wedges.vertex.size();
  // Positions are single precision: relative to the model's centre, which
  // goes into the node's translation, they keep a tenth of a millimetre on
  // a 1 km object wherever its datum lies (UTM, ECEF).
  Eigen::AlignedBox3d box;
  for (size_t w = 0; w < num_wedges; ++w) {
    box.extend(mesh.vertices.positions[wedges.vertex[w]]);
  }
  const Eigen::Vector3d center =
      num_wedges > 0 ? Eigen::Vector3d(box.center()) : Eigen::Vector3d::Zero();
  Eigen::Vector3f min_position = Eigen::Vector3f::Constant(HUGE_VALF);
  Eigen::Vector3f max_position = -min_position;
  for (size_t w = 0; w < num_wedges; ++w) {
    const Eigen::Vector3f p =
        (mesh.vertices.positions[wedges.vertex[w]] - center).cast<float>();
    min_position = min_position.cwiseMin(p);
    max_position = max_position.cwiseMax(p);
    AppendBytes(&bin, p.data(), 3 * sizeof(float));
  }
  const size_t texcoord_offset = bin.size();
  for (size_t w = 0; w < num_wedges; ++w) {
    // glTF counts v from the top of the image.
    const float uv[2] = {wedges.uv[w].x(), 1.0f - wedges.uv[w].y()};
    AppendBytes(&bin, uv, sizeof(uv));
  }
  const size_t index_offset = bin.size();
  for (const Eigen::Vector3i& face : wedges.faces) {
    const uint32_t indices[3] = {
        uint32_t(face[0]), uint32_t(face[1]), uint32_t(face[2])};
    AppendBytes(&bin, indices, sizeof(indices));
  }
  const size_t image_offset = bin.size();
  bin += png;
  const size_t image_length = png.size();
  PadTo4(&bin, '\0');

  using nlohmann::ordered_json;
  ordered_json json;
  json["asset"] = {{"version", "2.0"}, {"generator", "bayon"}};
  if (!georeference_json.empty()) {
    json["asset"]["extras"]["georeference"] =
        ordered_json::parse(georeference_json);
  }
  json["scene"] = 0;
  json["scenes"] = ordered_json::array({{{"nodes", {0}}}});
  ordered_json node = {{"name", "model"}, {"mesh", 0}};
  if (y_up) {
    // bayon's datum has z up, glTF y up: a -90 degree turn about x maps
    // (x, y, z) to (x, z, -y). The positions themselves stay in the datum.
    const double s = std::sqrt(0.5);
    node["rotation"] = {-s, 0.0, 0.0, s};
    node["translation"] = {center.x(), center.z(), -center.y()};
  } else {
    node["translation"] = {center.x(), center.y(), center.z()};
  }
  json["nodes"] = ordered_json::array({node});
  json["meshes"] = ordered_json::array(
      {{{"name", "model"},
        {"primitives",
         ordered_json::array(
             {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}},
               {"indices", 2},
               {"material", 0},
               {"mode", 4}}})}}});
  json["materials"] =
      ordered_json::array({{{"name", "atlas"},
                            {"pbrMetallicRoughness",
                             {{"baseColorTexture", {{"index", 0}}},
                              {"metallicFactor", 0.0},
                              {"roughnessFactor", 1.0}}},
                            {"doubleSided", true}}});
  // Linear filtering, mipmaps when minifying, clamped at the atlas edges.
  json["samplers"] = ordered_json::array({{{"magFilter", 9729},
                                           {"minFilter", 9987},
                                           {"wrapS", 33071},
                                           {"wrapT", 33071}}});
  json["textures"] = ordered_json::array({{{"sampler", 0}, {"source", 0}}});
  json["images"] =
      ordered_json::array({{{"bufferView", 3}, {"mimeType", "image/png"}}});
  json["accessors"] = ordered_json::array(
      {{{"bufferView", 0},
        {"componentType", 5126},
        {"count", num_wedges},
        {"type", "VEC3"},
        {"min", {min_position.x(), min_position.y(), min_position.z()}},
        {"max", {max_position.x(), max_position.y(), max_position.z()}}},
       {{"bufferView", 1},
        {"componentType", 5126},
        {"count", num_wedges},
        {"type", "VEC2"}},
       {{"bufferView", 2},
        {"componentType", 5125},
        {"count", 3 * wedges.faces.size()},
        {"type", "SCALAR"}}});
  json["bufferViews"] =
      ordered_json::array({{{"buffer", 0},
                            {"byteOffset", 0},
                            {"byteLength", texcoord_offset},
                            {"target", 34962}},
                           {{"buffer", 0},
                            {"byteOffset", texcoord_offset},
                            {"byteLength", index_offset - texcoord_offset},
                            {"target", 34962}},
                           {{"buffer", 0},
                            {"byteOffset", index_offset},
                            {"byteLength", image_offset - index_offset},
                            {"target", 34963}},
                           {{"buffer", 0},
                            {"byteOffset", image_offset},
                            {"byteLength", image_length}}});
  json["buffers"] = ordered_json::array({{{"byteLength", bin.size()}}});

  std::string json_text = json.dump();
  PadTo4(&json_text, ' ');
  const uint32_t total = uint32_t(12 + 8 + json_text.size() + 8 + bin.size());
  std::string glb;
  glb.reserve(total);
  const uint32_t header[3] = {0x46546C67u /* "glTF" */, 2u, total};
  AppendBytes(&glb, header, sizeof(header));
  const uint32_t json_chunk[2] = {uint32_t(json_text.size()),
                                  0x4E4F534Au /* "JSON" */};
  AppendBytes(&glb, json_chunk, sizeof(json_chunk));
  glb += json_text;
  const uint32_t bin_chunk[2] = {uint32_t(bin.size()),
                                 0x004E4942u /* "BIN\0" */};
  AppendBytes(&glb, bin_chunk, sizeof(bin_chunk));
  glb += bin;
  return glb;
}

// ---------------------------------------------------------------------------
// Readers.

// An atlas as TexturedModel holds it: 8-bit BGR.
cv::Mat ToAtlas(cv::Mat image) {
  if (image.depth() == CV_16U) image.convertTo(image, CV_8U, 1.0 / 257.0);
  if (image.depth() != CV_8U) image.convertTo(image, CV_8U, 255.0);
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  return image;
}

// The atlas file a model names; errors name the model too.
cv::Mat ReadAtlasFile(const std::string& model_path,
                      const std::string& image_path) {
  try {
    return ToAtlas(ReadImage(image_path, ImageReadMode::kColor));
  } catch (const InputError& error) {
    ThrowInputError(model_path, ": its texture image: ", error.what());
  }
}

// Per-vertex texture coordinates -> per-corner (TriangleMesh's layout).
void SetCornerTexcoords(const std::vector<Eigen::Vector2f>& vertex_uv,
                        TriangleMesh* mesh) {
  mesh->face_texcoords.resize(mesh->NumFaces());
  for (size_t f = 0; f < mesh->NumFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      mesh->face_texcoords[f][k] = vertex_uv[mesh->faces[f][k]];
    }
  }
}

std::string Trim(const std::string& text) {
  size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin])))
    ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1])))
    --end;
  return text.substr(begin, end - begin);
}

std::string ResolveBeside(const std::string& file, const std::string& name) {
  const fs::path path(name);
  return path.is_absolute() ? name
                            : (fs::path(file).parent_path() / path).string();
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

TexturedModel ReadTexturedPly(const std::string& path) {
  TexturedModel model;
  model.mesh = ReadMeshPly(path);
  if (model.mesh.HasTexcoords()) {
    const std::string texture = PlyTextureFile(path);
    if (texture.empty()) {
      ThrowInputError(path,
                      ": has texture coordinates but no 'comment TextureFile' "
                      "header line naming the atlas");
    }
    model.atlas = ReadAtlasFile(path, texture);
  }
  return model;
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

// A glTF binary: header, JSON chunk, BIN chunk (glTF 2.0, section 4.4).
struct Glb {
  nlohmann::json json;
  std::string bin;
};

uint32_t ReadU32(const std::string& bytes, size_t offset) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + offset, sizeof(value));
  return value;
}

Glb ParseGlb(const std::string& path) {
  const std::string bytes = ReadFileToString(path);
  if (bytes.size() < 20 || ReadU32(bytes, 0) != 0x46546C67u) {
    ThrowInputError(path, ": not a glTF binary (no 'glTF' magic)");
  }
  if (ReadU32(bytes, 4) != 2) {
    ThrowInputError(
        path, ": glTF version ", ReadU32(bytes, 4), " (expected 2)");
  }
  if (ReadU32(bytes, 8) != bytes.size()) {
    ThrowInputError(path,
                    ": header says ",
                    ReadU32(bytes, 8),
                    " bytes, the file has ",
                    bytes.size(),
                    " (truncated?)");
  }
  Glb glb;
  bool has_json = false;
  for (size_t offset = 12; offset < bytes.size();) {
    if (offset + 8 > bytes.size()) {
      ThrowInputError(path, ": truncated chunk header at byte ", offset);
    }
    const uint32_t length = ReadU32(bytes, offset);
    const uint32_t type = ReadU32(bytes, offset + 4);
    if (length > bytes.size() - offset - 8) {
      ThrowInputError(path,
                      ": chunk at byte ",
                      offset,
                      " claims ",
                      length,
                      " bytes, only ",
                      bytes.size() - offset - 8,
                      " left");
    }
    const std::string data = bytes.substr(offset + 8, length);
    if (type == 0x4E4F534Au && !has_json) {
      try {
        glb.json = nlohmann::json::parse(data);
      } catch (const nlohmann::json::exception& error) {
        ThrowInputError(path, ": JSON chunk: ", error.what());
      }
      has_json = true;
    } else if (type == 0x004E4942u && glb.bin.empty()) {
      glb.bin = data;
    }
    offset += 8 + ((length + 3) & ~3u);
  }
  if (!has_json) ThrowInputError(path, ": no JSON chunk");
  return glb;
}

// Reads glTF accessors out of the GLB's binary chunk, checking every
// offset against the bytes there.
class GlbAccessors {
 public:
  GlbAccessors(const Glb& glb, std::string path)
      : glb_(glb), path_(std::move(path)) {}

  // The bytes of buffer view `index`.
  std::string View(int index) const {
    const nlohmann::json& view = Item("bufferViews", index);
    if (view.value("buffer", 0) != 0 ||
        glb_.json.at("buffers").at(0).contains("uri")) {
      Fail("bufferViews[", index, "] is not in the GLB's binary chunk");
    }
    const size_t offset = view.value("byteOffset", size_t(0));
    const size_t length = view.at("byteLength").get<size_t>();
    if (offset > glb_.bin.size() || length > glb_.bin.size() - offset) {
      Fail("bufferViews[",
           index,
           "] lies outside the binary chunk (",
           offset,
           " + ",
           length,
           " > ",
           glb_.bin.size(),
           ")");
    }
    return glb_.bin.substr(offset, length);
  }

  // Accessor `index` as doubles, `components` per element.
  std::vector<double> Read(int index, int components) const {
    const nlohmann::json& accessor = Item("accessors", index);
    if (accessor.contains("sparse")) Fail("sparse accessors[", index, "]");
    static const std::map<std::string, int> kComponents = {
        {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}};
    const auto type = kComponents.find(accessor.at("type").get<std::string>());
    if (type == kComponents.end() || type->second != components) {
      Fail("accessors[",
           index,
           "] has type ",
           accessor.at("type"),
           ", expected ",
           components,
           " components");
    }
    const int component_type = accessor.at("componentType").get<int>();
    size_t size = 0;
    switch (component_type) {
      case 5121:
        size = 1;
        break;  // UNSIGNED_BYTE
      case 5123:
        size = 2;
        break;  // UNSIGNED_SHORT
      case 5125:
        size = 4;
        break;  // UNSIGNED_INT
      case 5126:
        size = 4;
        break;  // FLOAT
      default:
        Fail("accessors[",
             index,
             "] component type ",
             component_type,
             " not supported");
    }
    const size_t count = accessor.at("count").get<size_t>();
    const int view_index = accessor.at("bufferView").get<int>();
    const std::string view = View(view_index);
    const size_t element_size = size * components;
    const int64_t given_stride =
        Item("bufferViews", view_index)
            .value("byteStride", int64_t(element_size));
    // glTF: a stride is a multiple of 4 in [4, 252] and holds one element.
    if (given_stride != int64_t(element_size) &&
        (given_stride < int64_t(element_size) || given_stride > 252 ||
         given_stride % 4 != 0)) {
      Fail("bufferViews[",
           view_index,
           "]: byteStride ",
           given_stride,
           " is not valid for ",
           element_size,
           "-byte elements");
    }
    const size_t stride = static_cast<size_t>(given_stride);
    const size_t offset = accessor.value("byteOffset", size_t(0));
    // Divided, not multiplied, so that no count can wrap around.
    if (count > 0 &&
        (offset > view.size() || element_size > view.size() - offset ||
         count - 1 > (view.size() - offset - element_size) / stride)) {
      Fail("accessors[",
           index,
           "]: ",
           count,
           " elements do not fit in ",
           "bufferViews[",
           view_index,
           "] (",
           view.size(),
           " bytes)");
    }
    const bool normalized = accessor.value("normalized", false);
    std::vector<double> values(count * components);
    for (size_t i = 0; i < count; ++i) {
      const char* element = view.data() + offset + i * stride;
      for (int c = 0; c < components; ++c) {
        const char* at = element + c * size;
        double value = 0;
        if (component_type == 5126) {
          float f;
          std::memcpy(&f, at, 4);
          value = f;
        } else if (component_type == 5125) {
          uint32_t u;
          std::memcpy(&u, at, 4);
          value = u;
        } else if (component_type == 5123) {
          uint16_t u;
          std::memcpy(&u, at, 2);
          value = normalized ? u / 65535.0 : u;
        } else {
          value = normalized ? uint8_t(*at) / 255.0 : uint8_t(*at);
        }
        if (!std::isfinite(value)) {
          Fail("accessors[", index, "] element ", i, " is not finite");
        }
        values[i * components + c] = value;
      }
    }
    return values;
  }

  const nlohmann::json& Item(const char* array, int index) const {
    if (!glb_.json.contains(array) || index < 0 ||
        size_t(index) >= glb_.json.at(array).size()) {
      Fail(array, "[", index, "] does not exist");
    }
    return glb_.json.at(array).at(index);
  }

  template <typename... Args>
  [[noreturn]] void Fail(Args&&... args) const {
    ThrowInputError(path_, ": ", std::forward<Args>(args)...);
  }

 private:
  const Glb& glb_;
  std::string path_;
};

TexturedModel ReadGlbChecked(const std::string& path) {
  const Glb glb = ParseGlb(path);
  const GlbAccessors accessors(glb, path);
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  std::vector<Eigen::Vector2f> vertex_uv;
  int image_index = -1;
  size_t primitives_with_uv = 0, num_primitives = 0;
  if (!glb.json.contains("meshes") || glb.json.at("meshes").empty()) {
    accessors.Fail("no meshes");
  }
  // Each mesh's offset: the translation of a node that draws it, in the
  // frame before the node's rotation (bayon's files: the model's centre in
  // the datum, the rotation only turning z-up to y-up, which the positions
  // returned here do not take).
  std::vector<Eigen::Vector3d> offsets(glb.json.at("meshes").size(),
                                       Eigen::Vector3d::Zero());
  try {
    for (const nlohmann::json& node :
         glb.json.value("nodes", nlohmann::json::array())) {
      if (!node.contains("mesh") || !node.contains("translation")) continue;
      const size_t m = node.at("mesh").get<size_t>();
      if (m >= offsets.size())
        accessors.Fail("a node draws mesh ", m, " that is not there");
      const auto& t = node.at("translation");
      Eigen::Vector3d translation(
          t.at(0).get<double>(), t.at(1).get<double>(), t.at(2).get<double>());
      Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
      if (node.contains("rotation")) {
        const auto& q = node.at("rotation");  // x, y, z, w
        rotation = Eigen::Quaterniond(q.at(3).get<double>(),
                                      q.at(0).get<double>(),
                                      q.at(1).get<double>(),
                                      q.at(2).get<double>());
        if (!(rotation.norm() > 0.5))
          accessors.Fail("a node's rotation is not a unit quaternion");
        rotation.normalize();
      }
      offsets[m] = rotation.inverse() * translation;
      if (!offsets[m].allFinite())
        accessors.Fail("a node's translation is not finite");
    }
  } catch (const nlohmann::json::exception& error) {
    accessors.Fail("invalid node: ", error.what());
  }
  size_t mesh_index = 0;
  for (const nlohmann::json& gltf_mesh : glb.json.at("meshes")) {
    const Eigen::Vector3d offset = offsets[mesh_index++];
    for (const nlohmann::json& primitive : gltf_mesh.at("primitives")) {
      ++num_primitives;
      const int mode = primitive.value("mode", 4);
      if (mode != 4) {
        accessors.Fail("primitive mode ", mode, " (only TRIANGLES, 4)");
      }
      const nlohmann::json& attributes = primitive.at("attributes");
      if (!attributes.contains("POSITION")) accessors.Fail("no POSITION");
      const std::vector<double> positions =
          accessors.Read(attributes.at("POSITION").get<int>(), 3);
      const size_t first = mesh.NumVertices();
      const size_t count = positions.size() / 3;
      for (size_t i = 0; i < count; ++i) {
        mesh.vertices.positions.push_back(
            Eigen::Vector3d(
                positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]) +
            offset);
      }
      // The base colour texture and the texture coordinate set it uses.
      int texcoord_set = 0, image = -1;
      if (primitive.contains("material")) {
        const nlohmann::json& material =
            accessors.Item("materials", primitive.at("material").get<int>());
        const nlohmann::json pbr =
            material.value("pbrMetallicRoughness", nlohmann::json::object());
        if (pbr.contains("baseColorTexture")) {
          const nlohmann::json& info = pbr.at("baseColorTexture");
          texcoord_set = info.value("texCoord", 0);
          image = accessors.Item("textures", info.at("index").get<int>())
                      .at("source")
                      .get<int>();
        }
      }
      const std::string uv_name = StrCat("TEXCOORD_", texcoord_set);
      if (image >= 0 && attributes.contains(uv_name)) {
        if (image_index >= 0 && image_index != image) {
          accessors.Fail(
              "primitives use more than one texture image; one "
              "atlas is supported");
        }
        image_index = image;
        const std::vector<double> uv =
            accessors.Read(attributes.at(uv_name).get<int>(), 2);
        if (uv.size() != 2 * count) {
          accessors.Fail(uv_name, " count differs from POSITION count");
        }
        for (size_t i = 0; i < count; ++i) {
          vertex_uv.emplace_back(float(uv[2 * i]), float(1.0 - uv[2 * i + 1]));
        }
        ++primitives_with_uv;
      } else {
        vertex_uv.resize(mesh.NumVertices(), Eigen::Vector2f::Zero());
      }
      std::vector<double> indices;
      if (primitive.contains("indices")) {
        indices = accessors.Read(primitive.at("indices").get<int>(), 1);
      } else {
        for (size_t i = 0; i < count; ++i) indices.push_back(double(i));
      }
      if (indices.size() % 3 != 0) {
        accessors.Fail("index count ",
                       indices.size(),
                       " is not a multiple "
                       "of 3");
      }
      for (size_t i = 0; i < indices.size(); i += 3) {
        Eigen::Vector3i face;
        for (int k = 0; k < 3; ++k) {
          if (indices[i + k] >= double(count)) {
            accessors.Fail(
                "index ", indices[i + k], " >= vertex count ", count);
          }
          face[k] = static_cast<int>(first + size_t(indices[i + k]));
        }
        mesh.faces.push_back(face);
      }
    }
  }
  if (mesh.faces.empty()) accessors.Fail("no triangles");
  if (primitives_with_uv > 0 && primitives_with_uv != num_primitives) {
    accessors.Fail(num_primitives - primitives_with_uv,
                   " of ",
                   num_primitives,
                   " primitives have no texture");
  }
  if (primitives_with_uv > 0) {
    SetCornerTexcoords(vertex_uv, &mesh);
    const nlohmann::json& image = accessors.Item("images", image_index);
    if (!image.contains("bufferView")) {
      accessors.Fail("images[", image_index, "] is not embedded (uri)");
    }
    model.atlas =
        ToAtlas(DecodeImage(accessors.View(image.at("bufferView").get<int>()),
                            ImageReadMode::kColor,
                            StrCat(path, ": embedded image")));
  }
  mesh.Check(path);
  return model;
}

TexturedModel ReadGlb(const std::string& path) {
  try {
    return ReadGlbChecked(path);
  } catch (const nlohmann::json::exception& error) {
    // A member of the wrong type or missing (at(), get<>()).
    ThrowInputError(path, ": malformed glTF JSON: ", error.what());
  }
}

std::string LowerExtension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

}  // namespace

std::vector<std::string> WriteTexturedModel(const TexturedModel& model,
                                            const std::string& output_dir,
                                            const ModelExportOptions& options) {
  CheckModel(model);
  if (options.stem.empty() ||
      options.stem.find_first_of("/\\ \t\"") != std::string::npos) {
    ThrowInputError("ModelExportOptions.stem must be a plain file name (got '",
                    options.stem,
                    "')");
  }
  std::error_code error;
  fs::create_directories(output_dir, error);
  if (!fs::is_directory(output_dir)) {
    throw RunFailure(StrCat(output_dir, ": cannot create the output folder"));
  }
  auto file = [&](const std::string& extension) {
    return (fs::path(output_dir) / (options.stem + extension)).string();
  };
  const std::string png_name = options.stem + ".png";
  std::vector<uchar> png_bytes;
  if (!cv::imencode(".png", model.atlas, png_bytes)) {
    throw RunFailure(StrCat(file(".png"), ": cannot encode the atlas"));
  }
  const std::string png(png_bytes.begin(), png_bytes.end());
  std::vector<std::string> written;
  WriteFileAtomically(file(".png"), png);
  written.push_back(file(".png"));

  const TriangleMesh& mesh = model.mesh;
  const Wedges wedges = SplitWedges(mesh);
  if (options.obj) {
    WriteFileAtomically(file(".mtl"), MtlText(png_name));
    WriteFileAtomically(file(".obj"),
                        ObjText(mesh, wedges, options.stem + ".mtl"));
    written.push_back(file(".obj"));
    written.push_back(file(".mtl"));
  }
  if (options.ply) {
    PlyWriteOptions ply_options;
    ply_options.comment = "TextureFile " + png_name;
    WriteMeshPly(mesh, file(".ply"), ply_options);
    written.push_back(file(".ply"));
  }
  if (options.vrml) {
    WriteFileAtomically(file(".wrl"), VrmlText(mesh, wedges, png_name));
    written.push_back(file(".wrl"));
  }
  if (options.gltf) {
    WriteFileAtomically(
        file(".glb"),
        GlbBytes(
            mesh, wedges, png, options.gltf_y_up, options.georeference_json));
    written.push_back(file(".glb"));
  }
  return written;
}

TexturedModel ReadTexturedModel(const std::string& path) {
  CheckFileExists(path, "model");
  const std::string extension = LowerExtension(path);
  if (extension == ".obj") return ReadObj(path);
  if (extension == ".ply") return ReadTexturedPly(path);
  if (extension == ".wrl") return ReadVrml(path);
  if (extension == ".glb") return ReadGlb(path);
  ThrowInputError(path,
                  ": unknown model format '",
                  extension,
                  "' (use .obj, .ply, .wrl or .glb)");
}

}  // namespace bayon
