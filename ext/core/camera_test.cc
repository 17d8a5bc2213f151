// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/camera.h"

#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <random>

namespace bayon {
namespace {

// A camera like the Bayon paper's: c = 35 mm on a 36 x 24 mm frame, 1800 x 1200
// pixels of 20 um, with every additional parameter non-zero.
Camera PaperCamera(double shear = -1e-4) {
  Camera camera =
      Camera::Create(CameraModelId::kBrownBeyer, 35.0 / 0.02, 1800, 1200, 0.02);
  camera.camera_id = 1;
  auto& p = camera.params;
  p[brown::kX0] = 0.05;
  p[brown::kY0] = -0.04;
  p[brown::kDc] = 0.08;
  p[brown::kDx0] = 0.03;
  p[brown::kDy0] = -0.02;
  p[brown::kK1] = -5e-5;
  p[brown::kK2] = 3e-8;
  p[brown::kK3] = -1e-11;
  p[brown::kP1] = 1e-5;
  p[brown::kP2] = -8e-6;
  p[brown::kB1] = 2e-4;
  p[brown::kB2] = shear;
  return camera;
}

Camera ColmapCamera(CameraModelId model) {
  Camera camera = Camera::Create(model, 800, 1000, 700);
  camera.camera_id = 2;
  const CameraModelInfo& info = camera.ModelInfo();
  if (info.focal_idxs.size() == 2) camera.params[1] = 810;
  camera.params[info.principal_point_idxs[0]] = 507;
  camera.params[info.principal_point_idxs[1]] = 344;
  const size_t first_extra = info.focal_idxs.size() + 2;
  const double extras[] = {
      -0.08, 0.01, 0.001, -0.0007, 0.002, 0.01, 0.002, 0.0005};
  for (size_t i = first_extra; i < camera.params.size(); ++i) {
    camera.params[i] = extras[i - first_extra];
  }
  return camera;
}

std::vector<Camera> AllCameras() {
  std::vector<Camera> cameras = {PaperCamera()};
  for (const auto& info : CameraModels()) {
    if (IsColmapCameraModel(info.id)) cameras.push_back(ColmapCamera(info.id));
  }
  return cameras;
}

TEST(Camera, ForwardInverseRoundTripOverTheFrame) {
  for (const Camera& camera : AllCameras()) {
    double max_error = 0;
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) {
        const Eigen::Vector2d pixel(camera.width * i / 20.0,
                                    camera.height * j / 20.0);
        Eigen::Vector3d ray;
        ASSERT_TRUE(camera.CamFromImg(pixel, &ray))
            << camera.ModelName() << " at " << pixel.transpose();
        const Eigen::Vector2d back = camera.ImgFromCam(3.7 * ray);
        max_error = std::max(max_error, (back - pixel).norm());
      }
    }
    EXPECT_LT(max_error, 1e-6) << camera.ModelName();
  }
}

TEST(Camera, BrownBeyerCorrectionsHaveTheDocumentedSigns) {
  Camera camera = PaperCamera(0);
  for (int idx = brown::kFirstAdditional; idx < brown::kNumParams; ++idx) {
    camera.params[idx] = 0;
  }
  camera.params[brown::kX0] = camera.params[brown::kY0] = 0;
  // A point on the x axis at 10 mm image radius: c X/Z = 10.
  const Eigen::Vector3d point(10.0 / 35.0, 0.0, 1.0);
  Eigen::Vector2d xy;
  ASSERT_TRUE(camera.FrameFromCam(point, &xy));
  EXPECT_NEAR(xy.x(), 10.0, 1e-12);
  camera.params[brown::kK1] = 1e-4;  // pincushion: outwards by x r^2 K1
  ASSERT_TRUE(camera.FrameFromCam(point, &xy));
  EXPECT_NEAR(xy.x(), 10.0 + 10.0 * 100.0 * 1e-4, 1e-12);
  camera.params[brown::kK1] = 0;
  camera.params[brown::kDc] = 0.35;  // c' = 1.01 c: 1 % larger image
  ASSERT_TRUE(camera.FrameFromCam(point, &xy));
  EXPECT_NEAR(xy.x(), 10.1, 1e-12);
  // y up: a point below the axis in the camera frame (Y > 0) has y < 0.
  ASSERT_TRUE(camera.FrameFromCam(Eigen::Vector3d(0, 0.1, 1), &xy));
  EXPECT_LT(xy.y(), 0);
  // Pixels: y up in mm is y down in pixels, the frame centre is the image
  // centre.
  EXPECT_NEAR(camera.DefaultFrame().PixelFromFrame(Eigen::Vector2d(0, 0)).x(),
              900,
              1e-12);
  EXPECT_NEAR(camera.DefaultFrame().PixelFromFrame(Eigen::Vector2d(0, 1)).y(),
              550,
              1e-12);
}

// Camera-frame point -> pixel through the templated model, for Ceres.
struct ProjectionFunctor {
  ProjectionFunctor(const Camera& camera) : camera(camera) {}
  template <typename T>
  bool operator()(T const* const* blocks, T* pixel) const {
    const T* params = blocks[0];
    const T* point = blocks[1];
    if (camera.model_id == CameraModelId::kBrownBeyer) {
      T xy[2];
      if (!BrownBeyerFrameFromCam(params, point, xy)) return false;
      camera.DefaultFrame().PixelFromFrame(xy, pixel);
      return true;
    }
    return ColmapImgFromCam(camera.model_id, params, point, pixel);
  }
  Camera camera;
};

TEST(Camera, AutodiffJacobiansEqualFiniteDifferences) {
  for (const Camera& camera : AllCameras()) {
    const int n = static_cast<int>(camera.params.size());
    auto* cost = new ceres::DynamicAutoDiffCostFunction<ProjectionFunctor, 4>(
        new ProjectionFunctor(camera));
    cost->AddParameterBlock(n);
    cost->AddParameterBlock(3);
    cost->SetNumResiduals(2);
    std::unique_ptr<ceres::CostFunction> owner(cost);
    std::vector<double> params = camera.params;
    double point[3] = {0.21, -0.13, 1.7};
    const double* blocks[2] = {params.data(), point};
    std::vector<double> jac_params(2 * n), jac_point(6);
    double* jacobians[2] = {jac_params.data(), jac_point.data()};
    double pixel[2];
    ASSERT_TRUE(cost->Evaluate(blocks, pixel, jacobians));
    EXPECT_NEAR(
        (camera.ImgFromCam(Eigen::Vector3d(point[0], point[1], point[2])) -
         Eigen::Vector2d(pixel[0], pixel[1]))
            .norm(),
        0,
        1e-9);
    // Central differences with a step that moves the pixel by about 1e-4 px,
    // so that round-off (pixels are ~1e3) and curvature both stay small.
    const Eigen::Vector3d p(point[0], point[1], point[2]);
    for (int j = 0; j < n; ++j) {
      const double slope =
          std::max(std::abs(jac_params[j]), std::abs(jac_params[n + j]));
      if (slope == 0) continue;  // c and dc of Brown are checked through dc
      const double h = 1e-4 / slope;
      Camera plus = camera, minus = camera;
      plus.params[j] += h;
      minus.params[j] -= h;
      const Eigen::Vector2d numeric =
          (plus.ImgFromCam(p) - minus.ImgFromCam(p)) / (2 * h);
      for (int r = 0; r < 2; ++r) {
        EXPECT_NEAR(jac_params[r * n + j], numeric(r), 1e-6 * slope)
            << camera.ModelName() << " param " << j;
      }
    }
    for (int j = 0; j < 3; ++j) {
      const double h = 1e-7;
      Eigen::Vector3d plus(point[0], point[1], point[2]), minus = plus;
      plus(j) += h;
      minus(j) -= h;
      const Eigen::Vector2d numeric =
          (camera.ImgFromCam(plus) - camera.ImgFromCam(minus)) / (2 * h);
      for (int r = 0; r < 2; ++r) {
        EXPECT_NEAR(jac_point[r * 3 + j],
                    numeric(r),
                    1e-5 * std::max(1.0, std::abs(numeric(r))))
            << camera.ModelName() << " point coordinate " << j;
      }
    }
  }
}

TEST(CameraConversion, BrownBeyerWithoutShearFitsFullOpenCVClosely) {
  const CameraConversion conversion =
      ConvertCamera(PaperCamera(0.0), CameraModelId::kFullOpenCV);
  // Only the second-order product B1 * distortion is not expressible.
  EXPECT_LT(conversion.rms_residual_px, 0.01);
  EXPECT_LT(conversion.max_residual_px, 0.05);
  EXPECT_EQ(conversion.camera.model_id, CameraModelId::kFullOpenCV);
  EXPECT_EQ(conversion.camera.camera_id, 1u);
}

TEST(CameraConversion, ShearShowsUpAsResidual) {
  // A shear of 1e-3 moves frame corners by 12 mm * 1e-3 = 0.6 px.
  const CameraConversion conversion =
      ConvertCamera(PaperCamera(1e-3), CameraModelId::kFullOpenCV);
  EXPECT_GT(conversion.max_residual_px, 0.1);
  EXPECT_GT(conversion.rms_residual_px, 0.05);
}

TEST(CameraConversion, ExactWhereTheModelCanExpressTheCamera) {
  // A pinhole Brown camera (only c and the principal point) is exactly PINHOLE.
  Camera pinhole = PaperCamera(0);
  for (int idx = brown::kK1; idx < brown::kNumParams; ++idx)
    pinhole.params[idx] = 0;
  for (CameraModelId model : {CameraModelId::kSimplePinhole,
                              CameraModelId::kPinhole,
                              CameraModelId::kOpenCV,
                              CameraModelId::kFullOpenCV}) {
    const CameraConversion conversion = ConvertCamera(pinhole, model);
    EXPECT_LT(conversion.max_residual_px, 1e-6)
        << CameraModelInfoFor(model).name;
  }
  // And back: a COLMAP OPENCV camera to BROWN_BEYER and to FULL_OPENCV.
  // With fx = fy: B1 scales x after the distortion, OpenCV's fx before it,
  // which differ by B1 times the distortion.
  Camera opencv = ColmapCamera(CameraModelId::kOpenCV);
  opencv.params[1] = opencv.params[0];
  const CameraConversion to_full =
      ConvertCamera(opencv, CameraModelId::kFullOpenCV);
  EXPECT_LT(to_full.max_residual_px, 1e-6);
  CameraConversionOptions options;
  options.pixel_pitch_mm = 0.005;
  const CameraConversion to_brown =
      ConvertCamera(opencv, CameraModelId::kBrownBeyer, options);
  EXPECT_LT(to_brown.max_residual_px, 0.02);
  EXPECT_NEAR(to_brown.camera.pixel_pitch_mm, 0.005, 1e-15);
}

TEST(CameraConversion, SimpleRadialCannotHoldTangentialDistortion) {
  Camera camera = PaperCamera(0);
  camera.params[brown::kP1] = 5e-5;
  const CameraConversion conversion =
      ConvertCamera(camera, CameraModelId::kSimpleRadial);
  EXPECT_GT(conversion.max_residual_px, 0.5);
}

TEST(Camera, CheckRejectsWrongParameterCount) {
  Camera camera = ColmapCamera(CameraModelId::kOpenCV);
  camera.params.pop_back();
  EXPECT_THROW(camera.Check(), InputError);
}

}  // namespace
}  // namespace bayon
