// SPDX-License-Identifier: BSD-3-Clause
//
// CGAL's advancing-front surface reconstruction behind meshing.h.
#include "ext/mesh/meshing.h"

#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>

namespace bayon {

TriangleMesh AdvancingFrontMesh(const PointCloud& cloud,
                                const AdvancingFrontOptions& options) {
  options.Check();
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  // Shifted to the centroid, as the other methods, for the same numerics.
  const Eigen::Vector3d center = Centroid(cloud.positions);
  std::vector<Kernel::Point_3> points;
  points.reserve(cloud.size());
  for (const Eigen::Vector3d& p : cloud.positions) {
    const Eigen::Vector3d q = p - center;
    points.emplace_back(q.x(), q.y(), q.z());
  }
  std::vector<std::array<std::size_t, 3>> facets;
  CGAL::advancing_front_surface_reconstruction(points.begin(),
                                               points.end(),
                                               std::back_inserter(facets),
                                               options.radius_ratio_bound,
                                               options.beta);
  TriangleMesh mesh;
  mesh.vertices = cloud;
  mesh.faces.reserve(facets.size());
  for (const auto& f : facets) {
    mesh.faces.emplace_back(
        static_cast<int>(f[0]), static_cast<int>(f[1]), static_cast<int>(f[2]));
  }
  return mesh;
}

}  // namespace bayon
