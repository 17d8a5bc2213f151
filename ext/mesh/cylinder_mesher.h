// SPDX-License-Identifier: BSD-3-Clause
//
// The Bayon paper's triangulation (sec. 3.4): "the 3D surface model ... was
// expanded to a plane by transforming the Cartesian coordinate system to a
// cylinder coordinate frame ... z is the vertical cylinder axis crossing the
// model center ... r is the Euclidean distance from the surface point to the
// z-axis and q is the angle around the z-axis. The 2.5D Delaunay
// triangulation was done in the qz plane."
//
// Here: the axis runs through `axis_point` (default the centroid) along
// `axis_direction` (default the datum's vertical, z). Each point maps to
// (x, y) = (theta * r_mean, f(h)), theta the angle around the axis in
// (-pi, pi], h the height along it, r_mean the mean distance from the axis.
//
// The metric decides the triangles' shape. kMeanRadius takes f(h) = h: true
// lengths where the object's radius is r_mean, triangles stretched
// sideways by r_mean / r elsewhere. kProfile (default) takes
// f(h) = r_mean * integral of sqrt(1 + r'(h)^2) / r(h) dh over the median
// radius profile r(h): for a surface of revolution this is a conformal map
// (lengths scale by r(h) / r_mean equally in both directions), so Delaunay's
// well-shaped plane triangles stay well-shaped on the object however its
// radius changes with height. Both keep f independent of theta, so going
// once round the axis is a pure translation by 2 pi r_mean in x: the seam at
// +-180 degrees is closed by copying a band of points across it, with
// coordinates quantised so that the copies are exact translations (exact
// predicates then see the same configurations on both sides), and keeping
// each triangle once: the copy whose centroid lies in [-pi r_mean, pi
// r_mean). A triangle is kept only when its circumcircle lies inside the
// band-extended plane: it is then Delaunay for the whole periodic point set
// and identical to its copy (the ones left out are the convex hull's
// fringe at top and bottom). The result has no gap and no overlap at the
// seam.
//
// Triangles are then removed when their longest 3D edge exceeds
// max_edge_factor times the local spacing (the mean of their vertices'
// distances to their 6th nearest neighbour: bridges over holes and the
// convex hull's fringe at top and bottom), or when their smallest 3D angle is
// below min_angle_deg (degenerate slivers where the surface folds back in the
// cylinder frame).
//
// Cone angle: with cone_angle_deg = alpha > 0 each point is projected along
// a direction tilted up by alpha in the half-plane of its angle: the graph
// coordinate t = h sin(alpha) + r cos(alpha) takes r's place and the profile
// coordinate s = h cos(alpha) - r sin(alpha) takes h's place (alpha = 0 is
// the paper's frame). The flat top of a ledge or tier, which faces up and
// folds in the cylinder frame, then stays a graph over (theta, s).
//
// Limitation: the frame needs t to be a function of (theta, s); surfaces
// that face away from the projection direction (the underside of a cornice
// with alpha > 0, a horizontal ledge with alpha = 0) or hide behind other
// parts of the object fold in the plane.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

#include <Eigen/Core>

#include <limits>
#include <string>

namespace bayon {

enum class CylinderMetric { kProfile, kMeanRadius };
std::string CylinderMetricName(CylinderMetric metric);

struct CylinderMeshOptions {
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitZ();
  // The axis passes through this point; NaN = the centroid of the points.
  Eigen::Vector3d axis_point =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  CylinderMetric metric = CylinderMetric::kProfile;
  // Tilt of the projection direction above the horizontal, degrees: 0 is
  // the paper's cylinder frame (r as a function of angle and height); 45
  // also unfolds the flat tops of ledges and tiers (see above).
  double cone_angle_deg = 0;
  // Width of the band copied across the seam, degrees: a few point spacings
  // at least (2 % of the circumference by default).
  double seam_band_deg = 7.2;
  double max_edge_factor = 4.0;
  double min_angle_deg = 0.1;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct CylinderMeshReport {
  Eigen::Vector3d axis_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitZ();
  double mean_radius = 0;
  size_t num_points = 0;
  size_t num_on_axis = 0;     // too close to the axis to have an angle
  size_t num_duplicates = 0;  // same plane position as another point
  size_t num_seam_copies = 0;
  size_t num_delaunay_faces = 0;  // in the plane, copies included
  size_t num_faces_once = 0;      // each face once
  size_t num_seam_faces = 0;      // faces across the seam
  // Faces whose circumcircle reaches beyond the copied band (only the
  // hull's fringe and bridges over wide holes in practice): left out.
  size_t num_seam_unsafe = 0;
  size_t num_long_removed = 0;
  size_t num_degenerate_removed = 0;
};

// Triangulates `cloud` (the mesh's vertices are the cloud's points, with
// their attributes); faces counter-clockwise seen from outside the axis.
// The cloud must be checked already (finite, at least 3 points).
TriangleMesh CylinderDelaunayMesh(const PointCloud& cloud,
                                  const CylinderMeshOptions& options,
                                  int num_threads,
                                  CylinderMeshReport* report);

}  // namespace bayon
