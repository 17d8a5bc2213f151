// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"
#include "ext/render/model_formats.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

namespace bayon {
namespace internal {

namespace {

void AppendBytes(std::string* bin, const void* data, size_t size) {
  bin->append(static_cast<const char*>(data), size);
}

void PadTo4(std::string* text, char pad) {
  while (text->size() % 4 != 0) text->push_back(pad);
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

}  // namespace

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

TexturedModel ReadGlb(const std::string& path) {
  try {
    return ReadGlbChecked(path);
  } catch (const nlohmann::json::exception& error) {
    // A member of the wrong type or missing (at(), get<>()).
    ThrowInputError(path, ": malformed glTF JSON: ", error.what());
  }
}

}  // namespace internal
}  // namespace bayon
