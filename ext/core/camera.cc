// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/camera.h"

#include "ext/core/errors.h"

#include <Eigen/Dense>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace bayon {
namespace {

// Solves distort(x) = target for x by Newton's method with a central-difference
// Jacobian, starting at `start`. Used for every model's inverse mapping.
template <typename DistortFn>
bool InvertDistortion(const DistortFn& distort,
                      const Eigen::Vector2d& target,
                      const Eigen::Vector2d& start,
                      double tolerance,
                      Eigen::Vector2d* solution) {
  constexpr int kMaxIterations = 100;
  Eigen::Vector2d x = start;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const Eigen::Vector2d fx = distort(x);
    const Eigen::Vector2d error = fx - target;
    if (!error.allFinite()) return false;
    if (error.norm() < tolerance) {
      *solution = x;
      return true;
    }
    Eigen::Matrix2d jacobian;
    for (int j = 0; j < 2; ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(x(j)));
      Eigen::Vector2d xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      jacobian.col(j) = (distort(xp) - distort(xm)) / (2 * h);
    }
    const double det = jacobian.determinant();
    if (!std::isfinite(det) || std::abs(det) < 1e-300) return false;
    Eigen::Vector2d step = jacobian.inverse() * error;
    // Damp steps that would jump far: the distortion polynomials turn back
    // outside the calibrated field, and the root we want is the inner one.
    const double max_step = 0.5 * std::max(1.0, x.norm());
    if (step.norm() > max_step) step *= max_step / step.norm();
    x -= step;
  }
  const Eigen::Vector2d error = distort(x) - target;
  if (error.allFinite() && error.norm() < 100 * tolerance) {
    *solution = x;
    return true;
  }
  return false;
}

}  // namespace

const std::vector<CameraModelInfo>& CameraModels() {
  static const std::vector<CameraModelInfo> kModels = {
      {CameraModelId::kSimplePinhole,
       "SIMPLE_PINHOLE",
       3,
       "f, cx, cy",
       {0},
       {1, 2}},
      {CameraModelId::kPinhole, "PINHOLE", 4, "fx, fy, cx, cy", {0, 1}, {2, 3}},
      {CameraModelId::kSimpleRadial,
       "SIMPLE_RADIAL",
       4,
       "f, cx, cy, k",
       {0},
       {1, 2}},
      {CameraModelId::kRadial, "RADIAL", 5, "f, cx, cy, k1, k2", {0}, {1, 2}},
      {CameraModelId::kOpenCV,
       "OPENCV",
       8,
       "fx, fy, cx, cy, k1, k2, p1, p2",
       {0, 1},
       {2, 3}},
      {CameraModelId::kOpenCVFisheye,
       "OPENCV_FISHEYE",
       8,
       "fx, fy, cx, cy, k1, k2, k3, k4",
       {0, 1},
       {2, 3}},
      {CameraModelId::kFullOpenCV,
       "FULL_OPENCV",
       12,
       "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6",
       {0, 1},
       {2, 3}},
      {CameraModelId::kFOV, "FOV", 5, "fx, fy, cx, cy, omega", {0, 1}, {2, 3}},
      {CameraModelId::kSimpleRadialFisheye,
       "SIMPLE_RADIAL_FISHEYE",
       4,
       "f, cx, cy, k",
       {0},
       {1, 2}},
      {CameraModelId::kRadialFisheye,
       "RADIAL_FISHEYE",
       5,
       "f, cx, cy, k1, k2",
       {0},
       {1, 2}},
      {CameraModelId::kThinPrismFisheye,
       "THIN_PRISM_FISHEYE",
       12,
       "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1",
       {0, 1},
       {2, 3}},
      {CameraModelId::kBrownBeyer,
       "BROWN_BEYER",
       brown::kNumParams,
       "c, x0, y0, dc, dx0, dy0, K1, K2, K3, P1, P2, B1, B2",
       {},
       {}},
  };
  return kModels;
}

bool IsKnownCameraModelId(int id) {
  for (const auto& info : CameraModels()) {
    if (static_cast<int>(info.id) == id) return true;
  }
  return false;
}

const CameraModelInfo& CameraModelInfoFor(CameraModelId id) {
  for (const auto& info : CameraModels()) {
    if (info.id == id) return info;
  }
  ThrowInputError("unknown camera model id ",
                  static_cast<int>(id),
                  " (known: ",
                  CameraModelNames(),
                  ")");
}

std::optional<CameraModelId> CameraModelIdFromName(const std::string& name) {
  for (const auto& info : CameraModels()) {
    if (name == info.name) return info.id;
  }
  return std::nullopt;
}

std::string CameraModelNames() {
  std::string names;
  for (const auto& info : CameraModels()) {
    if (!names.empty()) names += ", ";
    names += info.name;
  }
  return names;
}

Camera Camera::Create(CameraModelId model_id,
                      double focal_length_px,
                      uint64_t width,
                      uint64_t height,
                      double pixel_pitch_mm) {
  Camera camera;
  camera.model_id = model_id;
  camera.width = width;
  camera.height = height;
  const CameraModelInfo& info = CameraModelInfoFor(model_id);
  camera.params.assign(info.num_params, 0.0);
  if (model_id == CameraModelId::kBrownBeyer) {
    CheckOption(pixel_pitch_mm > 0,
                "pixel_pitch_mm",
                "> 0 for BROWN_BEYER",
                pixel_pitch_mm);
    camera.pixel_pitch_mm = pixel_pitch_mm;
    camera.params[brown::kC] = focal_length_px * pixel_pitch_mm;
    return camera;
  }
  for (int idx : info.focal_idxs) camera.params[idx] = focal_length_px;
  camera.params[info.principal_point_idxs[0]] = 0.5 * width;
  camera.params[info.principal_point_idxs[1]] = 0.5 * height;
  return camera;
}

void Camera::Check() const {
  const CameraModelInfo& info = CameraModelInfoFor(model_id);
  if (static_cast<int>(params.size()) != info.num_params) {
    ThrowInputError("camera ",
                    camera_id,
                    ": model ",
                    info.name,
                    " takes ",
                    info.num_params,
                    " parameters (",
                    info.params_info,
                    "), got ",
                    params.size());
  }
  if (width == 0 || height == 0) {
    ThrowInputError("camera ",
                    camera_id,
                    ": image size ",
                    width,
                    "x",
                    height,
                    " must be positive");
  }
  for (double value : params) {
    if (!std::isfinite(value)) {
      ThrowInputError("camera ", camera_id, ": parameter is not finite");
    }
  }
  if (model_id == CameraModelId::kBrownBeyer && !(pixel_pitch_mm > 0)) {
    ThrowInputError(
        "camera ", camera_id, ": BROWN_BEYER needs a positive pixel pitch");
  }
}

ImageFrame Camera::DefaultFrame() const {
  const double pitch = pixel_pitch_mm > 0 ? pixel_pitch_mm : 1.0;
  return ImageFrame::Digital(
      static_cast<double>(width), static_cast<double>(height), pitch);
}

double Camera::MeanFocalLengthPx() const {
  if (model_id == CameraModelId::kBrownBeyer) {
    return (params[brown::kC] + params[brown::kDc]) / pixel_pitch_mm;
  }
  const auto& idxs = ModelInfo().focal_idxs;
  double sum = 0;
  for (int idx : idxs) sum += params[idx];
  return sum / idxs.size();
}

Eigen::Vector2d Camera::PrincipalPointPx() const {
  if (model_id == CameraModelId::kBrownBeyer) {
    const Eigen::Vector2d pp_mm(params[brown::kX0] + params[brown::kDx0],
                                params[brown::kY0] + params[brown::kDy0]);
    return DefaultFrame().PixelFromFrame(pp_mm);
  }
  const auto& idxs = ModelInfo().principal_point_idxs;
  return Eigen::Vector2d(params[idxs[0]], params[idxs[1]]);
}

bool Camera::FrameFromCam(const Eigen::Vector3d& point_in_cam,
                          Eigen::Vector2d* xy_mm) const {
  return BrownBeyerFrameFromCam(
      params.data(), point_in_cam.data(), xy_mm->data());
}

bool Camera::CamFromFrame(const Eigen::Vector2d& xy_mm,
                          Eigen::Vector3d* ray) const {
  using namespace brown;
  const double c = params[kC] + params[kDc];
  // Solve for the ideal coordinates relative to the principal point.
  auto distort = [&](const Eigen::Vector2d& xb) {
    const Eigen::Vector3d point(xb.x() / c, -xb.y() / c, 1.0);
    Eigen::Vector2d xy;
    BrownBeyerFrameFromCam(params.data(), point.data(), xy.data());
    return xy;
  };
  const Eigen::Vector2d start(xy_mm.x() - params[kX0] - params[kDx0],
                              xy_mm.y() - params[kY0] - params[kDy0]);
  Eigen::Vector2d xb;
  // 1e-12 mm is far below any pixel (1e-6 px at 1 um pitch).
  if (!InvertDistortion(distort, xy_mm, start, 1e-12, &xb)) return false;
  *ray = Eigen::Vector3d(xb.x() / c, -xb.y() / c, 1.0);
  return true;
}

bool Camera::ImgFromCam(const Eigen::Vector3d& point_in_cam,
                        Eigen::Vector2d* pixel,
                        const ImageFrame* frame) const {
  if (model_id == CameraModelId::kBrownBeyer) {
    Eigen::Vector2d xy_mm;
    if (!FrameFromCam(point_in_cam, &xy_mm)) return false;
    *pixel = (frame ? *frame : DefaultFrame()).PixelFromFrame(xy_mm);
    return true;
  }
  return ColmapImgFromCam(
      model_id, params.data(), point_in_cam.data(), pixel->data());
}

Eigen::Vector2d Camera::ImgFromCam(const Eigen::Vector3d& point_in_cam,
                                   const ImageFrame* frame) const {
  Eigen::Vector2d pixel;
  if (!ImgFromCam(point_in_cam, &pixel, frame)) {
    pixel.setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return pixel;
}

bool Camera::CamFromImg(const Eigen::Vector2d& pixel,
                        Eigen::Vector3d* ray,
                        const ImageFrame* frame) const {
  if (model_id == CameraModelId::kBrownBeyer) {
    const Eigen::Vector2d xy_mm =
        (frame ? *frame : DefaultFrame()).FrameFromPixel(pixel);
    return CamFromFrame(xy_mm, ray);
  }
  // Normalized distorted coordinates, then undistort iteratively.
  const CameraModelInfo& info = ModelInfo();
  const double fx = params[info.focal_idxs.front()];
  const double fy = params[info.focal_idxs.back()];
  const double cx = params[info.principal_point_idxs[0]];
  const double cy = params[info.principal_point_idxs[1]];
  const Eigen::Vector2d distorted((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  const double* extra = params.data() + info.focal_idxs.size() + 2;
  auto distort = [&](const Eigen::Vector2d& uv) {
    Eigen::Vector2d out;
    DistortNormalized(model_id, extra, uv.x(), uv.y(), &out.x(), &out.y());
    return out;
  };
  Eigen::Vector2d uv;
  // 1e-13 in normalized units is about 1e-9 px for focal lengths below 10^4.
  if (!InvertDistortion(distort, distorted, distorted, 1e-13, &uv)) {
    return false;
  }
  *ray = Eigen::Vector3d(uv.x(), uv.y(), 1.0);
  return true;
}

Eigen::Vector3d Camera::CamFromImg(const Eigen::Vector2d& pixel,
                                   const ImageFrame* frame) const {
  Eigen::Vector3d ray;
  if (!CamFromImg(pixel, &ray, frame)) {
    ray.setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return ray;
}

std::string Camera::ParamsToString() const {
  std::ostringstream stream;
  stream << std::setprecision(10);
  std::istringstream names(ModelInfo().params_info);
  std::string name;
  for (size_t i = 0; i < params.size(); ++i) {
    std::getline(names, name, ',');
    if (!name.empty() && name[0] == ' ') name.erase(0, 1);
    if (i > 0) stream << ", ";
    stream << name << "=" << params[i];
  }
  if (model_id == CameraModelId::kBrownBeyer) {
    stream << ", pitch=" << pixel_pitch_mm << "mm";
  }
  return stream.str();
}

void CheckNumCameraParams(CameraModelId model,
                          size_t num_values,
                          const std::string& flag) {
  const CameraModelInfo& info = CameraModelInfoFor(model);
  if (num_values != static_cast<size_t>(info.num_params)) {
    ThrowInputError(flag,
                    ": ",
                    num_values,
                    " values, but ",
                    info.name,
                    " has ",
                    info.num_params,
                    " parameters (",
                    info.params_info,
                    ")");
  }
}

}  // namespace bayon
