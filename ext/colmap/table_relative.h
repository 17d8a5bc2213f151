// SPDX-License-Identifier: BSD-3-Clause
//
// bayon_relative_orientation: the result of `bayon relative` for an image
// pair, beside the two_view_geometries row COLMAP reads: the photogrammetric
// orientation elements with their standard deviations, sigma0, the number
// of blunders, the convergence angle, the DRT parameters L1..L8 and the
// blunder flag of every match row. Pairs that could not be oriented are
// recorded too (success 0, with the reason) and have no two-view geometry.
// Canonical pair order (image_id1 < image_id2), like COLMAP's tables.
//
// Frames (ext/orientation/relative_orientation.h): the model frame is image
// 1's photogrammetric image frame (x right, y up, z towards the viewer);
// omega, phi, kappa rotate image 2 into it (R = Rx Ry Rz); the base is
// image 2's projection centre in it, |b| = 1. cam2_from_cam1 is the same in
// COLMAP's camera frames.
#pragma once

#include "ext/colmap/bayon_tables.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct RelativeOrientationRecord {
  bool success = false;
  std::string reason;  // why not oriented
  bool calibrated = false;
  bool assume_zero_distortion = false;
  int num_matches = 0;
  int num_inliers = 0;
  int num_blunders = 0;
  Eigen::Vector3d omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d std_omega_phi_kappa_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d base = Eigen::Vector3d::UnitX();
  Eigen::Vector2d std_base_deg = Eigen::Vector2d::Zero();
  double sigma0_px = 0;
  double robust_sigma_px = 0;
  double convergence_angle_deg = 0;
  double median_intersection_angle_deg = 0;
  int num_iterations = 0;
  std::optional<Eigen::Matrix<double, 8, 1>> L;
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();
  Rigid3d cam2_from_cam1;
  // Per match row of the pair: 1 used, 0 blunder.
  std::vector<uint8_t> inliers;
  double seconds = 0;
};

extern const BayonTable kRelativeOrientationTable;

// image_id1 < image_id2 required.
void WriteRelativeOrientation(Database* database,
                              image_t image_id1,
                              image_t image_id2,
                              const RelativeOrientationRecord& record);
std::optional<RelativeOrientationRecord> ReadRelativeOrientation(
    Database* database, image_t image_id1, image_t image_id2);
// Every record, by pair id.
std::map<pair_t, RelativeOrientationRecord> ReadAllRelativeOrientations(
    Database* database);

}  // namespace bayon
