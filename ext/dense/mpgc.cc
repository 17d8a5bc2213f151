// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/mpgc.h"

#include "ext/adjustment/triangulation.h"
#include "ext/core/errors.h"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>

namespace bayon {

void MpgcOptions::Check() const {
  CheckNested("lsm", lsm);
  CheckOption(grey_sigma > 0, "grey_sigma", "> 0", grey_sigma);
  CheckOption(
      geometric_sigma_px > 0, "geometric_sigma_px", "> 0", geometric_sigma_px);
  CheckOption(max_iterations >= 1, "max_iterations", ">= 1", max_iterations);
  CheckOption(convergence_px > 0, "convergence_px", "> 0", convergence_px);
  CheckOption(
      convergence_sigma >= 0, "convergence_sigma", ">= 0", convergence_sigma);
  CheckOption(max_shift_px > 0, "max_shift_px", "> 0", max_shift_px);
  CheckOption(min_correlation > -1 && min_correlation < 1,
              "min_correlation",
              "in (-1, 1)",
              min_correlation);
  CheckOption(
      min_search_views >= 1, "min_search_views", ">= 1", min_search_views);
}

void MpgcOptions::Register(OptionRegistry* r) {
  r->AddNested("lsm", &lsm);
  r->Add("grey_sigma", &grey_sigma, "A priori sigma of a grey value");
  r->Add("geometric_sigma_px",
         &geometric_sigma_px,
         "A priori sigma of the collinearity conditions, px");
  r->Add("max_iterations", &max_iterations, "Most iterations per solution");
  r->Add("convergence_px",
         &convergence_px,
         "Converged when no patch centre moves more, px");
  r->Add("convergence_sigma",
         &convergence_sigma,
         "Converged also when a step moves the solution by less than this "
         "many standard deviations (0: off)");
  r->Add("max_shift_px",
         &max_shift_px,
         "Largest move of a patch from its approximation, px");
  r->Add("min_correlation",
         &min_correlation,
         "Search patches correlating less are dropped");
  r->Add("min_search_views",
         &min_search_views,
         "Fewest search images a point keeps");
}

void EpipolarSearchOptions::Check() const {
  CheckOption(window_radius >= 1, "window_radius", ">= 1", window_radius);
  CheckOption(step_px > 0, "step_px", "> 0", step_px);
  CheckOption(min_ncc > -1 && min_ncc < 1, "min_ncc", "in (-1, 1)", min_ncc);
  CheckOption(min_views >= 1, "min_views", ">= 1", min_views);
  CheckOption(best_views >= 0, "best_views", ">= 0", best_views);
  CheckOption(stride >= 1, "stride", ">= 1", stride);
  CheckOption(num_peaks >= 1, "num_peaks", ">= 1", num_peaks);
}

void EpipolarSearchOptions::Register(OptionRegistry* r) {
  r->Add("window_radius",
         &window_radius,
         "Correlation window along the ray: radius, px");
  r->Add("step_px", &step_px, "Largest epipolar step between ray samples, px");
  r->Add("min_ncc", &min_ncc, "Smallest mean correlation of an approximation");
  r->Add("min_views", &min_views, "Fewest views the best sample is seen in");
  r->Add("best_views",
         &best_views,
         "A sample's score over its best n views (0: all)");
  r->Add("stride",
         &stride,
         "Every n-th ray sample first, then around the best peaks (1: every "
         "sample)");
  r->Add("num_peaks", &num_peaks, "Peaks searched finely after the stride");
}

const char* MpgcStatusName(MpgcStatus status) {
  switch (status) {
    case MpgcStatus::kConverged:
      return "converged";
    case MpgcStatus::kOutsideImage:
      return "outside_image";
    case MpgcStatus::kFlatPatch:
      return "flat_patch";
    case MpgcStatus::kBehindCamera:
      return "behind_camera";
    case MpgcStatus::kTooFewViews:
      return "too_few_views";
    case MpgcStatus::kNotConverged:
      return "not_converged";
    case MpgcStatus::kSingular:
      return "singular";
  }
  return "unknown";
}

namespace {

// The least contrast of a search patch relative to the template that the
// radiometric fit may give it (a patch that does not correlate at all is
// dropped for its correlation, not flattened to nothing).
constexpr double kMinContrast = 0.05;

// How often a step that raised the sum of squares is halved before the
// iteration ends at the step's start.
constexpr int kMaxStepHalvings = 2;

bool Project(const MpgcView& view,
             const Eigen::Vector3d& xyz,
             Eigen::Vector2d* pixel) {
  return view.camera->ImgFromCam(view.cam_from_world * xyz, pixel, view.frame);
}

// d pixel / d X by central differences (the camera model's distortion has
// no closed-form derivative here); `step` in object units.
bool ProjectionJacobian(const MpgcView& view,
                        const Eigen::Vector3d& xyz,
                        double step,
                        Eigen::Matrix<double, 2, 3>* jacobian) {
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d plus = xyz, minus = xyz;
    plus(k) += step;
    minus(k) -= step;
    Eigen::Vector2d p, m;
    if (!Project(view, plus, &p) || !Project(view, minus, &m)) return false;
    jacobian->col(k) = (p - m) / (2 * step);
  }
  return true;
}

// The master rays of a pixel and of its right and lower neighbours (they
// fix the patch shapes), found once per point: inverting the distortion is
// the costly part of a ray.
struct MasterRays {
  Ray centre;
  std::array<Ray, 2> neighbours;
};

std::optional<MasterRays> RaysOf(const MpgcView& master,
                                 const Eigen::Vector2d& xy) {
  MasterRays rays;
  const auto ray = [&](const Eigen::Vector2d& pixel, Ray* out) {
    const std::optional<Ray> found = RayThroughPixel(
        *master.camera, master.cam_from_world, pixel, master.frame);
    if (found) *out = *found;
    return found.has_value();
  };
  if (!ray(xy, &rays.centre)) return std::nullopt;
  for (int k = 0; k < 2; ++k) {
    if (!ray(xy + Eigen::Vector2d::Unit(k), &rays.neighbours[k])) {
      return std::nullopt;
    }
  }
  return rays;
}

// The search patch's shape: how a plane through X with the given normal
// (facing the master where none is given) maps a master pixel step into
// the search image. Where the master rays of the pixel and of its
// neighbours meet the plane, projected into the search image (X itself need
// not lie on the master ray: it is an approximation).
bool InducedShape(const MasterRays& rays,
                  const MpgcView& view,
                  const Eigen::Vector3d& xyz,
                  const std::optional<Eigen::Vector3d>& plane_normal,
                  Eigen::Matrix2d* shape) {
  const Eigen::Vector3d normal = plane_normal.value_or(rays.centre.direction);
  const auto on_plane = [&](const Ray& ray, Eigen::Vector2d* pixel) {
    const double denominator = ray.direction.dot(normal);
    if (std::abs(denominator) < 1e-9) return false;
    return Project(
        view,
        ray.origin +
            ray.direction * ((xyz - ray.origin).dot(normal) / denominator),
        pixel);
  };
  Eigen::Vector2d centre;
  if (!on_plane(rays.centre, &centre)) return false;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d moved;
    if (!on_plane(rays.neighbours[k], &moved)) return false;
    shape->col(k) = moved - centre;
  }
  return true;
}

struct PatchState {
  int view = -1;  // index into `search`
  LsmParameters params;
  // At the approximation: where each solution starts from, and the centre
  // the patch may not wander far from.
  LsmParameters start;
  std::array<bool, kNumLsmParams> active{};
  LsmNormalEquations equations;
};

// The normal equations of all observations at (xyz, patches); false where a
// patch or projection fails (the culprit in *failed, -1 for the master).
// The unknowns are X and per patch its eight parameters, which meet only
// through X (a patch's collinearity condition ties its centre to X, its
// grey values tie it to nothing else): the matrix is a block arrow, kept as
// its blocks, and solved through the 3 x 3 Schur complement of X
// (SolveSystem) instead of as one dense matrix of 3 + 8 x views unknowns.
struct System {
  Eigen::Matrix3d N_xx = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs_x = Eigen::Vector3d::Zero();
  std::vector<LsmMatrix> N_pp;                    // per patch
  std::vector<Eigen::Matrix<double, 3, 2>> N_xc;  // X against (a0, b0)
  std::vector<LsmVector> rhs_p;
  double cost = 0;  // v'Pv in grey values^2
  int num_observations = 0;
  double max_centre_error_px = 0;  // largest |collinearity condition|
};

// The solution (X first, then each patch's parameters) and, where asked
// for, the inverse of the Schur complement of X, which is the X block of the
// inverse normal matrix (X's cofactor matrix); false where a block is
// singular.
bool SolveSystem(const System& system,
                 Eigen::VectorXd* delta,
                 Eigen::Matrix3d* xx_inverse = nullptr) {
  const size_t num_patches = system.N_pp.size();
  Eigen::Matrix3d schur = system.N_xx;
  Eigen::Vector3d reduced = system.rhs_x;
  // Per patch N_pp^-1 N_px and N_pp^-1 rhs_p.
  std::vector<Eigen::Matrix<double, kNumLsmParams, 3>> coupling(num_patches);
  std::vector<LsmVector> own(num_patches);
  for (size_t k = 0; k < num_patches; ++k) {
    const Eigen::LDLT<LsmMatrix> ldlt(system.N_pp[k]);
    if (ldlt.info() != Eigen::Success) return false;
    Eigen::Matrix<double, kNumLsmParams, 3> N_px =
        Eigen::Matrix<double, kNumLsmParams, 3>::Zero();
    N_px.topRows<2>() = system.N_xc[k].transpose();
    coupling[k] = ldlt.solve(N_px);
    own[k] = ldlt.solve(system.rhs_p[k]);
    schur -= system.N_xc[k] * coupling[k].topRows<2>();
    reduced -= system.N_xc[k] * own[k].head<2>();
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(schur);
  if (ldlt.info() != Eigen::Success) return false;
  delta->resize(3 + kNumLsmParams * static_cast<int>(num_patches));
  const Eigen::Vector3d delta_x = ldlt.solve(reduced);
  delta->head<3>() = delta_x;
  for (size_t k = 0; k < num_patches; ++k) {
    delta->segment<kNumLsmParams>(3 + kNumLsmParams * static_cast<int>(k)) =
        own[k] - coupling[k] * delta_x;
  }
  if (!delta->allFinite()) return false;
  if (xx_inverse == nullptr) return true;
  *xx_inverse = ldlt.solve(Eigen::Matrix3d::Identity());
  return xx_inverse->allFinite();
}

bool BuildSystem(const MpgcView& master,
                 const Eigen::Vector2d& master_xy,
                 const std::vector<MpgcView>& search,
                 const LsmTemplate& patch,
                 const Eigen::Vector3d& xyz,
                 double step,
                 double weight,
                 const MpgcOptions& options,
                 std::vector<PatchState>* patches,
                 int* failed,
                 System* system) {
  const size_t num_patches = patches->size();
  system->N_xx.setZero();
  system->rhs_x.setZero();
  system->N_pp.resize(num_patches);
  system->N_xc.resize(num_patches);
  system->rhs_p.resize(num_patches);
  system->cost = 0;
  system->num_observations = 0;
  system->max_centre_error_px = 0;
  // Master: P_m(X) - x_m = 0.
  {
    Eigen::Vector2d projected;
    Eigen::Matrix<double, 2, 3> J;
    if (!Project(master, xyz, &projected) ||
        !ProjectionJacobian(master, xyz, step, &J)) {
      *failed = -1;
      return false;
    }
    const Eigen::Vector2d c = projected - master_xy;
    system->N_xx += weight * J.transpose() * J;
    system->rhs_x -= weight * J.transpose() * c;
    system->cost += weight * c.squaredNorm();
    system->num_observations += 2;
    system->max_centre_error_px =
        std::max(system->max_centre_error_px, c.norm());
  }
  for (size_t k = 0; k < num_patches; ++k) {
    PatchState& state = (*patches)[k];
    const MpgcView& view = search[state.view];
    if (!BuildLsmNormalEquations(patch,
                                 *view.image,
                                 state.params,
                                 options.lsm.interpolation,
                                 &state.equations)) {
      *failed = static_cast<int>(k);
      return false;
    }
    // Radiometry at its best for the geometry as it stands (lsm.h): the
    // joint step would overshoot in contrast on these high-passed images.
    if (options.lsm.estimate_radiometry) {
      FitLsmRadiometry(kMinContrast, &state.params, &state.equations);
    }
    std::array<bool, kNumLsmParams> enabled;
    enabled.fill(true);
    if (!options.lsm.estimate_shape) {
      enabled[kLsmA1] = enabled[kLsmA2] = enabled[kLsmB1] = enabled[kLsmB2] =
          false;
    }
    if (!options.lsm.estimate_radiometry) {
      enabled[kLsmR0] = enabled[kLsmR1] = false;
    }
    // SelectLsmParameters answers which parameters are held (not
    // determinable or not enabled).
    const std::array<bool, kNumLsmParams> held =
        SelectLsmParameters(state.equations.N, enabled, options.lsm);
    for (int p = 0; p < kNumLsmParams; ++p) state.active[p] = !held[p];
    // The geometry fixes what the texture leaves open.
    state.active[kLsmA0] = state.active[kLsmB0] = true;
    LsmMatrix& N = system->N_pp[k];
    LsmVector& rhs = system->rhs_p[k];
    N = state.equations.N;
    rhs = state.equations.rhs;
    for (int p = 0; p < kNumLsmParams; ++p) {
      if (state.active[p]) continue;
      N.row(p).setZero();
      N.col(p).setZero();
      N(p, p) = 1;
      rhs(p) = 0;
    }
    system->cost += state.equations.residual_sq;
    system->num_observations += state.equations.num_observations;
    // Search image: (a0, b0) - P_j(X) = 0.
    Eigen::Vector2d projected;
    Eigen::Matrix<double, 2, 3> J;
    if (!Project(view, xyz, &projected) ||
        !ProjectionJacobian(view, xyz, step, &J)) {
      *failed = static_cast<int>(k);
      return false;
    }
    const Eigen::Vector2d c = state.params.Position() - projected;
    // C = [dc/dX = -J | dc/d(a0, b0) = I].
    system->N_xx += weight * J.transpose() * J;
    system->N_xc[k] = -weight * J.transpose();
    N.topLeftCorner<2, 2>() += weight * Eigen::Matrix2d::Identity();
    system->rhs_x += weight * J.transpose() * c;
    rhs.head<2>() -= weight * c;
    system->cost += weight * c.squaredNorm();
    system->num_observations += 2;
    system->max_centre_error_px =
        std::max(system->max_centre_error_px, c.norm());
  }
  return true;
}

// The lag-one autocorrelations, along u and v, of the grey residuals of
// all patches at their parameters (each patch's residuals about their
// mean).
void ResidualAutocorrelation(const LsmTemplate& patch,
                             const std::vector<MpgcView>& search,
                             const std::vector<PatchState>& patches,
                             Interpolation interpolation,
                             double* rho_u,
                             double* rho_v) {
  const int r = patch.radius, side = 2 * r + 1;
  double along_u = 0, along_v = 0, sum_sq = 0;
  std::vector<double> e(side * side);
  for (const PatchState& state : patches) {
    const auto& a = state.params.affine;
    double mean = 0;
    int k = 0;
    for (int v = -r; v <= r; ++v) {
      for (int u = -r; u <= r; ++u, ++k) {
        ImageSample sample;
        if (!SampleImage(*search[state.view].image,
                         a(0, 2) + a(0, 0) * u + a(0, 1) * v,
                         a(1, 2) + a(1, 0) * u + a(1, 1) * v,
                         interpolation,
                         &sample)) {
          return;
        }
        e[k] =
            patch.values[k] - state.params.r0 - state.params.r1 * sample.value;
        mean += e[k];
      }
    }
    mean /= e.size();
    for (double& x : e) x -= mean;
    for (int v = 0; v < side; ++v) {
      for (int u = 0; u < side; ++u) {
        const double x = e[v * side + u];
        sum_sq += x * x;
        if (u + 1 < side) along_u += x * e[v * side + u + 1];
        if (v + 1 < side) along_v += x * e[(v + 1) * side + u];
      }
    }
  }
  if (sum_sq > 0) {
    *rho_u = along_u / sum_sq;
    *rho_v = along_v / sum_sq;
  }
}

// The master's correlation window at a pixel and the rays that shape the
// search windows for it; nullopt where either cannot be had.
struct MasterWindow {
  MasterRays rays;
  LsmTemplate window;
};

std::optional<MasterWindow> WindowOf(const MpgcView& master,
                                     const Eigen::Vector2d& master_xy,
                                     int window_radius) {
  std::optional<MasterWindow> result(std::in_place);
  const std::optional<MasterRays> rays = RaysOf(master, master_xy);
  if (!rays || !ExtractLsmTemplate(*master.image,
                                   master_xy,
                                   window_radius,
                                   Interpolation::kBilinear,
                                   &result->window)) {
    return std::nullopt;
  }
  result->rays = *rays;
  return result;
}

// The master window against a view's window of `shape` around the
// projection of `xyz`; false where it projects outside.
bool CorrelateAt(const LsmTemplate& window,
                 const MpgcView& view,
                 const Eigen::Vector3d& xyz,
                 const Eigen::Matrix2d& shape,
                 double* correlation) {
  Eigen::Vector2d xy;
  return Project(view, xyz, &xy) && LsmCorrelation(window,
                                                   *view.image,
                                                   LsmParameters::At(xy, shape),
                                                   Interpolation::kBilinear,
                                                   correlation);
}

// The entries of `samples` (indices into `score`, in order along the ray)
// that were scored (above -2) and are at least as high as the entries
// beside them in the list; the first and last entries count only where
// with_ends.
std::vector<int> LocalMaxima(const std::vector<double>& score,
                             const std::vector<int>& samples,
                             bool with_ends) {
  std::vector<int> maxima;
  const size_t last = samples.size() - 1;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double here = score[samples[i]];
    if (here <= -2 || (!with_ends && (i == 0 || i == last))) continue;
    if ((i == 0 || here >= score[samples[i - 1]]) &&
        (i == last || here >= score[samples[i + 1]])) {
      maxima.push_back(samples[i]);
    }
  }
  return maxima;
}

// What one MPGC solution holds fixed: the master's patch, the search views
// and the weights.
struct MpgcProblem {
  const MpgcView& master;
  const Eigen::Vector2d& master_xy;
  const std::vector<MpgcView>& search;
  const LsmTemplate& patch;
  double step;    // of the numerical derivatives, object units
  double weight;  // of the geometric observations against the grey ones
  const MpgcOptions& options;

  bool Build(const Eigen::Vector3d& xyz,
             std::vector<PatchState>* patches,
             int* failed,
             System* system) const {
    return BuildSystem(master,
                       master_xy,
                       search,
                       patch,
                       xyz,
                       step,
                       weight,
                       options,
                       patches,
                       failed,
                       system);
  }

  // A patch moves by its centre's shift and by its shape's change at its
  // corners, as lsm.h judges single patches.
  bool SmallStep(const Eigen::VectorXd& delta, size_t num_patches) const {
    for (size_t k = 0; k < num_patches; ++k) {
      const LsmVector d =
          delta.segment<kNumLsmParams>(3 + kNumLsmParams * static_cast<int>(k));
      const double corners = options.lsm.patch_radius *
                             (std::abs(d[kLsmA1]) + std::abs(d[kLsmA2]) +
                              std::abs(d[kLsmB1]) + std::abs(d[kLsmB2]));
      if (d.head<2>().norm() >= options.convergence_px ||
          corners >= options.convergence_px) {
        return false;
      }
    }
    return true;
  }
};

// The search patches at the approximation, each shaped as the plane of
// `normal` (or the master's ray) induces; those that cannot be placed go
// into `dropped`.
std::vector<PatchState> PlacePatches(
    const MpgcProblem& problem,
    const Eigen::Vector3d& approximation,
    const std::optional<MasterRays>& rays,
    const std::optional<Eigen::Vector3d>& normal,
    std::vector<int>* dropped) {
  std::vector<PatchState> patches;
  for (size_t j = 0; j < problem.search.size(); ++j) {
    const MpgcView& view = problem.search[j];
    PatchState state;
    state.view = static_cast<int>(j);
    Eigen::Matrix2d shape;
    Eigen::Vector2d centre;
    if (!Project(view, approximation, &centre) ||
        (view.cam_from_world * approximation).z() <= 0 || !rays ||
        !InducedShape(*rays, view, approximation, normal, &shape)) {
      dropped->push_back(static_cast<int>(j));
      continue;
    }
    state.start = LsmParameters::At(centre, shape);
    state.params = state.start;
    patches.push_back(state);
  }
  return patches;
}

// How one run of iterations over the current patches ended.
struct MpgcIterations {
  std::optional<MpgcStatus> failure;  // the whole match fails
  bool built = false;                 // the last system was built
  bool converged = false;
  int drop = -2;  // a patch that failed or moved too far; -2: none
  int iterations = 0;
  System system;  // the last one built
};

// Gauss-Newton on xyz and the patches from where they are, until the step
// is small, a patch fails or wanders, or max_iterations.
//
// Step control as lsm.h's: where a step makes the sum of squares grow (the
// period-two oscillation that resampling can drive), half of it is taken
// from where it started instead; a halved step that is small ends the
// iteration as a converged one does, and so does a third failure (at the
// step's start) or a step that barely lowers the sum (convergence_sigma).
// One system per iteration. On the rendered tower the two endings took the
// mean number of iterations per point from 21 to 15 at the same accuracy;
// halving until small had spent a third of them.
MpgcIterations Iterate(const MpgcProblem& problem,
                       Eigen::Vector3d* xyz,
                       std::vector<PatchState>* patches) {
  const MpgcOptions& options = problem.options;
  MpgcIterations out;
  System& system = out.system;
  int failed = -2;
  out.built = problem.Build(*xyz, patches, &failed, &system);
  Eigen::Vector3d step_xyz = *xyz;
  std::vector<PatchState> step_patches;
  System step_system;
  double step_cost = std::numeric_limits<double>::infinity();
  int halvings = 0;
  Eigen::VectorXd delta;
  const auto take = [&](const Eigen::VectorXd& step) {
    *xyz = step_xyz + step.head<3>();
    for (size_t k = 0; k < patches->size(); ++k) {
      (*patches)[k].params = step_patches[k].params;
      (*patches)[k].params.Add(
          step.segment<kNumLsmParams>(3 + kNumLsmParams * static_cast<int>(k)));
    }
    failed = -2;
    out.built = problem.Build(*xyz, patches, &failed, &system);
  };
  int& iteration = out.iterations;
  for (; iteration < options.max_iterations; ++iteration) {
    if (!out.built) {
      if (failed == -1) {
        out.failure = MpgcStatus::kOutsideImage;
        return out;
      }
      out.drop = failed;
      break;
    }
    if (system.cost > step_cost) {
      if (halvings == kMaxStepHalvings) {
        // Neither the step nor its halves lower the sum of squares: the
        // step's start is its least, as near the minimum as the
        // linearisation can tell (the interpolated gradients are not
        // exactly the derivatives of the interpolated values, so the
        // Gauss-Newton step does not vanish there).
        *xyz = step_xyz;
        *patches = std::move(step_patches);
        system = std::move(step_system);
        out.built = true;
        out.converged = true;
        ++iteration;
        break;
      }
      ++halvings;
      delta *= 0.5;
      take(delta);
      if (problem.SmallStep(delta, patches->size())) {
        out.converged = out.built;
        ++iteration;
        break;
      }
      continue;
    }
    if (step_cost - system.cost < options.convergence_sigma *
                                      options.convergence_sigma * system.cost /
                                      system.num_observations) {
      // The step lowered the sum of squares by less than (k sigma0)^2
      // (sigma0^2 as v'Pv over the observations, which outnumber the
      // unknowns more than tenfold): it moved the solution by less than k of
      // its standard deviations (v'Pv falls by dx' N dx, and sigma0^2 N^-1 is
      // dx's covariance).
      out.converged = true;
      ++iteration;
      break;
    }
    halvings = 0;
    step_xyz = *xyz;
    step_patches = *patches;
    step_system = system;
    step_cost = system.cost;
    if (!SolveSystem(system, &delta)) {
      out.failure = MpgcStatus::kSingular;
      return out;
    }
    take(delta);
    // Patches that wandered off their approximation show something else.
    double worst = options.max_shift_px;
    for (size_t k = 0; k < patches->size(); ++k) {
      const PatchState& state = (*patches)[k];
      const double moved =
          (state.params.Position() - state.start.Position()).norm();
      if (moved > worst) {
        worst = moved;
        out.drop = static_cast<int>(k);
      }
    }
    if (out.drop >= 0) break;
    if (problem.SmallStep(delta, patches->size())) {
      out.converged = out.built;
      ++iteration;
      break;
    }
  }
  return out;
}

// The patch whose correlation with the template is lowest, if below
// `below`; -2: none.
int LeastCorrelated(const std::vector<PatchState>& patches, double below) {
  int least = -2;
  double lowest = below;
  for (size_t k = 0; k < patches.size(); ++k) {
    const double r = patches[k].equations.Correlation();
    if (r < lowest) {
      lowest = r;
      least = static_cast<int>(k);
    }
  }
  return least;
}

// sigma0, the point's covariance and the patches' positions at the
// converged solution, into `result`.
void ConcludeMpgc(const MpgcProblem& problem,
                  const std::vector<PatchState>& patches,
                  const Eigen::Vector3d& xyz,
                  const System& system,
                  MpgcResult* result) {
  const MpgcOptions& options = problem.options;
  int unknowns = 3;
  double noise_kept = 0, r1_sq = 0;
  int samples = 0;
  for (const PatchState& state : patches) {
    for (bool a : state.active) unknowns += a;
    noise_kept += state.equations.noise_gain_sum;
    samples += state.equations.num_observations;
    r1_sq += state.params.r1 * state.params.r1;
  }
  result->redundancy = system.num_observations - unknowns;
  if (result->redundancy <= 0) {
    result->status = MpgcStatus::kSingular;
    return;
  }
  result->sigma0 = std::sqrt(system.cost / result->redundancy);
  // Resampling removes part of the search images' noise from the
  // residuals (lsm.h): the same correction as single-patch matching.
  if (options.lsm.correct_resampling_noise && samples > 0) {
    const double kept = noise_kept / samples;
    r1_sq /= patches.size();
    result->sigma0 *= std::sqrt((1 + r1_sq) / (1 + r1_sq * kept));
  }
  // At the last system built: the step from it was small, but it is the
  // system of the parameters reported.
  Eigen::VectorXd unused;
  Eigen::Matrix3d xx_inverse;
  if (!SolveSystem(system, &unused, &xx_inverse)) {
    result->status = MpgcStatus::kSingular;
    return;
  }
  result->covariance = result->sigma0 * result->sigma0 * xx_inverse;
  // The covariance above treats the grey residuals as independent. Where
  // they are not (shading the radiometric model cannot follow, blur that
  // differs between images: smooth residual fields), the patch carries
  // fewer independent observations than pixels. The lag-one
  // autocorrelations of the residuals along u and v (rho, clamped to
  // [0, 0.9]) give the variance inflation of an AR(1) field,
  // (1 + rho_u)(1 + rho_v) / ((1 - rho_u)(1 - rho_v)), which brings the
  // rendered tower's median |error| / sigma from 2.4 towards its expected
  // value. White noise leaves the covariance as it is.
  ResidualAutocorrelation(problem.patch,
                          problem.search,
                          patches,
                          options.lsm.interpolation,
                          &result->residual_rho_u,
                          &result->residual_rho_v);
  // Bilinear resampling alone correlates the search patch's share of
  // white noise: neighbouring samples at sub-pixel offset f share a pixel,
  // correlation f (1 - f) / (f^2 + (1 - f)^2), about 0.25 on average; with
  // that share about 40 % of the residual variance, about 0.1 (0.11
  // measured on the exactly rendered plane of dense_test). That part
  // loses no information about the match and is taken off.
  constexpr double kResamplingRho = 0.1;
  const auto excess = [&](double rho) {
    return std::clamp((rho - kResamplingRho) / (1 - kResamplingRho), 0.0, 0.9);
  };
  const double rho_u = excess(result->residual_rho_u);
  const double rho_v = excess(result->residual_rho_v);
  result->covariance *= (1 + rho_u) * (1 + rho_v) / ((1 - rho_u) * (1 - rho_v));
  result->xyz = xyz;
  for (const PatchState& state : patches) {
    result->views.push_back(state.view);
    result->correlation.push_back(state.equations.Correlation());
    result->xy.push_back(state.params.Position());
  }
  result->status = MpgcStatus::kConverged;
}

}  // namespace

EpipolarSearchResult SearchMasterRay(const MpgcView& master,
                                     const Eigen::Vector2d& master_xy,
                                     const std::vector<MpgcView>& search,
                                     double min_distance,
                                     double max_distance,
                                     const EpipolarSearchOptions& options) {
  options.Check();
  CheckOption(min_distance > 0 && max_distance > min_distance,
              "SearchMasterRay distances",
              "0 < min_distance < max_distance",
              max_distance);
  EpipolarSearchResult result;
  const std::optional<MasterWindow> master_window =
      WindowOf(master, master_xy, options.window_radius);
  if (!master_window) return result;
  const MasterRays& rays = master_window->rays;
  const Eigen::Vector3d& origin = rays.centre.origin;
  const Eigen::Vector3d& direction = rays.centre.direction;
  // Samples even in inverse distance; as many as the longest epipolar
  // segment needs.
  double longest = 0;
  for (const MpgcView& view : search) {
    Eigen::Vector2d near, far;
    if (Project(view, origin + min_distance * direction, &near) &&
        Project(view, origin + max_distance * direction, &far)) {
      longest = std::max(longest, (near - far).norm());
    }
  }
  const int n = std::clamp(
      static_cast<int>(std::ceil(longest / options.step_px)) + 1, 2, 100000);
  result.num_samples = n;
  const auto distance_of = [&](double k) {
    const double inverse =
        1 / min_distance + k / (n - 1) * (1 / max_distance - 1 / min_distance);
    return 1 / inverse;
  };
  // The windows' shapes change slowly along the ray: each view's is taken
  // at the middle of the searched segment (two projections per view, not
  // per sample).
  const Eigen::Vector3d middle =
      origin + distance_of(0.5 * (n - 1)) * direction;
  std::vector<Eigen::Matrix2d> shapes(search.size());
  std::vector<bool> shaped(search.size(), false);
  for (size_t j = 0; j < search.size(); ++j) {
    shaped[j] = InducedShape(rays, search[j], middle, std::nullopt, &shapes[j]);
  }
  // score -2: not scored (or seen in too few views).
  std::vector<double> score(n, -2);
  std::vector<int> views(n, 0);
  std::vector<double> correlations;
  const auto score_sample = [&](int k) {
    ++result.num_scored;
    const Eigen::Vector3d xyz = origin + distance_of(k) * direction;
    correlations.clear();
    for (size_t j = 0; j < search.size(); ++j) {
      double correlation = 0;
      if (shaped[j] &&
          CorrelateAt(
              master_window->window, search[j], xyz, shapes[j], &correlation)) {
        correlations.push_back(correlation);
      }
    }
    views[k] = static_cast<int>(correlations.size());
    if (views[k] < options.min_views) return;
    int used = views[k];
    if (options.best_views > 0 && options.best_views < used) {
      used = options.best_views;
      std::nth_element(correlations.begin(),
                       correlations.begin() + (used - 1),
                       correlations.end(),
                       std::greater<double>());
    }
    score[k] = std::accumulate(
                   correlations.begin(), correlations.begin() + used, 0.0) /
               used;
  };
  const int stride = options.stride;
  if (stride <= 1 || n <= 4 * stride) {
    for (int k = 0; k < n; ++k) score_sample(k);
  } else {
    // The correlation peak of a high-passed window is a few samples wide:
    // the coarse samples find the peaks, the fine ones around the best of
    // them place each to a sample (and give the parabola its neighbours).
    std::vector<int> coarse;
    for (int k = 0; k < n; k += stride) coarse.push_back(k);
    if (coarse.back() != n - 1) coarse.push_back(n - 1);
    for (int k : coarse) score_sample(k);
    std::vector<int> peaks = LocalMaxima(score, coarse, true);
    const size_t kept = std::min<size_t>(peaks.size(), options.num_peaks);
    std::partial_sort(
        peaks.begin(), peaks.begin() + kept, peaks.end(), [&](int a, int b) {
          return score[a] > score[b];
        });
    for (size_t p = 0; p < kept; ++p) {
      for (int k = std::max(0, peaks[p] - stride + 1);
           k <= std::min(n - 1, peaks[p] + stride - 1);
           ++k) {
        if (k % stride != 0 && k != n - 1) score_sample(k);
      }
    }
  }
  const int best = static_cast<int>(
      std::max_element(score.begin(), score.end()) - score.begin());
  result.ncc = score[best];
  result.num_views = views[best];
  const int apart =
      static_cast<int>(std::ceil(options.window_radius / options.step_px));
  // Local maxima among the samples scored (a coarse sample between
  // unscored ones is compared with the scored samples beside it).
  std::vector<int> scored;
  for (int k = 0; k < n; ++k) {
    if (score[k] > -2) scored.push_back(k);
  }
  for (int k : LocalMaxima(score, scored, false)) {
    if (std::abs(k - best) > apart) {
      result.second_ncc = std::max(result.second_ncc, score[k]);
    }
  }
  double k = best;
  if (best > 0 && best < n - 1 && score[best - 1] > -2 &&
      score[best + 1] > -2) {
    const double curvature =
        score[best - 1] - 2 * score[best] + score[best + 1];
    if (curvature < 0) {
      k += std::clamp(
          0.5 * (score[best - 1] - score[best + 1]) / curvature, -0.5, 0.5);
    }
  }
  result.distance = distance_of(k);
  result.xyz = origin + result.distance * direction;
  result.found = result.ncc >= options.min_ncc;
  return result;
}

std::vector<double> ViewCorrelations(
    const MpgcView& master,
    const Eigen::Vector2d& master_xy,
    const std::vector<MpgcView>& views,
    const Eigen::Vector3d& xyz,
    int window_radius,
    const std::optional<Eigen::Vector3d>& normal) {
  std::vector<double> correlations(views.size(), -2);
  const std::optional<MasterWindow> master_window =
      WindowOf(master, master_xy, window_radius);
  if (!master_window) return correlations;
  for (size_t j = 0; j < views.size(); ++j) {
    Eigen::Matrix2d shape;
    if (!InducedShape(master_window->rays, views[j], xyz, normal, &shape) ||
        !CorrelateAt(
            master_window->window, views[j], xyz, shape, &correlations[j])) {
      correlations[j] = -2;
    }
  }
  return correlations;
}

MpgcResult MatchMpgc(const MpgcView& master,
                     const Eigen::Vector2d& master_xy,
                     const std::vector<MpgcView>& search,
                     const Eigen::Vector3d& approximation,
                     const MpgcOptions& options,
                     const std::optional<Eigen::Vector3d>& normal) {
  options.Check();
  MpgcResult result;
  result.xyz = approximation;
  LsmTemplate patch;
  if (!ExtractLsmTemplate(*master.image,
                          master_xy,
                          options.lsm.patch_radius,
                          options.lsm.interpolation,
                          &patch)) {
    result.status = MpgcStatus::kOutsideImage;
    return result;
  }
  if (patch.stddev < options.lsm.min_template_stddev) {
    result.status = MpgcStatus::kFlatPatch;
    return result;
  }
  const double depth = (master.cam_from_world * approximation).z();
  if (!(depth > 0)) {
    result.status = MpgcStatus::kBehindCamera;
    return result;
  }
  // Numerical derivative step: a hundredth of a pixel's footprint.
  const MpgcProblem problem{
      master,
      master_xy,
      search,
      patch,
      0.01 * depth / master.camera->MeanFocalLengthPx(),
      std::pow(options.grey_sigma / options.geometric_sigma_px, 2),
      options};
  std::vector<PatchState> patches = PlacePatches(problem,
                                                 approximation,
                                                 RaysOf(master, master_xy),
                                                 normal,
                                                 &result.dropped);
  // Solve; drop the worst search patch and solve again while one fails.
  // After a drop at convergence the rest start from where they were (their
  // solution barely changes without the culprit); after a divergence, from
  // the approximation.
  Eigen::Vector3d xyz = approximation;
  while (true) {
    if (static_cast<int>(patches.size()) < options.min_search_views) {
      result.status = MpgcStatus::kTooFewViews;
      return result;
    }
    const MpgcIterations run = Iterate(problem, &xyz, &patches);
    if (run.failure) {
      result.status = *run.failure;
      return result;
    }
    result.iterations += run.iterations;
    int drop = run.drop;
    bool warm = false;
    if (drop < 0 && run.converged) {
      // A search patch that does not look like the template after all.
      drop = LeastCorrelated(patches, options.min_correlation);
      warm = true;
    } else if (drop < 0 && run.built &&
               static_cast<int>(patches.size()) > options.min_search_views) {
      // A patch that shows something else (an occluder, a blunder) keeps
      // the joint solution from settling: the one that fits worst goes.
      drop = LeastCorrelated(patches, 2);
    }
    if (drop >= 0) {
      result.dropped.push_back(patches[drop].view);
      patches.erase(patches.begin() + drop);
      if (!warm) {
        xyz = approximation;
        for (PatchState& state : patches) state.params = state.start;
      }
      continue;
    }
    if (!run.converged) {
      result.status = MpgcStatus::kNotConverged;
      result.xyz = xyz;
      return result;
    }
    ConcludeMpgc(problem, patches, xyz, run.system, &result);
    return result;
  }
}

}  // namespace bayon
