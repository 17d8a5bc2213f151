// SPDX-License-Identifier: BSD-3-Clause
//
// "Bundle Adjustment in the Large" problems (Agarwal, Snavely, Seitz,
// Szeliski, ECCV 2010), the reference set for bundle adjustment speed, as a
// COLMAP workspace, so that `bayon adjust` and `colmap bundle_adjuster` run
// the same problem.
//
// BAL text format: a header `num_cameras num_points num_observations`, then
// one line `camera_index point_index x y` per observation, then 9 values per
// camera (Rodrigues rotation r, translation t, focal length f, radial k1,
// k2) and 3 per point, one value per line or several; white space separated.
// BAL's camera: P = R X + t, p = -P / P_z, p' = f (1 + k1 |p|^2 + k2 |p|^4) p,
// with the observation p' relative to the image centre, x right, y up; its
// camera looks down its -z axis.
//
// In COLMAP's convention (x right, y down, z forward) that is
// cam_from_world = diag(1, -1, -1) (R, t) and a RADIAL camera
// (f, cx, cy, k1, k2) on normalised coordinates (u, v) = (p_x, -p_y), whose
// pixels are (x + cx, cy - y). BAL gives no image size: the principal point
// is put at the centre of the smallest square that holds every observation.
#pragma once

#include "ext/core/scene.h"

#include <string>

namespace bayon {

// Throws InputError naming the file and the line for a malformed problem.
Scene ReadBalProblem(const std::string& path);

}  // namespace bayon
