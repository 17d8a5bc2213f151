// SPDX-License-Identifier: BSD-3-Clause
#include "ext/cloud/cloud_edit.h"

#include "ext/cloud/local_quadric.h"
#include "ext/cloud/pcl_cloud.h"
#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>
#include <pcl/filters/radius_outlier_removal.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace bayon {
namespace {

constexpr int kBlockSize = 512;

void ForEachPointInBlocks(size_t n,
                          int num_threads,
                          const std::function<void(size_t)>& fn) {
  const int num_blocks = static_cast<int>((n + kBlockSize - 1) / kBlockSize);
  ParallelFor(num_blocks, num_threads, [&](int block) {
    const size_t end = std::min(n, size_t{kBlockSize} * (block + 1));
    for (size_t i = size_t{kBlockSize} * block; i < end; ++i) fn(i);
  });
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t k = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// One pass of the local surface test over every point, with patches fitted
// to the points not flagged by the previous pass.
// For every point its `width` nearest other points (n x width, -1 where the
// cloud has fewer), found once: the passes then take the nearest unflagged
// ones from these lists instead of searching again.
std::vector<int> NearestNeighbors(const PointCloud& cloud,
                                  int width,
                                  int num_threads) {
  const size_t n = cloud.size();
  const CenteredPclCloud pcl_cloud(cloud.positions);
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(pcl_cloud.cloud);
  std::vector<int> lists(n * width, -1);
  ForEachPointInBlocks(n, num_threads, [&](size_t i) {
    std::vector<int> found(width + 1);
    std::vector<float> squared_distances(width + 1);
    const int num_found = tree.nearestKSearch(
        (*pcl_cloud.cloud)[i], width + 1, found, squared_distances);
    int count = 0;
    for (int j = 0; j < num_found && count < width; ++j) {
      if (found[j] != static_cast<int>(i))
        lists[i * width + count++] = found[j];
    }
  });
  return lists;
}

// The two-face test of SurfaceFitPass for point i: its neighbours
// `members` split into two faces by 2-means on their (unoriented) normals, a
// patch per face, and the smallest normalised deviation of the point from a
// face patch it lies over. False when the normals do not form two faces
// (less than 20 degrees apart) or the point lies over neither.
bool TwoFaceDeviation(const PointCloud& cloud,
                      const std::vector<Eigen::Vector3d>& sigmas,
                      const std::vector<Eigen::Vector3d>& normals,
                      const std::vector<int>& members,
                      size_t i,
                      double floor,
                      double spacing,
                      double* z) {
  const int m = static_cast<int>(members.size());
  if (m < 12) return false;
  // Start from the two most different normals.
  int a = 0, b = 1;
  double least = 2;
  for (int x = 0; x < m; ++x) {
    for (int y = x + 1; y < m; ++y) {
      const double c = std::abs(normals[members[x]].dot(normals[members[y]]));
      if (c < least) {
        least = c;
        a = x;
        b = y;
      }
    }
  }
  if (least > std::cos(20.0 * M_PI / 180)) return false;
  Eigen::Vector3d centers[2] = {normals[members[a]], normals[members[b]]};
  std::vector<int> side(m, 0);
  for (int round = 0; round < 4; ++round) {
    Eigen::Vector3d sums[2] = {Eigen::Vector3d::Zero(),
                               Eigen::Vector3d::Zero()};
    for (int x = 0; x < m; ++x) {
      const Eigen::Vector3d& n = normals[members[x]];
      side[x] = std::abs(n.dot(centers[1])) > std::abs(n.dot(centers[0]));
      sums[side[x]] += n.dot(centers[side[x]]) >= 0 ? n : Eigen::Vector3d(-n);
    }
    for (int c = 0; c < 2; ++c) {
      if (sums[c].norm() > 0) centers[c] = sums[c].normalized();
    }
  }
  if (std::abs(centers[0].dot(centers[1])) > std::cos(20.0 * M_PI / 180)) {
    return false;
  }
  const bool weighted = !sigmas.empty();
  const Eigen::Vector3d& p = cloud.positions[i];
  double best = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 2; ++c) {
    std::vector<Eigen::Vector3d> points, point_sigmas;
    for (int x = 0; x < m; ++x) {
      if (side[x] != c) continue;
      points.push_back(cloud.positions[members[x]]);
      if (weighted) point_sigmas.push_back(sigmas[members[x]]);
    }
    if (points.size() < 6) continue;
    const QuadricPatch patch =
        FitQuadricPatch(p, points, point_sigmas, centers[c]);
    if (!patch.valid) continue;
    // Does the point lie over this face? Its foot is the frame's origin.
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& q : points) {
      const Eigen::Vector3d local = patch.frame.transpose() * (q - p);
      nearest = std::min(nearest, std::hypot(local.x(), local.y()));
    }
    if (nearest > 2 * spacing) continue;
    const double point_variance =
        weighted ? VarianceAlong(patch.frame.col(2), sigmas[i]) : 1.0;
    const double variance = std::max(patch.variance_factor, floor) *
                            (point_variance + patch.c0_variance);
    best = std::min(best,
                    std::abs(patch.QueryDeviation()) /
                        std::sqrt(std::max(variance, 1e-300)));
  }
  if (!std::isfinite(best)) return false;
  *z = best;
  return true;
}

// Every point tested against the patch of its nearest unflagged neighbours
// at one scale.
struct ScaleTest {
  std::vector<double> deviation;  // from the patch, NaN: no patch
  std::vector<double> factor;     // the patch's variance factor
  std::vector<double> z;          // normalised deviation, -1: untested
  // The point's stated variance along the patch's normal (1 without).
  std::vector<double> own_variance;
  double floor = 0;  // the least factor z was scaled by
};

// The test against the patch of the `count` nearest unflagged neighbours
// (the first `count` of the point's row of `neighbor_index`, `width` wide),
// in a frame whose normal is their mean normal. A point without a patch is
// kept, untested.
ScaleTest TestAtScale(const PointCloud& cloud,
                      const std::vector<Eigen::Vector3d>& sigmas,
                      const std::vector<int>& neighbor_index,
                      const std::vector<Eigen::Vector3d>& normals,
                      int width,
                      int count,
                      double min_variance,
                      int num_threads) {
  const size_t n = cloud.size();
  const bool weighted = !sigmas.empty();
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  ScaleTest test;
  test.deviation.assign(n, kNaN);
  test.factor.assign(n, kNaN);
  test.own_variance.assign(n, 1.0);
  // The variance of the deviation before scaling by the factor.
  std::vector<double> unit_variance(n);
  ForEachPointInBlocks(n, num_threads, [&](size_t i) {
    std::vector<Eigen::Vector3d> neighbors, neighbor_sigmas, neighbor_normals;
    neighbors.reserve(count);
    neighbor_normals.reserve(count);
    for (int j = 0; j < count && neighbor_index[i * width + j] >= 0; ++j) {
      const int index = neighbor_index[i * width + j];
      neighbors.push_back(cloud.positions[index]);
      if (weighted) neighbor_sigmas.push_back(sigmas[index]);
      if (normals[index].squaredNorm() > 0) {
        neighbor_normals.push_back(normals[index]);
      }
    }
    const QuadricPatch patch = FitQuadricPatch(cloud.positions[i],
                                               neighbors,
                                               neighbor_sigmas,
                                               MeanAxis(neighbor_normals));
    if (!patch.valid) return;
    test.deviation[i] = patch.QueryDeviation();
    test.factor[i] = patch.variance_factor;
    // The point's own variance along the normal (1 in units of the factor
    // without stated precision) plus the patch's height uncertainty.
    if (weighted) {
      test.own_variance[i] = VarianceAlong(patch.frame.col(2), sigmas[i]);
    }
    unit_variance[i] = test.own_variance[i] + patch.c0_variance;
  });

  // The factor scales the test where the surface is rougher than the patch
  // at this scale, but never below the cloud's typical (median) factor, nor
  // below 1 with stated precision: a factor from a few residuals is noisy,
  // and a small one is mostly chance.
  std::vector<double> factors;
  factors.reserve(n);
  for (double f : test.factor) {
    if (!std::isnan(f)) factors.push_back(f);
  }
  test.floor = Median(std::move(factors));
  if (weighted) test.floor = std::max(test.floor, 1.0);
  test.z.assign(n, -1.0);
  for (size_t i = 0; i < n; ++i) {
    if (std::isnan(test.deviation[i])) continue;
    const double variance = std::max(
        std::max(test.factor[i], test.floor) * unit_variance[i], min_variance);
    test.z[i] = std::abs(test.deviation[i]) / std::sqrt(variance);
  }
  return test;
}

// The k nearest unflagged neighbours of every point (n x k, itself left
// out; -1 where more than width - k of its `width` nearest are flagged) and
// the normal of every unflagged point from its neighbourhood (zero where
// they lie on a line).
struct Neighborhoods {
  std::vector<int> index;
  std::vector<Eigen::Vector3d> normals;
};

Neighborhoods UnflaggedNeighborhoods(const PointCloud& cloud,
                                     const std::vector<int>& nearest,
                                     int width,
                                     int k,
                                     const std::vector<EditReason>& reasons,
                                     int num_threads) {
  const size_t n = cloud.size();
  Neighborhoods hoods;
  hoods.index.assign(n * k, -1);
  hoods.normals.assign(n, Eigen::Vector3d::Zero());
  ForEachPointInBlocks(n, num_threads, [&](size_t i) {
    int count = 0;
    for (int j = 0; j < width && count < k; ++j) {
      const int index = nearest[i * width + j];
      if (index < 0) break;
      if (reasons[index] == EditReason::kKept) {
        hoods.index[i * k + count++] = index;
      }
    }
    if (reasons[i] != EditReason::kKept || count < 3) return;
    std::vector<Eigen::Vector3d> own = {cloud.positions[i]};
    for (int j = 0; j < count; ++j) {
      own.push_back(cloud.positions[hoods.index[i * k + j]]);
    }
    Eigen::Matrix3d axes;
    Eigen::Vector3d eigenvalues;
    PrincipalAxes(own, &axes, &eigenvalues);
    if (eigenvalues(1) > 1e-12 * eigenvalues(0)) hoods.normals[i] = axes.col(2);
  });
  return hoods;
}

void SurfaceFitPass(const PointCloud& cloud,
                    const std::vector<Eigen::Vector3d>& sigmas,
                    const std::vector<int>& nearest,
                    int width,
                    double spacing,
                    const SurfaceFitEditOptions& options,
                    double min_variance,
                    int num_threads,
                    std::vector<EditReason>* reasons,
                    EditIterationReport* report) {
  const size_t n = cloud.size();
  const int k = options.num_neighbors;
  const Neighborhoods hoods =
      UnflaggedNeighborhoods(cloud, nearest, width, k, *reasons, num_threads);
  const std::vector<int>& neighbor_index = hoods.index;
  const std::vector<Eigen::Vector3d>& normals = hoods.normals;

  // Then every point against the patch of its neighbours, and against the
  // plane of its few nearest ones.
  ScaleTest patch = TestAtScale(
      cloud, sigmas, neighbor_index, normals, k, k, min_variance, num_threads);
  const std::vector<double>& deviation = patch.deviation;
  const std::vector<double>& factor = patch.factor;
  std::vector<double>& z = patch.z;
  const double floor = patch.floor;
  // The close test catches a blunder over a thin part of the cloud, whose
  // patch reaches over corners and ledges that no quadric fits: the
  // inflated factor hides it there, while the few nearest points, on the
  // surface below it, fit a plane well.
  std::vector<double> close_z;
  if (options.num_close_neighbors > 0) {
    close_z = TestAtScale(cloud,
                          sigmas,
                          neighbor_index,
                          normals,
                          k,
                          options.num_close_neighbors,
                          min_variance,
                          num_threads)
                  .z;
  }
  // Where a patch fits its neighbours far worse than is typical (scatter
  // beyond twice the typical), the neighbourhood may straddle an edge (a
  // cornice, a step): one quadric across two faces fits neither and its
  // inflated scatter lets blunders there pass. Such neighbourhoods are
  // split by their normals into two faces, each gets its own patch, and the
  // point is judged by the face patch that fits it best among those it lies
  // over (its foot within two point spacings of the face's points): a good
  // point fits its own face, a blunder off the edge fits neither.
  const double tight = 4.0 * floor;
  ForEachPointInBlocks(n, num_threads, [&](size_t i) {
    if (!(z[i] >= 0) || factor[i] <= tight) return;
    std::vector<int> members;
    for (int j = 0; j < k && neighbor_index[i * k + j] >= 0; ++j) {
      if (normals[neighbor_index[i * k + j]].squaredNorm() > 0) {
        members.push_back(neighbor_index[i * k + j]);
      }
    }
    double two_sided;
    if (TwoFaceDeviation(
            cloud, sigmas, normals, members, i, floor, spacing, &two_sided)) {
      z[i] = two_sided;
    }
  });

  std::vector<EditReason> next(n, EditReason::kKept);
  std::vector<double> normalized(n, -1.0);  // -1: not tested
  for (size_t i = 0; i < n; ++i) {
    const bool close_tested = !close_z.empty() && close_z[i] >= 0;
    if (z[i] >= 0) {
      normalized[i] = z[i];
      if (z[i] > options.max_deviation_sigma) {
        next[i] = EditReason::kDeviationSigma;
      } else if (options.max_deviation_m > 0 &&
                 std::abs(deviation[i]) > options.max_deviation_m) {
        next[i] = EditReason::kDeviationAbsolute;
      }
    } else if (close_tested) {
      normalized[i] = close_z[i];
    }
    if (next[i] == EditReason::kKept && close_tested &&
        close_z[i] > options.max_close_deviation_sigma) {
      next[i] = EditReason::kDeviationClose;
    }
  }

  std::vector<double> tested;
  tested.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const bool was = (*reasons)[i] != EditReason::kKept;
    const bool is = next[i] != EditReason::kKept;
    if (normalized[i] >= 0) {
      tested.push_back(normalized[i]);
      ++report->num_tested;
    } else {
      ++report->num_untested;
    }
    if (is) ++report->num_flagged;
    if (is && !was) ++report->num_newly_flagged;
    if (was && !is) ++report->num_restored;
    if (next[i] == EditReason::kDeviationSigma) ++report->num_sigma;
    if (next[i] == EditReason::kDeviationAbsolute) ++report->num_absolute;
    if (next[i] == EditReason::kDeviationClose) ++report->num_close;
  }
  report->median_normalized_deviation = Median(std::move(tested));
  *reasons = std::move(next);
}

// The sigma that errors unmodelled by the stated precision add to every
// point (SurfaceFitEditOptions::added_sigma_m), from the deviations of every
// point from the patch of its `k` nearest neighbours, none flagged: the
// points binned by their stated variance along the normal (deciles), a
// robust variance of the deviations per bin (median of d^2 over that of
// chi-square(1)), and a line var = a sigma^2 + b through the bins by least
// squares; sqrt(b / a), or 0 where b <= 0 or a <= 0 (the stated sigmas
// already explain the scatter).
// The bins of stated variance EstimateAddedSigma fits its line through, and
// the fewest tested points that fill them (20 each).
constexpr int kBins = 10;
constexpr size_t kMinPointsToEstimateAddedSigma = 20 * kBins;

double EstimateAddedSigma(const PointCloud& cloud,
                          const std::vector<Eigen::Vector3d>& sigmas,
                          const std::vector<int>& nearest,
                          int width,
                          int k,
                          double min_variance,
                          int num_threads) {
  const Neighborhoods hoods = UnflaggedNeighborhoods(
      cloud,
      nearest,
      width,
      k,
      std::vector<EditReason>(cloud.size(), EditReason::kKept),
      num_threads);
  const ScaleTest test = TestAtScale(cloud,
                                     sigmas,
                                     hoods.index,
                                     hoods.normals,
                                     k,
                                     k,
                                     min_variance,
                                     num_threads);
  std::vector<std::pair<double, double>> samples;  // (sigma^2, d^2)
  for (size_t i = 0; i < test.z.size(); ++i) {
    if (test.z[i] >= 0) {
      samples.emplace_back(test.own_variance[i],
                           test.deviation[i] * test.deviation[i]);
    }
  }
  if (samples.size() < kMinPointsToEstimateAddedSigma) return 0;
  std::sort(samples.begin(), samples.end());
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (int bin = 0; bin < kBins; ++bin) {
    const size_t begin = samples.size() * bin / kBins,
                 end = samples.size() * (bin + 1) / kBins;
    double mean_variance = 0;
    std::vector<double> squares;
    for (size_t j = begin; j < end; ++j) {
      mean_variance += samples[j].first;
      squares.push_back(samples[j].second);
    }
    mean_variance /= end - begin;
    const double robust = Median(std::move(squares)) / kChiSquare1Median;
    const Eigen::Vector2d row(mean_variance, 1.0);
    normal += row * row.transpose();
    rhs += robust * row;
  }
  const Eigen::Vector2d ab = normal.ldlt().solve(rhs);
  if (!(ab(0) > 0) || !(ab(1) > 0)) return 0;
  return std::sqrt(ab(1) / ab(0));
}

// A floor for the deviation's variance, so that noise-free input is not
// judged against a zero scatter.
double MinDeviationVariance(const PointCloud& cloud) {
  Eigen::Vector3d min = cloud.positions[0], max = cloud.positions[0];
  for (const Eigen::Vector3d& p : cloud.positions) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  return std::pow(1e-7 * (max - min).norm(), 2);
}

// The neighbours found per point for patches of k: spares for those flagged
// on the way (2 % blunders leave about one in a neighbourhood of 24; eight
// spares cover clusters).
int NeighborhoodWidth(int k) { return k + 8; }

// The median distance from a point to its nearest neighbour, over up to
// 20000 points spread over the cloud.
double MedianSpacing(const CenteredPclCloud& pcl_cloud) {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(pcl_cloud.cloud);
  const size_t n = pcl_cloud.cloud->size();
  const size_t step = std::max<size_t>(1, n / 20000);
  std::vector<double> spacing;
  std::vector<int> found(2);
  std::vector<float> squared(2);
  for (size_t i = 0; i < n; i += step) {
    if (tree.nearestKSearch((*pcl_cloud.cloud)[i], 2, found, squared) == 2) {
      spacing.push_back(std::sqrt(squared[1]));
    }
  }
  return Median(std::move(spacing));
}

void RunStatistical(const PointCloud& cloud,
                    const StatisticalEditOptions& options,
                    std::vector<EditReason>* reasons) {
  const CenteredPclCloud pcl_cloud(cloud.positions);
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter(true);
  filter.setInputCloud(pcl_cloud.cloud);
  filter.setMeanK(options.mean_k);
  filter.setStddevMulThresh(options.stddev_mul);
  pcl::Indices kept;
  filter.filter(kept);
  for (const auto index : *filter.getRemovedIndices()) {
    (*reasons)[index] = EditReason::kStatistical;
  }
}

double RunRadius(const PointCloud& cloud,
                 const RadiusEditOptions& options,
                 std::vector<EditReason>* reasons) {
  const CenteredPclCloud pcl_cloud(cloud.positions);
  const double radius =
      options.radius_m > 0 ? options.radius_m : 5.0 * MedianSpacing(pcl_cloud);
  pcl::RadiusOutlierRemoval<pcl::PointXYZ> filter(true);
  filter.setInputCloud(pcl_cloud.cloud);
  filter.setRadiusSearch(radius);
  filter.setMinNeighborsInRadius(options.min_neighbors);
  pcl::Indices kept;
  filter.filter(kept);
  for (const auto index : *filter.getRemovedIndices()) {
    (*reasons)[index] = EditReason::kRadius;
  }
  return radius;
}

}  // namespace

double MedianPointSpacing(const PointCloud& cloud) {
  if (cloud.size() < 2) return 0;
  return MedianSpacing(CenteredPclCloud(cloud.positions));
}

std::string CloudEditMethodName(CloudEditMethod method) {
  switch (method) {
    case CloudEditMethod::kSurfaceFit:
      return "surface_fit";
    case CloudEditMethod::kStatistical:
      return "statistical";
    case CloudEditMethod::kRadius:
      return "radius";
  }
  return "?";
}

std::string EditReasonName(EditReason reason) {
  switch (reason) {
    case EditReason::kKept:
      return "kept";
    case EditReason::kDeviationSigma:
      return "deviation beyond the sigma threshold";
    case EditReason::kDeviationAbsolute:
      return "deviation beyond the absolute threshold";
    case EditReason::kStatistical:
      return "statistical outlier";
    case EditReason::kRadius:
      return "too few neighbours within the radius";
    case EditReason::kDeviationClose:
      return "deviation from the plane of its nearest points beyond the "
             "sigma threshold";
  }
  return "?";
}

void SurfaceFitEditOptions::Check() const {
  CheckOption(num_neighbors >= 8 && num_neighbors <= 500,
              "num_neighbors",
              "in [8, 500]",
              num_neighbors);
  CheckOption(num_iterations >= 1 && num_iterations <= 20,
              "num_iterations",
              "in [1, 20]",
              num_iterations);
  CheckOption(max_deviation_sigma > 0,
              "max_deviation_sigma",
              "> 0",
              max_deviation_sigma);
  CheckOption(max_deviation_m >= 0, "max_deviation_m", ">= 0", max_deviation_m);
  CheckOption(
      num_close_neighbors == 0 ||
          (num_close_neighbors >= 6 && num_close_neighbors <= num_neighbors),
      "num_close_neighbors",
      "0 or in [6, num_neighbors]",
      num_close_neighbors);
  CheckOption(added_sigma_m >= 0 || added_sigma_m == -1,
              "added_sigma_m",
              ">= 0, or -1 to estimate it",
              added_sigma_m);
  CheckOption(max_close_deviation_sigma > 0,
              "max_close_deviation_sigma",
              "> 0",
              max_close_deviation_sigma);
}

void StatisticalEditOptions::Check() const {
  CheckOption(mean_k >= 2, "mean_k", ">= 2", mean_k);
  CheckOption(stddev_mul > 0, "stddev_mul", "> 0", stddev_mul);
}

void RadiusEditOptions::Check() const {
  CheckOption(radius_m >= 0, "radius_m", ">= 0 (0 = automatic)", radius_m);
  CheckOption(min_neighbors >= 1, "min_neighbors", ">= 1", min_neighbors);
}

void CloudEditOptions::Check() const {
  CheckNested("surface_fit", surface_fit);
  CheckNested("statistical", statistical);
  CheckNested("radius", radius);
}

void SurfaceFitEditOptions::Register(OptionRegistry* r) {
  r->Add("num_neighbors", &num_neighbors, "Neighbours per second-order patch");
  r->Add("num_iterations",
         &num_iterations,
         "Passes of fitting and testing (paper: 3-5)");
  r->Add("max_deviation_sigma",
         &max_deviation_sigma,
         "Delete beyond this many standard deviations");
  r->Add("max_deviation_m",
         &max_deviation_m,
         "Delete beyond this distance, metres (0 = off)");
  r->Add("num_close_neighbors",
         &num_close_neighbors,
         "The close test, against the plane of this many nearest points (0 = "
         "off)");
  r->Add("max_close_deviation_sigma",
         &max_close_deviation_sigma,
         "The close test's threshold, standard deviations");
  r->Add("use_point_precision",
         &use_point_precision,
         "1 = weights and sigma units from s_normal, or sx, sy, sz");
  r->Add("added_sigma_m",
         &added_sigma_m,
         "Sigma added to every stated one in quadrature, metres (-1 = "
         "estimated from the cloud, 0 = none)");
}

void StatisticalEditOptions::Register(OptionRegistry* r) {
  r->Add("mean_k", &mean_k, "Neighbours for the mean distance");
  r->Add("stddev_mul", &stddev_mul, "Threshold in standard deviations");
}

void RadiusEditOptions::Register(OptionRegistry* r) {
  r->Add(
      "radius_m", &radius_m, "Search radius, metres (0 = 5 x median spacing)");
  r->Add(
      "min_neighbors", &min_neighbors, "Fewest neighbours within the radius");
}

void CloudEditOptions::Register(OptionRegistry* r) {
  r->AddChoice("method",
               &method,
               ChoicesOf<CloudEditMethod>(CloudEditMethodName,
                                          {CloudEditMethod::kSurfaceFit,
                                           CloudEditMethod::kStatistical,
                                           CloudEditMethod::kRadius}),
               "surface_fit, statistical, radius");
  r->AddNested("surface_fit", &surface_fit);
  r->AddNested("statistical", &statistical);
  r->AddNested("radius", &radius);
  r->Add("num_threads", &num_threads, "-1 = all cores");
}

namespace {

double CheckedSigma(const PointAttribute& attribute,
                    size_t i,
                    const std::string& what) {
  const double s = attribute.values[i];
  if (!(s > 0) || !std::isfinite(s)) {
    ThrowInputError(what,
                    ": point ",
                    i,
                    " has ",
                    attribute.name,
                    " = ",
                    s,
                    "; standard deviations must be positive and finite");
  }
  return s;
}

}  // namespace

double EstimateUnmodelledSigma(const PointCloud& cloud,
                               int num_neighbors,
                               int num_threads,
                               const std::string& what) {
  if (cloud.size() < kMinPointsToEstimateAddedSigma) return 0;
  CheckCloudSpansSurface(cloud, num_neighbors + 1, what);
  const std::vector<Eigen::Vector3d> sigmas = PointSigmas(cloud, what);
  if (sigmas.empty()) return 0;
  const int width = NeighborhoodWidth(num_neighbors);
  return EstimateAddedSigma(cloud,
                            sigmas,
                            NearestNeighbors(cloud, width, num_threads),
                            width,
                            num_neighbors,
                            MinDeviationVariance(cloud),
                            num_threads);
}

std::vector<Eigen::Vector3d> PointSigmas(const PointCloud& cloud,
                                         const std::string& what) {
  // A dense matcher's covariance is long along the viewing ray and leans
  // with it, so the per-axis sigmas (its diagonal) say little about the
  // precision across the surface; where the cloud carries that figure
  // (s_normal, from the full covariance), it stands for all three axes.
  if (const PointAttribute* s_normal = cloud.FindAttribute("s_normal")) {
    std::vector<Eigen::Vector3d> sigmas(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      sigmas[i].setConstant(CheckedSigma(*s_normal, i, what));
    }
    return sigmas;
  }
  const PointAttribute* attributes[3] = {cloud.FindAttribute("sx"),
                                         cloud.FindAttribute("sy"),
                                         cloud.FindAttribute("sz")};
  for (const PointAttribute* attribute : attributes) {
    if (attribute == nullptr) return {};
  }
  std::vector<Eigen::Vector3d> sigmas(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      sigmas[i](k) = CheckedSigma(*attributes[k], i, what);
    }
  }
  return sigmas;
}

void CheckCloudSpansSurface(const PointCloud& cloud,
                            size_t min_points,
                            const std::string& what) {
  if (cloud.empty()) ThrowInputError(what, ": the cloud has no points");
  if (cloud.size() < min_points) {
    ThrowInputError(what,
                    ": ",
                    cloud.size(),
                    " points are too few (need at least ",
                    min_points,
                    ")");
  }
  cloud.Check(what);
  const size_t step = std::max<size_t>(1, cloud.size() / 100000);
  std::vector<Eigen::Vector3d> sample;
  for (size_t i = 0; i < cloud.size(); i += step) {
    sample.push_back(cloud.positions[i]);
  }
  Eigen::Matrix3d axes;
  Eigen::Vector3d eigenvalues;
  PrincipalAxes(sample, &axes, &eigenvalues);
  if (!(eigenvalues(1) > 1e-10 * eigenvalues(0))) {
    ThrowInputError(what,
                    ": all ",
                    cloud.size(),
                    " points lie on one line (or coincide); there is no "
                    "surface to fit");
  }
}

std::vector<size_t> CloudEditReport::CountByReason() const {
  std::vector<size_t> counts(kNumEditReasons, 0);
  for (EditReason reason : reasons) ++counts[static_cast<int>(reason)];
  return counts;
}

std::string CloudEditReport::Summary() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  out << CloudEditMethodName(method) << ": " << num_input << " points in, "
      << num_kept << " kept, " << num_removed << " removed ("
      << (num_input > 0 ? 100.0 * num_removed / num_input : 0.0) << " %) in "
      << seconds << " s";
  if (method == CloudEditMethod::kSurfaceFit) {
    out << (used_point_precision
                ? "; weights and sigma units from the points' own precision"
                : "; sigma units from the local scatter");
    if (added_sigma_m > 0) {
      out << std::setprecision(5) << " (+ " << added_sigma_m
          << " m in quadrature)" << std::setprecision(2);
    }
    out << (converged ? "; converged" : "");
  }
  if (method == CloudEditMethod::kRadius)
    out << "; radius " << radius_m << " m";
  const std::vector<size_t> counts = CountByReason();
  for (int r = 1; r < kNumEditReasons; ++r) {
    if (counts[r] > 0) {
      out << "\n  removed " << counts[r] << ": "
          << EditReasonName(static_cast<EditReason>(r));
    }
  }
  for (const EditIterationReport& it : iterations) {
    out << "\n  iteration " << it.iteration << ": tested " << it.num_tested
        << " (untested " << it.num_untested << "), flagged " << it.num_flagged
        << " (new " << it.num_newly_flagged << ", restored " << it.num_restored
        << "; by sigma " << it.num_sigma << ", absolute " << it.num_absolute
        << ", close " << it.num_close << "), median |d|/sigma "
        << std::setprecision(3) << it.median_normalized_deviation
        << std::setprecision(2) << ", " << it.seconds << " s";
  }
  return out.str();
}

PointCloud EditPointCloud(const PointCloud& cloud,
                          const CloudEditOptions& options,
                          CloudEditReport* report,
                          const std::string& what) {
  options.Check();
  const Timer timer;
  const int min_points = options.method == CloudEditMethod::kSurfaceFit
                             ? options.surface_fit.num_neighbors + 1
                             : 3;
  CheckCloudSpansSurface(cloud, min_points, what);
  *report = CloudEditReport();
  report->method = options.method;
  report->num_input = cloud.size();
  report->reasons.assign(cloud.size(), EditReason::kKept);

  if (options.method == CloudEditMethod::kSurfaceFit) {
    std::vector<Eigen::Vector3d> sigmas;
    if (options.surface_fit.use_point_precision) {
      sigmas = PointSigmas(cloud, what);
    }
    report->used_point_precision = !sigmas.empty();
    const double min_variance = MinDeviationVariance(cloud);
    const int width = NeighborhoodWidth(options.surface_fit.num_neighbors);
    const std::vector<int> nearest =
        NearestNeighbors(cloud, width, options.num_threads);
    const double spacing = MedianPointSpacing(cloud);
    double added = options.surface_fit.added_sigma_m;
    if (!sigmas.empty() && added != 0) {
      if (added < 0) {
        added = EstimateAddedSigma(cloud,
                                   sigmas,
                                   nearest,
                                   width,
                                   options.surface_fit.num_neighbors,
                                   min_variance,
                                   options.num_threads);
        LOG(INFO) << "edit: estimated sigma added to the stated ones: " << added
                  << " m";
      }
      for (Eigen::Vector3d& sigma : sigmas) {
        sigma = (sigma.array().square() + added * added).sqrt();
      }
      report->added_sigma_m = added;
    }
    for (int iteration = 1; iteration <= options.surface_fit.num_iterations;
         ++iteration) {
      const Timer pass_timer;
      EditIterationReport it;
      it.iteration = iteration;
      SurfaceFitPass(cloud,
                     sigmas,
                     nearest,
                     width,
                     spacing,
                     options.surface_fit,
                     min_variance,
                     options.num_threads,
                     &report->reasons,
                     &it);
      it.seconds = pass_timer.Seconds();
      LOG(INFO) << "edit: iteration " << iteration << ": " << it.num_flagged
                << " flagged (" << it.num_newly_flagged << " new, "
                << it.num_restored << " restored)";
      report->iterations.push_back(it);
      if (iteration > 1 && it.num_newly_flagged == 0 && it.num_restored == 0) {
        report->converged = true;
        break;
      }
    }
  } else {
    const Timer pass_timer;
    if (options.method == CloudEditMethod::kStatistical) {
      RunStatistical(cloud, options.statistical, &report->reasons);
    } else {
      report->radius_m = RunRadius(cloud, options.radius, &report->reasons);
    }
    EditIterationReport pass;
    pass.iteration = 1;
    pass.num_tested = cloud.size();
    for (EditReason reason : report->reasons) {
      if (reason != EditReason::kKept) ++pass.num_flagged;
    }
    pass.num_newly_flagged = pass.num_flagged;
    pass.seconds = pass_timer.Seconds();
    report->iterations.push_back(pass);
  }

  std::vector<bool> keep(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    keep[i] = report->reasons[i] == EditReason::kKept;
  }
  PointCloud edited = cloud;
  edited.Filter(keep);
  report->num_kept = edited.size();
  report->num_removed = cloud.size() - edited.size();
  report->seconds = timer.Seconds();
  return edited;
}

nlohmann::ordered_json CloudEditReportJson(const CloudEditReport& report,
                                           const std::string& input_path) {
  nlohmann::ordered_json json;
  json["input_path"] = input_path;
  json["method"] = CloudEditMethodName(report.method);
  json["num_input"] = report.num_input;
  json["num_kept"] = report.num_kept;
  json["num_removed"] = report.num_removed;
  json["used_point_precision"] = report.used_point_precision;
  json["added_sigma_m"] = report.added_sigma_m;
  json["converged"] = report.converged;
  if (report.method == CloudEditMethod::kRadius) {
    json["radius_m"] = report.radius_m;
  }
  json["seconds"] = report.seconds;
  nlohmann::ordered_json reasons = nlohmann::ordered_json::object();
  const std::vector<size_t> counts = report.CountByReason();
  for (int r = 1; r < kNumEditReasons; ++r) {
    if (counts[r] > 0) {
      reasons[EditReasonName(static_cast<EditReason>(r))] = counts[r];
    }
  }
  json["removed_by_reason"] = reasons;
  json["iterations"] = nlohmann::ordered_json::array();
  for (const EditIterationReport& it : report.iterations) {
    json["iterations"].push_back(
        {{"iteration", it.iteration},
         {"num_tested", it.num_tested},
         {"num_untested", it.num_untested},
         {"num_flagged", it.num_flagged},
         {"num_newly_flagged", it.num_newly_flagged},
         {"num_restored", it.num_restored},
         {"num_sigma", it.num_sigma},
         {"num_absolute", it.num_absolute},
         {"num_close", it.num_close},
         {"median_normalized_deviation", it.median_normalized_deviation},
         {"seconds", it.seconds}});
  }
  return json;
}

}  // namespace bayon
