// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/scene_database.h"

#include "ext/core/errors.h"

#include <Eigen/Dense>

#include <map>

namespace bayon {
namespace {

Eigen::Matrix3d CrossMatrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d CalibrationMatrix(const Camera& camera) {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  const CameraModelInfo& info = camera.ModelInfo();
  K(0, 0) = camera.params[info.focal_idxs.front()];
  K(1, 1) = camera.params[info.focal_idxs.back()];
  K(0, 2) = camera.params[info.principal_point_idxs[0]];
  K(1, 2) = camera.params[info.principal_point_idxs[1]];
  return K;
}

}  // namespace

TwoViewGeometry TwoViewGeometryFromPoses(const Camera& camera1,
                                         const Rigid3d& cam1_from_world,
                                         const Camera& camera2,
                                         const Rigid3d& cam2_from_world) {
  const Rigid3d cam2_from_cam1 = cam2_from_world * cam1_from_world.Inverse();
  TwoViewGeometry geometry;
  geometry.config = TwoViewConfig::kCalibrated;
  const Eigen::Vector3d t = cam2_from_cam1.translation.normalized();
  const Eigen::Matrix3d R = cam2_from_cam1.rotation.toRotationMatrix();
  const Eigen::Matrix3d E = CrossMatrix(t) * R;
  geometry.E = E;
  geometry.F = CalibrationMatrix(camera2).inverse().transpose() * E *
               CalibrationMatrix(camera1).inverse();
  const Eigen::Quaterniond& q = cam2_from_cam1.rotation;
  geometry.qvec = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  geometry.tvec = t;
  return geometry;
}

SceneImportSummary ImportSceneIntoDatabase(const Scene& scene,
                                           const SceneImportOptions& options,
                                           Database* database) {
  SceneImportSummary summary;
  auto transaction = database->BeginTransaction();
  std::map<camera_t, camera_t> camera_ids;
  for (const auto& [camera_id, camera] : scene.cameras) {
    camera_ids[camera_id] = database->WriteCamera(camera, options.keep_ids);
    ++summary.num_cameras;
  }
  std::map<image_t, image_t> image_ids;
  for (const auto& [image_id, image] : scene.images) {
    DatabaseImage row;
    row.image_id = image_id;
    row.name = image.name;
    row.camera_id = camera_ids.at(image.camera_id);
    image_ids[image_id] = database->WriteImage(row, options.keep_ids);
    std::vector<Eigen::Vector2d> xy;
    xy.reserve(image.points2D.size());
    for (const Point2D& point : image.points2D) xy.push_back(point.xy);
    database->WriteKeypoints(image_ids[image_id], KeypointsFromXY(xy));
    summary.num_keypoints += static_cast<int64_t>(xy.size());
    ++summary.num_images;
  }
  // Correspondences from the tracks, per ordered pair (id1 < id2).
  std::map<std::pair<image_t, image_t>,
           std::vector<std::pair<point2D_t, point2D_t>>>
      pairs;
  for (const auto& [point3D_id, point] : scene.points3D) {
    for (size_t a = 0; a < point.track.size(); ++a) {
      for (size_t b = a + 1; b < point.track.size(); ++b) {
        TrackElement e1 = point.track[a];
        TrackElement e2 = point.track[b];
        if (e1.image_id == e2.image_id) continue;
        if (e1.image_id > e2.image_id) std::swap(e1, e2);
        pairs[{e1.image_id, e2.image_id}].emplace_back(e1.point2D_idx,
                                                       e2.point2D_idx);
      }
    }
  }
  for (const auto& [ids, correspondences] : pairs) {
    if (static_cast<int>(correspondences.size()) <
        options.min_num_shared_points) {
      continue;
    }
    FeatureMatches matches(correspondences.size(), 2);
    for (size_t i = 0; i < correspondences.size(); ++i) {
      matches(i, 0) = correspondences[i].first;
      matches(i, 1) = correspondences[i].second;
    }
    const Image& image1 = scene.images.at(ids.first);
    const Image& image2 = scene.images.at(ids.second);
    const image_t db_id1 = image_ids.at(ids.first);
    const image_t db_id2 = image_ids.at(ids.second);
    database->WriteMatches(db_id1, db_id2, matches);
    TwoViewGeometry geometry =
        TwoViewGeometryFromPoses(scene.cameras.at(image1.camera_id),
                                 image1.cam_from_world,
                                 scene.cameras.at(image2.camera_id),
                                 image2.cam_from_world);
    geometry.inlier_matches = matches;
    database->WriteTwoViewGeometry(db_id1, db_id2, geometry);
    ++summary.num_pairs;
    summary.num_matches += matches.rows();
  }
  transaction.Commit();
  return summary;
}

}  // namespace bayon
