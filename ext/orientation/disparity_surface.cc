// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/disparity_surface.h"

#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace bayon {

void DisparitySurfaceOptions::Register(OptionRegistry* r) {
  r->Add("points_per_cell",
         &points_per_cell,
         "Grid cell size: conjugate points per cell");
  r->Add("cell_size_factors",
         &cell_size_factors,
         "Cell sizes tried by cross-validation (times the above)");
  r->Add("max_cells", &max_cells, "Most cells along the longer image side");
  r->Add("smoothness_candidates",
         &smoothness_candidates,
         "Smoothness weights tried by cross-validation");
  r->Add("num_folds", &num_folds, "Cross-validation folds");
  r->Add("blunder_threshold",
         &blunder_threshold,
         "Tukey constant / blunder limit, local robust sigmas");
  r->Add("band_quantile",
         &band_quantile,
         "Share of cross-validated predictions the band holds");
  r->Add("min_band_k", &min_band_k, "Smallest band half width, local sigmas");
  r->Add("min_sigma_px", &min_sigma_px, "Smallest local sigma, pixels");
  r->Add("depth_tolerance",
         &depth_tolerance,
         "Unsampled relief the band holds, share of the depth");
  r->Add("range_neighbors",
         &range_neighbors,
         "Nearest points whose inverse depths the band holds");
  r->Add("gradient_factor",
         &gradient_factor,
         "Band growth with disparity gradient times data distance");
  r->Add("support_radius_spacings",
         &support_radius_spacings,
         "Supported within this many point spacings of the data");
  r->Add("growth_px_per_px",
         &growth_px_per_px,
         "Band growth off the supported region, px per px");
  r->Add("min_num_points",
         &min_num_points,
         "Pairs with fewer usable points get no surface");
  r->Add("seed", &seed, "Seed of the cross-validation folds");
}

void DisparitySurfaceOptions::Check() const {
  CheckOption(points_per_cell > 0,
              "DisparitySurfaceOptions.points_per_cell",
              "> 0",
              points_per_cell);
  CheckOption(
      min_cells >= 1, "DisparitySurfaceOptions.min_cells", ">= 1", min_cells);
  CheckOption(max_cells >= min_cells && max_cells <= 256,
              "DisparitySurfaceOptions.max_cells",
              ">= min_cells and <= 256",
              max_cells);
  CheckOption(!smoothness_candidates.empty(),
              "DisparitySurfaceOptions.smoothness_candidates",
              "not empty",
              smoothness_candidates.size());
  for (double smoothness : smoothness_candidates) {
    CheckOption(smoothness > 0,
                "DisparitySurfaceOptions.smoothness_candidates",
                "all > 0",
                smoothness);
  }
  CheckOption(
      num_folds >= 2, "DisparitySurfaceOptions.num_folds", ">= 2", num_folds);
  CheckOption(screen_neighbors >= 3,
              "DisparitySurfaceOptions.screen_neighbors",
              ">= 3",
              screen_neighbors);
  CheckOption(screen_threshold > 0,
              "DisparitySurfaceOptions.screen_threshold",
              "> 0",
              screen_threshold);
  CheckOption(blunder_threshold > 1,
              "DisparitySurfaceOptions.blunder_threshold",
              "> 1",
              blunder_threshold);
  CheckOption(max_iterations >= 1,
              "DisparitySurfaceOptions.max_iterations",
              ">= 1",
              max_iterations);
  CheckOption(min_local_points >= 3,
              "DisparitySurfaceOptions.min_local_points",
              ">= 3",
              min_local_points);
  CheckOption(band_scale_quantile >= 0.5 && band_scale_quantile < 1,
              "DisparitySurfaceOptions.band_scale_quantile",
              "in [0.5, 1)",
              band_scale_quantile);
  CheckOption(band_quantile > 0 && band_quantile <= 1,
              "DisparitySurfaceOptions.band_quantile",
              "in (0, 1]",
              band_quantile);
  CheckOption(
      min_band_k > 0, "DisparitySurfaceOptions.min_band_k", "> 0", min_band_k);
  CheckOption(min_sigma_px > 0,
              "DisparitySurfaceOptions.min_sigma_px",
              "> 0",
              min_sigma_px);
  CheckOption(support_radius_spacings > 0,
              "DisparitySurfaceOptions.support_radius_spacings",
              "> 0",
              support_radius_spacings);
  CheckOption(!cell_size_factors.empty(),
              "DisparitySurfaceOptions.cell_size_factors",
              "not empty",
              cell_size_factors.size());
  for (double factor : cell_size_factors) {
    CheckOption(factor > 0,
                "DisparitySurfaceOptions.cell_size_factors",
                "all > 0",
                factor);
  }
  CheckOption(growth_px_per_px >= 0,
              "DisparitySurfaceOptions.growth_px_per_px",
              ">= 0",
              growth_px_per_px);
  CheckOption(depth_tolerance >= 0 && depth_tolerance < 1,
              "DisparitySurfaceOptions.depth_tolerance",
              "in [0, 1)",
              depth_tolerance);
  CheckOption(gradient_factor >= 0,
              "DisparitySurfaceOptions.gradient_factor",
              ">= 0",
              gradient_factor);
  CheckOption(range_neighbors >= 0,
              "DisparitySurfaceOptions.range_neighbors",
              ">= 0",
              range_neighbors);
  CheckOption(min_num_points >= 3,
              "DisparitySurfaceOptions.min_num_points",
              ">= 3",
              min_num_points);
}

namespace {

constexpr double kMadToSigma = 1.4826;

// The epipolar line of one image-1 point (see the header): rays
// q(w) = A - w E of image 2, plane points m = c2 q_xy / (-q_z).
struct EpipolarLine {
  Eigen::Vector3d A = Eigen::Vector3d::Zero();
  Eigen::Vector3d E = Eigen::Vector3d::Zero();
  double c2 = 1;
  // Homogeneous line of the plane points (m, -c2); its normal, unit.
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
  // Unit direction of growing w in the plane (x right, y up).
  Eigen::Vector2d direction = Eigen::Vector2d::Zero();
  bool valid = false;

  EpipolarLine(const Eigen::Matrix3d& R,
               const Eigen::Vector3d& b,
               const Eigen::Vector3d& n1,
               double camera_constant2)
      : A(R.transpose() * n1), E(R.transpose() * b), c2(camera_constant2) {
    l = A.cross(E);
    const Eigen::Vector2d g = A.z() * E.head<2>() - A.head<2>() * E.z();
    const double ln = l.head<2>().norm();
    valid = ln > 1e-12 && g.norm() > 1e-12 && HasFront();
    if (!valid) return;
    normal = l.head<2>() / ln;
    direction = g.normalized();
  }

  double QZ(double w) const { return A.z() - w * E.z(); }
  bool InFront(double w) const { return std::isfinite(w) && QZ(w) < 0; }
  Eigen::Vector3d Ray(double w) const { return A - w * E; }
  Eigen::Vector2d Plane(double w) const {
    const Eigen::Vector3d q = Ray(w);
    return c2 * q.head<2>() / -q.z();
  }
  // |dm/dw|, plane pixels per unit inverse depth.
  double Rate(double w) const {
    const double qz = QZ(w);
    return c2 * (A.z() * E.head<2>() - A.head<2>() * E.z()).norm() / (qz * qz);
  }
  // The valid inverse depths: w >= 0 (in front of image 1) with the point
  // in front of image 2, [lower, upper) (upper may be +inf).
  double Lower() const {
    if (A.z() < 0) return 0;
    // A.z >= 0 needs E.z > 0 (HasFront).
    return A.z() / E.z() * (1 + 1e-9) + 1e-12;
  }
  double Upper() const {
    if (E.z() >= 0) return std::numeric_limits<double>::infinity();
    return A.z() / E.z();  // A.z < 0 here (HasFront)
  }
  bool HasFront() const { return A.z() < 0 || E.z() > 0; }
  // Signed distance of a plane point from the line.
  double Across(const Eigen::Vector2d& m) const {
    return (l.head<2>().dot(m) - c2 * l.z()) / l.head<2>().norm();
  }
  // Inverse depth of a plane point on the line (the foot of the
  // perpendicular for others).
  double InverseDepthOf(const Eigen::Vector2d& m) const {
    const Eigen::Vector2d foot = m - Across(m) * normal;
    const Eigen::Vector3d v(foot.x(), foot.y(), -c2);
    const Eigen::Vector3d ev = E.cross(v);
    const double den = ev.squaredNorm();
    if (den <= 0) return std::numeric_limits<double>::quiet_NaN();
    return A.cross(v).dot(ev) / den;
  }
};

// Bilinear cell of a point: the four nodes and their weights.
struct CellWeights {
  int node[4] = {0, 0, 0, 0};
  double weight[4] = {0, 0, 0, 0};
};

CellWeights CellOf(const DisparitySurfaceRecord& r, const Eigen::Vector2d& xy) {
  const Eigen::Vector2d s = (xy - r.origin) / r.cell_size_px;
  const int i = std::clamp(static_cast<int>(std::floor(s.x())), 0, r.cols - 1);
  const int j = std::clamp(static_cast<int>(std::floor(s.y())), 0, r.rows - 1);
  const double fx = std::clamp(s.x() - i, 0.0, 1.0);
  const double fy = std::clamp(s.y() - j, 0.0, 1.0);
  const int stride = r.cols + 1;
  CellWeights cell;
  cell.node[0] = j * stride + i;
  cell.node[1] = j * stride + i + 1;
  cell.node[2] = (j + 1) * stride + i;
  cell.node[3] = (j + 1) * stride + i + 1;
  cell.weight[0] = (1 - fx) * (1 - fy);
  cell.weight[1] = fx * (1 - fy);
  cell.weight[2] = (1 - fx) * fy;
  cell.weight[3] = fx * fy;
  return cell;
}

// Gradient of the bilinear function at xy, per image-1 pixel.
Eigen::Vector2d GradientAt(const DisparitySurfaceRecord& r,
                           const std::vector<double>& nodes,
                           const Eigen::Vector2d& xy) {
  const CellWeights c = CellOf(r, xy);
  // Weights (1 - fx)(1 - fy), fx (1 - fy), (1 - fx) fy, fx fy.
  const double fx = c.weight[1] + c.weight[3];
  const double fy = c.weight[2] + c.weight[3];
  const double* v = nodes.data();
  const double dx = ((1 - fy) * (v[c.node[1]] - v[c.node[0]]) +
                     fy * (v[c.node[3]] - v[c.node[2]])) /
                    r.cell_size_px;
  const double dy = ((1 - fx) * (v[c.node[2]] - v[c.node[0]]) +
                     fx * (v[c.node[3]] - v[c.node[1]])) /
                    r.cell_size_px;
  return Eigen::Vector2d(dx, dy);
}

double Evaluate(const CellWeights& cell, const std::vector<double>& nodes) {
  double value = 0;
  for (int k = 0; k < 4; ++k) value += cell.weight[k] * nodes[cell.node[k]];
  return value;
}

Eigen::Vector2d NodePosition(const DisparitySurfaceRecord& r, int node) {
  const int stride = r.cols + 1;
  return r.origin +
         r.cell_size_px * Eigen::Vector2d(static_cast<double>(node % stride),
                                          static_cast<double>(node / stride));
}

// Convex hull, counter-clockwise (Andrew's monotone chain).
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(),
            points.end(),
            [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
              return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
            });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  const auto cross = [](const Eigen::Vector2d& o,
                        const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) -
           (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
    hull[k++] = points[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

double PolygonArea(const std::vector<Eigen::Vector2d>& polygon) {
  double area = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    area += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(area);
}

// Distance from a point outside a counter-clockwise convex polygon to it; 0
// inside.
double DistanceOutsideHull(const std::vector<Eigen::Vector2d>& hull,
                           const Eigen::Vector2d& p) {
  if (hull.empty()) return std::numeric_limits<double>::infinity();
  bool inside = hull.size() >= 3;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2d ab = b - a;
    if (ab.x() * (p.y() - a.y()) - ab.y() * (p.x() - a.x()) < 0) {
      inside = false;
    }
    const double len2 = ab.squaredNorm();
    const double t =
        len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - p).norm());
  }
  return inside ? 0.0 : best;
}

// One conjugate point as the fit sees it.
struct Observation {
  int index = 0;  // into the input points
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double w = 0;     // observed inverse depth
  double rate = 1;  // |du2/dw|, pixels per unit inverse depth
  CellWeights cell;
};

// The weighted least-squares problem on the grid: data rows
// sqrt(weight) * rate * (phi . v - w) and the thin-plate rows.
class GridProblem {
 public:
  GridProblem(const DisparitySurfaceRecord& grid,
              const std::vector<Observation>& observations)
      : observations_(observations), num_nodes_(grid.NumNodes()) {
    std::vector<Eigen::Triplet<double>> triplets;
    int row = 0;
    const int stride = grid.cols + 1;
    const auto node = [stride](int i, int j) { return j * stride + i; };
    for (int j = 0; j <= grid.rows; ++j) {
      for (int i = 1; i < grid.cols; ++i, ++row) {
        triplets.emplace_back(row, node(i - 1, j), 1.0);
        triplets.emplace_back(row, node(i, j), -2.0);
        triplets.emplace_back(row, node(i + 1, j), 1.0);
      }
    }
    for (int i = 0; i <= grid.cols; ++i) {
      for (int j = 1; j < grid.rows; ++j, ++row) {
        triplets.emplace_back(row, node(i, j - 1), 1.0);
        triplets.emplace_back(row, node(i, j), -2.0);
        triplets.emplace_back(row, node(i, j + 1), 1.0);
      }
    }
    const double s2 = std::sqrt(2.0);
    for (int j = 0; j < grid.rows; ++j) {
      for (int i = 0; i < grid.cols; ++i, ++row) {
        triplets.emplace_back(row, node(i, j), s2);
        triplets.emplace_back(row, node(i + 1, j), -s2);
        triplets.emplace_back(row, node(i, j + 1), -s2);
        triplets.emplace_back(row, node(i + 1, j + 1), s2);
      }
    }
    num_smoothness_rows_ = std::max(row, 1);
    Eigen::SparseMatrix<double> D(num_smoothness_rows_, num_nodes_);
    D.setFromTriplets(triplets.begin(), triplets.end());
    smoothness_ = (D.transpose() * D).pruned();
    identity_.resize(num_nodes_, num_nodes_);
    identity_.setIdentity();
  }

  // Node values minimising the weighted data term plus smoothness; false
  // if the system is singular (too few points with weight).
  bool Solve(const std::vector<double>& weights,
             double smoothness,
             std::vector<double>* nodes) {
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(16 * observations_.size());
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(num_nodes_);
    double data_weight = 0;
    int num_weighted = 0;
    // Every point enters the pattern (with weight 0 if need be), so that
    // the ordering is found once per grid.
    for (size_t k = 0; k < observations_.size(); ++k) {
      const Observation& o = observations_[k];
      const double p = std::max(0.0, weights[k]) * o.rate * o.rate;
      data_weight += p;
      num_weighted += p > 0;
      for (int a = 0; a < 4; ++a) {
        rhs(o.cell.node[a]) += p * o.cell.weight[a] * o.w;
        for (int b = 0; b < 4; ++b) {
          triplets.emplace_back(o.cell.node[a],
                                o.cell.node[b],
                                p * o.cell.weight[a] * o.cell.weight[b]);
        }
      }
    }
    if (num_weighted < 3) return false;
    Eigen::SparseMatrix<double> N(num_nodes_, num_nodes_);
    N.setFromTriplets(triplets.begin(), triplets.end());
    // Smoothness relative to the data: lambda times the mean data weight
    // per smoothness row, so that lambda means the same on any grid.
    N += (smoothness * data_weight / num_smoothness_rows_) * smoothness_;
    // A whisper of ridge keeps nodes far from all data determined.
    N += (1e-10 * data_weight / num_weighted) * identity_;
    if (!analyzed_) {
      solver_.analyzePattern(N);
      analyzed_ = true;
    }
    solver_.factorize(N);
    if (solver_.info() != Eigen::Success) return false;
    const Eigen::VectorXd v = solver_.solve(rhs);
    if (solver_.info() != Eigen::Success || !v.allFinite()) return false;
    nodes->assign(v.data(), v.data() + v.size());
    return true;
  }

 private:
  const std::vector<Observation>& observations_;
  int num_nodes_ = 0;
  int num_smoothness_rows_ = 1;
  Eigen::SparseMatrix<double> smoothness_;
  Eigen::SparseMatrix<double> identity_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
  bool analyzed_ = false;
};

// Residuals along the line, image-2 pixels.
std::vector<double> Residuals(const std::vector<Observation>& observations,
                              const std::vector<double>& nodes) {
  std::vector<double> residuals(observations.size());
  for (size_t k = 0; k < observations.size(); ++k) {
    const Observation& o = observations[k];
    residuals[k] = o.rate * (Evaluate(o.cell, nodes) - o.w);
  }
  return residuals;
}

// z with P(|N(0, 1)| <= z) = q.
double HalfNormalQuantile(double q) {
  double lo = 0, hi = 10;
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (std::erf(mid / std::sqrt(2.0)) < q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The robust scale of |values| around each node: their q-quantile over the
// points within `radius` of it (or the `min_points` nearest if fewer),
// divided by that quantile of |N(0, 1)| (q = 0.5: 1.4826 times the median);
// only points with mask 1 count. At least min_sigma.
std::vector<double> LocalScales(const DisparitySurfaceRecord& grid,
                                const std::vector<Observation>& observations,
                                const std::vector<double>& values,
                                const std::vector<uint8_t>& mask,
                                double radius,
                                int min_points,
                                double min_sigma,
                                double q = 0.5) {
  const double z = HalfNormalQuantile(q);
  std::vector<int> members;
  for (size_t k = 0; k < observations.size(); ++k) {
    if (mask[k]) members.push_back(static_cast<int>(k));
  }
  std::vector<double> scales(grid.NumNodes(), min_sigma);
  if (members.empty()) return scales;
  std::vector<std::pair<double, double>> near(members.size());
  std::vector<double> chosen;
  const double radius2 = radius * radius;
  for (int node = 0; node < grid.NumNodes(); ++node) {
    const Eigen::Vector2d p = NodePosition(grid, node);
    int within = 0;
    for (size_t m = 0; m < members.size(); ++m) {
      const int k = members[m];
      near[m] = {(observations[k].xy - p).squaredNorm(), std::abs(values[k])};
      within += near[m].first <= radius2;
    }
    const size_t count = std::min(
        near.size(), static_cast<size_t>(std::max(within, min_points)));
    std::nth_element(near.begin(), near.begin() + (count - 1), near.end());
    chosen.clear();
    for (size_t m = 0; m < count; ++m) chosen.push_back(near[m].second);
    scales[node] = std::max(min_sigma, Quantile(chosen, q) / z);
  }
  return scales;
}

double Tukey(double t) {
  if (std::abs(t) >= 1) return 0;
  const double u = 1 - t * t;
  return u * u;
}

// The fit of one smoothness weight: IRLS from `start` weights.
struct RobustFit {
  std::vector<double> nodes;
  std::vector<double> weights;
  std::vector<double> residuals;
  std::vector<double> scales;  // per node
  bool success = false;
};

RobustFit FitRobust(const DisparitySurfaceRecord& grid,
                    GridProblem* problem,
                    const std::vector<Observation>& observations,
                    const std::vector<double>& start,
                    double smoothness,
                    double scale_radius,
                    const DisparitySurfaceOptions& options) {
  RobustFit fit;
  fit.weights = start;
  const std::vector<uint8_t> all(observations.size(), 1);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::vector<double> nodes;
    if (!problem->Solve(fit.weights, smoothness, &nodes)) return fit;
    double change = 0;
    if (!fit.nodes.empty()) {
      for (size_t k = 0; k < nodes.size(); ++k) {
        change = std::max(change, std::abs(nodes[k] - fit.nodes[k]));
      }
    }
    fit.nodes = std::move(nodes);
    fit.success = true;
    fit.residuals = Residuals(observations, fit.nodes);
    fit.scales = LocalScales(grid,
                             observations,
                             fit.residuals,
                             all,
                             scale_radius,
                             options.min_local_points,
                             options.min_sigma_px);
    std::vector<double> weights(observations.size());
    for (size_t k = 0; k < observations.size(); ++k) {
      const double s = Evaluate(observations[k].cell, fit.scales);
      weights[k] = Tukey(fit.residuals[k] / (options.blunder_threshold * s));
    }
    const bool same_set = [&] {
      for (size_t k = 0; k < weights.size(); ++k) {
        if ((weights[k] > 0) != (fit.weights[k] > 0)) return false;
      }
      return true;
    }();
    fit.weights = std::move(weights);
    // Converged: the same points in use and the nodes settled (relative
    // to the inverse-depth scale of the data).
    if (iteration > 0 && same_set && change < 1e-7) break;
  }
  return fit;
}

// Cross-validated residuals: each fold predicted by the fit to the others,
// with fixed weights.
std::vector<double> CrossValidate(GridProblem* problem,
                                  const std::vector<Observation>& observations,
                                  const std::vector<double>& weights,
                                  const std::vector<int>& fold,
                                  int num_folds,
                                  double smoothness,
                                  bool* ok) {
  std::vector<double> cv(observations.size(),
                         std::numeric_limits<double>::infinity());
  *ok = true;
  for (int f = 0; f < num_folds; ++f) {
    std::vector<double> train = weights;
    bool any = false;
    for (size_t k = 0; k < observations.size(); ++k) {
      if (fold[k] == f) {
        train[k] = 0;
        any = true;
      }
    }
    if (!any) continue;
    std::vector<double> nodes;
    if (!problem->Solve(train, smoothness, &nodes)) {
      *ok = false;
      continue;
    }
    for (size_t k = 0; k < observations.size(); ++k) {
      if (fold[k] != f) continue;
      const Observation& o = observations[k];
      cv[k] = o.rate * (Evaluate(o.cell, nodes) - o.w);
    }
  }
  return cv;
}

// Mean square of the smaller 90 % of the cross-validated residuals of the
// points in use: the score of a smoothness weight.
double CrossValidationScore(const std::vector<double>& cv,
                            const std::vector<double>& weights) {
  std::vector<double> squares;
  for (size_t k = 0; k < cv.size(); ++k) {
    if (weights[k] > 0 && std::isfinite(cv[k]))
      squares.push_back(cv[k] * cv[k]);
  }
  if (squares.empty()) return std::numeric_limits<double>::infinity();
  std::sort(squares.begin(), squares.end());
  const size_t keep = std::max<size_t>(1, (squares.size() * 9) / 10);
  return std::accumulate(squares.begin(), squares.begin() + keep, 0.0) / keep;
}

// The screening: each point against the median of its nearest neighbours.
std::vector<double> ScreenWeights(const std::vector<Observation>& observations,
                                  const DisparitySurfaceOptions& options) {
  const size_t n = observations.size();
  const size_t k_near =
      std::min(n - 1, static_cast<size_t>(options.screen_neighbors));
  std::vector<double> weights(n, 1.0);
  if (k_near < 3) return weights;
  std::vector<std::pair<double, int>> order(n);
  std::vector<double> values, deviations;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      order[j] = {(observations[j].xy - observations[i].xy).squaredNorm(),
                  static_cast<int>(j)};
    }
    order[i].first = std::numeric_limits<double>::infinity();
    std::nth_element(order.begin(), order.begin() + (k_near - 1), order.end());
    values.clear();
    for (size_t m = 0; m < k_near; ++m) {
      values.push_back(observations[order[m].second].w);
    }
    const double median = Median(values);
    deviations.clear();
    for (size_t m = 0; m < k_near; ++m) {
      deviations.push_back(observations[order[m].second].rate *
                           std::abs(values[m] - median));
    }
    const double scale =
        std::max(options.min_sigma_px, kMadToSigma * Median(deviations));
    const double residual =
        observations[i].rate * std::abs(observations[i].w - median);
    if (residual > options.screen_threshold * scale) weights[i] = 0;
  }
  return weights;
}

// The bounding box of image 1's image coordinates (its border mapped).
Eigen::AlignedBox2d ImageDomain(const ImageVectors& vectors) {
  Eigen::AlignedBox2d box;
  const double w = vectors.width(), h = vectors.height();
  const int steps = 16;
  for (int k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / steps;
    for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(t * w, 0),
                                         Eigen::Vector2d(t * w, h),
                                         Eigen::Vector2d(0, t * h),
                                         Eigen::Vector2d(w, t * h)}) {
      Eigen::Vector3d u;
      if (vectors.FromPixel(pixel, &u)) box.extend(u.head<2>());
    }
  }
  return box;
}

EpipolarLine LineOf(const Eigen::Matrix3d& R,
                    const Eigen::Vector3d& b,
                    const Eigen::Vector3d& u1,
                    double c2) {
  return EpipolarLine(R, b, u1 / -u1.z(), c2);
}

// Length of the line inside image 2 for w >= 0 and in front of image 2.
double FullRange(const EpipolarLine& line, const ImageVectors& vectors2) {
  if (!line.valid) return 0;
  // The rays A - w E, w >= 0, are the positive combinations of A and -E:
  // walk from one to the other in equal angles.
  const Eigen::Vector3d a = line.A.normalized(), e = -line.E.normalized();
  const double angle = std::acos(std::clamp(a.dot(e), -1.0, 1.0));
  const int steps = 512;
  const double width = vectors2.width(), height = vectors2.height();
  double length = 0;
  bool have_previous = false;
  Eigen::Vector2d previous = Eigen::Vector2d::Zero();
  for (int k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / steps;
    const Eigen::Vector3d q =
        angle > 1e-12 ? Eigen::Vector3d(std::sin((1 - t) * angle) * a +
                                        std::sin(t * angle) * e)
                      : a;
    Eigen::Vector2d pixel;
    const bool inside = q.z() < 0 && vectors2.ToPixel(q, &pixel) &&
                        pixel.x() >= 0 && pixel.y() >= 0 &&
                        pixel.x() <= width && pixel.y() <= height;
    if (inside && have_previous) length += (pixel - previous).norm();
    have_previous = inside;
    if (inside) previous = pixel;
  }
  return length;
}

}  // namespace

// ------------------------------------------------------------ the surface

DisparitySurface::DisparitySurface(DisparitySurfaceRecord record,
                                   ImageVectors vectors1,
                                   ImageVectors vectors2)
    : record_(std::move(record)),
      vectors1_(std::move(vectors1)),
      vectors2_(std::move(vectors2)) {
  Prepare();
}

void DisparitySurface::Prepare() {
  ElementsFromCam2FromCam1(record_.cam2_from_cam1, &rotation_, &base_);
  bucket_start_.clear();
  bucket_points_.clear();
  bucket_cols_ = bucket_rows_ = 0;
  const std::vector<Eigen::Vector2d>& points = record_.support_points;
  if (points.empty()) return;
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector2d& p : points) box.extend(p);
  const double extent = std::max({box.sizes().x(), box.sizes().y(), 1.0});
  bucket_size_ = std::max(record_.spacing_px, extent / 256);
  bucket_origin_ = box.min();
  bucket_cols_ = static_cast<int>(box.sizes().x() / bucket_size_) + 1;
  bucket_rows_ = static_cast<int>(box.sizes().y() / bucket_size_) + 1;
  const auto bucket_of = [&](const Eigen::Vector2d& p) {
    const int i =
        std::min(bucket_cols_ - 1,
                 static_cast<int>((p.x() - bucket_origin_.x()) / bucket_size_));
    const int j =
        std::min(bucket_rows_ - 1,
                 static_cast<int>((p.y() - bucket_origin_.y()) / bucket_size_));
    return j * bucket_cols_ + i;
  };
  bucket_start_.assign(bucket_cols_ * bucket_rows_ + 1, 0);
  for (const Eigen::Vector2d& p : points) ++bucket_start_[bucket_of(p) + 1];
  for (size_t b = 1; b < bucket_start_.size(); ++b) {
    bucket_start_[b] += bucket_start_[b - 1];
  }
  bucket_points_.resize(points.size());
  std::vector<int> fill(bucket_start_.begin(), bucket_start_.end() - 1);
  for (size_t k = 0; k < points.size(); ++k) {
    bucket_points_[fill[bucket_of(points[k])]++] = static_cast<int>(k);
  }
}

void DisparitySurface::NearestSupport(
    const Eigen::Vector2d& xy,
    int k,
    double radius,
    std::vector<std::pair<double, int>>* nearest) const {
  nearest->clear();
  if (bucket_cols_ == 0 || k < 1) return;
  const Eigen::Vector2d s = (xy - bucket_origin_) / bucket_size_;
  const int ci =
      std::clamp(static_cast<int>(std::floor(s.x())), 0, bucket_cols_ - 1);
  const int cj =
      std::clamp(static_cast<int>(std::floor(s.y())), 0, bucket_rows_ - 1);
  const double radius2 = radius * radius;
  // The k-th distance so far (or the radius): buckets farther are skipped.
  const auto limit = [&] {
    return static_cast<int>(nearest->size()) < k
               ? radius2
               : std::min(radius2, nearest->back().first);
  };
  const int max_ring = std::max(bucket_cols_, bucket_rows_);
  for (int ring = 0; ring <= max_ring; ++ring) {
    bool any_near = false;
    for (int j = cj - ring; j <= cj + ring; ++j) {
      if (j < 0 || j >= bucket_rows_) continue;
      for (int i = ci - ring; i <= ci + ring; ++i) {
        if (i < 0 || i >= bucket_cols_) continue;
        if (std::max(std::abs(i - ci), std::abs(j - cj)) != ring) continue;
        // Distance from the query to the bucket's box.
        const Eigen::Vector2d lo =
            bucket_origin_ + bucket_size_ * Eigen::Vector2d(i, j);
        const Eigen::Vector2d hi = lo + Eigen::Vector2d::Constant(bucket_size_);
        const Eigen::Vector2d gap = (lo - xy).cwiseMax(xy - hi).cwiseMax(0.0);
        if (gap.squaredNorm() > limit()) continue;
        any_near = true;
        const int b = j * bucket_cols_ + i;
        for (int m = bucket_start_[b]; m < bucket_start_[b + 1]; ++m) {
          const int index = bucket_points_[m];
          const double d2 = (record_.support_points[index] - xy).squaredNorm();
          if (d2 > limit()) continue;
          nearest->emplace_back(d2, index);
          std::sort(nearest->begin(), nearest->end());
          if (static_cast<int>(nearest->size()) > k) nearest->pop_back();
        }
      }
    }
    // Rings around the (clamped) bucket of the query only get farther.
    if (!any_near) break;
  }
}

double DisparitySurface::Interpolate(const std::vector<double>& nodes,
                                     const Eigen::Vector2d& xy) const {
  return Evaluate(CellOf(record_, xy), nodes);
}

double DisparitySurface::InverseDepthAt(const Eigen::Vector2d& xy) const {
  return Interpolate(record_.inverse_depth, xy);
}

double DisparitySurface::NearestSupportDistance(
    const Eigen::Vector2d& xy) const {
  std::vector<std::pair<double, int>> nearest;
  NearestSupport(xy, 1, std::numeric_limits<double>::infinity(), &nearest);
  return nearest.empty() ? std::numeric_limits<double>::infinity()
                         : std::sqrt(nearest[0].first);
}

double DisparitySurface::SupportDistance(const Eigen::Vector2d& xy) const {
  return std::max(NearestSupportDistance(xy),
                  DistanceOutsideHull(record_.hull, xy));
}

double DisparitySurface::HalfWidth(const Eigen::Vector2d& xy,
                                   double support_distance,
                                   double rate) const {
  const double relative = support_distance / record_.spacing_px;
  const double excess =
      std::max(0.0, support_distance - record_.support_radius_px);
  const double gradient =
      rate * GradientAt(record_, record_.inverse_depth, xy).norm();
  return record_.band_k * Interpolate(record_.sigma_px, xy) *
             std::sqrt(1 + relative * relative) +
         record_.gradient_factor * gradient * support_distance +
         record_.growth_px_per_px * excess;
}

SearchInterval DisparitySurface::Search(const Eigen::Vector2d& pixel1) const {
  Eigen::Vector3d u1;
  if (!record_.success || !vectors1_.FromPixel(pixel1, &u1)) {
    return SearchInterval();
  }
  return SearchAt(u1);
}

SearchInterval DisparitySurface::SearchAt(const Eigen::Vector3d& u1) const {
  SearchInterval result;
  if (!record_.success) return result;
  const EpipolarLine line =
      LineOf(rotation_, base_, u1, vectors2_.camera_constant_px());
  if (!line.valid) return result;
  const Eigen::Vector2d xy = u1.head<2>();
  const double lower = line.Lower(), upper = line.Upper();
  double w = InverseDepthAt(xy);
  // A prediction off the valid half line (extrapolation gone wrong) is
  // moved onto it; the band still spans what it spans.
  if (!(w >= lower)) w = lower;
  if (!(w < upper)) w = std::nextafter(upper, 0.0);
  if (!line.InFront(w)) return result;
  result.valid = true;
  result.inverse_depth = w;
  result.support_distance_px = SupportDistance(xy);
  result.supported = result.support_distance_px <= record_.support_radius_px;
  result.half_width_px =
      HalfWidth(xy, result.support_distance_px, line.Rate(w));

  // 1. The statistical band around the prediction.
  const Eigen::Vector2d m = line.Plane(w);
  double w_begin =
      line.InverseDepthOf(m - result.half_width_px * line.direction);
  double w_end = line.InverseDepthOf(m + result.half_width_px * line.direction);
  if (!(line.InFront(w_begin) && w_begin <= w)) w_begin = lower;
  if (!(line.InFront(w_end) && w_end >= w)) w_end = upper;
  // 2. The range of the nearest points used.
  std::vector<std::pair<double, int>> nearest;
  NearestSupport(
      xy, record_.range_neighbors, record_.support_radius_px, &nearest);
  for (const auto& [d2, index] : nearest) {
    const double wj = record_.support_inverse_depth[index];
    w_begin = std::min(w_begin, wj);
    w_end = std::max(w_end, wj);
  }
  // 3. Relief the points do not sample: depths a factor (1 +- tolerance)
  // beyond the ends.
  const double tolerance = record_.depth_tolerance;
  w_begin /= 1 + tolerance;
  w_end = tolerance < 1 ? w_end / (1 - tolerance)
                        : std::numeric_limits<double>::infinity();
  // Clipped at the vanishing point (w = 0) or where the line leaves image
  // 2's front, and at the epipole.
  w_begin = std::max(w_begin, lower);
  w_end = std::min(w_end, upper);
  const auto nudge = [&](double value, double towards) {
    for (int k = 0; k < 60 && !line.InFront(value); ++k) {
      value += 1e-9 * (1 + std::abs(value)) * (towards > value ? 1 : -1) *
               (1 << std::min(k, 30));
    }
    return value;
  };
  if (!line.InFront(w_begin)) w_begin = nudge(w_begin, w);
  if (std::isfinite(w_end) && !line.InFront(w_end)) w_end = nudge(w_end, w);
  result.min_inverse_depth = w_begin;
  result.max_inverse_depth = w_end;

  vectors2_.ToPixel(line.Ray(w), &result.predicted);
  vectors2_.ToPixel(line.Ray(w_begin), &result.begin);
  result.along_begin_px = (line.Plane(w_begin) - m).dot(line.direction);
  if (std::isfinite(w_end)) {
    vectors2_.ToPixel(line.Ray(w_end), &result.end);
    result.along_end_px = (line.Plane(w_end) - m).dot(line.direction);
  } else {
    // The epipole (image 1's centre, in front of image 2).
    vectors2_.ToPixel(-line.E, &result.end);
    const Eigen::Vector2d epipole = -line.c2 * line.E.head<2>() / line.E.z();
    result.along_end_px = (epipole - m).dot(line.direction);
  }
  result.length_px = result.along_end_px - result.along_begin_px;
  // The line's direction in pixels (distortion included).
  const Eigen::Vector2d ahead = m + line.direction;
  Eigen::Vector2d ahead_pixel;
  vectors2_.ToPixel(Eigen::Vector3d(ahead.x(), ahead.y(), -line.c2),
                    &ahead_pixel);
  const Eigen::Vector2d step = ahead_pixel - result.predicted;
  if (step.norm() > 0) result.direction = step.normalized();
  return result;
}

EpipolarPosition DisparitySurface::Locate(const Eigen::Vector2d& pixel1,
                                          const Eigen::Vector2d& pixel2) const {
  EpipolarPosition position;
  if (!record_.success) return position;
  Eigen::Vector3d u1, u2;
  if (!vectors1_.FromPixel(pixel1, &u1) || !vectors2_.FromPixel(pixel2, &u2)) {
    return position;
  }
  const EpipolarLine line =
      LineOf(rotation_, base_, u1, vectors2_.camera_constant_px());
  if (!line.valid) return position;
  const Eigen::Vector2d m = u2.head<2>() * (line.c2 / -u2.z());
  position.across_px = line.Across(m);
  position.inverse_depth = line.InverseDepthOf(m);
  position.valid = line.InFront(position.inverse_depth);
  double w = InverseDepthAt(u1.head<2>());
  w = std::clamp(w, line.Lower(), std::nextafter(line.Upper(), 0.0));
  const Eigen::Vector2d foot = m - position.across_px * line.normal;
  position.along_px = (foot - line.Plane(w)).dot(line.direction);
  return position;
}

bool DisparitySurface::Contains(const Eigen::Vector2d& pixel1,
                                const Eigen::Vector2d& pixel2,
                                double max_across_px) const {
  const SearchInterval interval = Search(pixel1);
  if (!interval.valid) return false;
  const EpipolarPosition position = Locate(pixel1, pixel2);
  return position.valid && std::abs(position.across_px) <= max_across_px &&
         position.inverse_depth >= interval.min_inverse_depth &&
         position.inverse_depth <= interval.max_inverse_depth;
}

bool DisparitySurface::PointAt(const Eigen::Vector2d& pixel1,
                               double inverse_depth,
                               Eigen::Vector2d* pixel2) const {
  Eigen::Vector3d u1;
  if (!vectors1_.FromPixel(pixel1, &u1)) return false;
  const EpipolarLine line =
      LineOf(rotation_, base_, u1, vectors2_.camera_constant_px());
  if (!line.valid || !line.InFront(inverse_depth)) return false;
  return vectors2_.ToPixel(line.Ray(inverse_depth), pixel2);
}

double DisparitySurface::FullRangePx(const Eigen::Vector2d& pixel1) const {
  Eigen::Vector3d u1;
  if (!vectors1_.FromPixel(pixel1, &u1)) return 0;
  return FullRange(LineOf(rotation_, base_, u1, vectors2_.camera_constant_px()),
                   vectors2_);
}

// ------------------------------------------------------------ fitting

namespace {

// The grid of a cell size over the domain.
DisparitySurfaceRecord MakeGrid(const Eigen::AlignedBox2d& domain,
                                double cell) {
  DisparitySurfaceRecord grid;
  grid.origin = domain.min();
  grid.cell_size_px = cell;
  grid.cols = std::max(
      1, static_cast<int>(std::ceil(domain.sizes().x() / cell - 1e-9)));
  grid.rows = std::max(
      1, static_cast<int>(std::ceil(domain.sizes().y() / cell - 1e-9)));
  return grid;
}

// A surface tried in the cross-validation: grid, smoothness and the
// weights of its first robust fit.
struct Candidate {
  double score = std::numeric_limits<double>::infinity();
  double cell = 0;
  double smoothness = 0;
  std::vector<double> weights;
};

// The observations: inverse depth and rate of each conjugate point in front
// of both cameras.
std::vector<Observation> InverseDepthObservations(
    const ConjugatePoints& points,
    const Eigen::Matrix3d& rotation,
    const Eigen::Vector3d& base,
    double c2) {
  std::vector<Observation> observations;
  for (int k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& u1 = points.u1[k];
    const Eigen::Vector3d& u2 = points.u2[k];
    if (!(u1.z() < 0) || !(u2.z() < 0)) continue;
    const EpipolarLine line = LineOf(rotation, base, u1, c2);
    if (!line.valid) continue;
    const Eigen::Vector2d m = u2.head<2>() * (c2 / -u2.z());
    const double w = line.InverseDepthOf(m);
    if (!line.InFront(w)) continue;
    Observation o;
    o.index = k;
    o.xy = u1.head<2>();
    o.w = w;
    o.rate = line.Rate(w);
    if (!std::isfinite(o.rate) || o.rate <= 0) continue;
    observations.push_back(o);
  }
  return observations;
}

// Each observation's fold of the cross-validation, shuffled by the seed.
std::vector<int> CrossValidationFolds(int num_observations,
                                      const DisparitySurfaceOptions& options) {
  std::vector<int> fold(num_observations);
  std::vector<int> order(num_observations);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 rng(options.seed);
  std::shuffle(order.begin(), order.end(), rng);
  for (int k = 0; k < num_observations; ++k) {
    fold[order[k]] = k % options.num_folds;
  }
  return fold;
}

// Cell size and smoothness by cross-validation: each cell size gets its
// robust fit at the middle smoothness, then every smoothness is scored with
// those weights (on the points the screening kept, so that the scores
// compare). The cell sizes are the factors of `base_cell`, within the
// grid's bounds over `longer`, the domain's longer side.
Candidate ChooseGridAndSmoothness(std::vector<Observation>* observations,
                                  const Eigen::AlignedBox2d& domain,
                                  double base_cell,
                                  const std::vector<double>& screened,
                                  const std::vector<int>& fold,
                                  const DisparitySurfaceOptions& options) {
  const double longer = std::max(domain.sizes().x(), domain.sizes().y());
  const std::vector<double>& smoothnesses = options.smoothness_candidates;
  const double start_smoothness = smoothnesses[smoothnesses.size() / 2];
  Candidate best;
  std::vector<double> tried;
  for (double factor : options.cell_size_factors) {
    const double cell = std::clamp(factor * base_cell,
                                   longer / options.max_cells,
                                   longer / options.min_cells);
    if (std::any_of(tried.begin(), tried.end(), [&](double c) {
          return std::abs(c - cell) < 1e-6 * cell;
        })) {
      continue;
    }
    tried.push_back(cell);
    const DisparitySurfaceRecord grid = MakeGrid(domain, cell);
    for (Observation& o : *observations) o.cell = CellOf(grid, o.xy);
    GridProblem problem(grid, *observations);
    const RobustFit start = FitRobust(grid,
                                      &problem,
                                      *observations,
                                      screened,
                                      start_smoothness,
                                      1.5 * cell,
                                      options);
    if (!start.success) continue;
    for (double smoothness : smoothnesses) {
      bool ok = false;
      const std::vector<double> cv = CrossValidate(&problem,
                                                   *observations,
                                                   start.weights,
                                                   fold,
                                                   options.num_folds,
                                                   smoothness,
                                                   &ok);
      const double score = ok ? CrossValidationScore(cv, screened)
                              : std::numeric_limits<double>::infinity();
      if (score < best.score) {
        best.score = score;
        best.cell = cell;
        best.smoothness = smoothness;
        best.weights = start.weights;
      }
    }
  }
  return best;
}

// The support of a fitted surface: the points used, their spacing, and for
// each the distance to its nearest neighbour and to the nearest point of
// the other folds (where the cross-validation predicted it from; infinite
// where there is none).
struct Support {
  std::vector<int> members;
  std::vector<double> nearest;
  std::vector<double> nearest_other_fold;
  double spacing_px = 1;
};

Support SupportOf(const std::vector<Observation>& observations,
                  const std::vector<uint8_t>& used,
                  const std::vector<int>& fold) {
  Support support;
  const int num_observations = static_cast<int>(observations.size());
  for (int k = 0; k < num_observations; ++k) {
    if (used[k]) support.members.push_back(k);
  }
  std::vector<double>& nearest = support.nearest;
  std::vector<double>& nearest_other_fold = support.nearest_other_fold;
  nearest.assign(num_observations, std::numeric_limits<double>::infinity());
  nearest_other_fold = nearest;
  for (int a : support.members) {
    for (int b : support.members) {
      if (a == b) continue;
      const double d2 = (observations[a].xy - observations[b].xy).squaredNorm();
      nearest[a] = std::min(nearest[a], d2);
      if (fold[a] != fold[b]) {
        nearest_other_fold[a] = std::min(nearest_other_fold[a], d2);
      }
    }
  }
  std::vector<double> spacings;
  for (int k : support.members) {
    nearest[k] = std::sqrt(nearest[k]);
    nearest_other_fold[k] = std::sqrt(nearest_other_fold[k]);
    if (std::isfinite(nearest[k])) spacings.push_back(nearest[k]);
  }
  support.spacing_px = std::max(1.0, Median(spacings));
  return support;
}

}  // namespace

DisparitySurface DisparitySurface::Fit(const ConjugatePoints& points,
                                       const Rigid3d& cam2_from_cam1,
                                       const ImageVectors& vectors1,
                                       const ImageVectors& vectors2,
                                       const DisparitySurfaceOptions& options,
                                       DisparityFitReport* report) {
  options.Check();
  CHECK_EQ(points.u1.size(), points.u2.size());
  Timer timer;
  DisparityFitReport local_report;
  DisparityFitReport& rep = report ? *report : local_report;
  rep = DisparityFitReport();
  const int n = points.size();
  rep.num_points = n;
  rep.used.assign(n, 0);
  rep.residual_px.assign(n, 0);
  rep.cv_residual_px.assign(n, 0);

  DisparitySurface surface;
  surface.vectors1_ = vectors1;
  surface.vectors2_ = vectors2;
  DisparitySurfaceRecord& record = surface.record_;
  record.cam2_from_cam1 = cam2_from_cam1;
  record.num_points = n;
  surface.Prepare();
  const auto fail = [&](const std::string& reason) {
    record.success = false;
    record.reason = reason;
    record.num_used = 0;
    record.num_blunders = n;
    record.seconds = timer.Seconds();
    rep.success = false;
    rep.reason = reason;
    rep.num_blunders = n;
    return surface;
  };

  const double c2 = vectors2.camera_constant_px();
  std::vector<Observation> observations =
      InverseDepthObservations(points, surface.rotation_, surface.base_, c2);
  const int num_observations = static_cast<int>(observations.size());
  if (num_observations < options.min_num_points) {
    return fail(StrCat("too few usable conjugate points (",
                       num_observations,
                       " of ",
                       n,
                       ", need ",
                       options.min_num_points,
                       ")"));
  }

  // The domain: image 1 (its border mapped) and every point.
  Eigen::AlignedBox2d domain = ImageDomain(vectors1);
  std::vector<Eigen::Vector2d> xy;
  for (const Observation& o : observations) {
    domain.extend(o.xy);
    xy.push_back(o.xy);
  }
  const double support_area =
      std::max(PolygonArea(ConvexHull(xy)), 1e-4 * domain.volume());
  const double base_cell =
      std::sqrt(support_area * options.points_per_cell / num_observations);
  const std::vector<double> screened = ScreenWeights(observations, options);
  const std::vector<int> fold = CrossValidationFolds(num_observations, options);
  const Candidate best = ChooseGridAndSmoothness(
      &observations, domain, base_cell, screened, fold, options);
  if (!std::isfinite(best.score)) {
    return fail("the surface cannot be fitted (points degenerate)");
  }

  // The surface.
  const DisparitySurfaceRecord grid = MakeGrid(domain, best.cell);
  record.origin = grid.origin;
  record.cell_size_px = grid.cell_size_px;
  record.cols = grid.cols;
  record.rows = grid.rows;
  for (Observation& o : observations) o.cell = CellOf(record, o.xy);
  GridProblem problem(record, observations);
  const double scale_radius = 1.5 * best.cell;
  const RobustFit fit = FitRobust(record,
                                  &problem,
                                  observations,
                                  best.weights,
                                  best.smoothness,
                                  scale_radius,
                                  options);
  if (!fit.success) {
    return fail("the surface cannot be fitted (points degenerate)");
  }
  record.smoothness = best.smoothness;
  record.inverse_depth = fit.nodes;
  std::vector<uint8_t> used(num_observations, 0);
  int num_used = 0;
  for (int k = 0; k < num_observations; ++k) {
    used[k] = fit.weights[k] > 0;
    num_used += used[k];
  }
  if (num_used < options.min_num_points) {
    return fail(StrCat("too few consistent conjugate points (",
                       num_used,
                       " of ",
                       n,
                       ", need ",
                       options.min_num_points,
                       ")"));
  }
  bool ok = false;
  const std::vector<double> cv = CrossValidate(&problem,
                                               observations,
                                               fit.weights,
                                               fold,
                                               options.num_folds,
                                               best.smoothness,
                                               &ok);
  if (!ok) return fail("the cross-validation fits are singular");

  // The support: the points used, their hull and spacing.
  const Support support = SupportOf(observations, used, fold);
  const std::vector<int>& members = support.members;
  const std::vector<double>& nearest_other_fold = support.nearest_other_fold;
  record.spacing_px = support.spacing_px;
  for (int k : members) {
    record.support_points.push_back(observations[k].xy);
    record.support_inverse_depth.push_back(observations[k].w);
  }
  record.range_neighbors = options.range_neighbors;
  record.hull = ConvexHull(record.support_points);
  record.support_radius_px =
      options.support_radius_spacings * record.spacing_px;
  record.growth_px_per_px = options.growth_px_per_px;

  // The band: the cross-validated errors, less the gradient term and
  // reduced to the data's spacing (the half width grows as
  // sqrt(1 + (d / spacing)^2) with the distance d from the nearest point),
  // give the local scale; the factor holds band_quantile of them.
  record.gradient_factor = options.gradient_factor;
  record.depth_tolerance = options.depth_tolerance;
  std::vector<double> gradient(num_observations, 0);
  std::vector<double> reduced(num_observations, 0);
  for (int k : members) {
    const Observation& o = observations[k];
    const double d =
        std::isfinite(nearest_other_fold[k]) ? nearest_other_fold[k] : 0.0;
    gradient[k] = o.rate * GradientAt(record, fit.nodes, o.xy).norm();
    const double relative = d / record.spacing_px;
    const double tolerance =
        record.depth_tolerance * o.rate * std::abs(Evaluate(o.cell, fit.nodes));
    reduced[k] = std::max(0.0,
                          std::abs(cv[k]) - tolerance -
                              record.gradient_factor * gradient[k] * d) /
                 std::sqrt(1 + relative * relative);
  }
  record.sigma_px = LocalScales(record,
                                observations,
                                reduced,
                                used,
                                scale_radius,
                                options.min_local_points,
                                options.min_sigma_px,
                                options.band_scale_quantile);
  // Predictions from farther than the support radius are not what the band
  // is for (off the supported region it grows anyway).
  std::vector<double> normalized, used_residuals, used_cv;
  for (int k : members) {
    used_residuals.push_back(std::abs(fit.residuals[k]));
    used_cv.push_back(std::abs(cv[k]));
    if (!(nearest_other_fold[k] <= record.support_radius_px)) continue;
    normalized.push_back(reduced[k] /
                         Evaluate(observations[k].cell, record.sigma_px));
  }
  record.band_k =
      std::max(options.min_band_k, Quantile(normalized, options.band_quantile));

  // Statistics.
  record.success = true;
  record.reason.clear();
  record.num_used = num_used;
  record.num_blunders = n - num_used;
  record.robust_sigma_px = kMadToSigma * Median(used_residuals);
  record.cv_sigma_px = kMadToSigma * Median(used_cv);
  surface.Prepare();
  {
    int inside = 0;
    for (int k : members) {
      const Observation& o = observations[k];
      const double d =
          std::isfinite(nearest_other_fold[k]) ? nearest_other_fold[k] : 0.0;
      const double w = Evaluate(o.cell, fit.nodes);
      inside += std::abs(cv[k]) <= surface.HalfWidth(o.xy, d, o.rate) +
                                       record.depth_tolerance * o.rate * w;
    }
    record.cv_coverage = static_cast<double>(inside) / num_used;
    // Band and full range over the supported region (at its grid nodes).
    const double c1 = vectors1.camera_constant_px();
    std::vector<double> bands, ranges;
    int count = 0;
    for (int node = 0; node < record.NumNodes(); ++node) {
      const Eigen::Vector2d p = NodePosition(record, node);
      const Eigen::Vector3d u1(p.x(), p.y(), -c1);
      const SearchInterval interval = surface.SearchAt(u1);
      if (!interval.valid || !interval.supported) continue;
      bands.push_back(interval.length_px);
      if (count++ % 4 == 0) {
        ranges.push_back(FullRange(
            LineOf(surface.rotation_, surface.base_, u1, c2), vectors2));
      }
    }
    record.median_band_px = Median(bands);
    record.median_range_px = Median(ranges);
  }
  record.seconds = timer.Seconds();

  rep.success = true;
  rep.num_used = num_used;
  rep.num_blunders = n - num_used;
  for (int k = 0; k < num_observations; ++k) {
    const int index = observations[k].index;
    rep.used[index] = used[k];
    rep.residual_px[index] = fit.residuals[k];
    rep.cv_residual_px[index] = cv[k];
  }
  return surface;
}

// ------------------------------------------------------------ database

std::optional<PairOrientation> ReadPairOrientation(Database* database,
                                                   image_t image_id1,
                                                   image_t image_id2) {
  const image_t lo = std::min(image_id1, image_id2);
  const image_t hi = std::max(image_id1, image_id2);
  PairOrientation orientation;
  bool found = false;
  if (const auto record = ReadRelativeOrientation(database, lo, hi);
      record && record->success) {
    orientation.cam2_from_cam1 = record->cam2_from_cam1;
    orientation.assume_zero_distortion = record->assume_zero_distortion;
    orientation.from_bayon = true;
    found = true;
  } else if (database->ExistsTwoViewGeometry(lo, hi)) {
    const TwoViewGeometry geometry = database->ReadTwoViewGeometry(lo, hi);
    const bool posed = geometry.config == TwoViewConfig::kCalibrated ||
                       geometry.config == TwoViewConfig::kUncalibrated;
    const std::optional<Rigid3d> pose = geometry.StoredPose();
    if (posed && pose) {
      orientation.cam2_from_cam1 = *pose;
      found = true;
    }
  }
  if (!found) return std::nullopt;
  if (image_id1 > image_id2) {
    orientation.cam2_from_cam1 = orientation.cam2_from_cam1.Inverse();
    orientation.cam2_from_cam1.translation.normalize();
  }
  return orientation;
}

std::optional<DisparitySurface> LoadDisparitySurface(Database* database,
                                                     image_t image_id1,
                                                     image_t image_id2,
                                                     std::string* reason) {
  std::string local_reason;
  std::string& why = reason ? *reason : local_reason;
  why.clear();
  std::optional<DisparitySurfaceRecord> record =
      ReadDisparitySurface(database, image_id1, image_id2);
  if (!record) {
    why = "no disparity surface (run `bayon disparity`)";
    return std::nullopt;
  }
  if (!record->success) {
    why = StrCat("no disparity surface: ", record->reason);
    return std::nullopt;
  }
  const std::optional<PairOrientation> orientation =
      ReadPairOrientation(database, image_id1, image_id2);
  if (!orientation) {
    why = "the pair is no longer oriented";
    return std::nullopt;
  }
  const Rigid3d& now = orientation->cam2_from_cam1;
  const Rigid3d& then = record->cam2_from_cam1;
  if (RotationAngleBetween(now.rotation, then.rotation) > 1e-9 ||
      (now.translation - then.translation).norm() > 1e-9 ||
      orientation->assume_zero_distortion != record->assume_zero_distortion) {
    why =
        "stale: the pair was oriented again since (run `bayon disparity` "
        "again)";
    return std::nullopt;
  }
  const ImageVectors vectors1 = ImageVectors::FromDatabase(
      database, database->ReadImage(image_id1), record->assume_zero_distortion);
  const ImageVectors vectors2 = ImageVectors::FromDatabase(
      database, database->ReadImage(image_id2), record->assume_zero_distortion);
  return DisparitySurface(std::move(*record), vectors1, vectors2);
}

}  // namespace bayon
