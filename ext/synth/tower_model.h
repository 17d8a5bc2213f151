// SPDX-License-Identifier: BSD-3-Clause
//
// A procedural tower in the spirit of the face towers of the Bayon (Angkor,
// late 12th century), the object of Gruen, Zhang and Visnovcova: a square
// body in tiers that step back as they rise, each tier carrying four large
// faces carved in relief that look north, east, south and west, cornices
// with ornament bands between the tiers, a lotus-bud finial, all standing on
// a stepped platform. The stone has detail at every scale for area-based
// matching: relief faces (metres), carved ornament and wall panels
// (decimetres), masonry blocks and joints (centimetres), weathering, lichen,
// pits and grain (millimetres).
//
// Frame: world coordinates in metres, z up, the tower axis on the z axis,
// the ground at z = 0; x points east, y north. The walls face +x (E), +y
// (N), -x (W), -y (S).
//
// What is geometry and what is texture: the mesh carries the relief down to
// about twice `mesh_spacing_m` (faces, ornament, block offsets, coarse
// weathering), so shadows of the relief move with the sun; finer detail
// (joints, pits, grain, lichen) lives in the texture atlas, whose
// albedo also darkens crevices (baked cavity shading). The true surface for
// evaluation is the mesh; the texture is part of the truth for texture
// evaluation.
//
// Coded targets (num_coded_targets): plates showing a coded marker, drawn
// unlit like the control plates, named as bayon targets names them.
//
// Signalised control: square black target plates with a white disc, 3 mm in
// front of flat (undisplaced) spots of walls and platform, and two on a
// vertical levelling bar (a striped staff standing on the ground), whose
// disc centres are the control points. Target plates are drawn unlit in
// renders (retro-reflective targets under a flash) so that cast shadows
// never bias their centres.
#pragma once

#include "ext/core/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace bayon {

struct TowerOptions {
  // Width of the lowest tier's walls (the faces stand out further) and
  // height of the tower from the platform top to the tip of the finial.
  double width_m = 4.0;
  double height_m = 6.0;
  // How far the carved faces stand out of the walls.
  double relief_depth_m = 0.25;
  // Tiers with four faces each.
  int num_tiers = 3;
  // The stepped platform the tower stands on.
  double platform_width_m = 7.0;
  double platform_height_m = 0.7;
  // Spacing of the mesh vertices on the tower's lowest tier (finer on the
  // narrower tiers above); the geometric detail scale.
  double mesh_spacing_m = 0.02;
  // Texture resolution on the stone, and on the ground.
  double texel_size_m = 0.004;
  double ground_texel_size_m = 0.025;
  // Side of the square ground around the platform.
  double ground_size_m = 40.0;
  // Levelling bar: distance between its two targets.
  double bar_target_distance_m = 1.5;
  // Coded targets (ext/targets/coded_targets.h, the default dictionary) on
  // flat spots of the walls and the platform, codes 0, 1, ..., spread
  // evenly over the spots that take one; the black square's side.
  int num_coded_targets = 0;
  double coded_target_side_m = 0.2;
  uint32_t seed = 1;
  void Check() const;
};

struct ControlTarget {
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();   // disc centre, world
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // facing away
  double disc_radius_m = 0;
  double plate_half_size_m = 0;
  bool on_bar = false;  // a levelling bar target
  // A coded target's code (its plate shows the code's marker with a white
  // margin of one cell, centre = the marker's centre); -1: a disc target.
  int code = -1;
  double marker_half_size_m = 0;  // coded: half the black square's side
};

struct TowerModel {
  // Everything that is drawn: faces [0, num_object_faces) are the object
  // (tower, platform, levelling bar: closed surfaces, the true surface),
  // then the target plates, then the ground.
  TriangleMesh mesh;
  size_t num_object_faces = 0;
  size_t num_target_faces = 0;
  // The texture atlas for mesh.face_texcoords: linear reflectance (albedo)
  // scaled to 0..255, BGR.
  cv::Mat texture;
  // Control points first, then the bar's two, then the coded targets.
  std::vector<ControlTarget> targets;
  // Names of the levelling bar's lower and upper target.
  std::string bar_bottom_name;
  std::string bar_top_name;
  // Bounding box of the object (tower, platform, bar), and of the tower
  // alone.
  Eigen::AlignedBox3d object_bounds;
  Eigen::AlignedBox3d tower_bounds;

  // Unlit flags for MeshRenderer::SetUnlitFaces: the target plates.
  std::vector<bool> UnlitFaces() const;
  // The object's faces alone with their vertices (welded, closed), normals
  // and texture coordinates: the true surface.
  TriangleMesh Surface() const;
};

// Builds the tower, deterministic for options.seed.
TowerModel BuildTower(const TowerOptions& options);

}  // namespace bayon
