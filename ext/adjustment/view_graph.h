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
// The test is first on triangles, the shortest loops, one pair at a time:
// the pair most of whose triangles fail, with the most failing triangles
// and then the largest median error, is dropped, and the triangles are
// counted again without it, until no pair is left whose failing triangles
// are the majority. A correct pair that shares a triangle with a false one
// thus keeps it once the false one is gone.
//
// Then on longer loops: a false pair between photographs of a repeated
// structure (the faces of a symmetric tower, a courtyard's alike facades)
// often lies on no triangle, only on a loop around the object. A spanning
// tree of the pairs gives every image a rotation, and each pair outside it
// closes one loop through the tree; the loop fails when its error exceeds
// max_loop_error_deg x sqrt(pairs on it / 3) (a triangle's allowance,
// growing as random errors add up) and max_loop_error_sigmas of its
// standard deviation. Of many spanning trees (the heaviest first, then
// drawn at random with the pairs' weights, their conjugate points), the
// one whose loops close for the largest weight is the consensus. A pair
// whose loop through it fails is dropped only where the heaviest tree that
// contains the pair closes less weight: where loops alone do not tell
// which pair of a failing loop is false, the pair with fewer points gives
// way, and where nothing tells (a single loop of equal pairs) none is
// dropped. Pairs on no loop (a bridge between two parts of the graph)
// cannot be tested and are kept.
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
  // The pair's weight in the longer-loop test (> 0): its conjugate points.
  double weight = 1;
};

struct ViewGraphOptions {
  // A triangle fails when its loop error exceeds both, degrees and
  // standard deviations (above).
  double max_loop_error_deg = 5.0;
  double max_loop_error_sigmas = 3.0;
  // Spanning trees tried for the longer loops' consensus.
  int num_spanning_trees = 100;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct DroppedPair {
  int pair_idx = -1;  // into the pairs given
  // Dropped by the triangles: how many it lies on, how many fail.
  int num_triangles = 0;
  int num_failing = 0;
  double median_loop_error_deg = 0;
  // Dropped by a longer loop (num_triangles 0): the loop it closes through
  // the consensus tree, its pairs, error and allowance.
  int loop_length = 0;
  double loop_error_deg = 0;
  double loop_limit_deg = 0;
};

// The pairs that disagree with the loops they lie on, in the order they
// were dropped.
std::vector<DroppedPair> FindInconsistentPairs(
    const std::vector<ViewGraphPair>& pairs, const ViewGraphOptions& options);

// Why the pair was dropped, one line: the triangles that fail, or the
// longer loop, with the limits of `options`.
std::string WhyDropped(const DroppedPair& dropped,
                       const ViewGraphOptions& options);

// The angle of a rotation matrix, degrees.
double RotationAngleDeg(const Eigen::Matrix3d& rotation);

}  // namespace bayon
