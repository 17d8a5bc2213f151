// SPDX-License-Identifier: BSD-3-Clause
//
// The focal length of a camera whose lens is unknown (no EXIF, scanned
// film), from the conjugate points of the image pairs it took: a search over
// focal hypotheses, each scored by how well calibrated relative orientations
// (relative_orientation.h: DRT, LMedS, the rigorous coplanarity adjustment)
// fit the pairs.
//
// Why a search and not a formula. Two views with a common focal length and
// a known principal point fix the focal length through the fundamental
// matrix (Bougnoux 1998; Mendonca and Cipolla 1999), but not when their
// optical axes meet (Newsam et al. 1996). Around an object, where every
// photograph looks at the centre, that is every pair. The closed forms then
// return nonsense, at best with a warning. Scoring a hypothesis by the
// residuals of all strong pairs together keeps what each pair says, however
// weakly, and the score's curvature says how well the photographs fix the
// focal length at all.
//
// The pairs. Only those that some hypothesis of the grid orients (with a
// robust sigma of max_pair_sigma_px or better) count: identical images,
// chance matches and other motions say nothing about f, and would only add
// noise.
//
// The score. For a hypothesis f each pair's image vectors are u = (x, y, -f)
// (x, y: pixels from the principal point of the guessed camera, y up). The
// calibrated relative orientation is estimated, and every conjugate point's
// Sampson residual r_i (pixels) under it counts min(r_i^2, T^2) (the
// truncated quadratic of MSAC, Torr and Zisserman 2000), so that blunders
// count the same at every f. The score is the sum over the pairs.
//
// The search. ln f on a grid from min_focal_ratio to max_focal_ratio times
// the image's long side, then golden-section search between the grid
// neighbours of the best value. The standard deviation of ln f follows from
// the score's curvature there, as for any least-squares estimate:
// var(ln f) = 2 s^2 / S'' with s^2 = S / (n - 5 m - 1) (n points, m pairs).
// That counts the image noise only: the principal point, taken at the
// image centre, adds a bias (fountain-P11, 16 px off the centre: the
// estimate is 0.6 % short, at a standard deviation of 0.1 %), which the
// bundle's self-calibration removes.
//
// When the photographs do not fix it. The score's curvature alone can be
// fooled by the samples' noise in a flat score, so the estimate must also
// lie in a well: the score at 1.5 times and 1 / 1.5 times the estimate at
// least 10 % above its minimum (the blunders, which count T^2 at every f,
// keep the ratio small). A ring at one height, every photograph aimed at
// the object's centre (temple-ring), is such a case: the samples' noise
// makes a minimum at 0.39 x the true focal length with a rise of 4.6 %,
// where fountain-P11's is 70 % and a ring walked on foot (the tests) 17 %.
#pragma once

#include "ext/orientation/relative_orientation.h"

#include <string>
#include <vector>

namespace bayon {

struct FocalLengthOptions {
  // The hypotheses: f / long side of the image, geometric grid.
  double min_focal_ratio = 0.3;
  double max_focal_ratio = 6.0;
  double grid_step = 1.1;  // ratio of successive grid values
  // The golden-section search stops at this relative width.
  double tolerance = 1e-4;
  // T of the truncated quadratic, pixels.
  double inlier_threshold_px = 2.0;
  // A pair counts when some hypothesis orients it with a robust sigma of
  // at most this, pixels (relative_orientation.h's max_sigma_px).
  double max_pair_sigma_px = 1.0;
  // Relative orientation of each pair at each hypothesis: fewer samples
  // and candidates than the final orientation needs.
  RelativeOrientationOptions estimation;
  // The focal length counts as determined when its relative standard
  // deviation is at most this, and when the score at min_rise_ratio times
  // and 1 / min_rise_ratio times the estimate is at least min_rise times
  // its minimum: a shallow ripple is the samples' noise, not a well.
  double max_relative_sigma = 0.05;
  double min_rise_ratio = 1.5;
  double min_rise = 1.1;
  int num_threads = -1;  // pairs in parallel; -1 = all cores
  FocalLengthOptions();
  void Check() const;
};

struct FocalLengthEstimate {
  bool success = false;
  std::string reason;  // why not, one line
  double focal_length_px = 0;
  double relative_sigma = 0;  // of focal_length_px
  int num_pairs = 0;
  int num_points = 0;
  double score = 0;  // at the estimate
  // The score over the grid, for the log: (f, score).
  std::vector<std::pair<double, double>> grid;
};

// `pairs`: each pair's conjugate points as image vectors of the guessed
// camera (only x and y are used; z is replaced by -f). `long_side_px`: the
// image's longer side, which scales the grid.
FocalLengthEstimate EstimateFocalLength(
    const std::vector<ConjugatePoints>& pairs,
    double long_side_px,
    const FocalLengthOptions& options);

}  // namespace bayon
