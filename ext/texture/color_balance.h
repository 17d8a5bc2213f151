// SPDX-License-Identifier: BSD-3-Clause
//
// True colours for a texture drawn from many photographs: the photographs'
// differences in exposure and white balance are removed, the object's
// colours are kept.
//
// 1. Exposure balance. Each photograph j and channel c gets a gain and an
//    offset, I' = a_jc I + b_jc, solved jointly over all overlaps: every
//    face seen by photographs j and k should have the same mean colour in
//    both after the correction,
//        min sum_f sum_{j<k seeing f} rho(a_j m_jf + b_j - a_k m_kf - b_k),
//    with rho Huber's loss (iteratively reweighted; the scale from the
//    median absolute residual), so that occlusions the mesh misses,
//    highlights and misregistered detail do not pull the solution, plus
//    Brown and Lowe's prior that keeps each gain near 1 and each offset
//    near 0 (without it a group of photographs can agree by all turning
//    flat: gain near 0, offset the mean colour). The
//    correction is relative: in each group of photographs linked by shared
//    faces the mean gain is held at 1 and the mean offset at 0, so the
//    texture keeps the photographs' average exposure and white balance. A
//    sample clipped in any channel does not count (the linear model does not
//    hold there).
// 2. Seam levelling (Waechter, Moehrle, Goesele, "Let there be color!",
//    ECCV 2014, global seam levelling): what the balance leaves at the
//    borders between charts (shading that depends on the view, vignetting)
//    is levelled by an additive colour per mesh vertex and chart,
//    interpolated over each face: the two sides of every chart border
//    should agree, neighbouring vertices of one chart should change alike
//    (weight `smoothness`), and the adjustment is otherwise small. One
//    sparse least-squares system for all charts, solved once for the three
//    channels.
#pragma once

#include "ext/core/point_cloud.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <array>
#include <functional>
#include <vector>

namespace bayon {

// A photograph's correction, per channel in its channel order (BGR);
// colour values in 8-bit grey levels.
struct GainOffset {
  Eigen::Vector3f gain = Eigen::Vector3f::Ones();
  Eigen::Vector3f offset = Eigen::Vector3f::Zero();
};

// The mean colour of one face in one photograph.
struct FaceColor {
  int image = -1;
  Eigen::Vector3f color;
};

struct ColorBalanceOptions {
  int num_iterations = 5;  // of reweighting
  // Huber's threshold in robust standard deviations of the residuals.
  double huber_k = 1.345;
  // A channel at or above this value (8-bit) is clipped.
  float saturated = 250.0f;
  // Faces used at most (evenly spread); enough for a few hundred unknowns.
  int max_faces = 100000;
  // The prior of Brown and Lowe's gain compensation (IJCV 2007: 10 grey
  // levels and 0.1): the colours' noise, and how far a gain and an offset
  // (grey levels) are expected to stray from 1 and 0.
  double sigma_noise = 10;
  double sigma_gain = 1.0;
  double sigma_offset = 100;
  void Check() const;
};

struct ColorBalanceReport {
  int num_faces = 0;   // faces seen by two or more photographs
  int num_pairs = 0;   // pairs of a face's observations compared
  int num_groups = 0;  // groups of photographs linked by shared faces
  // Robust standard deviation of the pairwise differences, grey levels,
  // before and after (mean over channels).
  double sigma_before = 0;
  double sigma_after = 0;
};

// `faces`: for each face, its mean colour in the photographs that see it.
// Photographs linked by shared faces are balanced as a group, each group
// with mean gain 1 and mean offset 0; a photograph that overlaps no other
// keeps gain 1 and offset 0. Throws InputError for a photograph index
// outside [0, num_images).
std::vector<GainOffset> BalanceExposures(
    const std::vector<std::vector<FaceColor>>& faces,
    int num_images,
    const ColorBalanceOptions& options,
    ColorBalanceReport* report = nullptr);

// Applies a correction to an 8-bit BGR image.
cv::Mat ApplyGainOffset(const cv::Mat& bgr, const GainOffset& correction);

// An edge with exactly two faces (manifold, not on a boundary).
struct TwoFaceEdge {
  int a, b;  // its vertices
  int f, g;  // its faces
};

struct SeamLevelingOptions {
  // Weight of the difference across each edge inside a chart against that
  // of a chart border edge (its samples together weigh 1); Waechter et
  // al. use 0.1.
  double smoothness = 0.1;
  // Weight pulling each adjustment to 0, so that the colours of a mesh
  // part without chart borders are kept.
  double regularization = 1e-4;
  // Samples along each chart border edge.
  int samples_per_edge = 4;
  void Check() const;
};

// The colour of `face` at barycentric coordinates `b` as the texture would
// draw it before levelling; false where no photograph gives one.
using FaceColorAt = std::function<bool(
    int face, const Eigen::Vector3d& b, Eigen::Vector3f* color)>;

struct SeamLevelingReport {
  int num_seam_edges = 0;  // chart-border edges with samples on both sides
  int num_unknowns = 0;    // vertex-and-chart pairs
  // The conjugate gradients: iterations and relative residual reached.
  int solver_iterations = 0;
  double solver_error = 0;
  // Mean absolute difference across the chart borders' samples, grey
  // levels, before and after the levelling.
  double difference_before = 0;
  double difference_after = 0;
};

// The adjustment of every face corner (BGR grey levels, added to the
// colour interpolated barycentrically). `chart`: each face's chart, -1 for
// faces in none (left unchanged); `edges`: the mesh's two-face edges.
std::vector<std::array<Eigen::Vector3f, 3>> LevelSeams(
    const TriangleMesh& mesh,
    const std::vector<int>& chart,
    const std::vector<TwoFaceEdge>& edges,
    const FaceColorAt& color_at,
    const SeamLevelingOptions& options,
    SeamLevelingReport* report = nullptr);

}  // namespace bayon
