// SPDX-License-Identifier: BSD-3-Clause
//
// Distances between points and a triangle mesh (the true surface, or a
// reconstructed mesh): exact closest points on triangles (Ericson, Real-Time
// Collision Detection, 2005, sec. 5.1.5) found through a bounding-volume
// hierarchy of axis-aligned boxes, and the statistics the evaluation reports
// (mean, RMS, median, 95th percentile, max). Object units throughout.
//
// A cloud against the true surface is PointToMeshDistances(cloud, truth); a
// mesh against the truth "both ways" is CompareMeshes: area-uniform samples
// of each surface measured against the other.
#pragma once

#include "ext/core/point_cloud.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace bayon {

class MeshDistance {
 public:
  // Keeps a copy of the vertex positions and faces; throws InputError if the
  // mesh has no faces.
  explicit MeshDistance(const TriangleMesh& mesh);
  ~MeshDistance();
  MeshDistance(const MeshDistance&) = delete;
  MeshDistance& operator=(const MeshDistance&) = delete;

  struct Hit {
    double distance = 0;
    Eigen::Vector3d closest_point = Eigen::Vector3d::Zero();
    int face = -1;
  };
  // The closest point of the mesh to `point`. Thread-safe.
  Hit Closest(const Eigen::Vector3d& point) const;

  // Distances of many points, in parallel (num_threads <= 0: all cores).
  std::vector<double> Distances(const std::vector<Eigen::Vector3d>& points,
                                int num_threads = -1) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct DistanceStatistics {
  size_t count = 0;
  double mean = 0;
  double rms = 0;
  double median = 0;
  double p95 = 0;
  double max = 0;
};
DistanceStatistics ComputeDistanceStatistics(std::vector<double> distances);

std::vector<double> PointToMeshDistances(const PointCloud& cloud,
                                         const TriangleMesh& mesh,
                                         int num_threads = -1);

struct MeshComparisonOptions {
  // Area-uniform samples drawn on each surface.
  size_t num_samples = 200000;
  uint64_t seed = 1;
  // Samples of the truth farther than this from every point of
  // `coverage_points` are left out of truth_to_mesh (parts of the truth that
  // no input point saw, e.g. the underside); 0 keeps all samples.
  double coverage_radius = 0;
  std::vector<Eigen::Vector3d> coverage_points;
  int num_threads = -1;
};

struct MeshComparison {
  DistanceStatistics mesh_to_truth;  // accuracy
  DistanceStatistics truth_to_mesh;  // completeness side
  // Share of truth samples kept by the coverage test (1 without one).
  double truth_fraction_covered = 1;
};

// Both directions between a mesh and the true surface.
MeshComparison CompareMeshes(const TriangleMesh& mesh,
                             const TriangleMesh& truth,
                             const MeshComparisonOptions& options = {});

// {"count", "mean", "rms", "median", "p95", "max"}, as the reports give them.
nlohmann::ordered_json DistanceStatisticsJson(const DistanceStatistics& s);

}  // namespace bayon
