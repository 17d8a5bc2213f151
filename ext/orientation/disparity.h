// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon disparity`: the disparity surfaces (disparity_surface.h) of every
// oriented pair of a COLMAP database, in both directions, from the pair's
// inlier matches (two_view_geometries, as `bayon relative` wrote them; the
// sub-pixel conjugate points of bayon_matches where they exist) in its
// relative orientation (bayon_relative_orientation, or COLMAP's qvec/tvec
// where bayon did not orient the pair), with the interior orientation the
// pair was oriented with.
//
// Written per pair and direction: a bayon_disparity_surfaces row
// (ext/colmap/table_disparity.h), the surface or, for a pair that cannot
// have one, the reason. Rows are written in transactions; a surface whose
// pair has been oriented again since is stale and fitted again, others are
// kept unless `overwrite`.
#pragma once

#include "ext/core/types.h"
#include "ext/orientation/disparity_surface.h"

#include <string>
#include <vector>

namespace bayon {

struct DisparityOptions {
  DisparitySurfaceOptions surface;
  // Use bayon_matches' sub-pixel conjugate points where they exist (else
  // the keypoint positions).
  bool use_subpixel_points = true;
  // Fit pairs again that have a current surface (or failure) already.
  bool overwrite = false;
  int num_threads = -1;  // pairs in parallel; -1 = all cores
  // Every field, the surfaces' without a prefix.
  void Register(OptionRegistry* registry);
  void Check() const;
};

// One surface (one direction of a pair).
struct DisparityReport {
  image_t image_id1 = kInvalidImageId;  // searched from
  image_t image_id2 = kInvalidImageId;  // searched in
  std::string name1, name2;
  bool fitted = false;
  bool skipped = false;
  std::string reason;
  bool subpixel = false;
  int num_points = 0;
  int num_used = 0;
  int num_blunders = 0;
  double robust_sigma_px = 0;
  double cv_sigma_px = 0;
  double cv_coverage = 0;
  double median_band_px = 0;
  double median_range_px = 0;
  int cols = 0;
  int rows = 0;
  double smoothness = 0;
  double seconds = 0;
};

struct DisparitySummary {
  std::vector<DisparityReport> surfaces;
  int num_pairs = 0;  // oriented pairs
  int num_fitted = 0;
  int num_failed = 0;
  int num_skipped = 0;
  double seconds = 0;
};

// What was fitted, in one line: points used, blunders, the median band.
std::string DisparitySummaryLine(const DisparitySummary& summary);

// Fits the surfaces. Bad input throws InputError before anything is written
// (no database, no images, no oriented pairs); a pair that cannot have a
// surface is reported, the others are still done.
DisparitySummary FitDisparitySurfaces(const std::string& database_path,
                                      const DisparityOptions& options);

}  // namespace bayon
