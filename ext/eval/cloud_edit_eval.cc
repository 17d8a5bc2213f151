// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/cloud_edit_eval.h"

#include "ext/core/errors.h"

#include <algorithm>
#include <cstdio>

namespace bayon {
namespace {

// Splits a cloud's positions by its blunder flag.
void SplitByFlag(const PointCloud& cloud,
                 const std::string& what,
                 std::vector<Eigen::Vector3d>* good,
                 std::vector<Eigen::Vector3d>* blunders) {
  const PointAttribute* flags = cloud.FindAttribute("blunder");
  if (flags == nullptr) {
    ThrowInputError(what, ": no 'blunder' attribute to evaluate an edit by");
  }
  for (size_t i = 0; i < cloud.size(); ++i) {
    (flags->values[i] != 0 ? blunders : good)->push_back(cloud.positions[i]);
  }
}

}  // namespace

double CloudEditEvaluation::BlundersRemovedFraction() const {
  return num_blunders_before == 0
             ? 1.0
             : 1.0 - static_cast<double>(num_blunders_after) /
                         num_blunders_before;
}

namespace {

double RemovedFraction(size_t before, size_t after) {
  return before == 0 ? 0.0 : 1.0 - static_cast<double>(after) / before;
}

size_t CountBeyond(const std::vector<double>& distances, double limit) {
  return limit > 0 ? std::count_if(distances.begin(),
                                   distances.end(),
                                   [&](double d) { return d > limit; })
                   : 0;
}

}  // namespace

double CloudEditEvaluation::GoodRemovedFraction() const {
  return RemovedFraction(num_good_before, num_good_after);
}

double CloudEditEvaluation::OnSurfaceRemovedFraction() const {
  return RemovedFraction(num_good_before - num_off_surface_before,
                         num_good_after - num_off_surface_after);
}

double CloudEditEvaluation::OffSurfaceRemovedFraction() const {
  return RemovedFraction(num_off_surface_before, num_off_surface_after);
}

std::string CloudEditEvaluation::TableHeader() {
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "%-22s %9s %9s %10s %10s %10s %10s %12s %12s %12s",
                "edit",
                "blunders",
                "removed%",
                "good",
                "removed%",
                "off surf.",
                "removed%",
                "RMS ref mm",
                "RMS kept mm",
                "RMS good mm");
  return line;
}

std::string CloudEditEvaluation::Table(const std::string& label) const {
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "%-22s %9zu %9.2f %10zu %10.3f %10zu %10.2f %12.4f %12.4f "
                "%12.4f",
                label.c_str(),
                num_blunders_before,
                100 * BlundersRemovedFraction(),
                num_good_before,
                100 * GoodRemovedFraction(),
                num_off_surface_before,
                100 * OffSurfaceRemovedFraction(),
                1e3 * good_before.rms,
                1e3 * kept_after.rms,
                1e3 * good_after.rms);
  return line;
}

CloudEditEvaluation EvaluateCloudEdit(const PointCloud& before,
                                      const PointCloud& after,
                                      const MeshDistance& distance,
                                      double off_surface_m,
                                      int num_threads) {
  std::vector<Eigen::Vector3d> good_before, blunders_before, good_after,
      blunders_after;
  SplitByFlag(before, "cloud before editing", &good_before, &blunders_before);
  SplitByFlag(after, "edited cloud", &good_after, &blunders_after);
  CloudEditEvaluation evaluation;
  evaluation.num_blunders_before = blunders_before.size();
  evaluation.num_blunders_after = blunders_after.size();
  evaluation.num_good_before = good_before.size();
  evaluation.num_good_after = good_after.size();
  evaluation.off_surface_m = off_surface_m;
  std::vector<double> good_before_d =
      distance.Distances(good_before, num_threads);
  evaluation.num_off_surface_before = CountBeyond(good_before_d, off_surface_m);
  evaluation.good_before = ComputeDistanceStatistics(std::move(good_before_d));
  const std::vector<double> good_d =
      distance.Distances(good_after, num_threads);
  evaluation.num_off_surface_after = CountBeyond(good_d, off_surface_m);
  std::vector<double> kept_d = distance.Distances(blunders_after, num_threads);
  kept_d.insert(kept_d.end(), good_d.begin(), good_d.end());
  evaluation.good_after = ComputeDistanceStatistics(good_d);
  evaluation.kept_after = ComputeDistanceStatistics(std::move(kept_d));
  return evaluation;
}

nlohmann::ordered_json CloudEditEvaluationJson(const CloudEditEvaluation& e) {
  return {{"num_blunders", e.num_blunders_before},
          {"blunders_removed", e.BlundersRemovedFraction()},
          {"num_good", e.num_good_before},
          {"good_removed", e.GoodRemovedFraction()},
          {"off_surface_m", e.off_surface_m},
          {"num_off_surface", e.num_off_surface_before},
          {"off_surface_removed", e.OffSurfaceRemovedFraction()},
          {"on_surface_removed", e.OnSurfaceRemovedFraction()},
          {"rms_good_before_m", e.good_before.rms},
          {"rms_kept_m", e.kept_after.rms},
          {"rms_good_kept_m", e.good_after.rms}};
}

}  // namespace bayon
