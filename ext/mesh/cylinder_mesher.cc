// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/cylinder_mesher.h"

#include "ext/cloud/pcl_cloud.h"
#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/core/parallel.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <Eigen/Geometry>
#include <glog/logging.h>
#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;

double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t k = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// Median of each bin, empty bins filled from their neighbours, then a
// light 3-bin smoothing (the derivative taken of it amplifies bin noise).
std::vector<double> SmoothBinMedians(std::vector<std::vector<double>> bins) {
  const int num_bins = static_cast<int>(bins.size());
  std::vector<double> m(num_bins, std::numeric_limits<double>::quiet_NaN());
  for (int b = 0; b < num_bins; ++b) {
    if (!bins[b].empty()) m[b] = Median(std::move(bins[b]));
  }
  int last = -1;
  for (int b = 0; b < num_bins; ++b) {
    if (std::isnan(m[b])) continue;
    for (int e = last + 1; e < b; ++e) {
      m[e] = last < 0 ? m[b]
                      : m[last] + (m[b] - m[last]) * (e - last) / (b - last);
    }
    last = b;
  }
  for (int e = last + 1; e < num_bins; ++e) m[e] = last < 0 ? 0.0 : m[last];
  std::vector<double> smooth(num_bins);
  for (int b = 0; b < num_bins; ++b) {
    const int lo = std::max(0, b - 1), hi = std::min(num_bins - 1, b + 1);
    double sum = 0;
    for (int e = lo; e <= hi; ++e) sum += m[e];
    smooth[b] = sum / (hi - lo + 1);
  }
  return smooth;
}

// Profile coordinate s -> plane y for the kProfile metric: r_mean times the
// integral of sqrt(1 + t'(s)^2) / r(s) ds over the median profile, t the
// graph coordinate (distance along the projection direction) and r the
// distance from the axis, piecewise linear between bin centres, extended
// linearly beyond them. With a zero cone angle s = h and t = r.
class ProfileMap {
 public:
  ProfileMap(const std::vector<double>& profile,
             const std::vector<double>& graph,
             const std::vector<double>& radii,
             double mean_radius) {
    const double s_min = *std::min_element(profile.begin(), profile.end());
    const double s_max = *std::max_element(profile.begin(), profile.end());
    const int num_bins = std::clamp(
        static_cast<int>(std::sqrt(static_cast<double>(profile.size())) / 2),
        4,
        256);
    const double width = std::max(s_max - s_min, 1e-12) / num_bins;
    std::vector<std::vector<double>> graph_bins(num_bins),
        radius_bins(num_bins);
    for (size_t i = 0; i < profile.size(); ++i) {
      const int b = std::min(num_bins - 1,
                             static_cast<int>((profile[i] - s_min) / width));
      graph_bins[b].push_back(graph[i]);
      radius_bins[b].push_back(radii[i]);
    }
    const std::vector<double> t = SmoothBinMedians(std::move(graph_bins));
    const std::vector<double> r = SmoothBinMedians(std::move(radius_bins));
    centers_.resize(num_bins);
    values_.resize(num_bins);
    std::vector<double> integrand(num_bins);
    for (int b = 0; b < num_bins; ++b) {
      centers_[b] = s_min + (b + 0.5) * width;
      const int lo = std::max(0, b - 1), hi = std::min(num_bins - 1, b + 1);
      const double slope =
          hi > lo ? (t[hi] - t[lo]) / ((hi - lo) * width) : 0.0;
      integrand[b] = mean_radius * std::sqrt(1 + slope * slope) /
                     std::max(r[b], 1e-3 * mean_radius);
    }
    values_[0] = 0;
    for (int b = 1; b < num_bins; ++b) {
      values_[b] =
          values_[b - 1] + 0.5 * (integrand[b - 1] + integrand[b]) * width;
    }
    first_slope_ = integrand.front();
    last_slope_ = integrand.back();
  }

  double operator()(double h) const {
    if (h <= centers_.front()) {
      return values_.front() + (h - centers_.front()) * first_slope_;
    }
    if (h >= centers_.back()) {
      return values_.back() + (h - centers_.back()) * last_slope_;
    }
    const size_t b = std::upper_bound(centers_.begin(), centers_.end(), h) -
                     centers_.begin();
    const double t = (h - centers_[b - 1]) / (centers_[b] - centers_[b - 1]);
    return values_[b - 1] + t * (values_[b] - values_[b - 1]);
  }

 private:
  std::vector<double> centers_;
  std::vector<double> values_;
  double first_slope_ = 1;
  double last_slope_ = 1;
};

double AngleDeg(double opposite, double a, double b) {
  if (!(a > 0 && b > 0)) return 0;
  const double c = std::clamp(
      (a * a + b * b - opposite * opposite) / (2 * a * b), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

}  // namespace

std::string CylinderMetricName(CylinderMetric metric) {
  return metric == CylinderMetric::kProfile ? "profile" : "mean_radius";
}

void CylinderMeshOptions::Register(OptionRegistry* r) {
  r->Add("axis_direction",
         &axis_direction,
         "The object's vertical axis, x,y,z (datum z)");
  r->Add("axis_point",
         &axis_point,
         "A point on the axis, x,y,z (empty: the centroid)");
  r->AddChoice("metric",
               &metric,
               ChoicesOf<CylinderMetric>(
                   CylinderMetricName,
                   {CylinderMetric::kProfile, CylinderMetric::kMeanRadius}),
               "profile or mean_radius");
  r->Add("cone_angle_deg",
         &cone_angle_deg,
         "Tilt of the projection above the horizontal (0 = the paper's "
         "cylinder; 45 unfolds flat ledge tops)");
  r->Add("seam_band_deg",
         &seam_band_deg,
         "Band copied across the +-180 degree seam");
  r->Add("max_edge_factor",
         &max_edge_factor,
         "Drop triangles with an edge longer than this many local spacings");
  r->Add(
      "min_angle_deg", &min_angle_deg, "Drop triangles with a smaller angle");
}

void CylinderMeshOptions::Check() const {
  CheckOption(axis_direction.allFinite() && axis_direction.norm() > 0,
              "axis_direction",
              "a non-zero vector",
              axis_direction.transpose());
  CheckOption(cone_angle_deg >= 0 && cone_angle_deg < 80,
              "cone_angle_deg",
              "in [0, 80)",
              cone_angle_deg);
  CheckOption(seam_band_deg > 0 && seam_band_deg <= 90,
              "seam_band_deg",
              "in (0, 90]",
              seam_band_deg);
  CheckOption(max_edge_factor > 1, "max_edge_factor", "> 1", max_edge_factor);
  CheckOption(min_angle_deg >= 0 && min_angle_deg < 30,
              "min_angle_deg",
              "in [0, 30)",
              min_angle_deg);
}

TriangleMesh CylinderDelaunayMesh(const PointCloud& cloud,
                                  const CylinderMeshOptions& options,
                                  int num_threads,
                                  CylinderMeshReport* report) {
  options.Check();
  *report = CylinderMeshReport();
  const size_t n = cloud.size();
  report->num_points = n;
  const Eigen::Vector3d axis = options.axis_direction.normalized();
  Eigen::Vector3d center = options.axis_point;
  if (!center.allFinite()) {
    center = Centroid(cloud.positions);
  }
  report->axis_point = center;
  report->axis_direction = axis;
  // e1, e2, axis: right-handed, so the angle grows counter-clockwise seen
  // from the tip of the axis.
  int least = 0;
  axis.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3d e1 =
      axis.cross(Eigen::Vector3d::Unit(least)).normalized();
  const Eigen::Vector3d e2 = axis.cross(e1);

  // Cylinder coordinates.
  std::vector<double> theta(n), height(n), radius(n);
  double extent = 0, radius_sum = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = cloud.positions[i] - center;
    height[i] = d.dot(axis);
    const double x = d.dot(e1), y = d.dot(e2);
    radius[i] = std::hypot(x, y);
    theta[i] = std::atan2(y, x);
    extent = std::max({extent, radius[i], std::abs(height[i])});
    radius_sum += radius[i];
  }
  const double mean_radius = radius_sum / std::max<size_t>(n, 1);
  report->mean_radius = mean_radius;
  if (!(mean_radius > 0)) {
    ThrowInputError("every point lies on the cylinder axis");
  }
  const double on_axis = 1e-6 * extent;

  // The plane: x = theta / (2 pi) * period, y = f(h), quantised to a power of
  // two so that x +- period is exact.
  const double quantum =
      std::ldexp(1.0, static_cast<int>(std::floor(std::log2(extent))) - 40);
  auto quantise = [quantum](double v) {
    return std::round(v / quantum) * quantum;
  };
  const double period = quantise(2 * M_PI * mean_radius);
  // The profile coordinate s and the graph coordinate t in the half-plane
  // of each point's angle: t along the projection direction (outward,
  // tilted up by the cone angle), s across it (up the wall, inward on a
  // ledge).
  const double alpha = options.cone_angle_deg * M_PI / 180;
  std::vector<double> profile(n), graph(n);
  for (size_t i = 0; i < n; ++i) {
    profile[i] = height[i] * std::cos(alpha) - radius[i] * std::sin(alpha);
    graph[i] = height[i] * std::sin(alpha) + radius[i] * std::cos(alpha);
  }
  std::vector<double> plane_y(n);
  if (options.metric == CylinderMetric::kProfile) {
    const ProfileMap map(profile, graph, radius, mean_radius);
    for (size_t i = 0; i < n; ++i) plane_y[i] = quantise(map(profile[i]));
  } else {
    for (size_t i = 0; i < n; ++i) plane_y[i] = quantise(profile[i]);
  }
  const double band = period * options.seam_band_deg / 360.0;
  std::vector<std::pair<Kernel::Point_2, int>> plane_points;
  plane_points.reserve(n + n / 8);
  for (size_t i = 0; i < n; ++i) {
    if (radius[i] <= on_axis) {
      ++report->num_on_axis;
      continue;
    }
    const double x = quantise(theta[i] / (2 * M_PI) * period);
    const int index = static_cast<int>(i);
    plane_points.emplace_back(Kernel::Point_2(x, plane_y[i]), index);
    if (x > 0.5 * period - band) {
      plane_points.emplace_back(Kernel::Point_2(x - period, plane_y[i]), index);
      ++report->num_seam_copies;
    } else if (x < -0.5 * period + band) {
      plane_points.emplace_back(Kernel::Point_2(x + period, plane_y[i]), index);
      ++report->num_seam_copies;
    }
  }

  const Delaunay triangulation(plane_points.begin(), plane_points.end());
  report->num_duplicates =
      plane_points.size() - triangulation.number_of_vertices();
  report->num_delaunay_faces = triangulation.number_of_faces();

  // Each face once: the copy whose centroid lies in [-period/2, period/2).
  std::vector<Eigen::Vector3i> faces;
  faces.reserve(triangulation.number_of_faces() / 2 + 16);
  for (auto f = triangulation.finite_faces_begin();
       f != triangulation.finite_faces_end();
       ++f) {
    const int a = f->vertex(0)->info(), b = f->vertex(1)->info(),
              c = f->vertex(2)->info();
    if (a == b || b == c || a == c) continue;
    double sum_x = 0;
    bool crosses = false;
    for (int k = 0; k < 3; ++k) {
      const double x = f->vertex(k)->point().x();
      sum_x += x;
      crosses |= x < -0.5 * period || x >= 0.5 * period;
    }
    const double mean_x = sum_x / 3;
    if (mean_x < -0.5 * period || mean_x >= 0.5 * period) continue;
    // A face is Delaunay for the whole periodic point set, and so the same
    // as its copy one period away, when its empty circumcircle lies where
    // the copied band makes the plane complete. Faces whose circle reaches
    // beyond (the hull's fringe at top and bottom, bridges over large
    // holes) might differ from their copies: left out, never doubled.
    const Kernel::Point_2 center = CGAL::circumcenter(
        f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
    const double radius =
        std::sqrt(CGAL::squared_distance(center, f->vertex(0)->point()));
    if (!(center.x() - radius >= -0.5 * period - band &&
          center.x() + radius <= 0.5 * period + band)) {
      ++report->num_seam_unsafe;
      continue;
    }
    if (crosses) ++report->num_seam_faces;
    faces.emplace_back(a, b, c);  // counter-clockwise in the plane
  }
  report->num_faces_once = faces.size();

  // Local spacing per point: the distance to its 6th nearest neighbour in
  // 3D (about 1.4 / sqrt(density) on a surface), independent of the
  // triangulation, whose fringe along the convex hull is what is judged.
  const auto& p = cloud.positions;
  std::vector<double> spacing(n, 0);
  {
    const CenteredPclCloud pcl_cloud(p);
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(pcl_cloud.cloud);
    constexpr int kNeighbors = 7;  // itself and six others
    constexpr int kBlock = 1024;
    ParallelFor(static_cast<int>((n + kBlock - 1) / kBlock),
                num_threads,
                [&](int block) {
                  std::vector<int> found(kNeighbors);
                  std::vector<float> squared(kNeighbors);
                  const size_t end = std::min(n, size_t{kBlock} * (block + 1));
                  for (size_t i = size_t{kBlock} * block; i < end; ++i) {
                    const int count = tree.nearestKSearch(
                        (*pcl_cloud.cloud)[i], kNeighbors, found, squared);
                    spacing[i] = count > 0 ? std::sqrt(squared[count - 1]) : 0;
                  }
                });
  }

  TriangleMesh mesh;
  mesh.vertices = cloud;
  mesh.faces.reserve(faces.size());
  for (const Eigen::Vector3i& f : faces) {
    const double ab = (p[f(0)] - p[f(1)]).norm();
    const double bc = (p[f(1)] - p[f(2)]).norm();
    const double ca = (p[f(2)] - p[f(0)]).norm();
    const double local = (spacing[f(0)] + spacing[f(1)] + spacing[f(2)]) / 3;
    if (std::max({ab, bc, ca}) > options.max_edge_factor * local) {
      ++report->num_long_removed;
      continue;
    }
    const double min_angle = std::min(
        {AngleDeg(bc, ab, ca), AngleDeg(ca, ab, bc), AngleDeg(ab, bc, ca)});
    if (min_angle < options.min_angle_deg) {
      ++report->num_degenerate_removed;
      continue;
    }
    mesh.faces.push_back(f);
  }
  LOG(INFO) << "cylinder: " << report->num_faces_once << " faces in the plane ("
            << report->num_seam_faces << " across the seam), "
            << report->num_long_removed << " too long, "
            << report->num_degenerate_removed << " degenerate";
  return mesh;
}

}  // namespace bayon
