// SPDX-License-Identifier: BSD-3-Clause
//
// Camera models: COLMAP's eleven models (ids 0-10, the set COLMAP 3.8 knows)
// and the photogrammetric Brown/Beyer camera with ten additional parameters.
//
// COLMAP models map a point in the camera frame (x right, y down, z forward)
// to a pixel: (u, v) = (X/Z, Y/Z), distortion on (u, v), then
// pixel = (fx u' + cx, fy v' + cy), with the centre of the upper-left pixel at
// (0.5, 0.5). The parameter orders are COLMAP's (colmap-interop.md, 1.5).
//
// The Brown/Beyer camera (kBrownBeyer, bayon only, never written to COLMAP's
// `cameras` table) works in image coordinates: millimetres in the image frame,
// x right, y up, origin at the frame centre (the fiducial centre of a film
// frame, the pixel-grid centre of a digital image). Its 13 parameters are
//
//   c, x0, y0            nominal camera constant and principal point [mm]
//   dc, dx0, dy0         corrections to c, x0, y0 [mm]
//   K1, K2, K3           radial distortion [mm^-2, mm^-4, mm^-6]
//   P1, P2               decentring distortion [mm^-1]
//   B1, B2               affinity (scale of x) and shear (of x by y) [-]
//
// which are the ten additional parameters of Brown (1971) as extended by
// Beyer (1992, "Geometric and radiometric analysis of a CCD-camera based
// photogrammetric close-range system", ETH Zurich, Mitteilungen Nr. 51),
// the set the Bayon paper's SGAP adjustment used. The nominal values c, x0, y0
// are held fixed in adjustments; dc, dx0, dy0 are what self-calibration finds.
//
// Forward mapping, from a point (X, Y, Z) in the camera frame to image
// coordinates (x, y) in mm:
//
//   c' = c + dc
//   xb =  c' X / Z                 ideal image coordinates relative to the
//   yb = -c' Y / Z                 principal point (y up, so Y down flips)
//   r2 = xb^2 + yb^2
//   dr = K1 r2 + K2 r2^2 + K3 r2^3
//   x  = x0 + dx0 + xb + xb dr + P1 (r2 + 2 xb^2) + 2 P2 xb yb + B1 xb + B2 yb
//   y  = y0 + dy0 + yb + yb dr + 2 P1 xb yb + P2 (r2 + 2 yb^2)
//
// The corrections are functions of the ideal coordinates, so the forward
// mapping is explicit and the inverse (image point to ray) is iterative.
// The affine pair follows the unambiguous form of Fraser (1997, ISPRS J.
// 52(4)): B1 scales x, B2 shears x by y, y is left alone, so that B1 and B2
// are not correlated with a rotation of the image frame. Signs: a positive K1
// moves points outwards (pincushion), positive dc makes the image larger.
//
// Image coordinates map to pixels through the image's interior orientation
// (ImageFrame, ext/core/image_frame.h): for a digital camera the pixel pitch
// and the image centre, for a scanned film frame the affine transformation
// found from the frame's edges.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

enum class CameraModelId : int {
  kInvalid = -1,
  kSimplePinhole = 0,
  kPinhole = 1,
  kSimpleRadial = 2,
  kRadial = 3,
  kOpenCV = 4,
  kOpenCVFisheye = 5,
  kFullOpenCV = 6,
  kFOV = 7,
  kSimpleRadialFisheye = 8,
  kRadialFisheye = 9,
  kThinPrismFisheye = 10,
  // bayon's own; kept in bayon_calibration, never in COLMAP's tables.
  kBrownBeyer = 100,
};

struct CameraModelInfo {
  CameraModelId id;
  const char* name;  // COLMAP's name, e.g. "SIMPLE_RADIAL"
  int num_params;
  const char* params_info;  // comma-separated parameter names
  // Indices of the focal length(s) and principal point in params (pixels);
  // empty for kBrownBeyer, whose values are in millimetres.
  std::vector<int> focal_idxs;
  std::vector<int> principal_point_idxs;
};

// All models, COLMAP's first in id order.
const std::vector<CameraModelInfo>& CameraModels();
// Throws InputError for an unknown id.
const CameraModelInfo& CameraModelInfoFor(CameraModelId id);
bool IsKnownCameraModelId(int id);
// A model COLMAP 3.8 can store (ids 0-10).
inline bool IsColmapCameraModel(CameraModelId id) {
  return static_cast<int>(id) >= 0 && static_cast<int>(id) <= 10;
}
std::optional<CameraModelId> CameraModelIdFromName(const std::string& name);
// "SIMPLE_PINHOLE, PINHOLE, ..." for error messages.
std::string CameraModelNames();

// Indices into the Brown/Beyer parameter vector.
namespace brown {
enum : int {
  kC = 0,
  kX0,
  kY0,
  kDc,
  kDx0,
  kDy0,
  kK1,
  kK2,
  kK3,
  kP1,
  kP2,
  kB1,
  kB2,
  kNumParams
};
// The ten additional parameters, in the order of the paper and the report.
constexpr int kFirstAdditional = kDc;
constexpr int kNumAdditional = 10;
}  // namespace brown

// ---------------------------------------------------------------------------
// Templated mappings, usable with ceres::Jet for automatic differentiation.

// Applies the model's distortion to normalized coordinates (u, v) for the
// COLMAP models. `extra` points at the first distortion parameter.
template <typename T>
void DistortNormalized(
    CameraModelId model, const T* extra, const T& u, const T& v, T* ud, T* vd);

// COLMAP models: camera frame point -> pixel. Returns false for points at or
// behind the camera (Z <= 0), leaving `pixel` unset.
template <typename T>
bool ColmapImgFromCam(CameraModelId model,
                      const T* params,
                      const T* point_in_cam,
                      T* pixel);

// Brown/Beyer: camera frame point -> image coordinates in mm (formulas above).
template <typename T>
bool BrownBeyerFrameFromCam(const T* params, const T* point_in_cam, T* xy_mm);

// ---------------------------------------------------------------------------
// Implementation.

namespace internal {

template <typename T>
void FisheyeTheta(const T& u, const T& v, T* theta_over_r, T* theta) {
  using std::atan;
  using std::sqrt;
  const T r2 = u * u + v * v;
  // At the optical axis atan(r)/r -> 1; the series keeps derivatives finite.
  if (r2 < T(1e-16)) {
    *theta_over_r = T(1) - r2 / T(3);
    *theta = sqrt(r2 + T(1e-300));
  } else {
    const T r = sqrt(r2);
    *theta = atan(r);
    *theta_over_r = *theta / r;
  }
}

}  // namespace internal

template <typename T>
void DistortNormalized(
    CameraModelId model, const T* extra, const T& u, const T& v, T* ud, T* vd) {
  using std::atan;
  using std::sqrt;
  using std::tan;
  const T u2 = u * u;
  const T v2 = v * v;
  const T uv = u * v;
  const T r2 = u2 + v2;
  switch (model) {
    case CameraModelId::kSimplePinhole:
    case CameraModelId::kPinhole:
      *ud = u;
      *vd = v;
      return;
    case CameraModelId::kSimpleRadial: {
      const T radial = T(1) + extra[0] * r2;
      *ud = u * radial;
      *vd = v * radial;
      return;
    }
    case CameraModelId::kRadial: {
      const T radial = T(1) + extra[0] * r2 + extra[1] * r2 * r2;
      *ud = u * radial;
      *vd = v * radial;
      return;
    }
    case CameraModelId::kOpenCV: {
      const T &k1 = extra[0], &k2 = extra[1], &p1 = extra[2], &p2 = extra[3];
      const T radial = T(1) + k1 * r2 + k2 * r2 * r2;
      *ud = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2);
      *vd = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2);
      return;
    }
    case CameraModelId::kFullOpenCV: {
      const T &k1 = extra[0], &k2 = extra[1], &p1 = extra[2], &p2 = extra[3];
      const T &k3 = extra[4], &k4 = extra[5], &k5 = extra[6], &k6 = extra[7];
      const T r4 = r2 * r2;
      const T r6 = r4 * r2;
      const T radial = (T(1) + k1 * r2 + k2 * r4 + k3 * r6) /
                       (T(1) + k4 * r2 + k5 * r4 + k6 * r6);
      *ud = u * radial + T(2) * p1 * uv + p2 * (r2 + T(2) * u2);
      *vd = v * radial + T(2) * p2 * uv + p1 * (r2 + T(2) * v2);
      return;
    }
    case CameraModelId::kOpenCVFisheye:
    case CameraModelId::kSimpleRadialFisheye:
    case CameraModelId::kRadialFisheye: {
      T theta_over_r, theta;
      internal::FisheyeTheta(u, v, &theta_over_r, &theta);
      const T t2 = theta * theta;
      T factor = T(1);
      if (model == CameraModelId::kSimpleRadialFisheye) {
        factor = T(1) + extra[0] * t2;
      } else if (model == CameraModelId::kRadialFisheye) {
        factor = T(1) + extra[0] * t2 + extra[1] * t2 * t2;
      } else {
        const T t4 = t2 * t2;
        factor = T(1) + extra[0] * t2 + extra[1] * t4 + extra[2] * t4 * t2 +
                 extra[3] * t4 * t4;
      }
      *ud = u * theta_over_r * factor;
      *vd = v * theta_over_r * factor;
      return;
    }
    case CameraModelId::kFOV: {
      const T& omega = extra[0];
      // Devernay-Faugeras: rd = atan(2 r tan(omega/2)) / omega. Near r = 0 or
      // omega = 0 the limits are used so that Jacobians stay finite.
      T factor;
      if (omega * omega < T(1e-16)) {
        factor = T(1);
      } else if (r2 < T(1e-16)) {
        factor = T(2) * tan(omega / T(2)) / omega;
      } else {
        const T r = sqrt(r2);
        factor = atan(r * T(2) * tan(omega / T(2))) / (r * omega);
      }
      *ud = u * factor;
      *vd = v * factor;
      return;
    }
    case CameraModelId::kThinPrismFisheye: {
      T theta_over_r, theta;
      internal::FisheyeTheta(u, v, &theta_over_r, &theta);
      const T uu = u * theta_over_r;
      const T vv = v * theta_over_r;
      const T &k1 = extra[0], &k2 = extra[1], &p1 = extra[2], &p2 = extra[3];
      const T &k3 = extra[4], &k4 = extra[5], &sx1 = extra[6], &sy1 = extra[7];
      const T q2 = uu * uu + vv * vv;
      const T q4 = q2 * q2;
      const T radial = k1 * q2 + k2 * q4 + k3 * q4 * q2 + k4 * q4 * q4;
      *ud = uu + uu * radial + T(2) * p1 * uu * vv +
            p2 * (q2 + T(2) * uu * uu) + sx1 * q2;
      *vd = vv + vv * radial + T(2) * p2 * uu * vv +
            p1 * (q2 + T(2) * vv * vv) + sy1 * q2;
      return;
    }
    default:
      *ud = u;
      *vd = v;
      return;
  }
}

template <typename T>
bool ColmapImgFromCam(CameraModelId model,
                      const T* params,
                      const T* point_in_cam,
                      T* pixel) {
  if (!(point_in_cam[2] > T(0))) return false;
  const T u = point_in_cam[0] / point_in_cam[2];
  const T v = point_in_cam[1] / point_in_cam[2];
  T ud, vd;
  switch (model) {
    case CameraModelId::kSimplePinhole:
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kRadial:
    case CameraModelId::kSimpleRadialFisheye:
    case CameraModelId::kRadialFisheye:
      DistortNormalized(model, params + 3, u, v, &ud, &vd);
      pixel[0] = params[0] * ud + params[1];
      pixel[1] = params[0] * vd + params[2];
      return true;
    case CameraModelId::kPinhole:
    case CameraModelId::kOpenCV:
    case CameraModelId::kOpenCVFisheye:
    case CameraModelId::kFullOpenCV:
    case CameraModelId::kFOV:
    case CameraModelId::kThinPrismFisheye:
      DistortNormalized(model, params + 4, u, v, &ud, &vd);
      pixel[0] = params[0] * ud + params[2];
      pixel[1] = params[1] * vd + params[3];
      return true;
    default:
      return false;
  }
}

template <typename T>
bool BrownBeyerFrameFromCam(const T* params, const T* point_in_cam, T* xy_mm) {
  if (!(point_in_cam[2] > T(0))) return false;
  using namespace brown;
  const T c = params[kC] + params[kDc];
  const T xb = c * point_in_cam[0] / point_in_cam[2];
  const T yb = -c * point_in_cam[1] / point_in_cam[2];
  const T xb2 = xb * xb;
  const T yb2 = yb * yb;
  const T r2 = xb2 + yb2;
  const T dr =
      params[kK1] * r2 + params[kK2] * r2 * r2 + params[kK3] * r2 * r2 * r2;
  const T& p1 = params[kP1];
  const T& p2 = params[kP2];
  xy_mm[0] = params[kX0] + params[kDx0] + xb + xb * dr +
             p1 * (r2 + T(2) * xb2) + T(2) * p2 * xb * yb + params[kB1] * xb +
             params[kB2] * yb;
  xy_mm[1] = params[kY0] + params[kDy0] + yb + yb * dr + T(2) * p1 * xb * yb +
             p2 * (r2 + T(2) * yb2);
  return true;
}

}  // namespace bayon
