// SPDX-License-Identifier: BSD-3-Clause
//
// Control and measurement files in a workspace's control/ folder: plain text,
// one record per line, fields separated by white space, '#' starts a comment.
// bayon synth writes them as ground truth; bayon strip/adjust read them.
//
// control/points.txt          NAME X Y Z [SX SY SZ [TYPE]]
//     Object coordinates in metres. SX SY SZ are standard deviations in
//     metres (0 0 0 or omitted: a fixed point). TYPE is `control` (used in
//     the datum; the default) or `check` (only evaluated against the result).
// control/observations.txt    NAME IMAGE_NAME X Y [SIGMA]
//     Image measurements in COLMAP pixels (centre of the upper-left pixel at
//     0.5, 0.5) of control points, or manual tie point measurements for a
//     model automatic matching cannot handle. SIGMA in pixels (omitted: the
//     adjustment's default image precision).
// control/distances.txt       NAME_A NAME_B DISTANCE [SIGMA [vertical]]
//     A measured distance in metres between two points (with its standard
//     deviation); `vertical` marks a levelling bar, whose direction defines
//     the object's vertical axis (the paper's minimum datum).
// Names may not contain white space; image names are relative to the image
// folder as in the database.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

enum class ControlPointType { kControl, kCheck };

struct ControlPoint {
  std::string name;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();  // 0 = fixed
  ControlPointType type = ControlPointType::kControl;
  bool IsFixed() const { return sigma.isZero(); }
};

struct ImageMeasurement {
  std::string point_name;
  std::string image_name;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // pixels
  double sigma_px = 0;                           // 0: the default precision
};

struct DistanceObservation {
  std::string name1;
  std::string name2;
  double distance_m = 0;
  double sigma_m = 0;
  bool vertical = false;
};

// The SIGMA of an image measurement measured with a covariance (pixels^2):
// its larger axis, so that the stated precision is never better than the
// covariance's in any direction.
double MeasurementSigma(const Eigen::Matrix2d& covariance);

// Readers throw InputError "path:line: what is wrong" for malformed lines,
// non-finite numbers, negative standard deviations and duplicate records.
std::vector<ControlPoint> ReadControlPoints(const std::string& path);
std::vector<ImageMeasurement> ReadImageMeasurements(const std::string& path);
std::vector<DistanceObservation> ReadDistances(const std::string& path);

// Writers (atomic), with a header comment explaining the columns.
void WriteControlPoints(const std::string& path,
                        const std::vector<ControlPoint>& points);
void WriteImageMeasurements(const std::string& path,
                            const std::vector<ImageMeasurement>& measurements);
void WriteDistances(const std::string& path,
                    const std::vector<DistanceObservation>& distances);

}  // namespace bayon
