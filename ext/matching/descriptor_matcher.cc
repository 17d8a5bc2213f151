// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/descriptor_matcher.h"

#include "ext/core/errors.h"

#include <Eigen/Core>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace bayon {

void DescriptorMatchingOptions::Register(OptionRegistry* r) {
  r->Add("max_ratio",
         &max_ratio,
         "Nearest / second-nearest distance below this (Lowe's ratio test)");
  r->Add("max_distance",
         &max_distance,
         "Largest angle between descriptors, radians");
  r->Add("cross_check", &cross_check, "1 = mutual nearest only");
}

void DescriptorMatchingOptions::Check() const {
  CheckOption(
      max_ratio > 0 && max_ratio <= 1, "max_ratio", "in (0, 1]", max_ratio);
  CheckOption(max_distance > 0 && max_distance <= M_PI,
              "max_distance",
              "in (0, pi] radians",
              max_distance);
}

namespace {

double Angle(float dot) {
  return std::acos(std::clamp(static_cast<double>(dot), -1.0, 1.0));
}

}  // namespace

UnitDescriptors ToUnitDescriptors(const FeatureDescriptors& descriptors) {
  CHECK_EQ(descriptors.cols(), 128);
  // COLMAP's scale: 512 for unit norm.
  return descriptors.cast<float>() / 512.f;
}

UnitDescriptors ToUnitDescriptors(const FeatureDescriptors& descriptors,
                                  const std::vector<int>& rows) {
  CHECK_EQ(descriptors.cols(), 128);
  UnitDescriptors unit(rows.size(), 128);
  for (size_t i = 0; i < rows.size(); ++i) {
    unit.row(i) = descriptors.row(rows[i]).cast<float>() / 512.f;
  }
  return unit;
}

std::vector<DescriptorMatch> MatchDescriptors(
    const FeatureDescriptors& descriptors1,
    const std::vector<int>& rows1,
    const FeatureDescriptors& descriptors2,
    const std::vector<int>& rows2,
    const DescriptorMatchingOptions& options) {
  std::vector<DescriptorMatch> matches =
      MatchDescriptors(ToUnitDescriptors(descriptors1, rows1),
                       ToUnitDescriptors(descriptors2, rows2),
                       options);
  for (DescriptorMatch& match : matches) {
    match.idx1 = rows1[match.idx1];
    match.idx2 = rows2[match.idx2];
  }
  return matches;
}

std::vector<DescriptorMatch> MatchDescriptors(
    const UnitDescriptors& unit1,
    const UnitDescriptors& unit2,
    const DescriptorMatchingOptions& options) {
  options.Check();
  std::vector<DescriptorMatch> matches;
  const int n1 = static_cast<int>(unit1.rows());
  const int n2 = static_cast<int>(unit2.rows());
  if (n1 == 0 || n2 == 0) return matches;

  // Per row of either image its nearest and second nearest row of the
  // other by dot product (the larger the nearer).
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  std::vector<int> best12(n1, -1);
  std::vector<float> best_dot12(n1), second_dot12(n1);
  std::vector<int> best21(n2, -1);
  std::vector<float> best_dot21(n2, kNone), second_dot21(n2, kNone);
  constexpr int kBlock = 512;
  UnitDescriptors dots;
  for (int begin = 0; begin < n1; begin += kBlock) {
    const int size = std::min(kBlock, n1 - begin);
    dots.noalias() = unit1.middleRows(begin, size) * unit2.transpose();
    for (int i = 0; i < size; ++i) {
      float first = kNone, second = kNone;
      int first_j = -1;
      const float* row = dots.data() + static_cast<size_t>(i) * n2;
      for (int j = 0; j < n2; ++j) {
        const float dot = row[j];
        if (dot > first) {
          second = first;
          first = dot;
          first_j = j;
        } else if (dot > second) {
          second = dot;
        }
        if (dot > best_dot21[j]) {
          second_dot21[j] = best_dot21[j];
          best_dot21[j] = dot;
          best21[j] = begin + i;
        } else if (dot > second_dot21[j]) {
          second_dot21[j] = dot;
        }
      }
      best12[begin + i] = first_j;
      best_dot12[begin + i] = first;
      second_dot12[begin + i] = second;
    }
  }

  // Near enough and distinctive: below max_distance and below max_ratio
  // times the second nearest (none: no second candidate).
  const auto passes = [&](float best_dot, float second_dot) {
    const double distance = Angle(best_dot);
    const double second = second_dot == kNone ? M_PI : Angle(second_dot);
    return distance <= options.max_distance &&
           distance < options.max_ratio * second;
  };
  for (int i = 0; i < n1; ++i) {
    const int j = best12[i];
    if (j < 0 || !passes(best_dot12[i], second_dot12[i])) continue;
    // Mutual, as COLMAP's cross check: image-2 row j's own nearest is i,
    // and it passes the same tests.
    if (options.cross_check &&
        (best21[j] != i || !passes(best_dot21[j], second_dot21[j]))) {
      continue;
    }
    matches.push_back({i, j, static_cast<float>(Angle(best_dot12[i]))});
  }
  return matches;
}

}  // namespace bayon
