// SPDX-License-Identifier: BSD-3-Clause
#include "ext/mesh/normals.h"

#include "ext/cloud/pcl_cloud.h"
#include "ext/core/errors.h"
#include "ext/core/parallel.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/property_map.h>
#include <glog/logging.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/search/kdtree.h>

#include <tuple>

namespace bayon {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using PointNormalIndex = std::tuple<Kernel::Point_3, Kernel::Vector_3, int>;

}  // namespace

std::string NormalOrientationName(NormalOrientation orientation) {
  return orientation == NormalOrientation::kMst ? "mst" : "outward";
}

void NormalEstimationOptions::Register(OptionRegistry* r) {
  r->Add("num_neighbors", &num_neighbors, "Neighbours for normal estimation");
  r->AddChoice("orientation",
               &orientation,
               ChoicesOf<NormalOrientation>(
                   NormalOrientationName,
                   {NormalOrientation::kMst, NormalOrientation::kOutward}),
               "mst or outward");
}

void NormalEstimationOptions::Check() const {
  CheckOption(num_neighbors >= 3 && num_neighbors <= 500,
              "num_neighbors",
              "in [3, 500]",
              num_neighbors);
}

size_t EstimateNormals(const NormalEstimationOptions& options,
                       PointCloud* cloud) {
  options.Check();
  const size_t n = cloud->size();
  const CenteredPclCloud pcl_cloud(cloud->positions);
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> estimation(
      EffectiveNumThreads(options.num_threads));
  estimation.setInputCloud(pcl_cloud.cloud);
  estimation.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(
      new pcl::search::KdTree<pcl::PointXYZ>));
  estimation.setKSearch(options.num_neighbors);
  // PCL turns each normal towards this viewpoint: the centroid, which the
  // outward rule below then reverses.
  estimation.setViewPoint(0, 0, 0);
  pcl::PointCloud<pcl::Normal> normals;
  estimation.compute(normals);

  cloud->normals.assign(n, Eigen::Vector3f::Zero());
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3f normal(
        normals[i].normal_x, normals[i].normal_y, normals[i].normal_z);
    if (!normal.allFinite() || normal.norm() < 0.5) {
      normal = (cloud->positions[i] - pcl_cloud.center).cast<float>();
    }
    // Outward: away from the centroid.
    const Eigen::Vector3f out =
        (cloud->positions[i] - pcl_cloud.center).cast<float>();
    if (normal.dot(out) < 0) normal = -normal;
    cloud->normals[i] = normal.normalized();
  }
  if (options.orientation == NormalOrientation::kOutward) return 0;

  std::vector<PointNormalIndex> points(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = cloud->positions[i] - pcl_cloud.center;
    const Eigen::Vector3f& v = cloud->normals[i];
    points[i] = {Kernel::Point_3(p.x(), p.y(), p.z()),
                 Kernel::Vector_3(v.x(), v.y(), v.z()),
                 static_cast<int>(i)};
  }
  const auto unoriented = CGAL::mst_orient_normals(
      points,
      static_cast<unsigned int>(options.num_neighbors),
      CGAL::parameters::point_map(
          CGAL::Nth_of_tuple_property_map<0, PointNormalIndex>())
          .normal_map(CGAL::Nth_of_tuple_property_map<1, PointNormalIndex>()));
  // MST fixes the normals relative to each other; the sign of the whole is
  // the outward rule's majority (CGAL starts from the highest point, whose
  // normal may be horizontal on an open tube).
  size_t outward = 0, oriented = 0;
  for (auto it = points.begin(); it != unoriented; ++it) {
    const int i = std::get<2>(*it);
    const Kernel::Vector_3& v = std::get<1>(*it);
    const Eigen::Vector3f normal(v.x(), v.y(), v.z());
    outward += normal.dot(cloud->normals[i]) > 0;
    ++oriented;
  }
  const float sign = 2 * outward >= oriented ? 1.0f : -1.0f;
  for (auto it = points.begin(); it != unoriented; ++it) {
    const Kernel::Vector_3& v = std::get<1>(*it);
    cloud->normals[std::get<2>(*it)] =
        sign * Eigen::Vector3f(v.x(), v.y(), v.z()).normalized();
  }
  const size_t num_unoriented = points.end() - unoriented;
  LOG(INFO) << "normals: " << oriented << " oriented by MST ("
            << (sign > 0 ? "" : "flipped, ") << num_unoriented
            << " kept outward)";
  return num_unoriented;
}

}  // namespace bayon
