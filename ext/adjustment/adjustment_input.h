// SPDX-License-Identifier: BSD-3-Clause
//
// What `bayon adjust` adjusts, gathered from a workspace: the input model
// (a COLMAP sparse model: bayon strip's, or stock `colmap mapper`'s hosted in
// the same database), whose tracks are the tie observations, with the image
// coordinates taken from the database's keypoints; the cameras'
// calibrations; the images' interior orientations; and the control.
//
// Cameras: to estimate the ten additional parameters the block works with
// the BROWN_BEYER camera. Its source, in order: calibration.json beside the
// input model (a previous adjustment), the database's bayon_calibration, or
// the model's COLMAP camera converted to BROWN_BEYER by a fit over the
// frame (ext/core/camera_conversion.h; the fit residual is reported). With
// `camera_model colmap` the model's COLMAP cameras are adjusted as they are
// (as colmap bundle_adjuster does).
#pragma once

#include "ext/adjustment/adjustment_block.h"
#include "ext/adjustment/datum.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/scene.h"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace bayon {

enum class CameraModelChoice { kBrownBeyer, kColmap };

// The tie observations of the block: the input model's tracks (its 2D
// points, which must be the database's keypoints; weighted with
// image_sigma_px), the multi-image tie points of `bayon tiepoints`
// (bayon_tie_points: least-squares matched, each observation weighted by its
// covariance) intersected from the model's orientations, or both (the
// tracks hold the block together where the tie points are sparse). kAuto is
// kBoth where the database has tie points, else kModel.
enum class TiePointSource { kAuto, kModel, kAlsm, kBoth };
// "auto", "model", "alsm" or "both".
std::string TiePointSourceName(TiePointSource source);
// Each source with its name, for the option that chooses one.
std::vector<std::pair<std::string, TiePointSource>> TiePointSourceChoices();

struct AdjustmentInputOptions {
  CameraModelChoice camera_model = CameraModelChoice::kBrownBeyer;
  // A priori standard deviation of an image coordinate of a tie point,
  // pixels: the reference sigma0 of the weights.
  double image_sigma_px = 1.0;
  TiePointSource tie_points = TiePointSource::kAuto;
  // Least-squares matching covariances are optimistic where the texture is
  // very strong (a standard deviation of a few thousandths of a pixel says
  // more about the patch than about the point); their eigenvalues are
  // raised to this standard deviation, pixels.
  double min_tie_sigma_px = 0.02;
  DatumOptions datum;
  // Every field, the datum's among them, under `bayon adjust`'s flags.
  void Register(OptionRegistry* registry);
  void Check() const;
};

struct CameraSource {
  camera_t camera_id = kInvalidCameraId;
  std::string source;            // where the adjusted camera came from
  std::string input_model;       // the model's camera model name
  double conversion_rms_px = 0;  // fit residual of a conversion, if any
};

struct AdjustmentInput {
  // The input model, its 2D points replaced by the keypoints; tie
  // observations are appended per image in point_id order (kAlsm: they are
  // the only 2D points, in the order of the keypoints of tiepoints' COLMAP
  // export, and 3D point ids are the tie point ids).
  Scene scene;
  AdjustmentBlock block;
  DatumSetup datum;
  std::vector<CameraSource> cameras;
  std::vector<std::string> notes;
};

// Reads and checks everything before any adjustment. Throws InputError
// naming the file and record for a model that does not fit the database
// (an image missing, 2D points that are not the keypoints), cameras without
// a usable calibration, or control that cannot define the datum.
// `control_path` may be empty (no control: free network unless the datum
// asks for control).
AdjustmentInput LoadAdjustmentInput(const std::string& database_path,
                                    const std::string& input_path,
                                    const std::string& control_path,
                                    const AdjustmentInputOptions& options);

// The tie points `source` asks for: none for kModel, else every tie point
// of the database; kAlsm and kBoth throw InputError where there are none.
std::vector<TiePointRecord> ReadTiePointsFor(Database* database,
                                             TiePointSource source);

// A least-squares covariance (pixels^2) with its eigenvalues raised to
// min_sigma^2 (min_tie_sigma_px).
Eigen::Matrix2d FlooredCovariance(const Eigen::Matrix2d& covariance,
                                  double min_sigma);

// Checks that a camera has a usable calibration (finite parameters, a
// positive focal length); throws InputError naming `what` otherwise.
void CheckCameraCalibration(const Camera& camera, const std::string& what);

}  // namespace bayon
