// SPDX-License-Identifier: BSD-3-Clause
//
// Matching by descriptor, as COLMAP's SIFT matcher does (Lowe 2004, 7.1):
// each keypoint of image 1 takes the keypoint of image 2 whose descriptor is
// nearest, if it is distinctive (Lowe's ratio test: its distance is below
// max_ratio times the second nearest's) and near enough, and, with
// cross_check, only if it is also that keypoint's nearest and passes the
// same tests in that direction (mutual best, as COLMAP checks it).
//
// Distances are angles between unit descriptors, acos(d1 . d2 / 512^2) for
// descriptors stored as COLMAP stores them (sift.h), so that max_distance
// and max_ratio mean what COLMAP's SiftMatching options mean.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/option_registry.h"

#include <Eigen/Core>

#include <vector>

namespace bayon {

struct DescriptorMatchingOptions {
  double max_ratio = 0.8;     // COLMAP's SiftMatching.max_ratio
  double max_distance = 0.7;  // radians; COLMAP's SiftMatching.max_distance
  bool cross_check = true;    // mutual best only
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

struct DescriptorMatch {
  int idx1 = 0;
  int idx2 = 0;
  float distance = 0;  // radians
};

// Descriptors as unit vectors, one per row: COLMAP's bytes / 512.
using UnitDescriptors =
    Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
UnitDescriptors ToUnitDescriptors(const FeatureDescriptors& descriptors);
UnitDescriptors ToUnitDescriptors(const FeatureDescriptors& descriptors,
                                  const std::vector<int>& rows);

// Matches every row of `unit1` with every row of `unit2`; indices in the
// result are the rows'. An image-1 row appears at most once, and with
// cross_check an image-2 row too. Cost O(n1 n2 128), in blocks so that
// memory stays O(n2).
std::vector<DescriptorMatch> MatchDescriptors(
    const UnitDescriptors& unit1,
    const UnitDescriptors& unit2,
    const DescriptorMatchingOptions& options);

// The same for the descriptor rows `rows1` of `descriptors1` and `rows2` of
// `descriptors2`, with those rows' indices in the result.
std::vector<DescriptorMatch> MatchDescriptors(
    const FeatureDescriptors& descriptors1,
    const std::vector<int>& rows1,
    const FeatureDescriptors& descriptors2,
    const std::vector<int>& rows2,
    const DescriptorMatchingOptions& options);

}  // namespace bayon
