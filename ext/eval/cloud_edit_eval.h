// SPDX-License-Identifier: BSD-3-Clause
//
// How well an edit removed the blunders of a synthetic cloud whose points
// carry the `blunder` flag (ext/synth/cloud_scene.h): blunders and good
// points before and after, and the distances to the true surface of the
// blunder-free input (the reference an edit must not worsen: no smoothing)
// and of everything the edit kept.
//
// A real matcher's cloud (`bayon dense`) has blunders of its own before any
// are injected: unflagged points as far from the truth as the injected ones.
// With an off-surface distance they are counted apart, so that "good points
// removed" can also be read as the share of points on the surface removed.
#pragma once

#include "ext/core/point_cloud.h"
#include "ext/eval/mesh_distance.h"

#include <nlohmann/json.hpp>

#include <string>

namespace bayon {

struct CloudEditEvaluation {
  size_t num_blunders_before = 0;
  size_t num_blunders_after = 0;
  size_t num_good_before = 0;
  size_t num_good_after = 0;
  // Unflagged points beyond the off-surface distance from the truth (the
  // input's own blunders), before and after; 0 without that distance.
  double off_surface_m = 0;
  size_t num_off_surface_before = 0;
  size_t num_off_surface_after = 0;
  double BlundersRemovedFraction() const;
  // Of all unflagged points.
  double GoodRemovedFraction() const;
  // Of the unflagged points within, and beyond, the off-surface distance.
  double OnSurfaceRemovedFraction() const;
  double OffSurfaceRemovedFraction() const;
  DistanceStatistics good_before;  // the blunder-free input
  DistanceStatistics kept_after;   // every point the edit kept
  DistanceStatistics good_after;   // the good points it kept

  std::string Table(const std::string& label) const;  // one line
  static std::string TableHeader();
};

// Distances to the true surface by `truth`; unflagged points farther than
// `off_surface_m` (> 0) from it are counted apart. Throws InputError when a
// cloud lacks the `blunder` attribute.
CloudEditEvaluation EvaluateCloudEdit(const PointCloud& before,
                                      const PointCloud& after,
                                      const MeshDistance& truth,
                                      double off_surface_m = 0,
                                      int num_threads = -1);

// The evaluation as `bayon evaluate` reports it ("edit").
nlohmann::ordered_json CloudEditEvaluationJson(const CloudEditEvaluation& e);

}  // namespace bayon
