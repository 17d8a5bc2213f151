// SPDX-License-Identifier: BSD-3-Clause
//
// Dense clouds and meshes against the true surface of a synthetic scene.
//
// Accuracy is the distance from the reconstruction to the true surface;
// completeness is the share of the true surface that the reconstruction
// reaches, counted only over the part of the truth that the photographs
// could see: area-uniform samples of the true surface that lie inside the
// evaluation region and are visible (not occluded, in front of the camera,
// inside the frame) in at least `min_views` of the true cameras, since a
// point seen once cannot be intersected. Visibility comes from depth maps
// of the true surface rendered through the true cameras (ext/render), so
// self-occlusion by the relief counts.
//
// Every distance is in object units (metres) and, where a ground sampling
// distance is known, also in GSDs.
#pragma once

#include "ext/core/mesh_geometry.h"
#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"
#include "ext/eval/mesh_distance.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace bayon {

struct VisibleSurfaceOptions {
  size_t num_samples = 200000;
  uint64_t seed = 1;
  // Samples outside this box are left out (the ground, the sky); empty:
  // the whole surface.
  Eigen::AlignedBox3d region;
  int min_views = 2;
  // A sample is visible in an image when its depth is within this share of
  // the rendered depth at its pixel (the pixel's footprint on a slanted
  // surface, not occlusion).
  double depth_tolerance = 0.01;
  int num_threads = -1;
};

struct VisibleSurface {
  std::vector<Eigen::Vector3d> samples;  // the visible ones
  std::vector<Eigen::Vector3d> normals;  // of the true faces they lie on
  size_t num_candidates = 0;             // samples inside the region
  double area = 0;                       // of the whole true surface
};

// Renders depth maps of `surface` through every image of `cameras` and keeps
// the samples seen often enough. Throws InputError if the scene has no
// images or no sample is visible.
VisibleSurface FindVisibleSurface(const TriangleMesh& surface,
                                  const Scene& cameras,
                                  const VisibleSurfaceOptions& options = {});

// The true surface by its orientation to the datum's vertical (z): tops
// (normals within 45 degrees of up), undersides (of down), walls (the rest).
// A ring of photographs taken from about the ground sees walls face on and
// tops, if at all, at grazing angles, where a dense pattern of image cells
// samples them sparsely: completeness per orientation says which.
enum class SurfaceOrientation { kWalls = 0, kTops, kUndersides };
constexpr int kNumSurfaceOrientations = 3;
const char* SurfaceOrientationName(SurfaceOrientation orientation);
SurfaceOrientation OrientationOf(const Eigen::Vector3d& normal);

struct OrientationCompleteness {
  size_t num_samples = 0;  // visible true samples of this orientation
  double fraction = 0;     // of them within the completeness threshold
};

struct SurfaceEvaluationOptions {
  // A true sample counts as reached when the reconstruction comes within
  // this distance (metres).
  double completeness_threshold_m = 0.01;
  // For figures in GSDs; 0: not known.
  double gsd_m = 0;
  // Reconstructed points (cloud points, mesh samples) outside this box are
  // not judged (the ground, stray points far away); empty: all.
  Eigen::AlignedBox3d region;
  // Samples drawn on a reconstructed mesh for its accuracy.
  size_t num_mesh_samples = 200000;
  uint64_t seed = 2;
  int num_threads = -1;
};

struct SurfaceEvaluation {
  size_t num_points = 0;  // judged (inside the region)
  size_t num_points_outside_region = 0;
  DistanceStatistics accuracy;      // reconstruction -> truth
  DistanceStatistics completeness;  // visible truth -> reconstruction
  // Share of the visible true samples within the completeness threshold.
  double completeness_fraction = 0;
  // The same per orientation of the true surface (SurfaceOrientation).
  std::array<OrientationCompleteness, kNumSurfaceOrientations>
      completeness_by_orientation{};
  double completeness_threshold_m = 0;
  double gsd_m = 0;
  size_t num_visible_samples = 0;
  // Meshes only: topology of the reconstruction and of the truth.
  bool is_mesh = false;
  MeshTopology topology;
  MeshTopology truth_topology;
};

// A dense cloud: accuracy from every point, completeness from the distance
// of each visible true sample to its nearest cloud point.
SurfaceEvaluation EvaluateCloud(const PointCloud& cloud,
                                const MeshDistance& truth,
                                const VisibleSurface& visible,
                                const SurfaceEvaluationOptions& options);

// A mesh: accuracy from area-uniform samples of the mesh, completeness from
// the distance of each visible true sample to the mesh, and the topology of
// both (manifold, closed, boundary loops).
SurfaceEvaluation EvaluateMesh(const TriangleMesh& mesh,
                               const TriangleMesh& truth_mesh,
                               const MeshDistance& truth,
                               const VisibleSurface& visible,
                               const SurfaceEvaluationOptions& options);

// One table row per evaluation: count, accuracy mean/RMS/median/p95,
// completeness within the threshold; in metres and GSDs.
std::string SurfaceTableHeader();
std::string SurfaceTableRow(const std::string& label,
                            const SurfaceEvaluation& evaluation);

// The evaluation as `bayon evaluate` reports it ("cloud", "mesh"): with
// accuracy in GSDs where the GSD is known, and a mesh's topology.
nlohmann::ordered_json SurfaceEvaluationJson(const SurfaceEvaluation& e);

// "  mesh   49612 faces, 0 boundary loops, ...: closed", one line.
std::string MeshTopologyLine(const std::string& label, const MeshTopology& t);

}  // namespace bayon
