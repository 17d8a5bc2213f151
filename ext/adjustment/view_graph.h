// SPDX-License-Identifier: BSD-3-Clause
//
// Loop consistency of the relative orientations before strip chains them.
// Around any loop of oriented pairs the relative rotations must compose to
// the identity: for images i, j, k with all three pairs oriented,
//
//   E_ijk = R_ik R_kj R_ji = I   (R_ba: camera b from camera a),
//
// and the angle of E_ijk, the loop error, is a few tenths of a degree for
// correct pairs (their own errors added up). A false orientation (chance
// matches between photographs that do not overlap, a repeated structure, a
// mirror solution) makes every loop it lies on fail by as much as it is
// wrong: tens of degrees.
//
// A triangle fails when its loop error exceeds max_loop_error_deg and
// max_loop_error_sigmas times its standard deviation, from its pairs' own
// (sqrt of the sum of their squares): a weak pair, with a rotation known to
// a few degrees, is not mistaken for a false one.
//
// The test is on triangles, the shortest loops, one pair at a time: the
// pair most of whose triangles fail,
// with the most failing triangles and then the largest median error, is
// dropped, and the triangles are counted again without it, until no pair
// is left whose failing triangles are the majority. A correct pair that
// shares a triangle with a false one thus keeps it once the false one is
// gone. Pairs on no triangle (a ring of neighbours only) cannot be tested
// and are kept.
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

struct ViewGraphPair {
  int image1 = -1;
  int image2 = -1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // cam2 from cam1
  // The rotation's standard deviation, degrees (0: unknown).
  double sigma_deg = 0;
};

struct ViewGraphOptions {
  // A triangle fails when its loop error exceeds both, degrees and
  // standard deviations (above).
  double max_loop_error_deg = 5.0;
  double max_loop_error_sigmas = 3.0;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct DroppedPair {
  int pair_idx = -1;  // into the pairs given
  int num_triangles = 0;
  int num_failing = 0;
  double median_loop_error_deg = 0;
};

// The pairs that disagree with the loops they lie on, in the order they
// were dropped.
std::vector<DroppedPair> FindInconsistentPairs(
    const std::vector<ViewGraphPair>& pairs, const ViewGraphOptions& options);

// The angle of a rotation matrix, degrees.
double RotationAngleDeg(const Eigen::Matrix3d& rotation);

}  // namespace bayon
