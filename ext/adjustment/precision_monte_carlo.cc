// SPDX-License-Identifier: BSD-3-Clause
//
// Monte Carlo check of the stated precision (scripts/bench.sh precision):
// one synthetic ring block (the points scene of `bayon synth`, with control
// points, check points, a levelling bar and a few distant points that only
// two neighbouring stations see) is adjusted again and again
// with fresh observation noise, in each of the three datums. Per coordinate
// of every tie point and camera centre, the standard deviation that the
// adjustment states (the mean of its variances over the draws) is compared
// with the empirical one (the RMS of estimate - truth over the draws).
//
// The errors are taken in the datum the sigmas refer to: the truth's frame
// for control and the minimum datum (both are defined in it), and for the
// free network after the similarity to the truth over the datum's tie
// points, which is what its inner constraints leave.
//
//   adjustment_precision_monte_carlo [--num_draws N] [--num_threads T]
#include "ext/adjustment/adjustment.h"
#include "ext/adjustment/datum.h"
#include "ext/core/alignment.h"
#include "ext/core/random.h"
#include "ext/synth/control_scene.h"
#include "ext/synth/points_scene.h"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace bayon {
namespace {

constexpr double kNoisePx = 0.3;

struct Setup {
  int num_draws = 50;
  int num_threads = -1;
};

// Sums over the draws for one group of coordinates (points or centres),
// per entity and axis.
struct Accumulator {
  std::vector<Eigen::Vector3d> stated_var;
  std::vector<Eigen::Vector3d> error_sq;
  std::vector<int> count;
  void Resize(size_t n) {
    stated_var.assign(n, Eigen::Vector3d::Zero());
    error_sq.assign(n, Eigen::Vector3d::Zero());
    count.assign(n, 0);
  }
  void Add(size_t i, const Eigen::Vector3d& error, const Eigen::Matrix3d& C) {
    stated_var[i] += C.diagonal();
    error_sq[i] += error.cwiseAbs2();
    ++count[i];
  }
};

struct Figures {
  Eigen::Vector3d pooled_ratio = Eigen::Vector3d::Zero();  // per axis
  double median_ratio = 0;
  double fraction_within = 0;  // of coordinates in [0.8, 1.25]
  Eigen::Vector3d stated_rms = Eigen::Vector3d::Zero();
  int num_coordinates = 0;
};

// Only entities present in every draw count.
Figures Summarise(const Accumulator& a, int num_draws) {
  Figures f;
  Eigen::Vector3d stated = Eigen::Vector3d::Zero(),
                  empirical = Eigen::Vector3d::Zero();
  std::vector<double> ratios;
  int n = 0;
  for (size_t i = 0; i < a.count.size(); ++i) {
    if (a.count[i] != num_draws) continue;
    stated += a.stated_var[i] / num_draws;
    empirical += a.error_sq[i] / num_draws;
    ++n;
    for (int k = 0; k < 3; ++k) {
      if (a.error_sq[i](k) <= 0) continue;
      ratios.push_back(std::sqrt(a.stated_var[i](k) / a.error_sq[i](k)));
    }
  }
  if (n == 0 || ratios.empty()) return f;
  f.pooled_ratio = (stated.array() / empirical.array()).sqrt();
  f.stated_rms = (stated / n).cwiseSqrt();
  std::sort(ratios.begin(), ratios.end());
  f.median_ratio = ratios[ratios.size() / 2];
  f.fraction_within =
      std::count_if(ratios.begin(),
                    ratios.end(),
                    [](double r) { return r >= 0.8 && r <= 1.25; }) /
      static_cast<double>(ratios.size());
  f.num_coordinates = static_cast<int>(ratios.size());
  return f;
}

struct Scenario {
  const char* name;
  DatumType datum;
};

// Exact control measurements of the scene; each draw adds its own noise.
SyntheticControl MakeControl(const SyntheticTruth& truth,
                             const PointsSceneOptions& scene_options) {
  SyntheticControlOptions options;
  options.num_control_points = 8;
  options.num_check_points = 8;
  options.levelling_bar = true;
  options.measurement_noise_px = 0;
  SyntheticControl control = SynthesizeControl(truth, scene_options, options);
  for (ImageMeasurement& m : control.measurements) m.sigma_px = kNoisePx;
  return control;
}

void RunScenario(const Setup& setup,
                 const Scenario& scenario,
                 const SyntheticTruth& truth,
                 const SyntheticControl& control) {
  Accumulator points, weak_points, centers;
  std::vector<bool> weak;
  std::vector<Eigen::Vector3d> true_xyz, true_centers;
  double sigma0_sum = 0;
  int num_datum_points = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int draw = 0; draw < setup.num_draws; ++draw) {
    std::mt19937 rng(1000 + draw);
    std::normal_distribution<double> noise(0, kNoisePx);
    Scene noisy = truth.scene;
    for (auto& [image_id, image] : noisy.images) {
      for (Point2D& point : image.points2D) {
        point.xy += RandomVector<2>(noise, rng);
      }
    }
    AdjustmentBlock block = BlockFromScene(noisy, kNoisePx);
    if (draw == 0) {
      for (const BlockPoint& p : block.points) true_xyz.push_back(p.xyz);
      for (const BlockImage& i : block.images) true_centers.push_back(i.center);
      points.Resize(block.points.size());
      weak_points.Resize(block.points.size());
      centers.Resize(block.images.size());
      const std::vector<double> angles = block.IntersectionAnglesDeg();
      for (double angle : angles) {
        weak.push_back(angle < kMinDatumIntersectionAngleDeg);
      }
    }
    // Approximations off the truth, as a strip would give them.
    std::normal_distribution<double> unit(0, 1);
    for (BlockPoint& p : block.points)
      p.xyz += 0.01 * RandomVector<3>(unit, rng);
    for (BlockImage& i : block.images) {
      i.center += 0.02 * RandomVector<3>(unit, rng);
    }
    ControlData data;
    data.folder = "synthetic control";
    if (scenario.datum != DatumType::kFree) {
      data.points = control.points;
      data.distances = control.distances;
      data.measurements = control.measurements;
      for (ImageMeasurement& m : data.measurements) {
        m.xy += RandomVector<2>(noise, rng);
      }
    }
    DatumOptions datum_options;
    datum_options.datum = scenario.datum;
    datum_options.measurement_sigma_px = kNoisePx;
    SetUpDatum(data, datum_options, &block);

    AdjustmentOptions options;
    options.self_calibration = SelfCalibration::kAll;
    options.solver.num_threads = setup.num_threads;
    const AdjustmentResult result = RunAdjustment(options, &block);
    const AdjustmentPrecision& precision = result.precision;
    sigma0_sum += precision.sigma0;
    num_datum_points = precision.num_datum_points;

    // The truth in the datum of the sigmas.
    Sim3d datum_from_truth;
    if (scenario.datum == DatumType::kFree) {
      const std::vector<bool> selected = InnerConstraintPoints(block);
      std::vector<Eigen::Vector3d> from, to;
      for (size_t p = 0; p < true_xyz.size(); ++p) {
        if (!selected[p]) continue;
        from.push_back(true_xyz[p]);
        to.push_back(block.points[p].xyz);
      }
      datum_from_truth = *EstimateSim3d(from, to);
    }
    for (size_t p = 0; p < true_xyz.size(); ++p) {
      const BlockPoint& point = block.points[p];
      if (!point.active || point.kind != PointKind::kTie) continue;
      (weak[p] ? weak_points : points)
          .Add(p,
               point.xyz - datum_from_truth * true_xyz[p],
               precision.point_covariance[p]);
    }
    for (size_t i = 0; i < true_centers.size(); ++i) {
      centers.Add(i,
                  block.images[i].center - datum_from_truth * true_centers[i],
                  precision.image_covariance[i].bottomRightCorner<3, 3>());
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  auto row = [&](const char* what, const Figures& f) {
    std::printf(
        "%-8s %-8s %6d %9.2f %9.2f %9.2f   %4.2f %4.2f %4.2f   %6.2f "
        "%8.1f %%\n",
        scenario.name,
        what,
        f.num_coordinates,
        1000 * f.stated_rms.x(),
        1000 * f.stated_rms.y(),
        1000 * f.stated_rms.z(),
        f.pooled_ratio.x(),
        f.pooled_ratio.y(),
        f.pooled_ratio.z(),
        f.median_ratio,
        100 * f.fraction_within);
  };
  row("points", Summarise(points, setup.num_draws));
  row("distant", Summarise(weak_points, setup.num_draws));
  row("centres", Summarise(centers, setup.num_draws));
  std::printf(
      "%-8s sigma0 %.3f px (noise %.2f px)%s, %.1f s for %d draws\n",
      scenario.name,
      sigma0_sum / setup.num_draws,
      kNoisePx,
      scenario.datum == DatumType::kFree
          ? (", " + std::to_string(num_datum_points) + " datum points").c_str()
          : "",
      seconds,
      setup.num_draws);
}

int Main(int argc, char** argv) {
  Setup setup;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--num_draws") == 0) {
      setup.num_draws = std::atoi(argv[i + 1]);
    } else if (std::strcmp(argv[i], "--num_threads") == 0) {
      setup.num_threads = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  FLAGS_minloglevel = google::GLOG_WARNING;  // one table, not every step
  if (setup.num_draws < 2) {
    std::fprintf(stderr, "--num_draws must be 2 or more\n");
    return 2;
  }
  // `bayon synth --scene points` with the portrait and landscape stations
  // that self-calibration needs.
  PointsSceneOptions scene_options;
  scene_options.alternate_roll_deg = 90;
  scene_options.keypoint_noise_px = 0;
  scene_options.num_distant_points = 16;
  const SyntheticTruth truth = SynthesizePointsScene(scene_options);
  const SyntheticControl control = MakeControl(truth, scene_options);
  std::printf(
      "stated / empirical standard deviations over %d noise draws "
      "(%d stations, %d points, %.1f px, all ten additional parameters;\n"
      "%d distant points %.0f m off, each seen by two neighbouring "
      "stations)\n",
      setup.num_draws,
      scene_options.num_views,
      scene_options.num_points,
      kNoisePx,
      scene_options.num_distant_points,
      scene_options.distant_points_m);
  std::printf("%-8s %-8s %6s %9s %9s %9s   %-14s   %6s %10s\n",
              "datum",
              "what",
              "coords",
              "sX [mm]",
              "sY [mm]",
              "sZ [mm]",
              "ratio X Y Z",
              "median",
              "0.8-1.25");
  for (const Scenario& scenario : {Scenario{"control", DatumType::kControl},
                                   Scenario{"minimum", DatumType::kMinimum},
                                   Scenario{"free", DatumType::kFree}}) {
    RunScenario(setup, scenario, truth, control);
  }
  return 0;
}

}  // namespace
}  // namespace bayon

int main(int argc, char** argv) { return bayon::Main(argc, argv); }
