// SPDX-License-Identifier: BSD-3-Clause
//
// Conjugate points by relaxation, the paper's step 3.2.1(c), after Zhang,
// Deriche, Faugeras and Luong (1995, "A robust technique for matching two
// uncalibrated images through the recovery of the unknown epipolar
// geometry", Artificial Intelligence 78): every candidate match (m1, m2)
// with correlation c >= r gets a strength from the candidates around it,
//
//   SM(m1, m2) = c(m1, m2) * sum over neighbours n1 of m1 of
//                  max over candidates (n1, n2) with n2 near m2 of
//                    c(n1, n2) * delta / (1 + dist / R)
//
// (continuity: neighbours move alike; the max lets each neighbour vote
// once), where, with d1 = n1 - m1, d2 = n2 - m2 and L the linear part of
// the approximate mapping from image 1 to image 2 (rotation and scale,
// estimated by the matcher),
//
//   r     = | |L d1| - |d2| | / dist,  dist = (|L d1| + |d2|) / 2,
//   delta = exp(-r / eps_r) if r < eps_r and the angle between L d1 and d2
//           is below max_angle, else 0.
//
// Uniqueness is reached by the "loser-takes-nothing" iteration: strengths
// are recomputed from the surviving candidates; at every point of either
// image with more than one candidate, the weakest one (the loser) is
// removed; candidates with too few consistent neighbours (min_support,
// min_support_fraction) are removed too. This repeats until every point keeps
// at most one partner. Losers never win anything back, but nothing is declared
// a winner before its competitors are gone, which keeps early mistakes from
// propagating.
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>

#include <vector>

namespace bayon {

struct MatchCandidate {
  int idx1 = -1;  // keypoint index in image 1
  int idx2 = -1;  // keypoint index in image 2
  float ncc = 0;  // correlation coefficient
};

struct RelaxationOptions {
  // Neighbourhood radius R as a fraction of the larger side of image 1
  // (Zhang et al.: 1/8 of the image).
  double neighborhood_fraction = 0.125;
  // At most this many nearest neighbours (with candidates) support a
  // candidate; bounds the cost on dense point sets.
  int max_neighbors = 24;
  // eps_r: tolerated relative difference of neighbour distances.
  double max_relative_distance_difference = 0.3;
  // Largest angle between L d1 and d2, degrees.
  double max_angle_deg = 45.0;
  // Consistent neighbours a match needs to survive: at least min_support,
  // and at least this fraction of its neighbours (those with candidates).
  // True matches on a smooth surface agree with most of their neighbours;
  // chance clusters of look-alike windows agree with few.
  int min_support = 2;
  double min_support_fraction = 0.1;
  // Iterations before the remaining ambiguities are settled by strength.
  int max_iterations = 30;
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct RelaxationResult {
  std::vector<MatchCandidate> matches;  // one-to-one
  std::vector<float> strength;          // SM per match
  std::vector<int> support;             // consistent neighbours per match
  int num_iterations = 0;
};

// `image2_from_image1` is the linear part L (2 x 2) of the approximate
// mapping between the images; `image_size1` the larger side of image 1.
RelaxationResult RelaxMatches(const std::vector<Eigen::Vector2d>& xy1,
                              const std::vector<Eigen::Vector2d>& xy2,
                              const std::vector<MatchCandidate>& candidates,
                              const Eigen::Matrix2d& image2_from_image1,
                              double image_size1,
                              const RelaxationOptions& options);

}  // namespace bayon
