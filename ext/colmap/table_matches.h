// SPDX-License-Identifier: BSD-3-Clause
//
// bayon_matches: what `bayon match` found for an image pair beyond COLMAP's
// `matches` row (which holds the keypoint indices): the in-plane rotation
// and approximate mapping between the images, and for every match row the
// sub-pixel conjugate points (the image-1 reference point and its conjugate
// in image 2, COLMAP pixel coordinates) with their correlation coefficient
// and the standard deviation of the conjugate.
// Stored in COLMAP's canonical order (image_id1 < image_id2), row for row
// with the `matches` row; a record whose row count differs from it is stale
// and ignored by readers.
#pragma once

#include "ext/colmap/bayon_tables.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct MatchRecord {
  int rotation_deg = 0;  // in-plane rotation of image 2 w.r.t. image 1
  bool mapping_found = false;
  // pixel2 ~= affine * (pixel1, 1), row-major 2 x 3.
  Eigen::Matrix<double, 2, 3> affine =
      (Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 1, 0).finished();
  int num_candidates = 0;
  double seconds = 0;
  // Per match row.
  std::vector<Eigen::Vector2f> xy1;
  std::vector<Eigen::Vector2f> xy2;
  std::vector<float> ncc;
  // Standard deviation of the image-2 position, pixels: least-squares
  // matching's where it refined the point, the matcher's nominal one for a
  // correlation peak. Empty in records written before bayon kept it (their
  // points count as equally precise).
  std::vector<float> sigma_px;
};

extern const BayonTable kMatchesTable;

// image_id1 < image_id2 required (canonical order).
void WriteMatchRecord(Database* database,
                      image_t image_id1,
                      image_t image_id2,
                      const MatchRecord& record);
std::optional<MatchRecord> ReadMatchRecord(Database* database,
                                           image_t image_id1,
                                           image_t image_id2);
void DeleteMatchRecord(Database* database,
                       image_t image_id1,
                       image_t image_id2);

// The bayon_* tables keyed by an image pair (columns image_id1, image_id2),
// whatever stage wrote them.
std::vector<std::string> BayonPairTables(Database* database);

// Removes everything derived from a pair's matches: COLMAP's matches and
// two-view geometry rows and the pair's rows in every bayon pair table.
void DeletePairResults(Database* database,
                       image_t image_id1,
                       image_t image_id2);

}  // namespace bayon
