// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment_block.h"

#include "ext/adjustment/cost_functions.h"
#include "ext/core/errors.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace bayon {

Rigid3d BlockImage::CamFromWorld() const {
  const Eigen::Quaterniond q(
      rotation(0), rotation(1), rotation(2), rotation(3));
  const Eigen::Quaterniond unit = q.normalized();
  return Rigid3d(unit, -(unit * center));
}

void BlockImage::SetCamFromWorld(const Rigid3d& cam_from_world) {
  const Eigen::Quaterniond q = cam_from_world.rotation.normalized();
  rotation = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  center = cam_from_world.Center();
}

const char* PointKindName(PointKind kind) {
  switch (kind) {
    case PointKind::kTie:
      return "tie";
    case PointKind::kControl:
      return "control";
    case PointKind::kCheck:
      return "check";
  }
  return "?";
}

std::vector<int> AdjustmentBlock::CountPointObservations() const {
  std::vector<int> counts(points.size(), 0);
  for (const BlockObservation& observation : observations) {
    if (observation.active) ++counts[observation.point_idx];
  }
  return counts;
}

int AdjustmentBlock::DeactivateWeakPoints() {
  const std::vector<int> counts = CountPointObservations();
  int num_deactivated = 0;
  for (size_t p = 0; p < points.size(); ++p) {
    BlockPoint& point = points[p];
    if (!point.active || point.kind != PointKind::kTie || counts[p] >= 2) {
      continue;
    }
    point.active = false;
    ++num_deactivated;
  }
  if (num_deactivated > 0) {
    for (BlockObservation& observation : observations) {
      if (!points[observation.point_idx].active) observation.active = false;
    }
  }
  return num_deactivated;
}

std::vector<double> AdjustmentBlock::IntersectionAnglesDeg() const {
  std::vector<std::vector<Eigen::Vector3d>> rays(points.size());
  for (const BlockObservation& observation : observations) {
    if (!observation.active) continue;
    const Eigen::Vector3d ray = points[observation.point_idx].xyz -
                                images[observation.image_idx].center;
    if (ray.norm() > 0) rays[observation.point_idx].push_back(ray.normalized());
  }
  std::vector<double> angles(points.size(), 0.0);
  for (size_t p = 0; p < points.size(); ++p) {
    double min_cosine = 1;
    for (size_t a = 0; a < rays[p].size(); ++a) {
      for (size_t b = a + 1; b < rays[p].size(); ++b) {
        min_cosine = std::min(min_cosine, rays[p][a].dot(rays[p][b]));
      }
    }
    angles[p] = std::acos(std::clamp(min_cosine, -1.0, 1.0)) * 180.0 / M_PI;
  }
  return angles;
}

std::vector<bool> InnerConstraintPoints(const AdjustmentBlock& block) {
  const std::vector<double> angles = block.IntersectionAnglesDeg();
  std::vector<bool> selected(block.points.size(), false);
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    selected[p] = point.active && point.kind == PointKind::kTie &&
                  angles[p] >= kMinDatumIntersectionAngleDeg;
  }
  return selected;
}

namespace {

template <CameraModelId kModel>
ceres::CostFunction* ColmapCost(const Eigen::Vector2d& observed,
                                const Eigen::Matrix2d& sqrt_information) {
  return ReprojectionCost<ColmapProjection<kModel>>::Create(observed,
                                                            sqrt_information);
}

}  // namespace

ceres::CostFunction* CreateReprojectionCost(
    CameraModelId model,
    const Eigen::Vector2d& observed,
    const Eigen::Matrix2d& sqrt_information,
    const ImageFrame& frame) {
  using M = CameraModelId;
  switch (model) {
    case M::kBrownBeyer:
      return ReprojectionCost<BrownBeyerProjection>::Create(
          observed, sqrt_information, frame);
    case M::kSimplePinhole:
      return ColmapCost<M::kSimplePinhole>(observed, sqrt_information);
    case M::kPinhole:
      return ColmapCost<M::kPinhole>(observed, sqrt_information);
    case M::kSimpleRadial:
      return ColmapCost<M::kSimpleRadial>(observed, sqrt_information);
    case M::kRadial:
      return ColmapCost<M::kRadial>(observed, sqrt_information);
    case M::kOpenCV:
      return ColmapCost<M::kOpenCV>(observed, sqrt_information);
    case M::kOpenCVFisheye:
      return ColmapCost<M::kOpenCVFisheye>(observed, sqrt_information);
    case M::kFullOpenCV:
      return ColmapCost<M::kFullOpenCV>(observed, sqrt_information);
    case M::kFOV:
      return ColmapCost<M::kFOV>(observed, sqrt_information);
    case M::kSimpleRadialFisheye:
      return ColmapCost<M::kSimpleRadialFisheye>(observed, sqrt_information);
    case M::kRadialFisheye:
      return ColmapCost<M::kRadialFisheye>(observed, sqrt_information);
    case M::kThinPrismFisheye:
      return ColmapCost<M::kThinPrismFisheye>(observed, sqrt_information);
    default:
      ThrowInputError(
          "camera model ", static_cast<int>(model), " cannot be adjusted");
  }
}

Eigen::Matrix2d ObservationSqrtInformation(const BlockObservation& observation,
                                           double sigma0_px) {
  if (observation.covariance.isZero()) {
    return Eigen::Matrix2d::Identity() * (sigma0_px / observation.sigma_px);
  }
  // C = L L^T, P = sigma0^2 C^-1 = W^T W with W = sigma0 L^-1.
  const Eigen::Matrix2d L = observation.covariance.llt().matrixL();
  return sigma0_px * L.inverse();
}

std::vector<ResidualTerm> BuildResidualTerms(AdjustmentBlock* block) {
  std::vector<ResidualTerm> terms;
  terms.reserve(block->observations.size() + block->distances.size());
  for (size_t o = 0; o < block->observations.size(); ++o) {
    const BlockObservation& observation = block->observations[o];
    BlockPoint& point = block->points[observation.point_idx];
    if (!observation.active || !point.active) continue;
    BlockImage& image = block->images[observation.image_idx];
    BlockCamera& camera = block->cameras[image.camera_idx];
    const Eigen::Matrix2d sqrt_information =
        ObservationSqrtInformation(observation, block->sigma0_px);
    ResidualTerm term;
    term.type = TermType::kReprojection;
    term.index = static_cast<int>(o);
    term.cost.reset(CreateReprojectionCost(
        camera.camera.model_id, observation.xy, sqrt_information, image.frame));
    term.parameters = {image.rotation.data(),
                       image.center.data(),
                       point.xyz.data(),
                       camera.camera.params.data()};
    terms.push_back(std::move(term));
  }
  for (size_t p = 0; p < block->points.size(); ++p) {
    BlockPoint& point = block->points[p];
    if (!point.active || !point.weighted) continue;
    Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 3; ++k) {
      // A coordinate held fixed is no observation (weight zero).
      if (!point.fixed[k]) {
        sqrt_information(k, k) = block->sigma0_px / point.given_sigma(k);
      }
    }
    ResidualTerm term;
    term.type = TermType::kPointPrior;
    term.index = static_cast<int>(p);
    term.cost.reset(PointPriorCost::Create(point.given_xyz, sqrt_information));
    term.parameters = {point.xyz.data()};
    terms.push_back(std::move(term));
  }
  for (size_t d = 0; d < block->distances.size(); ++d) {
    const BlockDistance& distance = block->distances[d];
    BlockPoint& a = block->points[distance.point_a];
    BlockPoint& b = block->points[distance.point_b];
    if (!a.active || !b.active) continue;
    ResidualTerm term;
    term.type = TermType::kDistance;
    term.index = static_cast<int>(d);
    term.cost.reset(DistanceCost::Create(distance.distance_m,
                                         block->sigma0_px / distance.sigma_m));
    term.parameters = {a.xyz.data(), b.xyz.data()};
    terms.push_back(std::move(term));
  }
  return terms;
}

std::vector<Eigen::Vector2d> ImageResiduals(AdjustmentBlock* block) {
  std::vector<Eigen::Vector2d> residuals(
      block->observations.size(),
      Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (const ResidualTerm& term : BuildResidualTerms(block)) {
    if (term.type != TermType::kReprojection) continue;
    Eigen::Vector2d weighted;
    if (!term.cost->Evaluate(
            term.parameters.data(), weighted.data(), nullptr)) {
      continue;
    }
    residuals[term.index] =
        ObservationSqrtInformation(block->observations[term.index],
                                   block->sigma0_px)
            .inverse() *
        weighted;
  }
  return residuals;
}

AdjustmentBlock BlockFromScene(const Scene& scene, double sigma_px) {
  AdjustmentBlock block;
  block.sigma0_px = sigma_px;
  std::map<camera_t, int> camera_idxs;
  for (const auto& [camera_id, camera] : scene.cameras) {
    BlockCamera block_camera;
    block_camera.camera = camera;
    block_camera.free.assign(camera.params.size(), false);
    block_camera.source_model = camera.model_id;
    camera_idxs[camera_id] = static_cast<int>(block.cameras.size());
    block.cameras.push_back(std::move(block_camera));
  }
  std::map<image_t, int> image_idxs;
  for (const auto& [image_id, image] : scene.images) {
    BlockImage block_image;
    block_image.image_id = image_id;
    block_image.name = image.name;
    block_image.camera_idx = camera_idxs.at(image.camera_id);
    block_image.SetCamFromWorld(image.cam_from_world);
    const Camera& camera = scene.cameras.at(image.camera_id);
    block_image.frame = image.frame ? *image.frame : camera.DefaultFrame();
    image_idxs[image_id] = static_cast<int>(block.images.size());
    block.images.push_back(std::move(block_image));
  }
  for (const auto& [point3D_id, point] : scene.points3D) {
    if (point.track.size() < 2) continue;
    BlockPoint block_point;
    block_point.point3D_id = point3D_id;
    block_point.xyz = point.xyz;
    block_point.color = point.color;
    const int point_idx = static_cast<int>(block.points.size());
    block.points.push_back(block_point);
    for (const TrackElement& element : point.track) {
      const Image& image = scene.images.at(element.image_id);
      BlockObservation observation;
      observation.image_idx = image_idxs.at(element.image_id);
      observation.point_idx = point_idx;
      observation.point2D_idx = element.point2D_idx;
      observation.xy = image.points2D.at(element.point2D_idx).xy;
      observation.sigma_px = sigma_px;
      block.observations.push_back(observation);
    }
  }
  return block;
}

void UpdateSceneFromBlock(const AdjustmentBlock& block, Scene* scene) {
  for (const BlockCamera& block_camera : block.cameras) {
    scene->cameras.Set(block_camera.camera.camera_id, block_camera.camera);
  }
  for (const BlockImage& block_image : block.images) {
    Image& image = scene->images.at(block_image.image_id);
    image.cam_from_world = block_image.CamFromWorld();
  }
  // Active tie observations per model point.
  std::map<point3D_t, std::vector<TrackElement>> tracks;
  std::map<point3D_t, int> point_idxs;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (point.kind == PointKind::kTie && point.active) {
      point_idxs[point.point3D_id] = static_cast<int>(p);
      tracks[point.point3D_id];
    }
  }
  for (const BlockObservation& observation : block.observations) {
    const BlockPoint& point = block.points[observation.point_idx];
    if (!observation.active || point.kind != PointKind::kTie || !point.active) {
      continue;
    }
    tracks[point.point3D_id].push_back(
        {block.images[observation.image_idx].image_id,
         observation.point2D_idx});
  }
  Scene updated = *scene;
  updated.points3D.clear();
  for (auto& [image_id, image] : updated.images) {
    for (Point2D& point2D : image.points2D) {
      point2D.point3D_id = kInvalidPoint3DId;
    }
  }
  for (const auto& [point3D_id, point] : scene->points3D) {
    auto it = tracks.find(point3D_id);
    if (it == tracks.end() || it->second.size() < 2) continue;
    Point3D adjusted = point;
    adjusted.xyz = block.points[point_idxs.at(point3D_id)].xyz;
    adjusted.track = it->second;
    for (const TrackElement& element : adjusted.track) {
      updated.images.at(element.image_id)
          .points2D.at(element.point2D_idx)
          .point3D_id = point3D_id;
    }
    updated.points3D.Set(point3D_id, std::move(adjusted));
  }
  *scene = std::move(updated);
}

}  // namespace bayon
