// SPDX-License-Identifier: BSD-3-Clause
//
// PCL's greedy projection triangulation and Poisson reconstruction behind
// meshing.h.
#include "ext/cloud/pcl_cloud.h"
#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/mesh/meshing.h"

#include <glog/logging.h>
#include <pcl/conversions.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/poisson.h>

#include <cmath>

namespace bayon {
namespace {

// Points and normals, shifted to their centroid (PCL stores floats).
pcl::PointCloud<pcl::PointNormal>::Ptr ToPointNormals(
    const PointCloud& cloud, const Eigen::Vector3d& center) {
  pcl::PointCloud<pcl::PointNormal>::Ptr out(
      new pcl::PointCloud<pcl::PointNormal>);
  out->resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f p = (cloud.positions[i] - center).cast<float>();
    pcl::PointNormal& q = (*out)[i];
    q.x = p.x();
    q.y = p.y();
    q.z = p.z();
    q.normal_x = cloud.normals[i].x();
    q.normal_y = cloud.normals[i].y();
    q.normal_z = cloud.normals[i].z();
  }
  return out;
}

void RequireNormals(const PointCloud& cloud, const char* method) {
  if (!cloud.HasNormals()) {
    ThrowInputError(method, " needs point normals and the cloud has none");
  }
}

}  // namespace

TriangleMesh GreedyProjectionMesh(const PointCloud& cloud,
                                  const GreedyProjectionOptions& options,
                                  double median_spacing) {
  options.Check();
  RequireNormals(cloud, "greedy_projection");
  const CenteredPclCloud centered(cloud.positions);
  const auto points = ToPointNormals(cloud, centered.center);
  pcl::search::KdTree<pcl::PointNormal>::Ptr tree(
      new pcl::search::KdTree<pcl::PointNormal>);
  tree->setInputCloud(points);
  pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
  gp3.setSearchRadius(options.search_radius_factor * median_spacing);
  gp3.setMu(options.mu);
  gp3.setMaximumNearestNeighbors(options.max_nearest_neighbors);
  gp3.setMaximumSurfaceAngle(options.max_surface_angle_deg * M_PI / 180);
  gp3.setMinimumAngle(options.min_angle_deg * M_PI / 180);
  gp3.setMaximumAngle(options.max_angle_deg * M_PI / 180);
  gp3.setNormalConsistency(true);  // the normals are oriented
  gp3.setConsistentVertexOrdering(true);
  gp3.setInputCloud(points);
  gp3.setSearchMethod(tree);
  std::vector<pcl::Vertices> polygons;
  gp3.reconstruct(polygons);
  TriangleMesh mesh;
  mesh.vertices = cloud;
  mesh.faces.reserve(polygons.size());
  for (const pcl::Vertices& polygon : polygons) {
    if (polygon.vertices.size() != 3) continue;
    mesh.faces.emplace_back(
        polygon.vertices[0], polygon.vertices[1], polygon.vertices[2]);
  }
  return mesh;
}

TriangleMesh PoissonMesh(const PointCloud& cloud,
                         const PoissonOptions& options,
                         double median_spacing,
                         int num_threads,
                         size_t* num_trimmed_faces) {
  options.Check();
  CheckEnoughPointsToClose(cloud, "poisson");
  RequireNormals(cloud, "poisson");
  const CenteredPclCloud centered(cloud.positions);
  const auto points = ToPointNormals(cloud, centered.center);
  pcl::Poisson<pcl::PointNormal> poisson;
  poisson.setDepth(options.depth);
  poisson.setSamplesPerNode(static_cast<float>(options.samples_per_node));
  poisson.setPointWeight(static_cast<float>(options.point_weight));
  poisson.setThreads(EffectiveNumThreads(num_threads));
  poisson.setManifold(true);
  poisson.setInputCloud(points);
  pcl::PointCloud<pcl::PointNormal> poisson_vertices;
  std::vector<pcl::Vertices> polygons;
  poisson.reconstruct(poisson_vertices, polygons);
  pcl::PointCloud<pcl::PointXYZ> vertices;
  vertices.resize(poisson_vertices.size());
  for (size_t i = 0; i < poisson_vertices.size(); ++i) {
    const pcl::PointNormal& p = poisson_vertices[i];
    vertices[i] = pcl::PointXYZ(p.x, p.y, p.z);
  }

  TriangleMesh mesh;
  mesh.vertices.positions.reserve(vertices.size());
  for (const pcl::PointXYZ& p : vertices) {
    mesh.vertices.positions.push_back(centered.FromPcl(p));
  }
  // Trim: faces with a vertex far from every input point. Far in units of
  // the point spacing, or of the octree's finest cell where that is coarser
  // (the surface runs through the cells: a vertex lies up to a cell away
  // from the points even where they cover the surface well; PCL's cube is
  // the bounding box's longest side, enlarged by its scale, 1.1).
  std::vector<bool> near(vertices.size(), true);
  if (options.trim_distance_factor > 0) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(centered.cloud);
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : cloud.positions) box.extend(p);
    const double cell =
        1.1 * box.sizes().maxCoeff() / std::ldexp(1.0, options.depth);
    const float limit = static_cast<float>(std::pow(
        options.trim_distance_factor * std::max(median_spacing, cell), 2));
    std::vector<int> found(1);
    std::vector<float> squared(1);
    for (size_t i = 0; i < vertices.size(); ++i) {
      near[i] = tree.nearestKSearch(vertices[i], 1, found, squared) == 1 &&
                squared[0] <= limit;
    }
  }
  *num_trimmed_faces = 0;
  for (const pcl::Vertices& polygon : polygons) {
    if (polygon.vertices.size() != 3) continue;
    const auto& v = polygon.vertices;
    if (!near[v[0]] || !near[v[1]] || !near[v[2]]) {
      ++*num_trimmed_faces;
      continue;
    }
    mesh.faces.emplace_back(v[0], v[1], v[2]);
  }
  LOG(INFO) << "poisson: depth " << options.depth << ", " << polygons.size()
            << " faces, " << *num_trimmed_faces << " trimmed";
  return mesh;
}

}  // namespace bayon
