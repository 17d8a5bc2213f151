// SPDX-License-Identifier: BSD-3-Clause
//
// Point-cloud editing: blunder removal without smoothing (the Bayon paper,
// sec. 3.4, an adaptation of Fua and Sander 1992's iterative local surface
// fitting without resampling or surface clustering).
//
// kSurfaceFit: in every iteration, around every point a second-order patch
// in a local frame (local_quadric.h) is fitted to its k nearest neighbours
// among the points not currently flagged (from its k + 8 nearest, found once
// with PCL's k-d tree), weighted by the
// neighbours' own precision (s_normal, or sx, sy, sz, of `bayon dense`) when
// the cloud has them. The point is flagged when its deviation from its patch
// exceeds `max_deviation_sigma` standard deviations of that deviation
// (its own sigma along the normal, the patch's height uncertainty, and the
// local roughness beyond the stated precision), or `max_deviation_m`. Every
// point, flagged or not, is tested again in the next iteration against
// patches fitted without the flagged points, so a good point that a nearby
// blunder had pulled away comes back. Only the points still flagged after the
// last iteration are deleted; the kept points are written unchanged (no
// resampling, no smoothing). Beside the patch, every point is also tested
// against the plane of its few nearest unflagged points (the close test),
// which catches blunders over thin parts of a cloud whose patch reaches over
// ledges no quadric fits. The stated sigmas get the sigma of the errors
// they leave out added in quadrature, estimated from the cloud (a variance
// component) before the first iteration.
//
// kStatistical and kRadius are PCL's StatisticalOutlierRemoval and
// RadiusOutlierRemoval, for comparison.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

enum class CloudEditMethod { kSurfaceFit, kStatistical, kRadius };

// "surface_fit", "statistical", "radius".
std::string CloudEditMethodName(CloudEditMethod method);

struct SurfaceFitEditOptions {
  // Neighbours per patch. More smooths the patch over more relief (misfit
  // on sharp features); fewer makes its height uncertain.
  int num_neighbors = 24;
  // Passes of fitting and testing; the paper uses 3 to 5. Stops early when
  // a pass flags exactly the points the previous one did.
  int num_iterations = 4;
  // Threshold in standard deviations of the deviation. Larger keeps more
  // blunders, smaller deletes good points in rough places.
  double max_deviation_sigma = 3.5;
  // Absolute threshold in metres; 0 = off. With both set, either flags.
  double max_deviation_m = 0;
  // The close test: the point also against the plane of its nearest
  // num_close_neighbors unflagged points (0 = off; at most num_neighbors;
  // from 9 on a quadric), flagged beyond max_close_deviation_sigma. It catches
  // blunders over thin parts of a cloud, where the patch of num_neighbors
  // reaches over corners and ledges, fits none of them, and its inflated
  // scatter lets the blunder pass.
  int num_close_neighbors = 8;
  double max_close_deviation_sigma = 4.5;
  // Weight by and test in units of the points' own precision (PointSigmas)
  // when present; otherwise (or when off) the local scatter around each
  // patch is the unit.
  bool use_point_precision = true;
  // A dense matcher's stated precision ranks its points but understates the
  // best of them: errors its covariance does not model (the surface's
  // departure from the matching window's plane, interpolation, the
  // orientation) come on top of every point's. This sigma is added to every
  // stated one in quadrature (all axes), in metres; -1 = estimated from the
  // cloud (a variance component: the deviations from the patches of a first
  // pass regressed on the stated variances, var = a sigma^2 + b, gives
  // sqrt(b / a)); 0 = the stated sigmas as they are. On the rendered
  // tower's MPGC cloud, without it the good points deleted had a median
  // s_normal of 1.44 mm against 2.09 mm for all.
  double added_sigma_m = -1;
  void Check() const;
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

struct StatisticalEditOptions {
  // PCL StatisticalOutlierRemoval: a point goes when its mean distance to its
  // mean_k neighbours exceeds the mean over all points by stddev_mul
  // standard deviations.
  int mean_k = 24;
  double stddev_mul = 2.0;
  void Check() const;
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

struct RadiusEditOptions {
  // PCL RadiusOutlierRemoval: a point goes when fewer than min_neighbors
  // other points lie within radius_m. 0 = 5 x the median nearest-neighbour
  // distance.
  double radius_m = 0;
  int min_neighbors = 6;
  void Check() const;
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

struct CloudEditOptions {
  CloudEditMethod method = CloudEditMethod::kSurfaceFit;
  SurfaceFitEditOptions surface_fit;
  StatisticalEditOptions statistical;
  RadiusEditOptions radius;
  int num_threads = -1;  // -1 = all cores
  void Check() const;
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

// Why a point was deleted.
enum class EditReason : uint8_t {
  kKept = 0,
  kDeviationSigma,     // beyond max_deviation_sigma
  kDeviationAbsolute,  // beyond max_deviation_m
  kStatistical,
  kRadius,
  kDeviationClose,  // beyond max_close_deviation_sigma of the close plane
};
constexpr int kNumEditReasons =
    static_cast<int>(EditReason::kDeviationClose) + 1;
std::string EditReasonName(EditReason reason);

struct EditIterationReport {
  int iteration = 0;  // 1-based
  size_t num_tested = 0;
  size_t num_untested = 0;  // neighbourhood too small or degenerate: kept
  size_t num_flagged = 0;   // flagged after this pass
  size_t num_newly_flagged = 0;
  size_t num_restored = 0;  // flagged before, within the threshold now
  size_t num_sigma = 0;     // flagged by the sigma test ...
  size_t num_absolute = 0;  // ... by the absolute one only ...
  size_t num_close = 0;     // ... and by the close test only
  // Median of |deviation| / sigma over the tested points: 0.674 when the
  // stated precision matches the scatter of a normal distribution.
  double median_normalized_deviation = 0;
  double seconds = 0;
};

struct CloudEditReport {
  CloudEditMethod method = CloudEditMethod::kSurfaceFit;
  size_t num_input = 0;
  size_t num_kept = 0;
  size_t num_removed = 0;
  bool used_point_precision = false;
  double added_sigma_m = 0;  // added to the stated sigmas (estimated or given)
  bool converged = false;    // the last pass changed nothing
  double radius_m = 0;       // kRadius: the radius used
  std::vector<EditIterationReport> iterations;
  std::vector<EditReason> reasons;  // per input point
  double seconds = 0;
  // Points per reason, indexed by EditReason (kKept: those kept).
  std::vector<size_t> CountByReason() const;
  // A few lines for the summary and the log.
  std::string Summary() const;
};

// Checks the cloud (not empty, finite, enough points, not all on a line:
// InputError naming `what`), edits it, and returns the kept points with all
// their attributes, in the input order.
PointCloud EditPointCloud(const PointCloud& cloud,
                          const CloudEditOptions& options,
                          CloudEditReport* report,
                          const std::string& what = "point cloud");

// The per-axis standard deviations sx, sy, sz of every point, or empty when
// the cloud lacks one of them; where it has s_normal (the standard
// deviation along the surface normal from a full covariance, as `bayon
// dense` writes), that for all three axes. Throws InputError naming `what` when
// one is not a positive finite number.
std::vector<Eigen::Vector3d> PointSigmas(const PointCloud& cloud,
                                         const std::string& what);

// The standard deviation that errors the points' stated precision leaves
// out add to every point, in object units: the variance component that
// kSurfaceFit estimates before its first iteration (every point's deviation
// from the second-order patch of its num_neighbors nearest, against its
// stated variance along the normal), for a matcher to state its points'
// precision with. It also holds the height uncertainty of the patches the
// points are compared with (about a fifth of the neighbours' variance), so
// it errs on the safe side. 0 where the cloud has no sigmas, too few points
// to tell (under 200) or sigmas that explain the scatter; InputError naming
// `what` for a cloud CheckCloudSpansSurface refuses or an invalid sigma.
double EstimateUnmodelledSigma(const PointCloud& cloud,
                               int num_neighbors,
                               int num_threads,
                               const std::string& what);

// The median distance from a point to its nearest neighbour, over up to
// 20000 points spread evenly over the cloud (0 for fewer than 2 points).
double MedianPointSpacing(const PointCloud& cloud);

// Throws InputError naming `what` when the cloud has fewer than
// `min_points` points, or all of them lie on one line (or coincide).
void CheckCloudSpansSurface(const PointCloud& cloud,
                            size_t min_points,
                            const std::string& what);

// The report `bayon edit` writes beside the edited cloud (edit.json).
nlohmann::ordered_json CloudEditReportJson(const CloudEditReport& report,
                                           const std::string& input_path);

}  // namespace bayon
