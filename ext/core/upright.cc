// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/upright.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>

namespace bayon {
namespace {

// The coordinate-wise median (the object's centre, robust to the stray
// points of a sparse model).
Eigen::Vector3d MedianOf(std::vector<Eigen::Vector3d> points) {
  Eigen::Vector3d median;
  for (int k = 0; k < 3; ++k) {
    const auto middle = points.begin() + points.size() / 2;
    std::nth_element(points.begin(),
                     middle,
                     points.end(),
                     [k](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
                       return a(k) < b(k);
                     });
    median(k) = (*middle)(k);
  }
  return median;
}

}  // namespace

std::optional<UprightFrame> EstimateUprightFrame(
    const std::vector<Rigid3d>& cam_from_world,
    const std::vector<Eigen::Vector3d>& points) {
  const int n = static_cast<int>(cam_from_world.size());
  if (n < 2) return std::nullopt;
  // Per image its axes in object space: x (right) and y (down).
  std::vector<Eigen::Vector3d> x_axes, y_axes, centres;
  for (const Rigid3d& pose : cam_from_world) {
    const Eigen::Matrix3d world_from_cam =
        pose.rotation.inverse().toRotationMatrix();
    x_axes.push_back(world_from_cam.col(0));
    y_axes.push_back(world_from_cam.col(1));
    centres.push_back(pose.Center());
  }
  // An image's candidate for up nearest g: -y, x, y or -x.
  const auto candidate = [&](int i, const Eigen::Vector3d& g) {
    const double along_x = x_axes[i].dot(g), along_y = y_axes[i].dot(g);
    if (std::abs(along_y) >= std::abs(along_x)) {
      return along_y <= 0 ? -y_axes[i] : y_axes[i];
    }
    return along_x >= 0 ? x_axes[i] : -x_axes[i];
  };
  const auto score = [&](const Eigen::Vector3d& g) {
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += candidate(i, g).dot(g);
    return sum;
  };
  // Images that see g as their -y axis: upright landscape photographs.
  const auto num_upright = [&](const Eigen::Vector3d& g) {
    int count = 0;
    for (int i = 0; i < n; ++i) {
      count += std::abs(y_axes[i].dot(g)) >= std::abs(x_axes[i].dot(g)) &&
               y_axes[i].dot(g) < 0;
    }
    return count;
  };
  const auto converge = [&](Eigen::Vector3d g) {
    for (int iteration = 0; iteration < 20; ++iteration) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int i = 0; i < n; ++i) sum += candidate(i, g);
      if (sum.norm() < 1e-9) break;
      const Eigen::Vector3d next = sum.normalized();
      const bool settled = (next - g).norm() < 1e-12;
      g = next;
      if (settled) break;
    }
    return g;
  };
  // 1. From the up candidates -y and x of (up to 100 of) the images, the
  //    consensus with the largest score; where several come within 5 % of
  //    it (photographs all facing one way agree on x as well as on -y), the
  //    one most images see as -y, upright: portrait photographs are the
  //    exception.
  std::vector<std::pair<Eigen::Vector3d, double>> solutions;
  const int stride = std::max(1, n / 100);
  for (int i = 0; i < n; i += stride) {
    for (const Eigen::Vector3d& start :
         {Eigen::Vector3d(-y_axes[i]), x_axes[i]}) {
      const Eigen::Vector3d g = converge(start);
      solutions.emplace_back(g, score(g));
    }
  }
  double best = 0;
  for (const auto& solution : solutions) {
    best = std::max(best, solution.second);
  }
  Eigen::Vector3d g = solutions.front().first;
  int most_upright = -1;
  for (const auto& [candidate_g, s] : solutions) {
    if (s < 0.95 * best) continue;
    for (const Eigen::Vector3d& signed_g :
         {candidate_g, Eigen::Vector3d(-candidate_g)}) {
      const int count = num_upright(signed_g);
      if (count > most_upright) most_upright = count, g = signed_g;
    }
  }
  // No consensus where the images' axes spread all round (a mean cosine
  // under 0.3: more than 72 degrees; photographs looking 60 degrees down
  // onto an object still give 0.5).
  if (score(g) < 0.3 * n) return std::nullopt;
  // The sign. Where as many images are upside down as upright (portrait
  // photographs turned both ways, as temple-ring's are), the stations
  // tell: photographs all round an object look down onto it, so up points
  // from the object's centre towards the stations. Where they stand level
  // with it (within 5 % of their distance), nothing tells.
  const Eigen::Vector3d centre = MedianOf(points.empty() ? centres : points);
  if (num_upright(g) == num_upright(-g)) {
    double height = 0, distance = 0;
    for (const Eigen::Vector3d& station : centres) {
      height += (station - centre).dot(g);
      distance += (station - centre).norm();
    }
    if (std::abs(height) < 0.05 * distance) return std::nullopt;
    if (height < 0) g = -g;
  }

  // 2. The horizontal axes: each image's axis other than its up candidate.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const bool up_is_y =
        std::abs(y_axes[i].dot(g)) >= std::abs(x_axes[i].dot(g));
    const Eigen::Vector3d& horizontal = up_is_y ? x_axes[i] : y_axes[i];
    scatter += horizontal * horizontal.transpose();
  }
  // Eigenvalues in increasing order; they sum to n. A ring's horizontal
  // axes fill the horizontal plane (the middle eigenvalue near n / 2); a
  // strip's lie along one line (it near 0). A tenth of the images turned
  // by 30 degrees from the rest still spans the plane.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(scatter);
  UprightFrame frame;
  if (axes.eigenvalues()(1) > 0.025 * n) {
    frame.up = axes.eigenvectors().col(0);
    if (frame.up.dot(g) < 0) frame.up = -frame.up;
    frame.source = "the images' horizontal axes (cameras held level)";
  } else {
    frame.up = g;
    frame.source = "the images' mean up axis (all facing one way)";
  }
  frame.centre = centre;
  const Eigen::Quaterniond rotation =
      Eigen::Quaterniond::FromTwoVectors(frame.up, Eigen::Vector3d::UnitZ());
  frame.new_from_old = Rigid3d(rotation, -(rotation * frame.centre));
  return frame;
}

}  // namespace bayon
