// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/fusion.h"

#include "ext/core/errors.h"

#include <opencv2/imgproc.hpp>

#include <cmath>

namespace bayon {

void FusionOptions::Check() const {
  CheckOption(min_consistent_views >= 0,
              "min_consistent_views",
              ">= 0",
              min_consistent_views);
  CheckOption(
      max_depth_error_px > 0, "max_depth_error_px", "> 0", max_depth_error_px);
  CheckOption(max_normal_error_deg > 0 && max_normal_error_deg <= 180,
              "max_normal_error_deg",
              "in (0, 180]",
              max_normal_error_deg);
  CheckOption(max_cost > 0 && max_cost <= 2, "max_cost", "in (0, 2]", max_cost);
  CheckOption(edge_margin_px >= 0, "edge_margin_px", ">= 0", edge_margin_px);
}

void FusionOptions::Register(OptionRegistry* r) {
  r->Add("min_consistent_views",
         &min_consistent_views,
         "Other depth maps that must agree with a pixel");
  r->Add("max_depth_error_px",
         &max_depth_error_px,
         "Agreement in depth, pixel footprints (depth / focal length) of the "
         "depth map compared with");
  r->Add("max_normal_error_deg",
         &max_normal_error_deg,
         "Agreement in normal, degrees");
  r->Add("max_cost", &max_cost, "Largest matching cost (1 - NCC) fused");
  r->Add("edge_margin_px",
         &edge_margin_px,
         "Depth-map pixels this near an area without depth are not fused "
         "(against edge fattening; 0: off)");
}

namespace {

// A depth map's camera in single precision, both ways.
struct MapCamera {
  Eigen::Matrix3f R_cw, R_wc;  // cam_from_world, world_from_cam
  Eigen::Vector3f t_cw, t_wc;
  Eigen::Matrix3f K, K_inv;
  explicit MapCamera(const PinholeView& view) {
    R_cw = view.cam_from_world.rotation.toRotationMatrix().cast<float>();
    t_cw = view.cam_from_world.translation.cast<float>();
    const Rigid3d world_from_cam = view.cam_from_world.Inverse();
    R_wc = world_from_cam.rotation.toRotationMatrix().cast<float>();
    t_wc = world_from_cam.translation.cast<float>();
    K = view.K.cast<float>();
    K_inv = view.K.inverse().cast<float>();
  }
  Eigen::Vector3f World(int x, int y, float depth) const {
    return R_wc * (depth * (K_inv * Eigen::Vector3f(x + 0.5f, y + 0.5f, 1))) +
           t_wc;
  }
};

}  // namespace

std::vector<FusedPoint> FuseDepthMaps(
    const std::vector<const PinholeView*>& views,
    const std::vector<const DepthMap*>& maps,
    const FusionOptions& options,
    std::vector<std::vector<FusionVerdict>>* verdicts) {
  options.Check();
  if (views.size() != maps.size()) {
    ThrowInputError(
        "fusion: ", views.size(), " views for ", maps.size(), " depth maps");
  }
  const int n = static_cast<int>(maps.size());
  std::vector<MapCamera> cameras;
  std::vector<std::vector<FusionVerdict>> local;
  if (verdicts == nullptr) verdicts = &local;
  verdicts->assign(n, {});
  for (int i = 0; i < n; ++i) {
    cameras.emplace_back(*views[i]);
    (*verdicts)[i].assign(maps[i]->depth.size(), FusionVerdict::kNone);
  }
  const float max_cost = static_cast<float>(options.max_cost);
  const float max_error = static_cast<float>(options.max_depth_error_px);
  const float min_cos =
      static_cast<float>(std::cos(options.max_normal_error_deg * M_PI / 180));
  // Pixels away from the edges of their depth maps (edge_margin_px).
  std::vector<cv::Mat> inner(n);
  for (int i = 0; i < n; ++i) {
    cv::Mat good(maps[i]->height, maps[i]->width, CV_8U);
    for (size_t q = 0; q < maps[i]->depth.size(); ++q) {
      good.data[q] = maps[i]->depth[q] > 0;
    }
    if (options.edge_margin_px > 0) {
      const int r = options.edge_margin_px;
      const cv::Mat square = cv::getStructuringElement(
          cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
      // Beyond the frame counts as depth (the default border of OpenCV's
      // morphology): the band at the frame where the window does not fit
      // is closed, and the frame is no edge of the object.
      cv::Mat closed;
      cv::morphologyEx(good, closed, cv::MORPH_CLOSE, square);
      cv::erode(closed, closed, square);
      good &= closed;
    }
    inner[i] = good;
  }
  const auto usable = [&](int i, size_t q) {
    return inner[i].data[q] != 0 && maps[i]->cost[q] <= max_cost;
  };
  const auto used = [&](int i, size_t q) {
    return (*verdicts)[i][q] == FusionVerdict::kMerged ||
           (*verdicts)[i][q] == FusionVerdict::kPoint;
  };

  std::vector<FusedPoint> points;
  std::vector<std::pair<int, size_t>> agreeing;
  for (int i = 0; i < n; ++i) {
    const DepthMap& map = *maps[i];
    const MapCamera& camera = cameras[i];
    std::vector<FusionVerdict>& verdict = (*verdicts)[i];
    for (int y = 0; y < map.height; ++y) {
      for (int x = 0; x < map.width; ++x) {
        const size_t p = map.index(x, y);
        if (map.depth[p] <= 0 || verdict[p] != FusionVerdict::kNone) continue;
        if (map.cost[p] > max_cost) {
          verdict[p] = FusionVerdict::kPoorMatch;
          continue;
        }
        if (!inner[i].data[p]) {
          verdict[p] = FusionVerdict::kDepthEdge;
          continue;
        }
        const Eigen::Vector3f X = camera.World(x, y, map.depth[p]);
        const Eigen::Vector3f normal = camera.R_wc * map.normal[p];
        agreeing.clear();
        for (int j = 0; j < n; ++j) {
          if (j == i) continue;
          const MapCamera& other = cameras[j];
          const Eigen::Vector3f in_j = other.R_cw * X + other.t_cw;
          if (in_j.z() <= 0) continue;
          const Eigen::Vector3f h = other.K * in_j;
          const float u = h.x() / h.z(), v = h.y() / h.z();
          if (!(u >= 0 && v >= 0 && u < maps[j]->width &&
                v < maps[j]->height)) {
            continue;
          }
          const size_t q =
              maps[j]->index(static_cast<int>(u), static_cast<int>(v));
          if (!usable(j, q)) continue;
          // A pixel's footprint along the depth grows with the slant of
          // the surface to the ray (by tan of the angle between them, up to
          // 80 degrees): the agreement a slanted wall or a ledge seen at a
          // grazing angle can show.
          const float cos_slant = std::max(
              0.17f,
              std::abs(normal.dot(in_j.normalized().transpose() * other.R_cw)));
          const float slant =
              1 + std::sqrt(1 - cos_slant * cos_slant) / cos_slant;
          if (std::abs(maps[j]->depth[q] - in_j.z()) >
              max_error * slant * in_j.z() / other.K(0, 0)) {
            continue;
          }
          if ((other.R_wc * maps[j]->normal[q]).dot(normal) < min_cos) continue;
          agreeing.emplace_back(j, q);
        }
        if (static_cast<int>(agreeing.size()) < options.min_consistent_views) {
          verdict[p] = FusionVerdict::kInconsistent;
          continue;
        }
        FusedPoint& point = points.emplace_back();
        Eigen::Vector3d sum = X.cast<double>();
        Eigen::Vector3f normal_sum = normal;
        int num_merged = 0;
        for (const auto& [j, q] : agreeing) {
          point.views.push_back(j);
          // A pixel another point took already confirms this one, but
          // stays that point's.
          if (used(j, q)) continue;
          ++num_merged;
          const DepthMap& other = *maps[j];
          const int qx = static_cast<int>(q % other.width);
          const int qy = static_cast<int>(q / other.width);
          sum += cameras[j].World(qx, qy, other.depth[q]).cast<double>();
          normal_sum += cameras[j].R_wc * other.normal[q];
          (*verdicts)[j][q] = FusionVerdict::kMerged;
        }
        verdict[p] = FusionVerdict::kPoint;
        point.xyz = sum / static_cast<double>(1 + num_merged);
        point.normal = normal_sum.normalized();
        point.master = i;
        point.master_xy = Eigen::Vector2d(x + 0.5, y + 0.5);
        point.cost = map.cost[p];
      }
    }
  }
  return points;
}

}  // namespace bayon
