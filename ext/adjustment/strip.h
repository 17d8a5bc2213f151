// SPDX-License-Identifier: BSD-3-Clause
//
// Approximations for the bundle adjustment without any other tool: the
// Bayon paper's strip adjustment (section 3.2.4). The relative orientations
// of successive image pairs ("models", from two_view_geometries: qvec/tvec,
// or the essential matrix decomposed with the cheirality test) are chained
// into a strip in model coordinates:
//
//  0. the view graph: a pair whose relative rotation disagrees with the
//     loops it lies on (a chance orientation between photographs that do
//     not overlap) is left out, with the reason (view_graph.h);
//  1. model connection: the first model fixes the strip system (its left
//     camera, base length 1); each next model is attached to the previous
//     one at their common image, its scale transferred through the tie
//     points the two models share (median ratio of their distances from the
//     common projection centre). Models follow the images' names, or, when
//     the names are not the sequence, the view graph (StripOrder);
//  2. a closed ring (the last image related to the first, as around the
//     Bayon tower) gives the closure error, which is distributed along the
//     strip: rotations in proportion to the image's place in the sequence,
//     positions in proportion to the path length;
//     An image that no model attaches (its relative orientations missing
//     or without common points) is placed by spatial resection from the tie
//     points already intersected (resection.h), as long as it sees enough
//     of them;
//  3. the tie points (tracks of the verified matches over all pairs, and
//     the multi-image tie points of `bayon tiepoints` where the database
//     has them, weighted by their least-squares covariance) are
//     intersected from all their rays, and the whole strip is adjusted in
//     model coordinates (bundle solution with the interior orientation held,
//     robust first, then observations above a residual limit removed);
//  4. with control, the 7-parameter similarity from the model to the object
//     system is fitted robustly to the control points (or computed from a
//     vertical levelling bar and one more point, the minimum datum;
//     datum.h), and its residuals are reported.
//
// The result is a COLMAP model whose 2D points are the database keypoints,
// so that `bayon adjust` and COLMAP's tools take it as it is; with tie
// points, each image's tie observations follow its keypoints (in point
// order; alone with tie_points kAlsm, in the order of tiepoints' COLMAP
// export).
#pragma once

#include "ext/adjustment/adjustment_input.h"
#include "ext/adjustment/datum.h"
#include "ext/adjustment/view_graph.h"
#include "ext/core/scene.h"

#include <string>
#include <vector>

namespace bayon {

enum class RingClosure { kAuto, kClosed, kOpen };
// The order in which models are connected: the images' names (a strip or
// ring photographed in sequence), or the view graph (each step the image
// sharing the most tie points with the strip); kAuto takes the names when
// every image is related to its predecessor.
enum class StripOrder { kAuto, kName, kGraph };

struct StripOptions {
  // kAuto: closed when the last image has a relative orientation with the
  // first.
  RingClosure ring = RingClosure::kAuto;
  StripOrder order = StripOrder::kAuto;
  // A model whose relative orientation is missing is bridged by a model
  // with an earlier image up to this many places back in the sequence.
  int max_gap = 2;
  // Tie points two consecutive models must share for the scale transfer.
  int min_common_points = 3;
  // Rays meeting at less than this angle do not fix a point.
  double min_intersection_angle_deg = 1.0;
  // The strip adjustment: observations with a residual above this are
  // removed after the robust solution.
  double max_reprojection_error_px = 4.0;
  bool adjust = true;
  // Precision of a keypoint (weights of the strip adjustment), pixels.
  double image_sigma_px = 1.0;
  // Which tie observations (adjustment_input.h; kAuto: both where the
  // database has bayon tie points, else the matches' tracks) and the floor
  // of their least-squares standard deviations.
  TiePointSource tie_points = TiePointSource::kAuto;
  double min_tie_sigma_px = 0.02;
  // Spatial resection of images no model attaches: at least this many
  // intersected tie points within resection_max_error_px.
  bool resection = true;
  int min_resection_points = 8;
  double resection_max_error_px = 2.0;
  // Datum of the object system: kAuto is control with three or more control
  // points, the minimum datum with a vertical bar, otherwise an error when
  // control is given (kFree keeps model coordinates).
  DatumOptions datum;
  // Pairs whose relative rotation disagrees with the loops it lies on
  // (view_graph.h) are left out before anything is chained.
  ViewGraphOptions view_graph;
  int num_threads = -1;
  // Every field but min_intersection_angle_deg and the datum's upright,
  // under `bayon strip`'s flags.
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct StripModel {
  std::string image1;
  std::string image2;
  bool connected = false;
  std::string reason;  // why not
  int num_matches = 0;
  int num_points = 0;         // points intersected in the model
  int num_common_points = 0;  // shared with the strip (scale transfer)
  double scale = 0;           // model base length in strip units
  double scale_spread = 0;    // robust relative spread of the ratios
};

struct StripResult {
  Scene model;  // COLMAP cameras, all keypoints as 2D points
  std::vector<StripModel> models;
  // Images placed by spatial resection: name, inliers, points, RMS (px).
  struct ResectedImage {
    std::string name;
    int num_inliers = 0;
    int num_points = 0;
    double rms_px = 0;
  };
  std::vector<ResectedImage> resected_images;
  std::vector<std::string> unoriented_images;
  // Pairs left out for their loops: "A - B: why".
  std::vector<std::string> dropped_pairs;
  int num_alsm_tie_points = 0;  // bayon tie points among the tracks
  std::string order;            // "name" or "graph"
  int num_tracks = 0;
  bool closed_ring = false;
  // The ring's closure error before distribution: rotation, and position as
  // a fraction of the strip's path length.
  double closure_rotation_deg = 0;
  double closure_position_relative = 0;
  double closure_scale = 1;
  // Strip adjustment.
  double sigma0_px = 0;
  int num_observations = 0;
  int num_observations_removed = 0;
  // The object system (control) or model coordinates (no control).
  bool has_control = false;
  DatumSetup datum;
  double time_s = 0;
};

// Throws InputError for a database without images or verified pairs,
// cameras without calibration (COLMAP's default focal length and no
// bayon_calibration), or control that cannot define the similarity (fewer
// than three control points, collinear ones, a point measured in no image).
// Throws RunFailure when not even the first model can be formed.
StripResult RunStrip(const std::string& database_path,
                     const std::string& control_path,
                     const StripOptions& options);

// The report written beside the model (strip.json).
std::string StripReportJson(const StripResult& result);

}  // namespace bayon
