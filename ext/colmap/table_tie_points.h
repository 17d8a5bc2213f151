// SPDX-License-Identifier: BSD-3-Clause
//
// bayon_tie_points and bayon_tie_observations: the result of
// `bayon tiepoints` (ext/matching/tie_points.h): multi-image tie points,
// each with its image observations and their precision, for the strip and
// bundle adjustments.
//
// A tie point is one object point; its observations are its conjugate image
// points, at most one per image, in COLMAP pixel coordinates (the centre of
// the upper-left pixel is (0.5, 0.5)). `source` says where the point came
// from: "alsm" (automatic: the reference observation is an interest point,
// every other one matched to it by least-squares matching), "manual" (the
// user's measurements file) or "target" (a coded target, measured by `bayon
// targets`); manual points and targets keep their names.
//
// Each observation carries the 2 x 2 covariance of its position (pixels^2):
// for matched observations the least-squares covariance sigma0^2 N^-1 of
// the shift, for the reference observation the one its own template would
// give (the same patch, matched against itself; the precision of a point
// measured in a single image), for manual ones and targets sigma^2 I.
//
// `bayon tiepoints` replaces all rows in one transaction, so readers always
// see one run's result.
#pragma once

#include "ext/colmap/bayon_tables.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

struct TieObservation {
  image_t image_id = kInvalidImageId;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  // pixels^2
  // Least-squares matching statistics (0 for references and manual ones).
  double sigma0 = 0;       // grey values
  double correlation = 0;  // template vs resampled patch
  bool reference = false;  // the point's interest point (alsm)
};

struct TiePointRecord {
  int64_t point_id = 0;  // 1, 2, ... in the order written
  std::string name;      // manual points' and targets' names, else empty
  std::string source;    // "alsm", "manual" or "target"
  std::vector<TieObservation> observations;  // image_id order
};

extern const BayonTable kTiePointsTable;
extern const BayonTable kTieObservationsTable;

// Replaces every tie point (and observation) by `points`, numbered 1..n in
// their order (point_id is ignored on input). Opens its own transaction
// unless one is open. Observations of an image not in `images` or two in
// one image throw InputError before anything is written.
void WriteTiePoints(Database* database,
                    const std::vector<TiePointRecord>& points);

// Every tie point in point_id order (empty without the tables).
std::vector<TiePointRecord> ReadTiePoints(Database* database);

}  // namespace bayon
