// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/surface_eval.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/string_printf.h"
#include "ext/render/mesh_renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>

namespace bayon {
namespace {

bool Inside(const Eigen::AlignedBox3d& region, const Eigen::Vector3d& p) {
  return region.isEmpty() || region.contains(p);
}

// Points hashed into cubic cells: the nearest point within one cell size of
// a query is found exactly by looking at the 27 cells around it.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3d>& points, double cell)
      : points_(points), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i) {
      cells_[Key(Cell(points[i]))].push_back(static_cast<int>(i));
    }
  }

  // Distance to the nearest point, or +inf when none is within one cell.
  double NearestWithinCell(const Eigen::Vector3d& query) const {
    const Eigen::Vector3i center = Cell(query);
    double best = std::numeric_limits<double>::infinity();
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = cells_.find(Key(center + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (int i : it->second) {
            best = std::min(best, (points_[i] - query).squaredNorm());
          }
        }
      }
    }
    best = std::sqrt(best);
    return best <= cell_ ? best : std::numeric_limits<double>::infinity();
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const {
    return (p / cell_).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    constexpr int64_t kOffset = 1 << 20;
    return ((c.x() + kOffset) << 42) | ((c.y() + kOffset) << 21) |
           (c.z() + kOffset);
  }

  const std::vector<Eigen::Vector3d>& points_;
  double cell_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

// Distances from the visible true samples to the nearest of `points`:
// exact up to `cap`, reported as `cap` beyond it (a part of the truth that
// the reconstruction does not reach at all).
std::vector<double> SampleToPointDistances(
    const std::vector<Eigen::Vector3d>& samples,
    const std::vector<Eigen::Vector3d>& points,
    double cap,
    int num_threads) {
  const PointGrid grid(points, cap);
  std::vector<double> distances(samples.size(), cap);
  ParallelFor(static_cast<int>(samples.size()), num_threads, [&](int i) {
    distances[i] = std::min(cap, grid.NearestWithinCell(samples[i]));
  });
  return distances;
}

void FillCompleteness(std::vector<double> distances,
                      const VisibleSurface& visible,
                      const SurfaceEvaluationOptions& options,
                      SurfaceEvaluation* evaluation) {
  std::array<size_t, kNumSurfaceOrientations> reached_by{};
  auto& by_orientation = evaluation->completeness_by_orientation;
  for (size_t i = 0; i < distances.size(); ++i) {
    const int o = static_cast<int>(OrientationOf(visible.normals[i]));
    ++by_orientation[o].num_samples;
    reached_by[o] += distances[i] <= options.completeness_threshold_m;
  }
  size_t reached = 0;
  for (int o = 0; o < kNumSurfaceOrientations; ++o) {
    reached += reached_by[o];
    if (by_orientation[o].num_samples > 0) {
      by_orientation[o].fraction =
          double(reached_by[o]) / by_orientation[o].num_samples;
    }
  }
  evaluation->num_visible_samples = distances.size();
  evaluation->completeness_fraction =
      distances.empty() ? 0.0 : double(reached) / distances.size();
  evaluation->completeness = ComputeDistanceStatistics(std::move(distances));
}

void CheckOptions(const SurfaceEvaluationOptions& options,
                  const VisibleSurface& visible) {
  if (!(options.completeness_threshold_m > 0)) {
    ThrowInputError("the completeness threshold must be positive, not ",
                    options.completeness_threshold_m);
  }
  if (visible.samples.empty()) {
    ThrowInputError("no visible true surface to evaluate against");
  }
}

}  // namespace

const char* SurfaceOrientationName(SurfaceOrientation orientation) {
  switch (orientation) {
    case SurfaceOrientation::kWalls:
      return "walls";
    case SurfaceOrientation::kTops:
      return "tops";
    case SurfaceOrientation::kUndersides:
      return "undersides";
  }
  return "?";
}

SurfaceOrientation OrientationOf(const Eigen::Vector3d& normal) {
  const double cos45 = std::sqrt(0.5);
  if (normal.z() > cos45) return SurfaceOrientation::kTops;
  if (normal.z() < -cos45) return SurfaceOrientation::kUndersides;
  return SurfaceOrientation::kWalls;
}

VisibleSurface FindVisibleSurface(const TriangleMesh& surface,
                                  const Scene& cameras,
                                  const VisibleSurfaceOptions& options) {
  if (cameras.images.empty()) {
    ThrowInputError("the true model has no images to judge visibility from");
  }
  if (options.min_views < 1 || !(options.depth_tolerance > 0)) {
    ThrowInputError(
        "visibility needs min_views >= 1 and a positive depth "
        "tolerance");
  }
  VisibleSurface visible;
  std::vector<Eigen::Vector3d> candidates, normals;
  for (const SurfaceSample& sample :
       SampleMeshSurface(surface, options.num_samples, options.seed)) {
    if (Inside(options.region, sample.position)) {
      candidates.push_back(sample.position);
      normals.push_back(FaceNormal(surface, sample.face));
    }
  }
  visible.num_candidates = candidates.size();
  visible.area = ComputeMeshTopology(surface).area;

  // Depth only: the surface's texture and colours play no part.
  TriangleMesh geometry;
  geometry.vertices.positions = surface.vertices.positions;
  geometry.faces = surface.faces;
  const MeshRenderer renderer(std::move(geometry));
  RenderOptions render;
  render.supersampling = 1;
  render.num_threads = options.num_threads;
  const Lighting unlit;

  std::vector<std::atomic<int>> views(candidates.size());
  for (auto& v : views) v = 0;
  for (const auto& [image_id, image] : cameras.images) {
    RenderView view;
    view.camera = cameras.cameras.at(image.camera_id);
    view.cam_from_world = image.cam_from_world;
    view.frame = image.frame;
    const RenderResult result = renderer.Render(view, unlit, render);
    const ImageFrame* frame = image.frame ? &*image.frame : nullptr;
    ParallelFor(
        static_cast<int>(candidates.size()), options.num_threads, [&](int i) {
          const Eigen::Vector3d in_cam = view.cam_from_world * candidates[i];
          Eigen::Vector2d pixel;
          if (in_cam.z() <= 0 ||
              !view.camera.ImgFromCam(in_cam, &pixel, frame)) {
            return;
          }
          const int col = static_cast<int>(std::floor(pixel.x()));
          const int row = static_cast<int>(std::floor(pixel.y()));
          if (col < 0 || row < 0 || col >= result.depth.cols ||
              row >= result.depth.rows) {
            return;
          }
          const float depth = result.depth.at<float>(row, col);
          if (depth > 0 &&
              std::abs(in_cam.z() - depth) <= options.depth_tolerance * depth) {
            ++views[i];
          }
        });
  }
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (views[i] >= options.min_views) {
      visible.samples.push_back(candidates[i]);
      visible.normals.push_back(normals[i]);
    }
  }
  if (visible.samples.empty()) {
    ThrowInputError("no sample of the true surface is seen in ",
                    options.min_views,
                    " or more of the true images; wrong truth or cameras?");
  }
  return visible;
}

SurfaceEvaluation EvaluateCloud(const PointCloud& cloud,
                                const MeshDistance& truth,
                                const VisibleSurface& visible,
                                const SurfaceEvaluationOptions& options) {
  CheckOptions(options, visible);
  SurfaceEvaluation evaluation;
  evaluation.completeness_threshold_m = options.completeness_threshold_m;
  evaluation.gsd_m = options.gsd_m;
  std::vector<Eigen::Vector3d> judged;
  judged.reserve(cloud.size());
  for (const Eigen::Vector3d& p : cloud.positions) {
    if (Inside(options.region, p)) judged.push_back(p);
  }
  evaluation.num_points = judged.size();
  evaluation.num_points_outside_region = cloud.size() - judged.size();
  if (judged.empty()) {
    ThrowInputError("none of the ",
                    cloud.size(),
                    " points lies inside the evaluation region");
  }
  evaluation.accuracy =
      ComputeDistanceStatistics(truth.Distances(judged, options.num_threads));
  FillCompleteness(SampleToPointDistances(visible.samples,
                                          judged,
                                          10 * options.completeness_threshold_m,
                                          options.num_threads),
                   visible,
                   options,
                   &evaluation);
  return evaluation;
}

SurfaceEvaluation EvaluateMesh(const TriangleMesh& mesh,
                               const TriangleMesh& truth_mesh,
                               const MeshDistance& truth,
                               const VisibleSurface& visible,
                               const SurfaceEvaluationOptions& options) {
  CheckOptions(options, visible);
  SurfaceEvaluation evaluation;
  evaluation.is_mesh = true;
  evaluation.completeness_threshold_m = options.completeness_threshold_m;
  evaluation.gsd_m = options.gsd_m;
  evaluation.topology = ComputeMeshTopology(mesh);
  evaluation.truth_topology = ComputeMeshTopology(truth_mesh);
  std::vector<Eigen::Vector3d> judged;
  size_t outside = 0;
  for (const SurfaceSample& sample :
       SampleMeshSurface(mesh, options.num_mesh_samples, options.seed)) {
    if (Inside(options.region, sample.position)) {
      judged.push_back(sample.position);
    } else {
      ++outside;
    }
  }
  evaluation.num_points = judged.size();
  evaluation.num_points_outside_region = outside;
  if (judged.empty()) {
    ThrowInputError("no part of the mesh lies inside the evaluation region");
  }
  evaluation.accuracy =
      ComputeDistanceStatistics(truth.Distances(judged, options.num_threads));
  const MeshDistance to_mesh(mesh);
  FillCompleteness(to_mesh.Distances(visible.samples, options.num_threads),
                   visible,
                   options,
                   &evaluation);
  return evaluation;
}

std::string SurfaceTableHeader() {
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "%-28s %9s %10s %10s %10s %10s %8s %9s",
                "surface",
                "points",
                "acc mean",
                "acc RMS",
                "acc median",
                "acc p95",
                "complete",
                "thresh");
  return line;
}

std::string SurfaceTableRow(const std::string& label,
                            const SurfaceEvaluation& e) {
  char line[512];
  std::snprintf(line,
                sizeof(line),
                "%-28s %9zu %10.5f %10.5f %10.5f %10.5f %7.2f%% %9.4f",
                label.c_str(),
                e.num_points,
                e.accuracy.mean,
                e.accuracy.rms,
                e.accuracy.median,
                e.accuracy.p95,
                100.0 * e.completeness_fraction,
                e.completeness_threshold_m);
  std::string row = line;
  if (e.gsd_m > 0) {
    std::snprintf(line,
                  sizeof(line),
                  "\n%-28s %9s %10.2f %10.2f %10.2f %10.2f %8s %9.2f",
                  "  (in GSD)",
                  "",
                  e.accuracy.mean / e.gsd_m,
                  e.accuracy.rms / e.gsd_m,
                  e.accuracy.median / e.gsd_m,
                  e.accuracy.p95 / e.gsd_m,
                  "",
                  e.completeness_threshold_m / e.gsd_m);
    row += line;
  }
  row += "\n  complete by orientation:";
  for (int o = 0; o < kNumSurfaceOrientations; ++o) {
    const OrientationCompleteness& c = e.completeness_by_orientation[o];
    std::snprintf(line,
                  sizeof(line),
                  "%s %s %.1f%% (%zu samples)",
                  o == 0 ? "" : ",",
                  SurfaceOrientationName(static_cast<SurfaceOrientation>(o)),
                  100.0 * c.fraction,
                  c.num_samples);
    row += line;
  }
  return row;
}

namespace {

nlohmann::ordered_json MeshTopologyJson(const MeshTopology& t) {
  return {{"vertices", t.num_vertices},
          {"faces", t.num_faces},
          {"boundary_loops", t.num_boundary_loops},
          {"non_manifold_edges", t.num_non_manifold_edges},
          {"non_manifold_vertices", t.num_non_manifold_vertices},
          {"components", t.num_components},
          {"manifold", t.IsManifold()},
          {"closed", t.IsClosed()}};
}

}  // namespace

nlohmann::ordered_json SurfaceEvaluationJson(const SurfaceEvaluation& e) {
  nlohmann::ordered_json json = {
      {"num_points", e.num_points},
      {"num_points_outside_region", e.num_points_outside_region},
      {"accuracy_m", DistanceStatisticsJson(e.accuracy)},
      {"completeness_m", DistanceStatisticsJson(e.completeness)},
      {"completeness_fraction", e.completeness_fraction},
      {"completeness_threshold_m", e.completeness_threshold_m},
      {"num_visible_true_samples", e.num_visible_samples}};
  nlohmann::ordered_json by_orientation = nlohmann::ordered_json::object();
  for (int o = 0; o < kNumSurfaceOrientations; ++o) {
    const OrientationCompleteness& c = e.completeness_by_orientation[o];
    by_orientation[SurfaceOrientationName(static_cast<SurfaceOrientation>(o))] =
        {{"num_visible_true_samples", c.num_samples},
         {"completeness_fraction", c.fraction}};
  }
  json["completeness_by_orientation"] = by_orientation;
  if (e.gsd_m > 0) {
    json["gsd_m"] = e.gsd_m;
    json["accuracy_gsd"] = {{"mean", e.accuracy.mean / e.gsd_m},
                            {"rms", e.accuracy.rms / e.gsd_m},
                            {"median", e.accuracy.median / e.gsd_m},
                            {"p95", e.accuracy.p95 / e.gsd_m}};
  }
  if (e.is_mesh) {
    json["topology"] = MeshTopologyJson(e.topology);
    json["truth_topology"] = MeshTopologyJson(e.truth_topology);
  }
  return json;
}

std::string MeshTopologyLine(const std::string& label, const MeshTopology& t) {
  return StringPrintf(
      "  %-6s %zu faces, %zu boundary loops, %zu non-manifold edges, "
      "%zu non-manifold vertices: %s\n",
      label.c_str(),
      t.num_faces,
      t.num_boundary_loops,
      t.num_non_manifold_edges,
      t.num_non_manifold_vertices,
      t.IsClosed() ? "closed"
                   : (t.IsManifold() ? "manifold, open" : "not manifold"));
}

}  // namespace bayon
