// SPDX-License-Identifier: BSD-3-Clause
//
// The datum of a block (which seven degrees of freedom of a similarity fix
// the object coordinate system) and the control that defines it, read from
// a workspace's control/ folder (formats in ext/colmap/control_io.h):
//
//  control   control points with their standard deviations: fixed (sigma 0)
//            or weighted observations of their coordinates; needs three or
//            more control points that are not collinear. Check points are
//            adjusted as new points and compared with their given
//            coordinates only.
//  minimum   the Bayon paper's minimum datum (section 3.2): a distance
//            measured on a vertical levelling bar (distances.txt, flag
//            `vertical`; NAME_A is the lower end) gives the scale and the
//            vertical axis (object Z up): A is held at its coordinates from
//            points.txt (or 0 0 0), B at A + (0, 0, distance). One more
//            point C (a control point of points.txt, `datum_point` or the
//            one farthest from A horizontally) gives the rotation about the
//            vertical: one of its horizontal coordinates (the one across the
//            direction A-C, the paper's "third depth control point") is held
//            at its given value. All other points of points.txt are check
//            points.
//  free      a free network: seven parameters held during the solution
//            (the first image's pose and one centre coordinate of the image
//            farthest from it), the result and its precision transformed to
//            inner constraints over the tie points (adjustment.h). Control
//            files are not used. With `upright` (the default) the block is
//            first turned so that z is the photographs' up direction and
//            moved so that the origin is at the object's centre, its scale
//            kept (ext/core/upright.h): render, the viewer and the cylinder
//            mesher, which take z as up, then show the object standing.
//  auto      control with three or more control points, else minimum with a
//            vertical distance, else free.
//
// Before the adjustment the block is brought into the object system: every
// point of the control files is intersected from its image measurements in
// the model's system, and the 7-parameter similarity from the model to the
// object system is fitted robustly (least median of squares, then least
// squares over the inliers; ext/core/alignment.h) to the control points
// (control) or computed from the bar and C (minimum).
#pragma once

#include "ext/adjustment/adjustment_block.h"
#include "ext/colmap/control_io.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/option_registry.h"
#include "ext/core/sim3.h"

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace bayon {

enum class DatumType { kAuto, kControl, kMinimum, kFree };
const char* DatumTypeName(DatumType type);

// The contents of a control/ folder; files that do not exist are empty.
struct ControlData {
  std::string folder;  // for messages
  std::vector<ControlPoint> points;
  std::vector<ImageMeasurement> measurements;
  std::vector<DistanceObservation> distances;
  bool empty() const {
    return points.empty() && measurements.empty() && distances.empty();
  }
};
// Throws InputError when the folder does not exist or a file is malformed.
ControlData ReadControlFolder(const std::string& folder);

// A named tie point of `bayon tiepoints` (a coded target of `bayon
// targets`, a manual point) whose name has coordinates in the control is
// that control or check point: its observations join the control's
// measurements (SIGMA the covariance's larger axis), in the images where
// observations.txt has none of it. Returns which tie points (indices) they
// were: the caller keeps them out of the tie points, so that no point
// enters the block twice.
std::set<size_t> TakeControlFromNamedTiePoints(
    const std::vector<TiePointRecord>& tie_points,
    const std::map<image_t, std::string>& image_names,
    ControlData* control);

struct DatumOptions {
  DatumType datum = DatumType::kAuto;
  // Minimum datum: the point that fixes the rotation about the vertical.
  std::string datum_point;
  // Precision of image measurements that give none, pixels.
  double measurement_sigma_px = 1.0;
  // Control points whose residual in the similarity exceeds this (metres;
  // 0: 2.5 robust standard deviations) are reported as suspect.
  double max_similarity_residual_m = 0.0;
  // Free network: z up along the photographs' up direction, the origin at
  // the object's centre (0: the relative orientation's coordinates).
  bool upright = true;
  // datum and datum_point (upright is the adjustment's own).
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct SimilarityResidual {
  std::string name;
  Eigen::Vector3d residual = Eigen::Vector3d::Zero();  // object - fitted
  bool inlier = true;
};

struct DatumSetup {
  DatumType type = DatumType::kFree;
  std::string description;
  Sim3d object_from_model;  // applied to the block's approximations
  // What gave the vertical: the control, the levelling bar, or for an
  // upright free network the photographs (empty: none, z is arbitrary).
  std::string vertical;
  std::vector<SimilarityResidual> similarity_residuals;
  double similarity_rms_m = 0;
  int num_control_points = 0;
  int num_check_points = 0;
  int num_manual_tie_points = 0;
  int num_measurements = 0;
  std::vector<std::string> notes;  // skipped measurements, suspect points
};

// Adds the measured points of `control` to the block, moves the block into
// the object system and holds the parameters of the datum. Throws InputError
// when the datum cannot be defined: no control where the datum needs it,
// fewer than three control points for the similarity, a point of
// points.txt measured in no image of the block, collinear control points,
// a levelling bar or datum point that is not measured.
DatumSetup SetUpDatum(const ControlData& control,
                      const DatumOptions& options,
                      AdjustmentBlock* block);

// The robust 7-parameter similarity object_from_model between points
// intersected in the model and their given coordinates (three or more, not
// collinear; InputError otherwise, naming `what`).
struct SimilarityFit {
  Sim3d object_from_model;
  std::vector<SimilarityResidual> residuals;
  double rms_m = 0;
};
SimilarityFit FitControlSimilarity(const std::vector<std::string>& names,
                                   const std::vector<Eigen::Vector3d>& model,
                                   const std::vector<Eigen::Vector3d>& object,
                                   double max_residual_m,
                                   const std::string& what);

// Applies a similarity to every point and pose of the block.
void TransformBlock(const Sim3d& new_from_old, AdjustmentBlock* block);

}  // namespace bayon
