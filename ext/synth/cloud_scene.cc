// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/cloud_scene.h"

#include "ext/core/errors.h"
#include "ext/core/mesh_geometry.h"
#include "ext/eval/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numeric>
#include <random>

namespace bayon {
namespace {

// A grid surface periodic in its first parameter (and in the second when
// `closed_second`), faces counter-clockwise with respect to the cross
// product d/du x d/dv.
TriangleMesh MakeGridSurface(
    int nu,
    int nv,
    bool closed_second,
    const std::function<Eigen::Vector3d(int, int)>& point) {
  TriangleMesh mesh;
  const int rows = closed_second ? nv : nv + 1;
  mesh.vertices.positions.reserve(static_cast<size_t>(nu) * rows);
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < nu; ++i) mesh.vertices.positions.push_back(point(i, j));
  }
  auto index = [&](int i, int j) { return (j % rows) * nu + i % nu; };
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      mesh.faces.emplace_back(
          index(i, j), index(i + 1, j), index(i + 1, j + 1));
      mesh.faces.emplace_back(
          index(i, j), index(i + 1, j + 1), index(i, j + 1));
    }
  }
  return mesh;
}

// A tube around the z axis, r = radius(theta, z), z in [0, height].
TriangleMesh MakeRadialSurface(
    int num_angles,
    int num_heights,
    double height,
    const std::function<double(double, double)>& radius) {
  return MakeGridSurface(
      num_angles, num_heights, false, [&](int i, int j) -> Eigen::Vector3d {
        const double theta = 2 * M_PI * i / num_angles - M_PI;
        const double z = height * j / num_heights;
        const double r = radius(theta, z);
        return {r * std::cos(theta), r * std::sin(theta), z};
      });
}

double Gaussian2(double dx, double dy, double sx, double sy) {
  return std::exp(-0.5 * (dx * dx / (sx * sx) + dy * dy / (sy * sy)));
}

// Angle difference wrapped to [-pi, pi).
double WrapAngle(double a) {
  return a - 2 * M_PI * std::floor((a + M_PI) / (2 * M_PI));
}

}  // namespace

void ReliefCylinderOptions::Check() const {
  CheckOption(radius_m > 0, "ReliefCylinderOptions.radius_m", "> 0", radius_m);
  CheckOption(height_m > 0, "ReliefCylinderOptions.height_m", "> 0", height_m);
  CheckOption(relief_m >= 0 && relief_m < 0.5 * radius_m,
              "ReliefCylinderOptions.relief_m",
              "in [0, radius_m / 2)",
              relief_m);
  CheckOption(num_angles >= 8 && num_heights >= 2,
              "ReliefCylinderOptions.num_angles/num_heights",
              ">= 8 / >= 2",
              StrCat(num_angles, "/", num_heights));
}

TriangleMesh MakeReliefCylinder(const ReliefCylinderOptions& options) {
  options.Check();
  const double h = options.height_m;
  const double r0 = options.radius_m;
  const double a = options.relief_m;
  // Bosses at fixed angles and heights (relative), about 8 to 15 cm wide.
  const double bosses[][3] = {{0.3, 0.25, 1.0},
                              {1.9, 0.55, -0.8},
                              {-2.2, 0.4, 1.2},
                              {-0.9, 0.8, 0.9},
                              {3.0, 0.7, 1.0}};
  return MakeRadialSurface(
      options.num_angles, options.num_heights, h, [&](double t, double z) {
        double relief = 0.35 * std::sin(3 * t) * std::cos(3 * M_PI * z / h) +
                        0.2 * std::sin(7 * t + 4 * z / h);
        for (const auto& boss : bosses) {
          const double arc = WrapAngle(t - boss[0]) * r0;
          relief += boss[2] * Gaussian2(arc, z - boss[1] * h, 0.15, 0.12);
        }
        return r0 + a * relief;
      });
}

void BoxTowerOptions::Check() const {
  CheckOption(
      half_width_m > 0, "BoxTowerOptions.half_width_m", "> 0", half_width_m);
  CheckOption(height_m > 0, "BoxTowerOptions.height_m", "> 0", height_m);
  CheckOption(relief_m >= 0 && relief_m < 0.25 * half_width_m,
              "BoxTowerOptions.relief_m",
              "in [0, half_width_m / 4)",
              relief_m);
  CheckOption(num_angles >= 16 && num_heights >= 8,
              "BoxTowerOptions.num_angles/num_heights",
              ">= 16 / >= 8",
              StrCat(num_angles, "/", num_heights));
}

TriangleMesh MakeBoxTower(const BoxTowerOptions& options) {
  options.Check();
  const double h = options.height_m;
  const double w = options.half_width_m;
  const double a = options.relief_m;
  // Tiers: [bottom, top) in relative height, the half width, and the ledge
  // below each tier slopes over the first 6 % of it.
  struct Tier {
    double bottom, top, half_width;
  };
  const Tier tiers[] = {{0.0, 0.42, 1.0}, {0.42, 0.76, 0.74}, {0.76, 1.0, 0.5}};
  auto tier_of = [&](double zr) {
    int k = 0;
    while (k < 2 && zr >= tiers[k].top) ++k;
    return k;
  };
  auto half_width = [&](double zr) {
    const int k = tier_of(zr);
    const double ramp = 0.06;
    if (k > 0 && zr < tiers[k].bottom + ramp) {
      const double s = (zr - tiers[k].bottom) / ramp;
      return w * (tiers[k - 1].half_width +
                  s * (tiers[k].half_width - tiers[k - 1].half_width));
    }
    return w * tiers[k].half_width;
  };
  return MakeRadialSurface(
      options.num_angles, options.num_heights, h, [&](double t, double z) {
        const double zr = z / h;
        const double half = half_width(zr);
        // A square with rounded corners (superellipse of exponent 8).
        const double c = std::abs(std::cos(t)), s = std::abs(std::sin(t));
        const double square =
            half / std::pow(std::pow(c, 8) + std::pow(s, 8), 1.0 / 8);
        // The face of this side: the nearest of the four directions.
        const double side = std::round(t / (M_PI / 2)) * (M_PI / 2);
        const double u = WrapAngle(t - side) * half;  // across the face
        const Tier& tier = tiers[tier_of(zr)];
        const double tier_h = (tier.top - tier.bottom) * h;
        const double v =
            z - (tier.bottom + 0.55 * (tier.top - tier.bottom)) * h;
        const double scale = tier.half_width;
        const double face =
            0.8 * Gaussian2(u, v - 0.22 * tier_h, 0.45 * half, 0.05 * tier_h) +
            1.0 * Gaussian2(u, v, 0.07 * half, 0.16 * tier_h) +
            0.6 * Gaussian2(u, v + 0.25 * tier_h, 0.22 * half, 0.05 * tier_h) +
            0.5 * Gaussian2(
                      std::abs(u) - 0.3 * half, v, 0.1 * half, 0.12 * tier_h);
        return square + a * scale * face;
      });
}

void TorusOptions::Check() const {
  CheckOption(major_radius_m > minor_radius_m && minor_radius_m > 0,
              "TorusOptions.major_radius_m/minor_radius_m",
              "major > minor > 0",
              StrCat(major_radius_m, "/", minor_radius_m));
  CheckOption(relief_m >= 0 && relief_m < 0.5 * minor_radius_m,
              "TorusOptions.relief_m",
              "in [0, minor_radius_m / 2)",
              relief_m);
  CheckOption(num_major >= 8 && num_minor >= 8,
              "TorusOptions.num_major/num_minor",
              ">= 8",
              StrCat(num_major, "/", num_minor));
}

TriangleMesh MakeTorus(const TorusOptions& options) {
  options.Check();
  const double big = options.major_radius_m;
  return MakeGridSurface(options.num_major,
                         options.num_minor,
                         true,
                         [&](int i, int j) -> Eigen::Vector3d {
                           const double u = 2 * M_PI * i / options.num_major;
                           const double v = 2 * M_PI * j / options.num_minor;
                           const double r = options.minor_radius_m +
                                            options.relief_m * std::sin(5 * u) *
                                                std::sin(3 * v);
                           return {(big + r * std::cos(v)) * std::cos(u),
                                   (big + r * std::cos(v)) * std::sin(u),
                                   r * std::sin(v)};
                         });
}

void NoisyCloudOptions::Register(OptionRegistry* r) {
  r->Add("num_points", &num_points, "Points to sample");
  r->Add("sigma_m", &sigma_m, "Mean standard deviation per coordinate, metres");
  r->Add("sigma_spread",
         &sigma_spread,
         "Per-point sigmas spread +- this fraction around sigma_m");
  r->Add("blunder_fraction",
         &blunder_fraction,
         "Share of points displaced along the normal");
  r->Add("blunder_min_m", &blunder_min_m, "Smallest offset");
  r->Add("blunder_max_m", &blunder_max_m, "Largest offset");
  r->Add("with_normals", &with_normals, "1: true normals");
  r->Add("with_sigmas", &with_sigmas, "1: sx, sy, sz");
  r->Add("seed", &seed, "Random seed");
}

void NoisyCloudOptions::Check() const {
  CheckOption(num_points > 0, "num_points", "> 0", num_points);
  CheckOption(sigma_m >= 0, "sigma_m", ">= 0", sigma_m);
  CheckOption(sigma_spread >= 0 && sigma_spread < 1,
              "sigma_spread",
              "in [0, 1)",
              sigma_spread);
  CheckOption(blunder_fraction >= 0 && blunder_fraction <= 1,
              "blunder_fraction",
              "in [0, 1]",
              blunder_fraction);
  CheckOption(blunder_min_m >= 0 && blunder_max_m >= blunder_min_m,
              "blunder_min_m/blunder_max_m",
              "0 <= min <= max",
              StrCat(blunder_min_m, "/", blunder_max_m));
}

namespace {

// Turns `num_blunders` of the candidate points, at random, into blunders:
// candidate k (cloud point candidates[k]) is moved from its place on the
// surface, on_surface[k], along the surface normal there, normals[k], to
// either side, by a distance uniform in [blunder_min_m, blunder_max_m]. A
// displacement that lands near another part of the surface (into the wall
// behind a relief, under a cornice) is no blunder of that size: with
// `distance` (the surface's), it is drawn again (up to 20 times) until the
// point is at least blunder_min_m from the whole surface. Returns the flags
// (0/1) of all the cloud's points.
std::vector<double> DisplaceBlunders(
    const MeshDistance* distance,
    const std::vector<size_t>& candidates,
    const std::vector<Eigen::Vector3d>& on_surface,
    const std::vector<Eigen::Vector3d>& normals,
    size_t num_blunders,
    const NoisyCloudOptions& options,
    std::mt19937_64* rng,
    PointCloud* cloud) {
  std::vector<size_t> order(candidates.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::shuffle(order.begin(), order.end(), *rng);
  std::vector<double> flags(cloud->size(), 0.0);
  std::uniform_real_distribution<double> offset(options.blunder_min_m,
                                                options.blunder_max_m);
  std::bernoulli_distribution side(0.5);
  for (size_t b = 0; b < std::min(num_blunders, order.size()); ++b) {
    const size_t k = order[b], i = candidates[k];
    for (int attempt = 0; attempt < 20; ++attempt) {
      const double d = offset(*rng) * (side(*rng) ? 1.0 : -1.0);
      cloud->positions[i] = on_surface[k] + d * normals[k];
      if (!distance || distance->Closest(cloud->positions[i]).distance >=
                           options.blunder_min_m) {
        break;
      }
    }
    flags[i] = 1.0;
  }
  return flags;
}

size_t NumBlunders(const NoisyCloudOptions& options, size_t cloud_size) {
  return static_cast<size_t>(
      std::llround(options.blunder_fraction * cloud_size));
}

}  // namespace

PointCloud SampleNoisyCloud(const TriangleMesh& surface,
                            const NoisyCloudOptions& options) {
  options.Check();
  const std::vector<SurfaceSample> samples =
      SampleMeshSurface(surface, options.num_points, options.seed);
  if (samples.empty()) ThrowInputError("surface to sample has no area");
  std::mt19937_64 rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> spread(1 - options.sigma_spread,
                                                1 + options.sigma_spread);
  std::normal_distribution<double> normal(0.0, 1.0);

  const size_t n = samples.size();
  PointCloud cloud;
  cloud.positions.resize(n);
  std::vector<Eigen::Vector3d> normals(n);
  std::vector<Eigen::Vector3d> sigmas(n);
  for (size_t i = 0; i < n; ++i) {
    normals[i] = FaceNormal(surface, samples[i].face);
    for (int k = 0; k < 3; ++k) sigmas[i](k) = options.sigma_m * spread(rng);
    Eigen::Vector3d noise;
    for (int k = 0; k < 3; ++k) noise(k) = sigmas[i](k) * normal(rng);
    cloud.positions[i] = samples[i].position + noise;
  }

  const size_t num_blunders = NumBlunders(options, n);
  std::unique_ptr<MeshDistance> distance;
  if (num_blunders > 0 && options.blunder_min_m > 0) {
    distance = std::make_unique<MeshDistance>(surface);
  }
  std::vector<size_t> all(n);
  std::iota(all.begin(), all.end(), size_t{0});
  std::vector<Eigen::Vector3d> on_surface(n);
  for (size_t i = 0; i < n; ++i) on_surface[i] = samples[i].position;
  std::vector<double> flags = DisplaceBlunders(distance.get(),
                                               all,
                                               on_surface,
                                               normals,
                                               num_blunders,
                                               options,
                                               &rng,
                                               &cloud);
  if (options.with_normals) {
    cloud.normals.resize(n);
    for (size_t i = 0; i < n; ++i) cloud.normals[i] = normals[i].cast<float>();
  }
  if (options.with_sigmas) {
    const char* names[] = {"sx", "sy", "sz"};
    for (int k = 0; k < 3; ++k) {
      PointAttribute& attribute =
          cloud.AddAttribute(names[k], PlyScalarType::kFloat);
      for (size_t i = 0; i < n; ++i) attribute.values[i] = sigmas[i](k);
    }
  }
  if (options.with_blunder_flags) {
    cloud.AddAttribute(kBlunderAttribute, PlyScalarType::kUChar).values = flags;
  }
  return cloud;
}

size_t InjectBlunders(const TriangleMesh& surface,
                      const NoisyCloudOptions& options,
                      PointCloud* cloud) {
  options.Check();
  if (cloud->empty()) ThrowInputError("the cloud to add blunders to is empty");
  const MeshDistance distance(surface);
  // The candidates: points on the surface (nearer than half the smallest
  // blunder), each with its closest surface point and that face's normal.
  std::vector<size_t> candidates;
  std::vector<Eigen::Vector3d> on_surface, normals;
  for (size_t i = 0; i < cloud->size(); ++i) {
    const MeshDistance::Hit hit = distance.Closest(cloud->positions[i]);
    if (hit.distance > 0.5 * options.blunder_min_m) continue;
    candidates.push_back(i);
    on_surface.push_back(hit.closest_point);
    normals.push_back(FaceNormal(surface, hit.face));
  }
  if (candidates.empty()) {
    ThrowInputError("no point of the cloud lies on the true surface (within ",
                    0.5 * options.blunder_min_m,
                    " m): is it in the truth's frame?");
  }
  std::mt19937_64 rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  // The share is of the whole cloud.
  const std::vector<double> flags =
      DisplaceBlunders(&distance,
                       candidates,
                       on_surface,
                       normals,
                       NumBlunders(options, cloud->size()),
                       options,
                       &rng,
                       cloud);
  const size_t count = std::count(flags.begin(), flags.end(), 1.0);
  cloud->AddAttribute(kBlunderAttribute, PlyScalarType::kUChar).values = flags;
  return count;
}

}  // namespace bayon
