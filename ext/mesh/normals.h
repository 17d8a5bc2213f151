// SPDX-License-Identifier: BSD-3-Clause
//
// Point normals for the meshing methods that need them: estimated with PCL
// (the smallest principal axis of each point's k nearest neighbours,
// NormalEstimationOMP) and oriented, because PCA gives only a direction:
//  kMst      propagated along a minimum spanning tree of the k-nearest-
//            neighbour graph, weighted by 1 - |n_i . n_j| (Hoppe et al.
//            1992; CGAL's mst_orient_normals), starting from the point
//            farthest from the centroid, whose normal is turned outward;
//            general, but slower and memory-hungry on millions of points;
//  kOutward  each normal turned away from the centroid: right for
//            star-shaped objects (a tower), wrong in concave parts.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

#include <string>

namespace bayon {

enum class NormalOrientation { kMst, kOutward };
std::string NormalOrientationName(NormalOrientation orientation);

struct NormalEstimationOptions {
  int num_neighbors = 24;
  NormalOrientation orientation = NormalOrientation::kMst;
  int num_threads = -1;
  // num_neighbors and orientation; num_threads is the caller's.
  void Register(OptionRegistry* registry);
  void Check() const;
};

// Sets cloud->normals (unit, float). Points whose orientation MST could not
// reach keep the outward rule. Returns the number of such points.
size_t EstimateNormals(const NormalEstimationOptions& options,
                       PointCloud* cloud);

}  // namespace bayon
