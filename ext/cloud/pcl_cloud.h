// SPDX-License-Identifier: BSD-3-Clause
//
// Internal to the cloud and mesh stages (it includes PCL; never include it
// from a public header): bayon's double-precision points as PCL clouds.
// PCL stores float coordinates, so points are shifted to their centroid
// first: metre-sized objects far from the datum origin keep sub-micrometre
// resolution.
#pragma once

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace bayon {

struct CenteredPclCloud {
  // All points, or those listed in `indices` (in that order).
  explicit CenteredPclCloud(const std::vector<Eigen::Vector3d>& positions);
  CenteredPclCloud(const std::vector<Eigen::Vector3d>& positions,
                   const std::vector<int>& indices);

  pcl::PointXYZ ToPcl(const Eigen::Vector3d& p) const {
    const Eigen::Vector3f q = (p - center).cast<float>();
    return pcl::PointXYZ(q.x(), q.y(), q.z());
  }
  Eigen::Vector3d FromPcl(const pcl::PointXYZ& p) const {
    return center + Eigen::Vector3d(p.x, p.y, p.z);
  }

  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;
};

}  // namespace bayon
