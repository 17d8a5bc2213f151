// SPDX-License-Identifier: BSD-3-Clause
//
// Disparity surfaces, the paper's step 3.2.2: with the relative orientation
// of a pair known, every point of image 1 has an epipolar line in image 2;
// the disparity surface says where on that line its conjugate point is to be
// expected and within what interval, so that later matching (tie points,
// MPGC) searches a short stretch of the line instead of all of it.
//
// The quantity: inverse depth in base lengths. With the model frame of
// relative_orientation.h (image 1's frame, image 2 placed by R and b,
// |b| = 1), the point of image 1 with image vector u1 = (x, y, -c1) lies at
// X = Z n1, n1 = u1 / c1, Z its depth. In image 2 it is seen along
//
//   q(w) = R^T (n1 - w b) = A - w E,   w = 1 / Z,
//
// so w = 0 is the point at infinity (the vanishing point A) and w -> inf
// the epipole (-E); image 2's vector is u2 = c2 q / (-q_z). w is the
// base-to-depth ratio of the point, dimensionless, and the position on the
// epipolar line is a fractional-linear function of it. We model w, not a
// pixel offset along the line, because
// - for a plane n . X = d, w = (n . n1) / d is exactly affine in (x, y):
//   a smooth object has a smooth, nearly affine w, whatever the
//   convergence of the pair, and the smoothness term below leaves affine
//   functions free;
// - w stays finite and ordered where pixel offsets do not: near the
//   epipole, and for convergent pairs whose vanishing points lie far off
//   image 2 or behind it.
//
// The function: w(x, y) over image 1's distortion-free image coordinates
// (pixels from the principal point, y up), bilinear on a grid of square
// cells, with a thin-plate smoothness term (the squared second differences
// of the node values in x, y and xy). Why not a global polynomial: the
// tower is smooth at the scale of a few cells (faces, tiers) but not at the
// scale of the image (tier steps, the corners of the body, the platform
// below), and a low-order polynomial fitted to the whole image leaves
// residuals of the size of those steps everywhere. The grid follows the
// object locally; its cell size (`cell_size_factors` times the size that
// puts `points_per_cell` points into a cell) and its smoothness weight are
// chosen together by k-fold cross-validation (the pair that predicts
// left-out points best), so the surface is as stiff as the data allow and
// no stiffer.
//
// Residuals are measured where they matter, along the epipolar line in
// image-2 pixels: r_i = J_i (w(x_i) - w_i), J_i = |du2/dw| at the point.
// Robust fitting in three steps:
// 1. screening (the LMedS idea, locally): each point against the median w
//    of its nearest neighbours in image 1, with the median absolute
//    deviation of that neighbourhood as the scale; points beyond
//    `screen_threshold` scales start with weight 0;
// 2. iteratively reweighted least squares with Tukey's biweight (constant
//    `blunder_threshold`) on r_i / s(x_i), s the local robust scale
//    (1.4826 median |r| of the nearest points around each grid node,
//    interpolated); points beyond the constant are blunders;
// 3. cross-validation: every point predicted by the fit without its fold.
//    These prediction errors (not the fit residuals, which the fit has
//    shrunk), reduced to the data's spacing, give the band's local scale
//    sigma(x) at the nodes, and its factor band_k = the `band_quantile` of
//    the reduced errors / sigma (at least `min_band_k`).
//
// The band, along the line, is the union of three things:
// - the statistical band around the prediction, half width
//     h = band_k sigma(x) sqrt(1 + (d / s)^2) + gradient_factor G d
//         + growth_px_per_px max(0, d - support radius),
//   d the distance from the nearest point used, s their typical spacing
//   (median distance between neighbours), G the disparity gradient (image-2
//   pixels per image-1 pixel): the error grows away from the data, fastest
//   where the disparity changes fast (oblique faces), and beyond the
//   supported region (within `support_radius_spacings` spacings of a point
//   used, and as far outside their convex hull) by a further
//   `growth_px_per_px`;
// - the inverse depths of the `range_neighbors` nearest points used: the
//   true surface between matched points seldom leaves their range;
// - and then depths a factor (1 +- depth_tolerance) beyond those ends:
//   relief that the conjugate points do not sample at all. On the tower
//   this is what sets the band: its tiers step back and its cornices and
//   the platform's steps stand out by decimetres at 11 to 13 m, and
//   correlation finds few points on cornices, ledges and steps, so neither
//   the fit nor its cross-validation can see them. Measured on the rendered
//   tower (tests/disparity_test.cc, 1200 x 800 and 1800 x 1200): with a
//   2 % tolerance the band holds 94-96 % of the true surface points it
//   supports (those it misses lie 3 to 11 % off in depth), with 6 % 99.1-
//   99.3 %, at a median length of 6 % of the epipolar line.
// So the band is narrow where the object is smooth and the points agree,
// wide at relief and steps, and honest off the data.
//
// Lens distortion: the image vectors come from ImageVectors (the pair's
// interior orientation), so the returned image-2 pixels lie on the true,
// slightly curved epipolar line; along-line distances are measured in the
// distortion-free image-2 plane (pixels up to the distortion's scale
// change).
#pragma once

#include "ext/colmap/database.h"
#include "ext/colmap/table_disparity.h"
#include "ext/core/option_registry.h"
#include "ext/orientation/image_vectors.h"
#include "ext/orientation/relative_orientation.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct DisparitySurfaceOptions {
  // Grid cell size: about this many conjugate points per cell over the
  // region they cover. Fewer: a more flexible surface, more reliance on the
  // smoothness term.
  double points_per_cell = 4.0;
  // That cell size times each of these is tried by cross-validation.
  std::vector<double> cell_size_factors = {0.5, 1.0, 2.0};
  // Cells along the longer side of image 1, at least and at most.
  int min_cells = 2;
  int max_cells = 64;
  // Smoothness weights tried by cross-validation (relative to the data
  // term; larger: stiffer, towards an affine w, i.e. a plane).
  std::vector<double> smoothness_candidates = {
      0.001, 0.01, 0.1, 1.0, 10.0, 100.0};
  int num_folds = 5;
  // Screening: neighbours of each point, and the threshold in units of the
  // neighbourhood's robust scale.
  int screen_neighbors = 8;
  double screen_threshold = 5.0;
  // Tukey biweight constant: points beyond it (in local robust scales) get
  // weight 0 and are blunders.
  double blunder_threshold = 5.0;
  int max_iterations = 10;
  // Points (the nearest) that give each node's local scale, at least.
  int min_local_points = 10;
  // The band's local scale is this quantile of the nearby cross-validated
  // errors, as a normal sigma (0.5: 1.4826 x the median). Above the median,
  // the band widens where a few points predict badly (a step, a limb)
  // rather than everywhere.
  double band_scale_quantile = 0.5;
  // The band: the share of cross-validated predictions it must hold, and
  // the smallest factor (band half width / local scale).
  double band_quantile = 0.995;
  double min_band_k = 3.0;
  // Local scales below this are raised to it (measurement precision of the
  // conjugate points), image-2 pixels.
  double min_sigma_px = 0.5;
  // The band widens by this share of the local disparity gradient (image-2
  // pixels per image-1 pixel along the line) times the distance from the
  // nearest point used: where the disparity changes fast (oblique faces,
  // limbs) a small gap in the data is a large one in image 2.
  double gradient_factor = 0.5;
  // Relief the conjugate points do not sample (a cornice, a ledge, a step
  // between them), as a share of the depth: the band always holds depths
  // within Z (1 +- depth_tolerance) of the surface's.
  double depth_tolerance = 0.06;
  // The band also holds the inverse depths of the nearest conjugate points
  // used (at most this many, within the support radius): the true surface
  // between matched points seldom leaves their range, steps included.
  int range_neighbors = 6;
  // Supported region: no farther from the nearest point used (and from
  // their convex hull) than this many spacings (the median distance
  // between neighbouring points used).
  double support_radius_spacings = 1.0;
  // Band growth beyond the supported region, image-2 pixels per image-1
  // pixel of distance.
  double growth_px_per_px = 0.25;
  // Fewer usable points than this: no surface.
  int min_num_points = 12;
  unsigned int seed = 1;
  void Register(OptionRegistry* registry);
  void Check() const;
};

// Where, and within what interval, to search image 2 for a point of
// image 1.
struct SearchInterval {
  // False where the question has no answer: the pixel cannot be turned
  // into a ray, or its epipolar line has no point in front of image 2.
  bool valid = false;
  // The query lies in the region the conjugate points support; elsewhere
  // the band has been widened for extrapolation.
  bool supported = false;
  // Expected conjugate point and the interval's ends, image-2 pixels, on
  // the epipolar line; `begin` is the end towards the point at infinity
  // (smaller inverse depth), `end` the one towards the epipole.
  Eigen::Vector2d predicted = Eigen::Vector2d::Zero();
  Eigen::Vector2d begin = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
  // The same as inverse depths (base lengths, see above); max may be
  // +infinity when the band reaches the epipole.
  double inverse_depth = 0;
  double min_inverse_depth = 0;
  double max_inverse_depth = 0;
  // Signed distances of `begin` (<= 0) and `end` (>= 0) from `predicted`
  // along the line, and their difference, the length of the search range,
  // image-2 pixels (distortion-free plane; +-infinity where the band runs
  // to the far end of the line).
  double along_begin_px = 0;
  double along_end_px = 0;
  double length_px = 0;
  // The statistical part of the band (half width), image-2 pixels.
  double half_width_px = 0;
  // Unit direction of the line at `predicted`, image-2 pixels (x right,
  // y down), towards the epipole.
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();
  // Distance from the nearest conjugate point used, image-1 pixels.
  double support_distance_px = 0;
};

// Where an image-2 point lies relative to the epipolar line of a point of
// image 1.
struct EpipolarPosition {
  bool valid = false;
  // Inverse depth of the foot of the perpendicular on the line.
  double inverse_depth = 0;
  // Signed distance from the surface's prediction along the line (positive
  // towards the epipole), and distance from the line, image-2 pixels.
  double along_px = 0;
  double across_px = 0;
};

struct DisparityFitReport {
  bool success = false;
  std::string reason;
  int num_points = 0;
  int num_used = 0;
  int num_blunders = 0;
  // Per input point: 1 used, 0 blunder (or unusable).
  std::vector<uint8_t> used;
  // Per input point: the fit residual and the cross-validated prediction
  // error along the line (image-2 pixels; 0 for unusable points).
  std::vector<double> residual_px;
  std::vector<double> cv_residual_px;
};

class DisparitySurface {
 public:
  DisparitySurface() = default;
  // A surface from its record (as stored) and the interior orientations of
  // its two images (with the record's assume_zero_distortion applied).
  DisparitySurface(DisparitySurfaceRecord record,
                   ImageVectors vectors1,
                   ImageVectors vectors2);

  // Fits the surface of image 1 for searching image 2 to conjugate points
  // (pixel1/pixel2 and u1/u2 of the same points; ConjugatePoints as the
  // relative orientation uses them) in the orientation cam2_from_cam1. An
  // unlucky pair (too few points) gives a record with success = false and
  // the reason.
  static DisparitySurface Fit(const ConjugatePoints& points,
                              const Rigid3d& cam2_from_cam1,
                              const ImageVectors& vectors1,
                              const ImageVectors& vectors2,
                              const DisparitySurfaceOptions& options,
                              DisparityFitReport* report = nullptr);

  bool success() const { return record_.success; }
  const DisparitySurfaceRecord& record() const { return record_; }
  const ImageVectors& vectors1() const { return vectors1_; }
  const ImageVectors& vectors2() const { return vectors2_; }

  // Where and within what interval to search image 2 for this image-1
  // pixel (COLMAP pixel coordinates).
  SearchInterval Search(const Eigen::Vector2d& pixel1) const;

  // A candidate conjugate point relative to pixel1's epipolar line and the
  // surface's prediction.
  EpipolarPosition Locate(const Eigen::Vector2d& pixel1,
                          const Eigen::Vector2d& pixel2) const;

  // Whether pixel2 lies in pixel1's band: within the interval along the
  // line and no farther than max_across_px from it.
  bool Contains(const Eigen::Vector2d& pixel1,
                const Eigen::Vector2d& pixel2,
                double max_across_px) const;

  // The image-2 pixel of pixel1's point at inverse depth w (false when that
  // point is not in front of image 2).
  bool PointAt(const Eigen::Vector2d& pixel1,
               double inverse_depth,
               Eigen::Vector2d* pixel2) const;

  // Length of pixel1's epipolar line inside image 2 for points in front of
  // both images, image-2 pixels: the search range without the surface.
  double FullRangePx(const Eigen::Vector2d& pixel1) const;

  // The surface's inverse depth at image-1 coordinates (x, y) (pixels from
  // the principal point, y up, distortion-free).
  double InverseDepthAt(const Eigen::Vector2d& xy) const;

 private:
  double Interpolate(const std::vector<double>& nodes,
                     const Eigen::Vector2d& xy) const;
  double NearestSupportDistance(const Eigen::Vector2d& xy) const;
  double SupportDistance(const Eigen::Vector2d& xy) const;
  double HalfWidth(const Eigen::Vector2d& xy,
                   double support_distance,
                   double rate) const;
  SearchInterval SearchAt(const Eigen::Vector3d& u1) const;
  // The (at most) k support points nearest to xy within `radius`, nearest
  // first: (squared distance, index).
  void NearestSupport(const Eigen::Vector2d& xy,
                      int k,
                      double radius,
                      std::vector<std::pair<double, int>>* nearest) const;
  void Prepare();

  DisparitySurfaceRecord record_;
  ImageVectors vectors1_;
  ImageVectors vectors2_;
  // The model-frame elements of record_.cam2_from_cam1.
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d base_ = Eigen::Vector3d::UnitX();
  // The support points in square buckets (row by row, CSR), for nearest
  // point queries.
  Eigen::Vector2d bucket_origin_ = Eigen::Vector2d::Zero();
  double bucket_size_ = 1;
  int bucket_cols_ = 0;
  int bucket_rows_ = 0;
  std::vector<int> bucket_start_;
  std::vector<int> bucket_points_;
};

// The surface for searching image `image_id2` from image `image_id1`
// (either order of a pair) as `bayon disparity` stored it, with both
// images' interior orientations from the database. nullopt, with the reason
// in *reason, when there is none, it could not be fitted, or it is stale
// (the pair was oriented again since).
std::optional<DisparitySurface> LoadDisparitySurface(
    Database* database,
    image_t image_id1,
    image_t image_id2,
    std::string* reason = nullptr);

// The current relative orientation of a pair for the disparity stage, in
// the caller's order (cam2_from_cam1 with image 1 = image_id1): the
// successful bayon_relative_orientation row, else the two_view_geometries
// row's qvec/tvec. nullopt if the pair is not oriented.
struct PairOrientation {
  Rigid3d cam2_from_cam1;
  bool assume_zero_distortion = false;
  bool from_bayon = false;  // bayon_relative_orientation (else COLMAP's)
};
std::optional<PairOrientation> ReadPairOrientation(Database* database,
                                                   image_t image_id1,
                                                   image_t image_id2);

}  // namespace bayon
