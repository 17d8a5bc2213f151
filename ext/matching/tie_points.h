// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon tiepoints`: automatic multi-image tie points by adaptive
// least-squares matching (the paper's section 3.2.3, with the selection of
// tie points, which the authors still did by hand, made automatic).
//
// 1. Candidates. In every image, the interest points of `bayon features`
//    (the keypoints table) are spread over a grid of cells; in each cell
//    the best-textured ones (PatchTextureScore: the precision their patch
//    allows in its weakest direction) are candidates, best first.
// 2. Following a candidate. From its reference image the point is followed
//    through the images that have a disparity surface (`bayon disparity`)
//    from an image the point has already been found in, breadth first, so
//    that along a ring it runs into both neighbours and on into theirs:
//    - approximation: the band of the surface (the stretch of the epipolar
//      line where the conjugate point is to be expected) is searched by
//      normalised cross-correlation of the reference patch, shaped as the
//      previous link of the chain found it and carried on by the local
//      affinity of the surface (a plane's image from one view to the
//      next), on a one-pixel grid along and across the line; the best
//      peaks above min_ncc are kept;
//    - least-squares matching of the reference patch in unconstrained mode
//      (affine + 2 radiometric parameters, adaptive; lsm.h), from each of
//      them;
//    - blunder checks: convergence, sigma0, correlation, the precision of
//      the shift, the move from the approximation, the shape within bounds
//      and matching back into the reference image (RefineObservation of
//      keypoint_refinement.h), then the epipolar lines of every image the
//      point is already in that has a surface to this one: the observation
//      must lie within max_epipolar_px of each line; beyond the reference's
//      neighbours, the patch of the observation the chain came from must
//      find the same point (within max_chain_px). Exactly one peak must
//      survive (repetitive masonry gives several).
//    Every observation is matched to the same reference patch, so the
//    observations of a point cannot drift apart along the chain.
// 3. One point, one track. Images are taken in order; a candidate within
//    min_distance_px of an observation of an earlier point is not followed,
//    and an observation that lands within that distance of another point's
//    observation in its image is dropped. Points seen in fewer than
//    min_images images are not kept.
// 4. Manual measurements (optional): the user's image measurements file
//    (ext/colmap/control_io.h: point name, image name, x, y, sigma) adds one
//    point per name, for the models that automatic matching cannot handle.
// 5. Output: bayon_tie_points / bayon_tie_observations (one transaction,
//    replacing the previous run's), and on request a COLMAP database (a
//    copy of the input, never the input itself) whose keypoints are the tie
//    observations and whose matches and inlier matches are the pairs of
//    observations of each point, so that stock `colmap point_triangulator`
//    and `colmap mapper` run on the tie points.
#pragma once

#include "ext/colmap/table_tie_points.h"
#include "ext/core/types.h"
#include "ext/matching/keypoint_refinement.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace bayon {

// Least-squares matching as tie points use it: the refinement's checks,
// tightened for points that must be good to a tenth of a pixel (shift
// precision, move from the correlation peak, correlation), on 21 x 21
// patches.
KeypointRefinementOptions DefaultTieMatchingOptions();

struct TiePointOptions {
  // Least-squares matching and its blunder checks (patch 21 x 21).
  KeypointRefinementOptions matching = DefaultTieMatchingOptions();
  // Candidates: a grid of cells over each image, this many per cell. Most
  // candidates find no conjugate that every check accepts (on the rendered
  // tower, least-squares matching started at the TRUE conjugate converges
  // within the checks for about one visible point in five: weak stone
  // texture and changing light), so it takes many candidates to keep a few
  // hundred points: 4 per cell of a 12 x 8 grid gave 64, 6 per cell of
  // 16 x 12 gives 233 (tests/tiepoints_test.cc).
  int grid_cols = 16;
  int grid_rows = 12;
  int candidates_per_cell = 6;
  // Candidates whose patch texture score (grey values^2 per pixel^2) is
  // below this are not followed.
  double min_texture_score = 4.0;
  // Correlation: the half side of the window and the acceptance of the
  // best peak.
  int correlation_radius = 5;
  double min_ncc = 0.6;
  double min_ncc_margin = 0.15;
  // Peaks closer than this to one another are the same peak, pixels; at
  // most max_peaks within min_ncc_margin of the best are tried by
  // least-squares matching, and more than one that passes every check
  // makes the link ambiguous.
  double peak_separation_px = 2.5;
  int max_peaks = 3;
  // Search across the epipolar line: +- this many pixels (the relative
  // orientation and the line's curvature between its ends).
  int across_px = 2;
  // Bands longer than this (unsupported extrapolation) are not searched.
  double max_band_px = 400;
  // Largest distance of an observation from the epipolar line of another
  // observation of the same point, pixels.
  double max_epipolar_px = 2.0;
  // Beyond the reference's neighbours, the previous link's own patch is
  // matched into the new image as well and must land within this distance
  // of the reference patch's result, pixels.
  double max_chain_px = 0.3;
  // A point is followed into at most this many images and kept when seen
  // in at least min_images.
  // Two-image points are not kept by default: nothing checks them but
  // their pair's own epipolar line, and on the rendered tower a few of them
  // are off by more than a pixel across it (wrong conjugates on repetitive
  // masonry that pass every single-pair test), while every point seen in
  // three or more images has passed a second, independent match.
  int max_images = 8;
  int min_images = 3;
  // Two points closer than this in one image are one point, pixels.
  double min_distance_px = 4.0;
  // Manual measurements (control_io.h format); empty: none.
  std::string manual_path;
  // Standard deviation of a manual measurement without its own, pixels.
  double manual_sigma_px = 0.5;
  // Coded targets measured by `bayon targets` (the same format, every
  // measurement with its sigma); empty: none. Named tie points of source
  // "target", beside the manual ones (a name in both is refused).
  std::string targets_path;
  int num_threads = -1;
  // Every field, the least-squares matching's as matching.*.
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

// Why a link of a chain (one image) was not added.
enum class TieLinkOutcome {
  kAccepted = 0,
  kNoBand,       // no valid band (off the surface, behind the camera)
  kLongBand,     // band longer than max_band_px
  kNoPeak,       // best correlation below min_ncc
  kAmbiguous,    // a second peak within min_ncc_margin
  kLsmRejected,  // least-squares matching or its blunder checks
  kEpipolar,     // off another observation's epipolar line
  kChain,        // the previous link's own patch disagrees
  kTaken,        // another point's observation is there
};
constexpr int kNumTieLinkOutcomes = 9;
const char* TieLinkOutcomeName(TieLinkOutcome outcome);

struct TieImageReport {
  image_t image_id = kInvalidImageId;
  std::string name;
  int num_keypoints = 0;
  int num_candidates = 0;
  int num_references = 0;    // points found from this image
  int num_observations = 0;  // observations of kept points in this image
};

struct TiePointSummary {
  std::vector<TiePointRecord> points;  // as written
  std::vector<TieImageReport> images;  // image_id order
  int num_surfaces = 0;                // usable disparity surfaces
  int num_candidates = 0;
  int num_followed = 0;  // candidates not already taken
  int num_points = 0;    // kept
  int num_manual_points = 0;
  int num_target_points = 0;
  int64_t num_observations = 0;
  double mean_images_per_point = 0;
  // Points by number of images (index = images, up to max_images).
  std::vector<int> points_by_images;
  // Median a-priori standard deviation of the matched observations (the
  // larger axis), pixels.
  double median_sigma_px = 0;
  // Link outcomes (index TieLinkOutcome), and rejections by LSM check
  // (index ObservationOutcome).
  std::array<int64_t, kNumTieLinkOutcomes> num_by_link{};
  std::array<int64_t, kNumObservationOutcomes> num_by_lsm{};
  int colmap_pairs = 0;  // pairs written to the COLMAP export
  double seconds = 0;
};

// The whole command. Reads the database (keypoints, disparity surfaces,
// interior orientations) and the images, finds the tie points and writes
// them into the database's bayon tie tables; with `colmap_output_path`,
// also the COLMAP export there (through a temporary file; an existing one
// only with `overwrite`). Throws InputError before anything is written for
// a missing or non-COLMAP database, no keypoints, no disparity surfaces,
// missing images or images of the wrong size, a bad manual file (naming
// the line) and an export path that exists or is the input.
TiePointSummary FindTiePoints(const std::string& database_path,
                              const std::string& image_path,
                              const std::string& colmap_output_path,
                              bool overwrite,
                              const TiePointOptions& options);

// The COLMAP export of step 5 from an existing database and its tie points
// (`database_path` is only read). Returns the number of image pairs
// written.
int ExportTiePointsToColmap(const std::string& database_path,
                            const std::vector<TiePointRecord>& points,
                            const std::string& output_path,
                            bool overwrite);

// The report `bayon tiepoints` writes.
nlohmann::ordered_json TiePointSummaryJson(const TiePointSummary& summary);

// Its tables per image, points by images, links and least-squares
// rejections, as the command prints them.
std::string TiePointTables(const TiePointSummary& summary);
// Its summary in one sentence: points, how many images, sigma, candidates.
std::string TiePointSummaryLine(const TiePointSummary& summary);

}  // namespace bayon
