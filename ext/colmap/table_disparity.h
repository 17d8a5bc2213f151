// SPDX-License-Identifier: BSD-3-Clause
//
// bayon_disparity_surfaces: the result of `bayon disparity` for an oriented
// image pair (ext/orientation/disparity_surface.h states the model): over
// the first image of a row, the expected position of a point along its
// epipolar line in the second image, as inverse depth on a grid of bilinear
// cells, with the half width of the search band and the region the
// conjugate points support.
//
// One row per direction: (image_id1, image_id2) is "search image_id2 for a
// point of image_id1", so every oriented pair has two rows, one in
// COLMAP's canonical order and one reversed; pair_id is the pair's COLMAP
// id either way. Pairs whose surface could not be fitted are recorded too
// (success 0, with the reason).
//
// Frames: the grid lies in image 1's photogrammetric image coordinates in
// pixels (x right, y up, origin at the principal point, distortion
// removed), the image vectors of ext/orientation/image_vectors.h without
// their z. cam2_from_cam1 is the relative orientation the surface was
// fitted in, image 1 = image_id1 of the row, |t| = 1; a reader compares it
// with the pair's current orientation to tell a stale surface.
#pragma once

#include "ext/colmap/bayon_tables.h"
#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

struct DisparitySurfaceRecord {
  bool success = false;
  std::string reason;  // why not fitted
  // The interior orientation the relative orientation was computed with.
  bool assume_zero_distortion = false;
  Rigid3d cam2_from_cam1;

  // Grid: node (i, j) at origin + cell_size_px * (i, j), i = 0..cols,
  // j = 0..rows; node values row by row (index j * (cols + 1) + i).
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double cell_size_px = 0;
  int cols = 0;
  int rows = 0;
  // Inverse depth in base lengths (|b| = 1): w = 1 / Z, Z the depth along
  // image 1's viewing direction.
  std::vector<double> inverse_depth;
  // Scale of the prediction error along the epipolar line at the data's
  // spacing, pixels of image 2 (band half width = band_k * sigma *
  // sqrt(1 + (d / spacing_px)^2) at distance d from the nearest support
  // point).
  std::vector<double> sigma_px;
  // The support: the conjugate points used (image-1 coordinates as the
  // grid), their convex hull (counter-clockwise) and their typical spacing
  // (median distance to the nearest other one, image-1 pixels).
  std::vector<Eigen::Vector2d> support_points;
  std::vector<double> support_inverse_depth;  // observed, per point
  std::vector<Eigen::Vector2d> hull;
  double spacing_px = 0;

  // The smoothness weight chosen by cross-validation.
  double smoothness = 0;
  double band_k = 0;
  // Within this distance of the nearest support point (and of the hull) a
  // query is supported; beyond it the band grows by growth_px_per_px per
  // image-1 pixel besides.
  double support_radius_px = 0;
  double growth_px_per_px = 0;
  // ... and by gradient_factor * (disparity gradient) * d everywhere.
  double gradient_factor = 0;
  // The band holds the inverse depths of the range_neighbors nearest
  // support points within support_radius_px, and then depths within a
  // factor (1 +- depth_tolerance) of its ends.
  double depth_tolerance = 0;
  int range_neighbors = 0;

  // Fit statistics.
  int num_points = 0;    // conjugate points offered
  int num_used = 0;      // kept by the robust fit
  int num_blunders = 0;  // rejected (num_points - num_used)
  // 1.4826 * median |residual| along the line, pixels: of the fit, and of
  // the cross-validated predictions (each point predicted without itself).
  double robust_sigma_px = 0;
  double cv_sigma_px = 0;
  // Share of the points used whose cross-validated prediction error lies
  // inside the band.
  double cv_coverage = 0;
  // Medians over the points used: full band width (2 x half width), and
  // length of the epipolar line inside image 2 in front of both cameras
  // (the search range without the surface), pixels of image 2.
  double median_band_px = 0;
  double median_range_px = 0;
  double seconds = 0;

  int NumNodes() const { return (cols + 1) * (rows + 1); }
};

extern const BayonTable kDisparitySurfacesTable;

// image_id1 != image_id2 required; either order (see above).
void WriteDisparitySurface(Database* database,
                           image_t image_id1,
                           image_t image_id2,
                           const DisparitySurfaceRecord& record);
std::optional<DisparitySurfaceRecord> ReadDisparitySurface(Database* database,
                                                           image_t image_id1,
                                                           image_t image_id2);
// Every record, by (image_id1, image_id2).
std::map<std::pair<image_t, image_t>, DisparitySurfaceRecord>
ReadAllDisparitySurfaces(Database* database);

}  // namespace bayon
