// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/camera_conversion.h"

#include "ext/core/errors.h"
#include "ext/core/least_squares.h"

#include <cmath>
#include <vector>

namespace bayon {
namespace {

struct Sample {
  Eigen::Vector3d ray;
  Eigen::Vector2d pixel;
};

std::vector<Sample> SampleRays(const Camera& source, int grid_size) {
  std::vector<Sample> samples;
  samples.reserve(grid_size * grid_size);
  for (int i = 0; i < grid_size; ++i) {
    for (int j = 0; j < grid_size; ++j) {
      const Eigen::Vector2d pixel(
          source.width * static_cast<double>(i) / (grid_size - 1),
          source.height * static_cast<double>(j) / (grid_size - 1));
      Eigen::Vector3d ray;
      if (source.CamFromImg(pixel, &ray)) samples.push_back({ray, pixel});
    }
  }
  return samples;
}

// Initial target camera: same focal length and principal point, no distortion.
Camera InitialTarget(const Camera& source,
                     CameraModelId target_model,
                     double pitch_mm) {
  Camera target = Camera::Create(target_model,
                                 source.MeanFocalLengthPx(),
                                 source.width,
                                 source.height,
                                 pitch_mm);
  target.camera_id = source.camera_id;
  target.has_prior_focal_length = source.has_prior_focal_length;
  const Eigen::Vector2d pp = source.PrincipalPointPx();
  if (target_model == CameraModelId::kBrownBeyer) {
    const Eigen::Vector2d pp_mm = target.DefaultFrame().FrameFromPixel(pp);
    target.params[brown::kX0] = pp_mm.x();
    target.params[brown::kY0] = pp_mm.y();
  } else {
    const auto& idxs = target.ModelInfo().principal_point_idxs;
    target.params[idxs[0]] = pp.x();
    target.params[idxs[1]] = pp.y();
  }
  return target;
}

}  // namespace

void CameraConversionOptions::Check() const {
  CheckOption(
      grid_size >= 5, "CameraConversionOptions.grid_size", ">= 5", grid_size);
  CheckOption(pixel_pitch_mm >= 0,
              "CameraConversionOptions.pixel_pitch_mm",
              ">= 0",
              pixel_pitch_mm);
}

CameraConversion ConvertCamera(const Camera& source,
                               CameraModelId target_model,
                               const CameraConversionOptions& options) {
  options.Check();
  source.Check();
  double pitch_mm = options.pixel_pitch_mm;
  if (pitch_mm == 0) {
    pitch_mm = source.pixel_pitch_mm > 0
                   ? source.pixel_pitch_mm
                   : 36.0 / std::max(source.width, source.height);
  }
  Camera target = InitialTarget(source, target_model, pitch_mm);

  // Which parameters are free, and their typical magnitudes for the
  // finite-difference steps.
  std::vector<int> free_idxs;
  std::vector<double> scales;
  const double size_px = std::max(source.width, source.height);
  if (target_model == CameraModelId::kBrownBeyer) {
    // c, x0, y0 are the nominal values (fixed); dc, dx0, dy0 absorb the rest.
    const double radius_mm =
        0.5 * pitch_mm *
        std::hypot(static_cast<double>(source.width), source.height);
    const double r2 = radius_mm * radius_mm;
    const double kScales[brown::kNumParams] = {0,
                                               0,
                                               0,
                                               1,
                                               1,
                                               1,
                                               1 / r2,
                                               1 / (r2 * r2),
                                               1 / (r2 * r2 * r2),
                                               1 / radius_mm,
                                               1 / radius_mm,
                                               1e-2,
                                               1e-2};
    for (int idx = brown::kFirstAdditional; idx < brown::kNumParams; ++idx) {
      free_idxs.push_back(idx);
      scales.push_back(kScales[idx]);
    }
  } else {
    const CameraModelInfo& info = target.ModelInfo();
    for (int idx = 0; idx < info.num_params; ++idx) {
      const bool rational = target_model == CameraModelId::kFullOpenCV &&
                            idx >= 9 && !options.fit_rational_terms;
      if (rational) continue;
      const bool intrinsic = idx < static_cast<int>(info.focal_idxs.size()) + 2;
      free_idxs.push_back(idx);
      scales.push_back(intrinsic ? size_px : 1.0);
    }
  }

  const std::vector<Sample> samples = SampleRays(source, options.grid_size);
  if (samples.size() < free_idxs.size()) {
    ThrowInputError("camera ",
                    source.camera_id,
                    ": too few invertible pixels to convert from ",
                    source.ModelName());
  }

  auto residuals = [&](const Eigen::VectorXd& x) {
    Camera trial = target;
    for (size_t k = 0; k < free_idxs.size(); ++k)
      trial.params[free_idxs[k]] = x(k);
    Eigen::VectorXd r(2 * samples.size());
    for (size_t i = 0; i < samples.size(); ++i) {
      Eigen::Vector2d pixel;
      if (!trial.ImgFromCam(samples[i].ray, &pixel)) {
        pixel.setConstant(1e6);
      }
      r.segment<2>(2 * i) = pixel - samples[i].pixel;
    }
    return r;
  };

  Eigen::VectorXd x(free_idxs.size());
  for (size_t k = 0; k < free_idxs.size(); ++k)
    x(k) = target.params[free_idxs[k]];
  Eigen::VectorXd scale_vector =
      Eigen::Map<const Eigen::VectorXd>(scales.data(), scales.size());
  LevenbergMarquardtOptions lm_options;
  lm_options.max_iterations = 200;
  SolveLevenbergMarquardt(residuals, scale_vector, lm_options, &x);
  for (size_t k = 0; k < free_idxs.size(); ++k)
    target.params[free_idxs[k]] = x(k);

  CameraConversion conversion;
  const Eigen::VectorXd r = residuals(x);
  double sum_sq = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double e = r.segment<2>(2 * i).norm();
    sum_sq += e * e;
    conversion.max_residual_px = std::max(conversion.max_residual_px, e);
  }
  conversion.num_samples = static_cast<int>(samples.size());
  conversion.rms_residual_px = std::sqrt(sum_sq / samples.size());
  conversion.camera = target;
  return conversion;
}

}  // namespace bayon

#include "ext/core/scene.h"

namespace bayon {

std::vector<SceneCameraConversion> ConvertSceneCamerasToColmap(
    Scene* scene, const CameraConversionOptions& options) {
  std::vector<SceneCameraConversion> conversions;
  for (auto& [camera_id, camera] : scene->cameras) {
    if (IsColmapCameraModel(camera.model_id)) continue;
    SceneCameraConversion entry;
    entry.source = camera;
    entry.conversion =
        ConvertCamera(camera, kColmapModelForBrownBeyer, options);
    camera = entry.conversion.camera;
    conversions.push_back(std::move(entry));
  }
  return conversions;
}

}  // namespace bayon
