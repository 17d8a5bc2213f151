// SPDX-License-Identifier: BSD-3-Clause
//
// Fusion of the masters' depth maps (patch_match.h) into one cloud. A pixel
// becomes a point when it is not at an edge of its depth map (see
// edge_margin_px), its plane was matched well (cost at most max_cost)
// and the depth maps of at least min_consistent_views other masters agree
// with it: the point projects into them onto a pixel whose depth is the
// point's within max_depth_error_px footprints of that depth map's pixel
// at that depth (depth / focal length, times 1 + tan of the surface's slant
// to the ray: the same agreement at any image size and on a ledge seen at
// a grazing angle) and whose normal is within
// max_normal_error_deg of its own. The pixel and those that agree and are
// not yet part of a point become one point, the mean of their object
// points, so that each surface element gives one point however many
// masters saw it (masters in the order given, pixels in row order: the
// result does not depend on the threads).
#pragma once

#include "ext/dense/patch_match.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace bayon {

struct FusionOptions {
  int min_consistent_views = 2;
  double max_depth_error_px = 2.0;
  double max_normal_error_deg = 30;
  double max_cost = 0.6;
  // Pixels within this many pixels (a square) of an area without depth are
  // neither fused nor count as agreeing. PatchMatch's window reaches
  // window_radius pixels past its centre: where it straddles an object's
  // edge against an untextured background (or sky, or a hole the matching
  // left), the texture of the object decides, and background pixels next to
  // the edge take the object's depth ("edge fattening"), which meshes turn
  // into a rim around the object. Coarse to fine (PatchMatchOptions::
  // num_levels), the half-size level's window reaches twice as far, and its
  // planes start the working size: 8 pixels covers the default window of
  // radius 4 at half the size (5, the working size's reach alone, left the
  // temple's silhouette IoU at 0.840 mean, 0.762 worst; 8: 0.852, 0.778; the
  // rendered tower 74.1 -> 73.1 % complete, RMS 1.03 -> 1.00 GSD). Holes
  // narrower than two margins (a few untextured or poorly matched pixels
  // inside a surface) are closed first and do not count as edges. 0: off.
  int edge_margin_px = 8;
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

// What became of a depth map's pixel in the fusion.
enum class FusionVerdict : uint8_t {
  kNone = 0,      // no depth (no texture, at the border)
  kPoorMatch,     // cost above max_cost
  kInconsistent,  // too few other depth maps agree
  kPoint,         // became a point (this master's)
  kMerged,        // part of a point of another master
  kDepthEdge,     // within edge_margin_px of a pixel without depth
};

struct FusedPoint {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // object system, unit
  int master = -1;                                   // index into the maps
  Eigen::Vector2d master_xy;  // working pixels of the master
  std::vector<int> views;     // the other maps that agreed
  float cost = 0;             // the master pixel's matching cost
};

// `views[i]` is the pinhole view of `maps[i]`. `verdicts`, if not null,
// gets one FusionVerdict per pixel of every map.
std::vector<FusedPoint> FuseDepthMaps(
    const std::vector<const PinholeView*>& views,
    const std::vector<const DepthMap*>& maps,
    const FusionOptions& options,
    std::vector<std::vector<FusionVerdict>>* verdicts);

}  // namespace bayon
