// SPDX-License-Identifier: BSD-3-Clause
//
// The block of a bundle adjustment: cameras (interior orientation, shared by
// images), images (exterior orientation: rotation and projection centre),
// object points (tie, control and check points), image observations, and
// geodetic observations (distances). Everything the solver changes lives
// here, so that the Ceres problem and the statistics (precision.h) read the
// same numbers through the same residual terms.
//
// Frames and units: object coordinates in metres (right-handed); images have
// X_cam = R (X - X0) with R = cam_from_world (COLMAP's camera axes: x right,
// y down, z forward); observations in COLMAP pixels; standard deviations of
// image observations in pixels, of object coordinates and distances in
// metres. Weights are relative to the reference image precision
// `sigma0_px` (the a priori sigma0): p = (sigma0_px / sigma)^2.
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/scene.h"
#include "ext/core/types.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ceres/cost_function.h>

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace bayon {

struct BlockCamera {
  // BROWN_BEYER or a COLMAP model; params are adjusted in place.
  Camera camera;
  // Per parameter: estimated (true) or held at its value.
  std::vector<bool> free;
  // COLMAP model the camera came from (to convert back on output).
  CameraModelId source_model = CameraModelId::kInvalid;
  // The focal length is COLMAP's guess (1.2 x the long side: no EXIF, no
  // calibration, and the photographs did not fix it in bayon relative): the
  // self-calibration estimates it first, alone, and keeps it (adjustment.h).
  bool focal_unknown = false;
};

struct BlockImage {
  image_t image_id = kInvalidImageId;
  std::string name;
  int camera_idx = -1;
  // cam_from_world rotation as (w, x, y, z), the Ceres quaternion order.
  Eigen::Vector4d rotation = Eigen::Vector4d(1, 0, 0, 0);
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  ImageFrame frame;  // interior orientation (BROWN_BEYER cameras)
  bool rotation_fixed = false;
  std::array<bool, 3> center_fixed{{false, false, false}};

  Rigid3d CamFromWorld() const;
  void SetCamFromWorld(const Rigid3d& cam_from_world);
};

enum class PointKind { kTie, kControl, kCheck };
const char* PointKindName(PointKind kind);

struct BlockPoint {
  point3D_t point3D_id = kInvalidPoint3DId;  // id in the input/output model
  std::string name;                          // control and check points
  PointKind kind = PointKind::kTie;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  // Control and check points: the given coordinates and their standard
  // deviations (metres). A control point with `weighted` enters as an
  // observation of its coordinates; coordinates in `fixed` are held.
  Eigen::Vector3d given_xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d given_sigma = Eigen::Vector3d::Zero();
  bool weighted = false;
  std::array<bool, 3> fixed{{false, false, false}};
  Eigen::Matrix<uint8_t, 3, 1> color = Eigen::Matrix<uint8_t, 3, 1>::Zero();
  // Tie points whose observations were all rejected leave the block.
  bool active = true;

  bool AllFixed() const { return fixed[0] && fixed[1] && fixed[2]; }
};

struct BlockObservation {
  int image_idx = -1;
  int point_idx = -1;
  // Keypoint row in the image (tie points); kInvalidPoint2DIdx for manual
  // measurements of control and check points.
  point2D_t point2D_idx = kInvalidPoint2DIdx;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // pixels
  // Precision: a 2 x 2 covariance (pixels^2; least-squares matching gives
  // one, elongated along weak texture), or where that is zero the same
  // sigma_px in x and y. With a covariance, sigma_px = sqrt(trace / 2).
  double sigma_px = 1.0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  // Sets the covariance and sigma_px with it; ScaleVariance multiplies both.
  void SetCovariance(const Eigen::Matrix2d& c) {
    covariance = c;
    sigma_px = std::sqrt(c.trace() / 2);
  }
  void ScaleVariance(double factor) {
    covariance *= factor;
    sigma_px *= std::sqrt(factor);
  }
  // Rejected observations (data snooping) stay listed but inactive.
  bool active = true;
};

struct BlockDistance {
  int point_a = -1;
  int point_b = -1;
  double distance_m = 0;
  double sigma_m = 0;
};

struct AdjustmentBlock {
  std::vector<BlockCamera> cameras;
  std::vector<BlockImage> images;
  std::vector<BlockPoint> points;
  std::vector<BlockObservation> observations;
  std::vector<BlockDistance> distances;
  // The reference (a priori) precision of an image coordinate, pixels.
  double sigma0_px = 1.0;
  // A free network: seven parameters are held for the solution, and the
  // result goes to the datum of inner constraints (datum.h, adjustment.h).
  bool free_network = false;

  // Number of active observations per point.
  std::vector<int> CountPointObservations() const;
  // Deactivates tie points with fewer than two active observations (and
  // their observations); returns how many were deactivated.
  int DeactivateWeakPoints();
  // Per point: the largest angle between two of its active rays, degrees
  // (0 for points with fewer than two).
  std::vector<double> IntersectionAnglesDeg() const;
};

// The tie points whose coordinates define a free network's datum (inner
// constraints, adjustment.h and precision.h): the active tie points whose
// rays intersect at kMinDatumIntersectionAngleDeg or more. A point seen from
// nearly one direction can slide along it (its standard deviation in depth
// is the lateral one over the sine of the angle); among the datum points its
// variance would enter the centroid and, through it, every covariance of the
// network. The limit is COLMAP's default for keeping a triangulated point
// (Mapper.filter_min_tri_angle).
constexpr double kMinDatumIntersectionAngleDeg = 1.5;
std::vector<bool> InnerConstraintPoints(const AdjustmentBlock& block);

// ---------------------------------------------------------------------------
// Residual terms: the cost functions of the block and the parameter blocks
// they read. The solver adds them to a ceres::Problem; the statistics
// evaluate their Jacobians directly.

enum class TermType { kReprojection, kPointPrior, kDistance };

struct ResidualTerm {
  TermType type = TermType::kReprojection;
  int index = -1;  // observation, point or distance index
  std::shared_ptr<ceres::CostFunction> cost;
  std::vector<double*> parameters;
  int num_residuals() const { return cost->num_residuals(); }
};

// W with W^T W = P, the weight matrix of an observation relative to the
// reference sigma0_px: the weighted residual is W (projected - observed).
Eigen::Matrix2d ObservationSqrtInformation(const BlockObservation& observation,
                                           double sigma0_px);

// The reprojection cost for a camera model (BROWN_BEYER or any COLMAP model).
// Throws InputError for a model without one.
ceres::CostFunction* CreateReprojectionCost(
    CameraModelId model,
    const Eigen::Vector2d& observed,
    const Eigen::Matrix2d& sqrt_information,
    const ImageFrame& frame);

// One term per active observation of an active point, per weighted control
// point and per distance, in that order. The block must outlive the terms
// (they point into it) and must not be resized meanwhile.
std::vector<ResidualTerm> BuildResidualTerms(AdjustmentBlock* block);

// Image residuals (projected - observed, pixels) of every observation of the
// block; NaN for inactive ones and for points that cannot be projected.
std::vector<Eigen::Vector2d> ImageResiduals(AdjustmentBlock* block);

// ---------------------------------------------------------------------------
// Conversion from and to scenes.

// The block of a scene's tracks: every image, every camera (as it is) and
// every 3D point with a track of at least two images, with the 2D points as
// observations of precision sigma_px.
AdjustmentBlock BlockFromScene(const Scene& scene, double sigma_px);

// Writes the adjusted cameras, poses and tie points back into `scene` (the
// scene the block was made from, or a copy). Control and check points are
// not added: their measurements are not keypoints, and the model's 2D points
// must stay the database's keypoints for COLMAP's tools; they are reported in
// adjustment.json. Rejected observations are unlinked from their points;
// points left with fewer than two observations are removed.
void UpdateSceneFromBlock(const AdjustmentBlock& block, Scene* scene);

}  // namespace bayon
