// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/pcl_cloud.h"

namespace bayon {
namespace {

Eigen::Vector3d Centroid(const std::vector<Eigen::Vector3d>& positions,
                         const std::vector<int>& indices) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i : indices) sum += positions[i];
  return indices.empty() ? sum : Eigen::Vector3d(sum / indices.size());
}

std::vector<int> AllIndices(size_t n) {
  std::vector<int> indices(n);
  for (size_t i = 0; i < n; ++i) indices[i] = static_cast<int>(i);
  return indices;
}

}  // namespace

CenteredPclCloud::CenteredPclCloud(
    const std::vector<Eigen::Vector3d>& positions)
    : CenteredPclCloud(positions, AllIndices(positions.size())) {}

CenteredPclCloud::CenteredPclCloud(
    const std::vector<Eigen::Vector3d>& positions,
    const std::vector<int>& indices)
    : center(Centroid(positions, indices)),
      cloud(new pcl::PointCloud<pcl::PointXYZ>) {
  cloud->resize(indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    (*cloud)[i] = ToPcl(positions[indices[i]]);
  }
}

}  // namespace bayon
