// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// ------------------------------------------------------------ binary

// Little-endian reader over a whole file; every read checks the bytes left.
class BinaryReader {
 public:
  explicit BinaryReader(const std::string& path)
      : path_(path), data_(ReadFileToString(path)) {}

  template <typename T>
  T Read(const char* what) {
    Need(sizeof(T), what);
    T value;
    std::memcpy(&value, data_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }

  std::string ReadString(const char* what) {
    const size_t end = data_.find('\0', offset_);
    if (end == std::string::npos) {
      Fail(StrCat("unterminated ", what));
    }
    std::string value = data_.substr(offset_, end - offset_);
    offset_ = end + 1;
    return value;
  }

  // Checks that `count` records of at least `record_bytes` each can follow.
  void NeedRecords(uint64_t count, size_t record_bytes, const char* what) {
    if (record_bytes > 0 && count > (data_.size() - offset_) / record_bytes) {
      Fail(StrCat(what,
                  " count ",
                  count,
                  " does not fit in the ",
                  data_.size() - offset_,
                  " bytes left"));
    }
  }

  void ExpectEnd() {
    if (offset_ != data_.size()) {
      Fail(StrCat(data_.size() - offset_,
                  " unexpected bytes after the last record"));
    }
  }

  [[noreturn]] void Fail(const std::string& message) const {
    ThrowInputError(path_,
                    ": ",
                    message,
                    " (at byte ",
                    offset_,
                    "; the file may be truncated or not a COLMAP model)");
  }

 private:
  void Need(size_t n, const char* what) {
    if (data_.size() - offset_ < n) {
      Fail(StrCat("truncated while reading ", what));
    }
  }

  std::string path_;
  std::string data_;
  size_t offset_ = 0;
};

template <typename T>
void Append(std::string* out, const T& value) {
  const size_t size = out->size();
  out->resize(size + sizeof(T));
  std::memcpy(&(*out)[size], &value, sizeof(T));
}

void CheckColmapCamera(const Camera& camera) {
  if (!IsColmapCameraModel(camera.model_id)) {
    ThrowInputError("camera ",
                    camera.camera_id,
                    ": model ",
                    camera.ModelName(),
                    " cannot be written to a COLMAP model; convert it first");
  }
}

// Quaternions are normalised on read, as COLMAP does, but values that are
// already unit length keep their exact bits (byte-identical round trips).
Eigen::Quaterniond QuaternionFromWXYZ(double w, double x, double y, double z) {
  Eigen::Quaterniond q(w, x, y, z);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-12 && norm > 0) q.coeffs() /= norm;
  return q;
}

// ------------------------------------------------------------ text

// Tokenised text lines with line numbers for messages.
class TextReader {
 public:
  explicit TextReader(const std::string& path)
      : path_(path), stream_(ReadFileToString(path)) {}

  // Next non-comment line (for images.txt, the points line may be empty:
  // use NextRawLine for it). Returns false at the end.
  bool NextDataLine(std::vector<std::string>* tokens) {
    std::string line;
    while (std::getline(stream_, line)) {
      ++line_number_;
      const size_t start = line.find_first_not_of(" \t\r");
      if (start == std::string::npos || line[start] == '#') continue;
      Tokenize(line, tokens);
      return true;
    }
    return false;
  }

  bool NextRawLine(std::vector<std::string>* tokens) {
    std::string line;
    if (!std::getline(stream_, line)) return false;
    ++line_number_;
    Tokenize(line, tokens);
    return true;
  }

  [[noreturn]] void Fail(const std::string& message) const {
    ThrowInputError(path_, ":", line_number_, ": ", message);
  }

  double Double(const std::string& token, const char* what) const {
    errno = 0;
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE) {
      Fail(StrCat(what, " '", token, "' is not a number"));
    }
    return value;
  }

  uint64_t Unsigned(const std::string& token, const char* what) const {
    errno = 0;
    char* end = nullptr;
    if (!token.empty() && token[0] == '-') {
      Fail(StrCat(what, " '", token, "' must not be negative"));
    }
    const unsigned long long value = std::strtoull(token.c_str(), &end, 10);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE) {
      Fail(StrCat(what, " '", token, "' is not a whole number"));
    }
    return value;
  }

  int64_t Signed(const std::string& token, const char* what) const {
    errno = 0;
    char* end = nullptr;
    const long long value = std::strtoll(token.c_str(), &end, 10);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE) {
      Fail(StrCat(what, " '", token, "' is not a whole number"));
    }
    return value;
  }

 private:
  static void Tokenize(const std::string& line,
                       std::vector<std::string>* tokens) {
    tokens->clear();
    std::istringstream words(line);
    std::string word;
    while (words >> word) tokens->push_back(word);
  }

  std::string path_;
  std::istringstream stream_;
  int line_number_ = 0;
};

// COLMAP writes text with 17 significant digits through an ostream.
std::ostringstream TextStream() {
  std::ostringstream stream;
  stream.precision(17);
  return stream;
}

}  // namespace

// =================================================================== read

void ReadCamerasBinary(const std::string& path, Scene* scene) {
  BinaryReader reader(path);
  const uint64_t num_cameras = reader.Read<uint64_t>("the camera count");
  reader.NeedRecords(num_cameras, 24, "camera");
  for (uint64_t i = 0; i < num_cameras; ++i) {
    Camera camera;
    camera.camera_id = reader.Read<uint32_t>("camera_id");
    const int32_t model_id = reader.Read<int32_t>("model_id");
    if (!IsKnownCameraModelId(model_id) ||
        !IsColmapCameraModel(static_cast<CameraModelId>(model_id))) {
      reader.Fail(StrCat("camera ",
                         camera.camera_id,
                         ": unknown model id ",
                         model_id,
                         " (COLMAP 3.8 knows 0-10)"));
    }
    camera.model_id = static_cast<CameraModelId>(model_id);
    camera.width = reader.Read<uint64_t>("width");
    camera.height = reader.Read<uint64_t>("height");
    camera.params.resize(camera.ModelInfo().num_params);
    for (double& param : camera.params) param = reader.Read<double>("params");
    if (scene->cameras.contains(camera.camera_id)) {
      reader.Fail(StrCat("camera ", camera.camera_id, " appears twice"));
    }
    scene->cameras.Set(camera.camera_id, std::move(camera));
  }
  reader.ExpectEnd();
}

void ReadImagesBinary(const std::string& path, Scene* scene) {
  BinaryReader reader(path);
  const uint64_t num_images = reader.Read<uint64_t>("the image count");
  reader.NeedRecords(num_images, 73, "image");
  scene->images.reserve(num_images);
  for (uint64_t i = 0; i < num_images; ++i) {
    Image image;
    image.image_id = reader.Read<uint32_t>("image_id");
    double q[4], t[3];
    for (double& v : q) v = reader.Read<double>("qvec");
    for (double& v : t) v = reader.Read<double>("tvec");
    image.cam_from_world.rotation = QuaternionFromWXYZ(q[0], q[1], q[2], q[3]);
    image.cam_from_world.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    image.camera_id = reader.Read<uint32_t>("camera_id");
    image.name = reader.ReadString("image name");
    const uint64_t num_points2D = reader.Read<uint64_t>("num_points2D");
    reader.NeedRecords(num_points2D, 24, "points2D");
    image.points2D.resize(num_points2D);
    for (Point2D& point : image.points2D) {
      point.xy.x() = reader.Read<double>("point2D x");
      point.xy.y() = reader.Read<double>("point2D y");
      point.point3D_id = reader.Read<uint64_t>("point3D_id");
    }
    if (scene->images.contains(image.image_id)) {
      reader.Fail(StrCat("image ", image.image_id, " appears twice"));
    }
    scene->images.Set(image.image_id, std::move(image));
  }
  reader.ExpectEnd();
}

void ReadPoints3DBinary(const std::string& path, Scene* scene) {
  BinaryReader reader(path);
  const uint64_t num_points = reader.Read<uint64_t>("the point count");
  reader.NeedRecords(num_points, 51, "point3D");
  scene->points3D.reserve(num_points);
  for (uint64_t i = 0; i < num_points; ++i) {
    const point3D_t point3D_id = reader.Read<uint64_t>("point3D_id");
    Point3D point;
    for (int k = 0; k < 3; ++k) point.xyz(k) = reader.Read<double>("xyz");
    for (int k = 0; k < 3; ++k) point.color(k) = reader.Read<uint8_t>("rgb");
    point.error = reader.Read<double>("error");
    const uint64_t track_length = reader.Read<uint64_t>("track_length");
    reader.NeedRecords(track_length, 8, "track");
    point.track.resize(track_length);
    for (TrackElement& element : point.track) {
      element.image_id = reader.Read<uint32_t>("track image_id");
      element.point2D_idx = reader.Read<uint32_t>("track point2D_idx");
    }
    if (scene->points3D.contains(point3D_id)) {
      reader.Fail(StrCat("3D point ", point3D_id, " appears twice"));
    }
    scene->points3D.Set(point3D_id, std::move(point));
  }
  reader.ExpectEnd();
}

void ReadCamerasText(const std::string& path, Scene* scene) {
  TextReader reader(path);
  std::vector<std::string> tokens;
  while (reader.NextDataLine(&tokens)) {
    if (tokens.size() < 4) {
      reader.Fail("expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS...");
    }
    Camera camera;
    camera.camera_id =
        static_cast<camera_t>(reader.Unsigned(tokens[0], "CAMERA_ID"));
    const auto model = CameraModelIdFromName(tokens[1]);
    if (!model || !IsColmapCameraModel(*model)) {
      reader.Fail(StrCat("unknown camera model '", tokens[1], "'"));
    }
    camera.model_id = *model;
    camera.width = reader.Unsigned(tokens[2], "WIDTH");
    camera.height = reader.Unsigned(tokens[3], "HEIGHT");
    const int num_params = camera.ModelInfo().num_params;
    if (static_cast<int>(tokens.size()) - 4 != num_params) {
      reader.Fail(StrCat(tokens[1],
                         " takes ",
                         num_params,
                         " parameters (",
                         camera.ModelInfo().params_info,
                         "), got ",
                         tokens.size() - 4));
    }
    for (int i = 0; i < num_params; ++i) {
      camera.params.push_back(reader.Double(tokens[4 + i], "parameter"));
    }
    if (scene->cameras.contains(camera.camera_id)) {
      reader.Fail(StrCat("camera ", camera.camera_id, " appears twice"));
    }
    scene->cameras.Set(camera.camera_id, std::move(camera));
  }
}

void ReadImagesText(const std::string& path, Scene* scene) {
  TextReader reader(path);
  std::vector<std::string> tokens;
  while (reader.NextDataLine(&tokens)) {
    if (tokens.size() < 10) {
      reader.Fail("expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    }
    if (tokens.size() > 10) {
      reader.Fail(
          "image names with spaces cannot be stored in images.txt; "
          "use the binary format");
    }
    Image image;
    image.image_id =
        static_cast<image_t>(reader.Unsigned(tokens[0], "IMAGE_ID"));
    double q[4], t[3];
    for (int i = 0; i < 4; ++i)
      q[i] = reader.Double(tokens[1 + i], "quaternion");
    for (int i = 0; i < 3; ++i)
      t[i] = reader.Double(tokens[5 + i], "translation");
    image.cam_from_world.rotation = QuaternionFromWXYZ(q[0], q[1], q[2], q[3]);
    image.cam_from_world.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    image.camera_id =
        static_cast<camera_t>(reader.Unsigned(tokens[8], "CAMERA_ID"));
    image.name = tokens[9];
    if (!reader.NextRawLine(&tokens)) {
      reader.Fail(
          StrCat("image ", image.image_id, ": the POINTS2D line is missing"));
    }
    if (tokens.size() % 3 != 0) {
      reader.Fail(StrCat("image ",
                         image.image_id,
                         ": POINTS2D must be X Y POINT3D_ID triples"));
    }
    image.points2D.resize(tokens.size() / 3);
    for (size_t i = 0; i < image.points2D.size(); ++i) {
      Point2D& point = image.points2D[i];
      point.xy.x() = reader.Double(tokens[3 * i], "X");
      point.xy.y() = reader.Double(tokens[3 * i + 1], "Y");
      const int64_t id = reader.Signed(tokens[3 * i + 2], "POINT3D_ID");
      point.point3D_id =
          id < 0 ? kInvalidPoint3DId : static_cast<point3D_t>(id);
    }
    if (scene->images.contains(image.image_id)) {
      reader.Fail(StrCat("image ", image.image_id, " appears twice"));
    }
    scene->images.Set(image.image_id, std::move(image));
  }
}

void ReadPoints3DText(const std::string& path, Scene* scene) {
  TextReader reader(path);
  std::vector<std::string> tokens;
  while (reader.NextDataLine(&tokens)) {
    if (tokens.size() < 8 || (tokens.size() - 8) % 2 != 0) {
      reader.Fail(
          "expected POINT3D_ID X Y Z R G B ERROR (IMAGE_ID POINT2D_IDX)...");
    }
    const point3D_t point3D_id = reader.Unsigned(tokens[0], "POINT3D_ID");
    Point3D point;
    for (int k = 0; k < 3; ++k)
      point.xyz(k) = reader.Double(tokens[1 + k], "coordinate");
    for (int k = 0; k < 3; ++k) {
      const uint64_t value = reader.Unsigned(tokens[4 + k], "colour");
      if (value > 255) reader.Fail("colour values go from 0 to 255");
      point.color(k) = static_cast<uint8_t>(value);
    }
    point.error = reader.Double(tokens[7], "ERROR");
    for (size_t i = 8; i < tokens.size(); i += 2) {
      TrackElement element;
      element.image_id =
          static_cast<image_t>(reader.Unsigned(tokens[i], "IMAGE_ID"));
      element.point2D_idx =
          static_cast<point2D_t>(reader.Unsigned(tokens[i + 1], "POINT2D_IDX"));
      point.track.push_back(element);
    }
    if (scene->points3D.contains(point3D_id)) {
      reader.Fail(StrCat("3D point ", point3D_id, " appears twice"));
    }
    scene->points3D.Set(point3D_id, std::move(point));
  }
}

ModelFormat DetectModelFormat(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) {
    ThrowInputError(path, ": model folder not found");
  }
  auto all_exist = [&](const char* extension) {
    for (const char* name : {"cameras", "images", "points3D"}) {
      if (!fs::is_regular_file(fs::path(path) / (std::string(name) + extension),
                               ec)) {
        return false;
      }
    }
    return true;
  };
  if (all_exist(".bin")) return ModelFormat::kBinary;
  if (all_exist(".txt")) return ModelFormat::kText;
  ThrowInputError(path,
                  ": not a COLMAP model (needs cameras, images and "
                  "points3D as .bin or .txt)");
}

Scene ReadModel(const std::string& path) {
  Scene scene;
  const fs::path folder(path);
  if (DetectModelFormat(path) == ModelFormat::kBinary) {
    ReadCamerasBinary((folder / "cameras.bin").string(), &scene);
    ReadImagesBinary((folder / "images.bin").string(), &scene);
    ReadPoints3DBinary((folder / "points3D.bin").string(), &scene);
  } else {
    ReadCamerasText((folder / "cameras.txt").string(), &scene);
    ReadImagesText((folder / "images.txt").string(), &scene);
    ReadPoints3DText((folder / "points3D.txt").string(), &scene);
  }
  scene.CheckConsistency(path);
  return scene;
}

// =================================================================== write

std::string CamerasBinary(const Scene& scene) {
  std::string out;
  Append<uint64_t>(&out, scene.cameras.size());
  for (const auto& [camera_id, camera] : scene.cameras) {
    CheckColmapCamera(camera);
    Append<uint32_t>(&out, camera_id);
    Append<int32_t>(&out, static_cast<int32_t>(camera.model_id));
    Append<uint64_t>(&out, camera.width);
    Append<uint64_t>(&out, camera.height);
    for (double param : camera.params) Append<double>(&out, param);
  }
  return out;
}

std::string ImagesBinary(const Scene& scene) {
  std::string out;
  Append<uint64_t>(&out, scene.images.size());
  for (const auto& [image_id, image] : scene.images) {
    Append<uint32_t>(&out, image_id);
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    Append<double>(&out, q.w());
    Append<double>(&out, q.x());
    Append<double>(&out, q.y());
    Append<double>(&out, q.z());
    for (int k = 0; k < 3; ++k) {
      Append<double>(&out, image.cam_from_world.translation(k));
    }
    Append<uint32_t>(&out, image.camera_id);
    out += image.name;
    out += '\0';
    Append<uint64_t>(&out, image.points2D.size());
    for (const Point2D& point : image.points2D) {
      Append<double>(&out, point.xy.x());
      Append<double>(&out, point.xy.y());
      Append<uint64_t>(&out, point.point3D_id);
    }
  }
  return out;
}

std::string Points3DBinary(const Scene& scene) {
  std::string out;
  Append<uint64_t>(&out, scene.points3D.size());
  for (const auto& [point3D_id, point] : scene.points3D) {
    Append<uint64_t>(&out, point3D_id);
    for (int k = 0; k < 3; ++k) Append<double>(&out, point.xyz(k));
    for (int k = 0; k < 3; ++k) Append<uint8_t>(&out, point.color(k));
    Append<double>(&out, point.error);
    Append<uint64_t>(&out, point.track.size());
    for (const TrackElement& element : point.track) {
      Append<uint32_t>(&out, element.image_id);
      Append<uint32_t>(&out, element.point2D_idx);
    }
  }
  return out;
}

std::string CamerasText(const Scene& scene) {
  std::ostringstream out = TextStream();
  out << "# Camera list with one line of data per camera:\n"
      << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      << "# Number of cameras: " << scene.cameras.size() << "\n";
  for (const auto& [camera_id, camera] : scene.cameras) {
    CheckColmapCamera(camera);
    out << camera_id << " " << camera.ModelName() << " " << camera.width << " "
        << camera.height;
    for (double param : camera.params) out << " " << param;
    out << "\n";
  }
  return out.str();
}

std::string ImagesText(const Scene& scene) {
  // COLMAP's figure counts 2D points with a 3D point over registered images.
  int num_observations = 0;
  for (const auto& [image_id, image] : scene.images) {
    num_observations += image.NumPoints3D();
  }
  const double mean_observations =
      scene.images.empty()
          ? 0.0
          : static_cast<double>(num_observations) / scene.images.size();
  std::ostringstream out = TextStream();
  out << "# Image list with two lines of data per image:\n"
      << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      << "# Number of images: " << scene.images.size()
      << ", mean observations per image: " << mean_observations << "\n";
  for (const auto& [image_id, image] : scene.images) {
    if (image.name.find_first_of(" \t\n\r") != std::string::npos) {
      ThrowInputError("image ",
                      image_id,
                      " '",
                      image.name,
                      "': names with spaces cannot be stored in images.txt; "
                      "use the binary format");
    }
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    out << image_id << " " << q.w() << " " << q.x() << " " << q.y() << " "
        << q.z() << " " << t.x() << " " << t.y() << " " << t.z() << " "
        << image.camera_id << " " << image.name << "\n";
    bool first = true;
    for (const Point2D& point : image.points2D) {
      if (!first) out << " ";
      first = false;
      out << point.xy.x() << " " << point.xy.y() << " ";
      if (point.HasPoint3D()) {
        out << point.point3D_id;
      } else {
        out << -1;
      }
    }
    out << "\n";
  }
  return out.str();
}

std::string Points3DText(const Scene& scene) {
  const SceneStats stats = scene.Stats();
  std::ostringstream out = TextStream();
  out << "# 3D point list with one line of data per point:\n"
      << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, "
         "POINT2D_IDX)\n"
      << "# Number of points: " << scene.points3D.size()
      << ", mean track length: " << stats.mean_track_length << "\n";
  for (const auto& [point3D_id, point] : scene.points3D) {
    out << point3D_id << " " << point.xyz.x() << " " << point.xyz.y() << " "
        << point.xyz.z() << " " << static_cast<int>(point.color(0)) << " "
        << static_cast<int>(point.color(1)) << " "
        << static_cast<int>(point.color(2)) << " " << point.error;
    for (const TrackElement& element : point.track) {
      out << " " << element.image_id << " " << element.point2D_idx;
    }
    out << "\n";
  }
  return out.str();
}

void WriteModel(const Scene& scene,
                const std::string& path,
                ModelFormat format) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) {
    ThrowInputError(path, ": output folder does not exist");
  }
  const fs::path folder(path);
  // Serialise everything first, so that a refused camera writes nothing.
  if (format == ModelFormat::kBinary) {
    const std::string cameras = CamerasBinary(scene);
    const std::string images = ImagesBinary(scene);
    const std::string points = Points3DBinary(scene);
    WriteFileAtomically((folder / "cameras.bin").string(), cameras);
    WriteFileAtomically((folder / "images.bin").string(), images);
    WriteFileAtomically((folder / "points3D.bin").string(), points);
  } else {
    const std::string cameras = CamerasText(scene);
    const std::string images = ImagesText(scene);
    const std::string points = Points3DText(scene);
    WriteFileAtomically((folder / "cameras.txt").string(), cameras);
    WriteFileAtomically((folder / "images.txt").string(), images);
    WriteFileAtomically((folder / "points3D.txt").string(), points);
  }
}

void WritePointsPly(const Scene& scene, const std::string& path) {
  std::string out =
      StrCat("ply\nformat binary_little_endian 1.0\nelement vertex ",
             scene.points3D.size(),
             "\nproperty float x\nproperty float y\nproperty "
             "float z\nproperty uchar red\nproperty uchar "
             "green\nproperty uchar blue\nend_header\n");
  for (const auto& [point3D_id, point] : scene.points3D) {
    for (int k = 0; k < 3; ++k)
      Append<float>(&out, static_cast<float>(point.xyz(k)));
    for (int k = 0; k < 3; ++k) Append<uint8_t>(&out, point.color(k));
  }
  WriteFileAtomically(path, out);
}

}  // namespace bayon
