// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/model_statistics.h"

#include "ext/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace bayon {

ModelStatistics ComputeModelStatistics(const Scene& model) {
  ModelStatistics stats;
  stats.num_cameras = static_cast<int>(model.cameras.size());
  stats.num_images = static_cast<int>(model.images.size());
  stats.num_points3D = static_cast<int>(model.points3D.size());

  std::vector<double> errors;
  double sum = 0, sum_sq = 0;
  for (const auto& [point3D_id, point] : model.points3D) {
    stats.num_observations += static_cast<int>(point.track.size());
    for (const TrackElement& element : point.track) {
      const Image& image = model.images.at(element.image_id);
      Eigen::Vector2d pixel;
      if (!model.Project(image, point.xyz, &pixel)) {
        ++stats.num_unprojected;
        continue;
      }
      const double error =
          (image.points2D.at(element.point2D_idx).xy - pixel).norm();
      errors.push_back(error);
      sum += error;
      sum_sq += error * error;
      stats.max_reprojection_error_px =
          std::max(stats.max_reprojection_error_px, error);
    }
  }
  if (stats.num_points3D > 0) {
    stats.mean_track_length =
        static_cast<double>(stats.num_observations) / stats.num_points3D;
  }
  const int n = static_cast<int>(errors.size());
  if (n > 0) {
    stats.mean_reprojection_error_px = sum / n;
    stats.rms_reprojection_error_px = std::sqrt(sum_sq / n);
    stats.median_reprojection_error_px = Median(std::move(errors));
  }

  for (const auto& [camera_id, camera] : model.cameras) {
    stats.num_camera_params += static_cast<int>(camera.params.size());
  }
  stats.num_unknowns =
      6 * stats.num_images + 3 * stats.num_points3D + stats.num_camera_params;
  stats.redundancy = 2 * n - stats.num_unknowns;
  if (stats.redundancy > 0) {
    stats.sigma0_px = std::sqrt(sum_sq / stats.redundancy);
  }
  return stats;
}

}  // namespace bayon
