// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/ply_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace bayon {
namespace {

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

enum class PlyType {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kFloat32,
  kFloat64
};

bool ParseType(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},
      {"int8", PlyType::kInt8},
      {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},
      {"short", PlyType::kInt16},
      {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16},
      {"uint16", PlyType::kUInt16},
      {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},
      {"uint", PlyType::kUInt32},
      {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32},
      {"float32", PlyType::kFloat32},
      {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [text, value] : kNames) {
    if (name == text) {
      *type = value;
      return true;
    }
  }
  return false;
}

size_t TypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUInt8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUInt16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUInt32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Reads values of a PLY body, binary or ASCII, with bounds checks.
class BodyReader {
 public:
  BodyReader(const std::string& path,
             const std::string& data,
             size_t offset,
             PlyFormat format)
      : path_(path), data_(data), offset_(offset), format_(format) {
    if (format_ == PlyFormat::kAscii) {
      text_.str(data_.substr(offset_));
    }
  }

  double Read(PlyType type, const char* what) {
    if (format_ == PlyFormat::kAscii) {
      std::string token;
      if (!(text_ >> token)) Fail(StrCat("file ends while reading ", what));
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') {
        Fail(StrCat(what, " '", token, "' is not a number"));
      }
      return value;
    }
    const size_t size = TypeSize(type);
    if (data_.size() - offset_ < size)
      Fail(StrCat("truncated while reading ", what));
    unsigned char bytes[8];
    std::memcpy(bytes, data_.data() + offset_, size);
    offset_ += size;
    if (format_ == PlyFormat::kBinaryBig) {
      for (size_t i = 0; i < size / 2; ++i)
        std::swap(bytes[i], bytes[size - 1 - i]);
    }
    switch (type) {
      case PlyType::kInt8: {
        int8_t v;
        std::memcpy(&v, bytes, 1);
        return v;
      }
      case PlyType::kUInt8: {
        uint8_t v;
        std::memcpy(&v, bytes, 1);
        return v;
      }
      case PlyType::kInt16: {
        int16_t v;
        std::memcpy(&v, bytes, 2);
        return v;
      }
      case PlyType::kUInt16: {
        uint16_t v;
        std::memcpy(&v, bytes, 2);
        return v;
      }
      case PlyType::kInt32: {
        int32_t v;
        std::memcpy(&v, bytes, 4);
        return v;
      }
      case PlyType::kUInt32: {
        uint32_t v;
        std::memcpy(&v, bytes, 4);
        return v;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, bytes, 4);
        return v;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, bytes, 8);
        return v;
      }
    }
    return 0;
  }

  // Can `count` records of at least `bytes` each still follow? In ASCII a
  // value takes a character and a separator (which the file's last value
  // may lack), so callers give 2 bytes per value.
  void NeedRecords(uint64_t count, size_t bytes, const std::string& what) {
    if (bytes == 0) return;
    size_t left = data_.size() - offset_;
    if (format_ == PlyFormat::kAscii) {
      const std::streamoff position = text_.tellg();
      left = position < 0 ? 1 : left - static_cast<size_t>(position) + 1;
    }
    if (count > left / bytes) {
      Fail(StrCat(what,
                  ": ",
                  count,
                  " records do not fit in the ",
                  data_.size() - offset_,
                  " bytes left"));
    }
  }

  [[noreturn]] void Fail(const std::string& message) const {
    if (format_ == PlyFormat::kAscii) {
      ThrowInputError(path_, ": ", message, " (the file may be truncated)");
    }
    ThrowInputError(path_,
                    ": ",
                    message,
                    " (at byte ",
                    offset_,
                    "; the file may be truncated)");
  }

 private:
  const std::string& path_;
  const std::string& data_;
  size_t offset_;
  PlyFormat format_;
  std::istringstream text_;
};

PlyScalarType ScalarTypeOf(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kInt16:
    case PlyType::kInt32:
      return PlyScalarType::kInt;
    case PlyType::kUInt8:
      return PlyScalarType::kUChar;
    case PlyType::kUInt16:
    case PlyType::kUInt32:
      return PlyScalarType::kUInt;
    case PlyType::kFloat32:
      return PlyScalarType::kFloat;
    case PlyType::kFloat64:
      return PlyScalarType::kDouble;
  }
  return PlyScalarType::kFloat;
}

void ParseHeader(const std::string& path,
                 const std::string& data,
                 PlyFormat* format,
                 std::vector<PlyElement>* elements,
                 size_t* body_offset) {
  if (data.compare(0, 4, "ply\n") != 0 && data.compare(0, 5, "ply\r\n") != 0) {
    ThrowInputError(path, ": not a PLY file (no 'ply' magic line)");
  }
  const size_t end = data.find("end_header");
  if (end == std::string::npos)
    ThrowInputError(path, ": PLY header has no end_header");
  size_t newline = data.find('\n', end);
  if (newline == std::string::npos)
    ThrowInputError(path, ": PLY header is not terminated");
  *body_offset = newline + 1;
  std::istringstream header(data.substr(0, end));
  std::string line;
  int line_number = 0;
  bool have_format = false;
  while (std::getline(header, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    auto fail = [&](const std::string& message) {
      ThrowInputError(path, ":", line_number, ": ", message);
    };
    if (keyword == "ply" || keyword == "comment" || keyword == "obj_info" ||
        keyword.empty()) {
      continue;
    }
    if (keyword == "format") {
      std::string name, version;
      words >> name >> version;
      if (name == "ascii")
        *format = PlyFormat::kAscii;
      else if (name == "binary_little_endian")
        *format = PlyFormat::kBinaryLittle;
      else if (name == "binary_big_endian")
        *format = PlyFormat::kBinaryBig;
      else
        fail("unknown format '" + name + "'");
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      long long count = -1;
      words >> element.name >> count;
      if (element.name.empty() || count < 0) fail("bad element line");
      element.count = static_cast<uint64_t>(count);
      elements->push_back(element);
    } else if (keyword == "property") {
      if (elements->empty()) fail("property before any element");
      PlyProperty property;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> property.name;
        property.is_list = true;
        if (!ParseType(count_type, &property.count_type) ||
            !ParseType(item_type, &property.type)) {
          fail("unknown list types '" + count_type + " " + item_type + "'");
        }
      } else {
        words >> property.name;
        if (!ParseType(type, &property.type))
          fail("unknown type '" + type + "'");
      }
      if (property.name.empty()) fail("property without a name");
      elements->back().properties.push_back(property);
    } else {
      fail("unknown header keyword '" + keyword + "'");
    }
  }
  if (!have_format) ThrowInputError(path, ": PLY header has no format line");
  // Records without properties take no bytes, so nothing in the file bounds
  // their count: reading 2^60 of them would never end.
  for (const PlyElement& element : *elements) {
    if (element.count > 0 && element.properties.empty()) {
      ThrowInputError(path,
                      ": element ",
                      element.name,
                      " has ",
                      element.count,
                      " records but no properties");
    }
  }
}

}  // namespace

TriangleMesh ReadPly(const std::string& path) {
  const std::string data = ReadFileToString(path);
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t body_offset = 0;
  ParseHeader(path, data, &format, &elements, &body_offset);
  BodyReader reader(path, data, body_offset, format);

  TriangleMesh mesh;
  PointCloud& cloud = mesh.vertices;
  bool have_vertices = false;
  for (const PlyElement& element : elements) {
    size_t fixed_bytes = 0;
    for (const PlyProperty& property : element.properties) {
      fixed_bytes += property.is_list ? TypeSize(property.count_type)
                                      : TypeSize(property.type);
    }
    reader.NeedRecords(element.count,
                       format == PlyFormat::kAscii
                           ? 2 * element.properties.size()
                           : fixed_bytes,
                       "element " + element.name);
    if (element.name == "vertex") {
      // A second vertex element would index the first one's arrays.
      if (have_vertices)
        ThrowInputError(path, ": more than one vertex element");
      have_vertices = true;
      int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, r = -1, g = -1,
          b = -1;
      std::vector<int> extra;
      for (size_t i = 0; i < element.properties.size(); ++i) {
        const PlyProperty& p = element.properties[i];
        const std::string& n = p.name;
        if (p.is_list) {
          ThrowInputError(path, ": vertex property '", n, "' is a list");
        }
        if (n == "x")
          x = i;
        else if (n == "y")
          y = i;
        else if (n == "z")
          z = i;
        else if (n == "nx")
          nx = i;
        else if (n == "ny")
          ny = i;
        else if (n == "nz")
          nz = i;
        else if (n == "red" || n == "diffuse_red")
          r = i;
        else if (n == "green" || n == "diffuse_green")
          g = i;
        else if (n == "blue" || n == "diffuse_blue")
          b = i;
        else
          extra.push_back(i);
      }
      if (x < 0 || y < 0 || z < 0) {
        ThrowInputError(path, ": vertex element lacks x, y or z");
      }
      const bool normals = nx >= 0 && ny >= 0 && nz >= 0;
      const bool colors = r >= 0 && g >= 0 && b >= 0;
      cloud.positions.resize(element.count);
      if (normals) cloud.normals.resize(element.count);
      if (colors) cloud.colors.resize(element.count);
      for (int i : extra) {
        cloud.attributes.push_back(
            PointAttribute{element.properties[i].name,
                           ScalarTypeOf(element.properties[i].type),
                           {}});
        cloud.attributes.back().values.resize(element.count);
      }
      std::vector<double> values(element.properties.size());
      for (uint64_t v = 0; v < element.count; ++v) {
        for (size_t i = 0; i < element.properties.size(); ++i) {
          values[i] =
              reader.Read(element.properties[i].type, "a vertex property");
        }
        cloud.positions[v] = Eigen::Vector3d(values[x], values[y], values[z]);
        if (normals) {
          cloud.normals[v] =
              Eigen::Vector3f(values[nx], values[ny], values[nz]);
        }
        if (colors) {
          auto channel = [&](int idx) {
            const double value = values[idx];
            // Float colours in [0, 1] exist in the wild; scale them.
            const double scaled =
                element.properties[idx].type == PlyType::kFloat32 ||
                        element.properties[idx].type == PlyType::kFloat64
                    ? 255.0 * value
                    : value;
            return static_cast<uint8_t>(
                std::clamp(std::lround(scaled), 0L, 255L));
          };
          cloud.colors[v] =
              Eigen::Matrix<uint8_t, 3, 1>(channel(r), channel(g), channel(b));
        }
        for (size_t k = 0; k < extra.size(); ++k) {
          cloud.attributes[k].values[v] = values[extra[k]];
        }
      }
    } else if (element.name == "face") {
      int indices = -1, texcoord = -1;
      for (size_t i = 0; i < element.properties.size(); ++i) {
        const std::string& n = element.properties[i].name;
        if ((n == "vertex_indices" || n == "vertex_index") &&
            element.properties[i].is_list) {
          indices = i;
        } else if (n == "texcoord" && element.properties[i].is_list) {
          texcoord = i;
        }
      }
      if (indices < 0)
        ThrowInputError(path, ": face element lacks vertex_indices");
      mesh.faces.reserve(element.count);
      for (uint64_t f = 0; f < element.count; ++f) {
        std::vector<int> polygon;
        std::vector<float> uv;
        for (size_t i = 0; i < element.properties.size(); ++i) {
          const PlyProperty& p = element.properties[i];
          if (!p.is_list) {
            reader.Read(p.type, "a face property");
            continue;
          }
          const double count = reader.Read(p.count_type, "a face list count");
          // Written so that NaN fails too (a float count type allows it).
          if (!(count >= 0 && count <= 1e6)) {
            reader.Fail(StrCat("face ", f, " has a list of ", count, " items"));
          }
          std::vector<double> items(static_cast<size_t>(count));
          for (double& item : items)
            item = reader.Read(p.type, "a face list item");
          if (static_cast<int>(i) == indices) {
            for (double item : items) {
              // Beyond int the cast is undefined; Check() refuses the rest.
              if (!(std::abs(item) <= std::numeric_limits<int>::max())) {
                reader.Fail(StrCat("face ", f, " has vertex index ", item));
              }
              polygon.push_back(static_cast<int>(item));
            }
          } else if (static_cast<int>(i) == texcoord) {
            for (double item : items) uv.push_back(static_cast<float>(item));
          }
        }
        if (polygon.size() < 3) {
          reader.Fail(StrCat("face ", f, " has ", polygon.size(), " vertices"));
        }
        for (size_t k = 1; k + 1 < polygon.size(); ++k) {
          mesh.faces.emplace_back(polygon[0], polygon[k], polygon[k + 1]);
          if (texcoord >= 0 && uv.size() == 2 * polygon.size()) {
            mesh.face_texcoords.push_back(
                {Eigen::Vector2f(uv[0], uv[1]),
                 Eigen::Vector2f(uv[2 * k], uv[2 * k + 1]),
                 Eigen::Vector2f(uv[2 * k + 2], uv[2 * k + 3])});
          }
        }
      }
      if (!mesh.face_texcoords.empty() &&
          mesh.face_texcoords.size() != mesh.faces.size()) {
        ThrowInputError(path, ": some faces lack texture coordinates");
      }
    } else {
      // Skip elements bayon does not use (edges, materials, ...).
      for (uint64_t e = 0; e < element.count; ++e) {
        for (const PlyProperty& p : element.properties) {
          if (p.is_list) {
            const double count = reader.Read(p.count_type, "a list count");
            if (!(count >= 0 && count <= 1e6)) reader.Fail("bad list count");
            for (int k = 0; k < static_cast<int>(count); ++k)
              reader.Read(p.type, "a list item");
          } else {
            reader.Read(p.type, "a property");
          }
        }
      }
    }
  }
  if (!have_vertices) ThrowInputError(path, ": PLY file has no vertex element");
  mesh.Check(path);
  return mesh;
}

PointCloud ReadPointCloudPly(const std::string& path) {
  return ReadPly(path).vertices;
}

TriangleMesh ReadMeshPly(const std::string& path) {
  TriangleMesh mesh = ReadPly(path);
  if (mesh.faces.empty()) ThrowInputError(path, ": PLY file has no faces");
  return mesh;
}

std::string PlyTextureFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInputError(path, ": cannot open the PLY file");
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") break;
    std::istringstream words(line);
    std::string keyword, tag, name;
    words >> keyword >> tag;
    if (keyword != "comment" || tag != "TextureFile") continue;
    std::getline(words >> std::ws, name);
    if (name.empty()) continue;
    const std::filesystem::path texture(name);
    return texture.is_absolute()
               ? name
               : (std::filesystem::path(path).parent_path() / texture).string();
  }
  return "";
}

namespace {

const char* TypeName(PlyScalarType type) {
  switch (type) {
    case PlyScalarType::kUChar:
      return "uchar";
    case PlyScalarType::kInt:
      return "int";
    case PlyScalarType::kUInt:
      return "uint";
    case PlyScalarType::kFloat:
      return "float";
    case PlyScalarType::kDouble:
      return "double";
  }
  return "float";
}

class BodyWriter {
 public:
  explicit BodyWriter(bool binary) : binary_(binary) {
    text_.precision(std::numeric_limits<double>::max_digits10);
  }
  template <typename T>
  void Write(T value) {
    if (binary_) {
      const size_t size = out_.size();
      out_.resize(size + sizeof(T));
      std::memcpy(&out_[size], &value, sizeof(T));
    } else {
      if (!first_) text_ << ' ';
      first_ = false;
      if constexpr (sizeof(T) == 1) {
        text_ << static_cast<int>(value);
      } else {
        text_ << value;
      }
    }
  }
  void WriteScalar(PlyScalarType type, double value) {
    switch (type) {
      case PlyScalarType::kUChar:
        Write<uint8_t>(static_cast<uint8_t>(std::clamp(value, 0.0, 255.0)));
        break;
      case PlyScalarType::kInt:
        Write<int32_t>(static_cast<int32_t>(value));
        break;
      case PlyScalarType::kUInt:
        Write<uint32_t>(static_cast<uint32_t>(std::max(0.0, value)));
        break;
      case PlyScalarType::kFloat:
        Write<float>(static_cast<float>(value));
        break;
      case PlyScalarType::kDouble:
        Write<double>(value);
        break;
    }
  }
  void EndRecord() {
    if (!binary_) {
      text_ << '\n';
      first_ = true;
    }
  }
  std::string Take() { return binary_ ? out_ : text_.str(); }

 private:
  bool binary_;
  bool first_ = true;
  std::string out_;
  std::ostringstream text_;
};

// `mesh` is null for a point cloud without faces.
std::string Header(const PointCloud& cloud,
                   const TriangleMesh* mesh,
                   const PlyWriteOptions& options) {
  std::ostringstream header;
  header << "ply\nformat "
         << (options.binary ? "binary_little_endian" : "ascii") << " 1.0\n";
  header << "comment written by bayon\n";
  if (!options.comment.empty()) header << "comment " << options.comment << "\n";
  header << "element vertex " << cloud.size() << "\n";
  const char* coordinate = options.double_coordinates ? "double" : "float";
  header << "property " << coordinate << " x\nproperty " << coordinate
         << " y\nproperty " << coordinate << " z\n";
  if (cloud.HasNormals()) {
    header << "property float nx\nproperty float ny\nproperty float nz\n";
  }
  if (cloud.HasColors()) {
    header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  }
  for (const PointAttribute& attribute : cloud.attributes) {
    header << "property " << TypeName(attribute.type) << " " << attribute.name
           << "\n";
  }
  if (mesh != nullptr) {
    header << "element face " << mesh->faces.size() << "\n";
    header << "property list uchar int vertex_indices\n";
    if (mesh->HasTexcoords()) header << "property list uchar float texcoord\n";
  }
  header << "end_header\n";
  return header.str();
}

std::string Body(const PointCloud& cloud,
                 const TriangleMesh* mesh,
                 const PlyWriteOptions& options) {
  BodyWriter writer(options.binary);
  for (size_t i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (options.double_coordinates) {
        writer.Write<double>(cloud.positions[i](k));
      } else {
        writer.Write<float>(static_cast<float>(cloud.positions[i](k)));
      }
    }
    if (cloud.HasNormals()) {
      for (int k = 0; k < 3; ++k) writer.Write<float>(cloud.normals[i](k));
    }
    if (cloud.HasColors()) {
      for (int k = 0; k < 3; ++k) writer.Write<uint8_t>(cloud.colors[i](k));
    }
    for (const PointAttribute& attribute : cloud.attributes) {
      writer.WriteScalar(attribute.type, attribute.values[i]);
    }
    writer.EndRecord();
  }
  if (mesh != nullptr) {
    for (size_t f = 0; f < mesh->faces.size(); ++f) {
      writer.Write<uint8_t>(3);
      for (int k = 0; k < 3; ++k) writer.Write<int32_t>(mesh->faces[f](k));
      if (mesh->HasTexcoords()) {
        writer.Write<uint8_t>(6);
        for (int k = 0; k < 3; ++k) {
          writer.Write<float>(mesh->face_texcoords[f][k].x());
          writer.Write<float>(mesh->face_texcoords[f][k].y());
        }
      }
      writer.EndRecord();
    }
  }
  return writer.Take();
}

}  // namespace

void WritePointCloudPly(const PointCloud& cloud,
                        const std::string& path,
                        const PlyWriteOptions& options) {
  cloud.Check(path);
  WriteFileAtomically(
      path, Header(cloud, nullptr, options) + Body(cloud, nullptr, options));
}

void WriteMeshPly(const TriangleMesh& mesh,
                  const std::string& path,
                  const PlyWriteOptions& options) {
  mesh.Check(path);
  WriteFileAtomically(path,
                      Header(mesh.vertices, &mesh, options) +
                          Body(mesh.vertices, &mesh, options));
}

void WriteColmapFusedPly(const PointCloud& cloud,
                         const std::string& path,
                         const std::string& comment,
                         const std::vector<std::vector<uint32_t>>* visibility) {
  PointCloud fused;
  fused.positions = cloud.positions;
  fused.normals = cloud.normals;
  fused.colors = cloud.colors;
  if (!fused.HasColors()) {
    fused.colors.assign(cloud.size(),
                        Eigen::Matrix<uint8_t, 3, 1>(128, 128, 128));
  }
  PlyWriteOptions options;
  options.double_coordinates = false;
  options.comment = comment;
  if (visibility != nullptr) {
    if (visibility->size() != cloud.size()) {
      ThrowInputError(path,
                      ": visibility for ",
                      visibility->size(),
                      " points, but the cloud has ",
                      cloud.size());
    }
    // COLMAP's layout: uint64 count, then per point a uint32 count and
    // that many uint32 image indices, little-endian (as on every machine
    // bayon builds for).
    std::string vis;
    const auto put = [&vis](auto value) {
      vis.append(reinterpret_cast<const char*>(&value), sizeof(value));
    };
    put(static_cast<uint64_t>(visibility->size()));
    for (const std::vector<uint32_t>& images : *visibility) {
      put(static_cast<uint32_t>(images.size()));
      for (uint32_t index : images) put(index);
    }
    WriteFileAtomically(path + ".vis", vis);
  }
  WritePointCloudPly(fused, path, options);
}

std::vector<std::vector<uint32_t>> ReadColmapVisibility(
    const std::string& path) {
  const std::string data = ReadFileToString(path);
  size_t offset = 0;
  const auto get = [&](auto* value) {
    if (offset + sizeof(*value) > data.size()) {
      ThrowInputError(
          path, ": truncated visibility file (", data.size(), " bytes)");
    }
    std::memcpy(value, data.data() + offset, sizeof(*value));
    offset += sizeof(*value);
  };
  uint64_t count = 0;
  get(&count);
  // Each point takes four bytes at least: a count beyond the file's size is
  // no visibility file.
  if (count > data.size() / 4) {
    ThrowInputError(path,
                    ": not a visibility file (",
                    count,
                    " points in ",
                    data.size(),
                    " bytes)");
  }
  std::vector<std::vector<uint32_t>> visibility(count);
  for (std::vector<uint32_t>& images : visibility) {
    uint32_t n = 0;
    get(&n);
    if (n > (data.size() - offset) / 4) {
      ThrowInputError(path, ": truncated visibility file");
    }
    images.resize(n);
    for (uint32_t& index : images) get(&index);
  }
  if (offset != data.size()) {
    ThrowInputError(path,
                    ": ",
                    data.size() - offset,
                    " bytes after the last point's visibility");
  }
  return visibility;
}

}  // namespace bayon
