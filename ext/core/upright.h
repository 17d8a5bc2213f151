// SPDX-License-Identifier: BSD-3-Clause
//
// The vertical of a block that nothing measured gives one (a free network:
// no control, no levelling bar). Photographers hold the camera level:
// turned about the vertical, tilted up or down, and rolled only by quarter
// turns (portrait photographs). So in every image one of the axes -y, x,
// y, -x points up but for the tilt, and the other image axis lies
// (nearly) horizontal, whatever the tilt.
//
//  1. Up is the direction g that the best-aligned of each image's four
//     candidates agree on most (the largest sum of their cosines with g):
//     from every candidate as a start, each image takes its candidate
//     nearest g, and g their mean, until nothing changes. Of g and -g, the
//     one most images see as -y (upright landscape) is up; where as many
//     see either (portrait photographs turned both ways), the one pointing
//     from the object's centre towards the stations (photographs all round
//     an object look down onto it).
//  2. Refined by the horizontal axes: where they span a plane (a ring, a
//     block: photographs turned about the vertical), g is the unit vector
//     most nearly perpendicular to them all, the eigenvector of the
//     smallest eigenvalue of sum h_i h_i'. Unlike the mean of the up axes,
//     this is not tilted by photographs that all look down onto an object
//     or up along a facade: the idea of COLMAP's model_orientation_aligner
//     (image orientation), made to survive portrait photographs.
//  Where the horizontal axes are all alike (photographs facing one way, a
//  strip along a facade), step 1's mean stays: it carries the photographs'
//  mean tilt. Nadir photographs (an aerial block) break the convention:
//  their up is the viewing direction reversed, which no image axis shows;
//  such blocks take their vertical from control.
#pragma once

#include "ext/core/rigid3.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

struct UprightFrame {
  // New (z up, origin at the object's centre) from old coordinates: a
  // rotation and a translation, the scale kept.
  Rigid3d new_from_old;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // in old coordinates
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  // What gave the vertical, for reports: the images' horizontal axes (2.)
  // or their mean up axis (1.).
  std::string source;
};

// cam_from_world of two or more photographs, and the object points (the
// centre is their coordinate-wise median; the camera centres' where there
// are none). std::nullopt where no vertical can be told (fewer than two
// images, or their up directions cancel).
std::optional<UprightFrame> EstimateUprightFrame(
    const std::vector<Rigid3d>& cam_from_world,
    const std::vector<Eigen::Vector3d>& points);

}  // namespace bayon
