// SPDX-License-Identifier: BSD-3-Clause
//
// Synthetic dense clouds with ground truth, for the editing and meshing
// stages: known surfaces (as fine triangle meshes) and point clouds sampled
// from any mesh the way a dense matcher delivers them: area-uniform points,
// Gaussian noise with a per-point standard deviation stored as the sx, sy, sz
// attributes (what `bayon dense` writes), optional true normals, and a share
// of blunders (gross errors) displaced along the surface normal, flagged in a
// `blunder` attribute so that evaluations can count them after editing.
// Object coordinates in metres, z up.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

#include <cstdint>
#include <string>

namespace bayon {

// A tube around the z axis whose radius varies with angle and height,
// r(theta, z) = radius_m + relief: smooth waves plus Gaussian bosses, the
// kind of relief a carved tower mantle has. Open at top and bottom.
struct ReliefCylinderOptions {
  double radius_m = 2.0;
  double height_m = 4.0;
  double relief_m = 0.08;  // amplitude of the relief
  // Grid of the true mesh (angle x height); fine enough that its facets are
  // far below the noise.
  int num_angles = 720;
  int num_heights = 400;
  void Check() const;
};
TriangleMesh MakeReliefCylinder(const ReliefCylinderOptions& options);

// A tiered tower with a square plan (rounded corners), three tiers that step
// in along sloping ledges, and on each tier four relief "faces" (bosses for
// brow, nose and cheeks) pointing in the four directions: the shape of a
// Bayon tower, kept star-shaped about the z axis. Open at top and bottom.
struct BoxTowerOptions {
  double half_width_m = 2.0;  // of the lowest tier
  double height_m = 6.0;
  double relief_m = 0.12;
  int num_angles = 960;
  int num_heights = 720;
  void Check() const;
};
TriangleMesh MakeBoxTower(const BoxTowerOptions& options);

// A torus around the z axis with a wavy surface: closed and not
// star-shaped, for the 3D meshing methods.
struct TorusOptions {
  double major_radius_m = 1.5;
  double minor_radius_m = 0.6;
  double relief_m = 0.03;
  int num_major = 480;
  int num_minor = 192;
  void Check() const;
};
TriangleMesh MakeTorus(const TorusOptions& options);

struct NoisyCloudOptions {
  int num_points = 100000;
  // Standard deviation of each coordinate: every point draws its own sx, sy,
  // sz uniformly in [sigma_m * (1 - sigma_spread), sigma_m * (1 +
  // sigma_spread)], then its noise from N(0, diag(sx^2, sy^2, sz^2)).
  double sigma_m = 0.002;
  double sigma_spread = 0.5;
  // Share of points turned into blunders: moved along the true normal, to
  // either side, by a distance uniform in [blunder_min_m, blunder_max_m]
  // (drawn again where that lands closer than blunder_min_m to another part
  // of the surface).
  double blunder_fraction = 0.02;
  double blunder_min_m = 0.01;
  double blunder_max_m = 0.20;
  bool with_normals = false;       // the true surface normals
  bool with_sigmas = true;         // the sx, sy, sz attributes
  bool with_blunder_flags = true;  // the `blunder` attribute (0/1)
  uint64_t seed = 1;
  void Register(OptionRegistry* registry);
  void Check() const;
};

// Samples `surface` (its faces counter-clockwise seen from outside).
PointCloud SampleNoisyCloud(const TriangleMesh& surface,
                            const NoisyCloudOptions& options);

// Blunders injected into an existing cloud (a dense matcher's) whose true
// surface is known: of the points on the surface (nearer to it than half
// blunder_min_m), round(blunder_fraction * cloud size) at random are moved
// along the surface normal as SampleNoisyCloud moves its blunders; the
// `blunder` attribute (replaced if there) flags them. Other attributes are
// kept. Returns the number of blunders; throws InputError on an empty
// cloud.
size_t InjectBlunders(const TriangleMesh& surface,
                      const NoisyCloudOptions& options,
                      PointCloud* cloud);

// The named attribute that marks blunders.
inline constexpr const char* kBlunderAttribute = "blunder";

}  // namespace bayon
