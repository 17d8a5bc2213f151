// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/bal_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace bayon {
namespace {

// Numbers of a text file, one after the other, with the line each is on.
class Tokens {
 public:
  explicit Tokens(const std::string& path)
      : path_(path), text_(ReadFileToString(path)) {}

  double Number(const char* what) {
    SkipSpace();
    if (pos_ >= text_.size()) {
      ThrowInputError(path_, ":", line_, ": file ends, expected ", what);
    }
    const char* start = text_.c_str() + pos_;
    char* end = nullptr;
    const double value = std::strtod(start, &end);
    if (end == start || !std::isfinite(value)) {
      ThrowInputError(path_, ":", line_, ": expected ", what);
    }
    pos_ += end - start;
    return value;
  }

  int Index(const char* what, int limit) {
    const double value = Number(what);
    if (value < 0 || value >= limit || value != std::floor(value)) {
      ThrowInputError(path_,
                      ":",
                      line_,
                      ": ",
                      what,
                      " ",
                      value,
                      " out of range [0, ",
                      limit,
                      ")");
    }
    return static_cast<int>(value);
  }

  int line() const { return line_; }
  size_t bytes_left() const { return text_.size() - pos_; }

 private:
  void SkipSpace() {
    while (pos_ < text_.size() &&
           std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }

  std::string path_;
  std::string text_;
  size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

Scene ReadBalProblem(const std::string& path) {
  Tokens tokens(path);
  const int num_cameras = tokens.Index("the number of cameras", 1 << 30);
  const int num_points = tokens.Index("the number of points", 1 << 30);
  const int num_observations =
      tokens.Index("the number of observations", 1 << 30);
  if (num_cameras < 1 || num_points < 1 || num_observations < 2) {
    ThrowInputError(path,
                    ": an empty problem (",
                    num_cameras,
                    " cameras, ",
                    num_points,
                    " points, ",
                    num_observations,
                    " observations)");
  }
  struct Observation {
    int camera;
    int point;
    Eigen::Vector2d xy;
  };
  // Grown as they are read: a forged count would allocate before the file
  // ends (each observation takes at least 8 bytes of text).
  std::vector<Observation> observations;
  observations.reserve(
      std::min<size_t>(num_observations, tokens.bytes_left() / 8));
  double extent = 1.0;
  for (int i = 0; i < num_observations; ++i) {
    Observation& o = observations.emplace_back();
    o.camera = tokens.Index("a camera index", num_cameras);
    o.point = tokens.Index("a point index", num_points);
    o.xy.x() = tokens.Number("x");
    o.xy.y() = tokens.Number("y");
    extent = std::max(extent, o.xy.cwiseAbs().maxCoeff());
  }
  // The principal point in the middle of a square frame that holds every
  // observation (pixel coordinates must be positive for COLMAP); the frame's
  // size must fit in an int.
  if (extent > 1e8) {
    ThrowInputError(path, ": an observation lies ", extent, " pixels out");
  }
  const double centre = std::ceil(extent) + 1.0;
  const uint64_t size = static_cast<uint64_t>(2 * centre);

  Scene scene;
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  for (int c = 0; c < num_cameras; ++c) {
    double values[9];
    for (double& value : values) value = tokens.Number("a camera parameter");
    const Eigen::Vector3d rodrigues(values[0], values[1], values[2]);
    const double angle = rodrigues.norm();
    const Eigen::Matrix3d R =
        angle > 0
            ? Eigen::AngleAxisd(angle, rodrigues / angle).toRotationMatrix()
            : Eigen::Matrix3d::Identity();
    if (!(values[6] > 0)) {
      ThrowInputError(path, ": camera ", c, " has focal length ", values[6]);
    }
    Camera camera;
    camera.camera_id = static_cast<camera_t>(c + 1);
    camera.model_id = CameraModelId::kRadial;
    camera.width = size;
    camera.height = size;
    camera.params = {values[6], centre, centre, values[7], values[8]};
    camera.has_prior_focal_length = true;
    scene.cameras.Set(camera.camera_id, camera);
    Image image;
    image.image_id = static_cast<image_t>(c + 1);
    char name[32];
    std::snprintf(name, sizeof(name), "camera_%05d.png", c);
    image.name = name;
    image.camera_id = camera.camera_id;
    const Eigen::Matrix3d rotation = flip * R;
    image.cam_from_world =
        Rigid3d(Eigen::Quaterniond(rotation).normalized(),
                flip * Eigen::Vector3d(values[3], values[4], values[5]));
    scene.images.Set(image.image_id, std::move(image));
  }
  for (int p = 0; p < num_points; ++p) {
    Point3D point;
    for (int k = 0; k < 3; ++k) point.xyz(k) = tokens.Number("a coordinate");
    point.color = Eigen::Matrix<uint8_t, 3, 1>(128, 128, 128);
    scene.points3D.Set(static_cast<point3D_t>(p + 1), std::move(point));
  }
  for (const Observation& o : observations) {
    Image& image = scene.images.at(static_cast<image_t>(o.camera + 1));
    Point2D point2D;
    point2D.xy = Eigen::Vector2d(o.xy.x() + centre, centre - o.xy.y());
    point2D.point3D_id = static_cast<point3D_t>(o.point + 1);
    image.points2D.push_back(point2D);
    scene.points3D.at(point2D.point3D_id)
        .track.push_back({image.image_id,
                          static_cast<point2D_t>(image.points2D.size() - 1)});
  }
  // Points seen in fewer than two images carry no information.
  std::vector<point3D_t> lonely;
  for (const auto& [id, point] : scene.points3D) {
    if (point.track.size() < 2) lonely.push_back(id);
  }
  for (point3D_t id : lonely) {
    for (const TrackElement& e : scene.points3D.at(id).track) {
      scene.images.at(e.image_id).points2D.at(e.point2D_idx).point3D_id =
          kInvalidPoint3DId;
    }
    scene.points3D.Erase(id);
  }
  scene.UpdateReprojectionErrors();
  return scene;
}

}  // namespace bayon
