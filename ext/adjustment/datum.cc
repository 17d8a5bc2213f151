// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/datum.h"

#include "ext/adjustment/triangulation.h"
#include "ext/core/alignment.h"
#include "ext/core/errors.h"
#include "ext/core/upright.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

namespace fs = std::filesystem;

namespace bayon {
namespace {

struct Measured {
  std::vector<int> image_idxs;
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> sigma_px;
  std::optional<Eigen::Vector3d> model_xyz;  // intersection in the model
};

std::optional<Eigen::Vector3d> Intersect(const AdjustmentBlock& block,
                                         const Measured& measured) {
  std::vector<Ray> rays;
  for (size_t k = 0; k < measured.image_idxs.size(); ++k) {
    const BlockImage& image = block.images[measured.image_idxs[k]];
    const Camera& camera = block.cameras[image.camera_idx].camera;
    const std::optional<Ray> ray = RayThroughPixel(
        camera, image.CamFromWorld(), measured.xy[k], &image.frame);
    if (ray) rays.push_back(*ray);
  }
  return IntersectRays(rays, 0.5);
}

// True when the points span less than a line's worth of a plane: the
// second singular value of the centred coordinates is tiny against the
// first.
bool Collinear(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) return true;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= points.size();
  Eigen::MatrixXd centred(points.size(), 3);
  for (size_t i = 0; i < points.size(); ++i) {
    centred.row(i) = (points[i] - mean).transpose();
  }
  const Eigen::Vector3d singular =
      Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  return singular(0) <= 0 || singular(1) < 1e-3 * singular(0);
}

std::string Joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names)
    text += (text.empty() ? "" : ", ") + name;
  return text;
}

class DatumBuilder {
 public:
  DatumBuilder(const ControlData& control,
               const DatumOptions& options,
               AdjustmentBlock* block)
      : control_(control), options_(options), block_(block) {}

  DatumSetup Build() {
    CollectMeasurements();
    CheckEveryPointIsMeasured();
    setup_.type = ResolveType();
    if (setup_.type != DatumType::kFree) {
      for (auto& [name, measured] : measured_) {
        measured.model_xyz = Intersect(*block_, measured);
      }
    }
    switch (setup_.type) {
      case DatumType::kControl:
        SetUpControl();
        break;
      case DatumType::kMinimum:
        SetUpMinimum();
        break;
      default:
        SetUpFree();
        break;
    }
    return std::move(setup_);
  }

 private:
  std::string PointsFile() const { return control_.folder + "/points.txt"; }

  void CollectMeasurements() {
    std::map<std::string, int> image_idxs;
    for (size_t i = 0; i < block_->images.size(); ++i) {
      image_idxs[block_->images[i].name] = static_cast<int>(i);
    }
    std::set<std::string> skipped_images;
    for (const ImageMeasurement& m : control_.measurements) {
      auto it = image_idxs.find(m.image_name);
      if (it == image_idxs.end()) {
        skipped_images.insert(m.image_name);
        continue;
      }
      Measured& measured = measured_[m.point_name];
      measured.image_idxs.push_back(it->second);
      measured.xy.push_back(m.xy);
      measured.sigma_px.push_back(
          m.sigma_px > 0 ? m.sigma_px : options_.measurement_sigma_px);
    }
    if (!skipped_images.empty()) {
      setup_.notes.push_back(StrCat(
          "measurements in images that are not in the model were skipped: ",
          Joined({skipped_images.begin(), skipped_images.end()})));
    }
    for (const ControlPoint& point : control_.points) {
      given_[point.name] = &point;
    }
  }

  void CheckEveryPointIsMeasured() const {
    for (const ControlPoint& point : control_.points) {
      if (measured_.count(point.name) == 0) {
        ThrowInputError(
            PointsFile(),
            ": ",
            point.type == ControlPointType::kCheck ? "check" : "control",
            " point '",
            point.name,
            "' is measured in no image of the model (",
            control_.folder,
            "/observations.txt, nor found by bayon targets)");
      }
    }
  }

  const DistanceObservation* VerticalDistance() const {
    for (const DistanceObservation& d : control_.distances) {
      if (d.vertical) return &d;
    }
    return nullptr;
  }

  std::vector<const ControlPoint*> ControlPoints() const {
    std::vector<const ControlPoint*> points;
    for (const ControlPoint& point : control_.points) {
      if (point.type == ControlPointType::kControl) points.push_back(&point);
    }
    return points;
  }

  DatumType ResolveType() const {
    const size_t num_control = ControlPoints().size();
    switch (options_.datum) {
      case DatumType::kControl:
        if (num_control == 0) {
          ThrowInputError("datum control: no control points (",
                          control_.folder.empty() ? std::string("no control "
                                                                "folder given")
                                                  : PointsFile(),
                          "); give --control_path, or use --datum minimum "
                          "or free");
        }
        return DatumType::kControl;
      case DatumType::kMinimum:
        if (VerticalDistance() == nullptr) {
          ThrowInputError(
              "datum minimum needs a distance on a vertical "
              "levelling bar (a line '... vertical' in ",
              control_.folder.empty() ? std::string("control")
                                      : control_.folder,
              "/distances.txt)");
        }
        return DatumType::kMinimum;
      case DatumType::kFree:
        return DatumType::kFree;
      case DatumType::kAuto:
        if (num_control >= 3) return DatumType::kControl;
        if (VerticalDistance() != nullptr) return DatumType::kMinimum;
        return DatumType::kFree;
    }
    return DatumType::kFree;
  }

  // Adds a measured point to the block with its observations.
  int AddPoint(const std::string& name,
               PointKind kind,
               const Eigen::Vector3d& xyz) {
    BlockPoint point;
    point.name = name;
    point.kind = kind;
    point.xyz = xyz;
    const auto given = given_.find(name);
    if (given != given_.end()) {
      point.given_xyz = given->second->xyz;
      point.given_sigma = given->second->sigma;
    }
    const int point_idx = static_cast<int>(block_->points.size());
    block_->points.push_back(point);
    const Measured& measured = measured_.at(name);
    for (size_t k = 0; k < measured.image_idxs.size(); ++k) {
      BlockObservation observation;
      observation.image_idx = measured.image_idxs[k];
      observation.point_idx = point_idx;
      observation.xy = measured.xy[k];
      observation.sigma_px = measured.sigma_px[k];
      block_->observations.push_back(observation);
      ++setup_.num_measurements;
    }
    point_idxs_[name] = point_idx;
    return point_idx;
  }

  // A point that is not held: its approximation is its intersection, moved
  // into the object system.
  void AddFreePoint(const std::string& name, PointKind kind) {
    const Measured& measured = measured_.at(name);
    if (!measured.model_xyz) {
      ThrowInputError(control_.folder,
                      "/observations.txt: ",
                      PointKindName(kind),
                      " point '",
                      name,
                      "' needs measurements in two or more images with "
                      "intersecting rays (it has ",
                      measured.image_idxs.size(),
                      ")");
    }
    AddPoint(name, kind, setup_.object_from_model * *measured.model_xyz);
  }

  void AddManualTiePoints() {
    for (const auto& [name, measured] : measured_) {
      if (given_.count(name) || point_idxs_.count(name)) continue;
      if (!measured.model_xyz) {
        setup_.notes.push_back(StrCat("manual tie point '",
                                      name,
                                      "' skipped: it needs two or more "
                                      "images with intersecting rays"));
        continue;
      }
      AddFreePoint(name, PointKind::kTie);
      ++setup_.num_manual_tie_points;
    }
  }

  void SetUpControl() {
    std::vector<std::string> names;
    std::vector<Eigen::Vector3d> model, object;
    for (const ControlPoint* point : ControlPoints()) {
      const Measured& measured = measured_.at(point->name);
      if (!measured.model_xyz) continue;
      names.push_back(point->name);
      model.push_back(*measured.model_xyz);
      object.push_back(point->xyz);
    }
    if (names.size() < 3) {
      ThrowInputError(PointsFile(),
                      ": the 7-parameter similarity needs three control "
                      "points measured in two or more images, found ",
                      names.size(),
                      names.empty() ? "" : " (" + Joined(names) + ")");
    }
    const SimilarityFit fit = FitControlSimilarity(
        names, model, object, options_.max_similarity_residual_m, PointsFile());
    setup_.object_from_model = fit.object_from_model;
    setup_.similarity_residuals = fit.residuals;
    setup_.similarity_rms_m = fit.rms_m;
    for (const SimilarityResidual& residual : fit.residuals) {
      if (!residual.inlier) {
        setup_.notes.push_back(
            StrCat("control point '",
                   residual.name,
                   "' disagrees with the others by ",
                   residual.residual.norm(),
                   " m in the similarity: check its coordinates and "
                   "measurements"));
      }
    }
    TransformBlock(setup_.object_from_model, block_);

    for (const ControlPoint& given : control_.points) {
      if (given.type == ControlPointType::kCheck) {
        AddFreePoint(given.name, PointKind::kCheck);
        ++setup_.num_check_points;
        continue;
      }
      const int idx = AddPoint(given.name, PointKind::kControl, given.xyz);
      BlockPoint& point = block_->points[idx];
      for (int k = 0; k < 3; ++k) point.fixed[k] = given.sigma(k) == 0;
      // Coordinates with a standard deviation are observations; a point
      // fixed in some coordinates and weighted in others keeps both.
      point.weighted = !point.AllFixed();
      ++setup_.num_control_points;
    }
    AddManualTiePoints();
    AddDistances();
    int num_fixed = 0;
    for (const BlockPoint& point : block_->points) {
      num_fixed += point.kind == PointKind::kControl && point.AllFixed();
    }
    setup_.vertical = "the control points";
    setup_.description = StrCat(setup_.num_control_points,
                                " control points (",
                                num_fixed,
                                " fixed, ",
                                setup_.num_control_points - num_fixed,
                                " weighted), ",
                                setup_.num_check_points,
                                " check points");
  }

  void AddDistances() {
    int count = 0;
    for (const DistanceObservation& d : control_.distances) {
      const auto a = point_idxs_.find(d.name1);
      const auto b = point_idxs_.find(d.name2);
      if (a == point_idxs_.end() || b == point_idxs_.end() || d.sigma_m <= 0) {
        setup_.notes.push_back(StrCat("distance ",
                                      d.name1,
                                      "-",
                                      d.name2,
                                      " not used as an observation (",
                                      d.sigma_m <= 0
                                          ? "no standard deviation"
                                          : "a point is not measured",
                                      ")"));
        continue;
      }
      BlockDistance distance;
      distance.point_a = a->second;
      distance.point_b = b->second;
      distance.distance_m = d.distance_m;
      distance.sigma_m = d.sigma_m;
      block_->distances.push_back(distance);
      ++count;
    }
    if (count > 0) {
      setup_.description += StrCat(", ", count, " distances");
    }
  }

  const ControlPoint* DatumPoint(const Eigen::Vector3d& origin,
                                 const DistanceObservation& bar) const {
    if (!options_.datum_point.empty()) {
      const auto it = given_.find(options_.datum_point);
      if (it == given_.end()) {
        ThrowInputError("datum_point: '",
                        options_.datum_point,
                        "' is not in ",
                        PointsFile());
      }
      return it->second;
    }
    const ControlPoint* best = nullptr;
    double best_distance = 0;
    for (const ControlPoint* point : ControlPoints()) {
      if (point->name == bar.name1 || point->name == bar.name2) continue;
      if (!measured_.at(point->name).model_xyz) continue;
      const double distance = (point->xyz - origin).head<2>().norm();
      if (distance > best_distance) {
        best = point;
        best_distance = distance;
      }
    }
    if (best == nullptr) {
      ThrowInputError(
          "datum minimum: besides the levelling bar, one more "
          "control point measured in two or more images is "
          "needed for the rotation about the vertical (",
          PointsFile(),
          ")");
    }
    return best;
  }

  const Eigen::Vector3d& ModelPoint(const std::string& name,
                                    const char* role) const {
    const auto it = measured_.find(name);
    if (it == measured_.end() || !it->second.model_xyz) {
      ThrowInputError("datum minimum: the ",
                      role,
                      " '",
                      name,
                      "' must be measured in two or more images (",
                      control_.folder,
                      "/observations.txt)");
    }
    return *it->second.model_xyz;
  }

  void SetUpMinimum() {
    const DistanceObservation& bar = *VerticalDistance();
    const auto given_a = given_.find(bar.name1);
    const Eigen::Vector3d a_object = given_a != given_.end()
                                         ? given_a->second->xyz
                                         : Eigen::Vector3d::Zero();
    const Eigen::Vector3d b_object =
        a_object + Eigen::Vector3d(0, 0, bar.distance_m);
    const ControlPoint& c = *DatumPoint(a_object, bar);
    const Eigen::Vector2d c_offset = (c.xyz - a_object).head<2>();
    if (c_offset.norm() < 1e-6 * std::max(1.0, bar.distance_m)) {
      ThrowInputError("datum minimum: the datum point '",
                      c.name,
                      "' lies on the levelling bar's vertical; it cannot fix "
                      "the rotation about it");
    }
    const Eigen::Vector3d a_model = ModelPoint(bar.name1, "levelling bar end");
    const Eigen::Vector3d b_model = ModelPoint(bar.name2, "levelling bar end");
    const Eigen::Vector3d c_model = ModelPoint(c.name, "datum point");
    const Eigen::Vector3d bar_model = b_model - a_model;
    if (bar_model.norm() <= 0) {
      ThrowInputError(
          "datum minimum: the ends of the levelling bar "
          "coincide in the model");
    }
    // Scale from the bar, the bar onto +Z, then the turn about Z that puts C
    // in its given azimuth from A.
    const double scale = bar.distance_m / bar_model.norm();
    const Eigen::Quaterniond level = Eigen::Quaterniond::FromTwoVectors(
        bar_model.normalized(), Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d c_levelled = level * (c_model - a_model);
    if (c_levelled.head<2>().norm() < 1e-9) {
      ThrowInputError("datum minimum: the datum point '",
                      c.name,
                      "' lies on the levelling bar's line in the model");
    }
    const double turn = std::atan2(c_offset.y(), c_offset.x()) -
                        std::atan2(c_levelled.y(), c_levelled.x());
    const Eigen::Quaterniond rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ())) *
        level;
    setup_.object_from_model = Sim3d(
        scale, rotation.normalized(), a_object - scale * (rotation * a_model));
    TransformBlock(setup_.object_from_model, block_);

    const int a = AddPoint(bar.name1, PointKind::kControl, a_object);
    block_->points[a].fixed = {true, true, true};
    const int b = AddPoint(bar.name2, PointKind::kControl, b_object);
    block_->points[b].fixed = {true, true, true};
    block_->points[b].given_xyz = b_object;
    const int c_idx = AddPoint(
        c.name, PointKind::kControl, setup_.object_from_model * c_model);
    BlockPoint& c_point = block_->points[c_idx];
    // Hold the horizontal coordinate across the direction A-C: it changes
    // most with a turn about the vertical.
    const int held = std::abs(c_offset.x()) >= std::abs(c_offset.y()) ? 1 : 0;
    c_point.fixed[held] = true;
    c_point.xyz(held) = c.xyz(held);
    setup_.num_control_points = 3;
    for (const ControlPoint& given : control_.points) {
      if (point_idxs_.count(given.name)) continue;
      AddFreePoint(given.name, PointKind::kCheck);
      ++setup_.num_check_points;
    }
    AddManualTiePoints();
    setup_.vertical = "the levelling bar";
    setup_.description = StrCat("minimum datum: levelling bar ",
                                bar.name1,
                                "-",
                                bar.name2,
                                " (",
                                bar.distance_m,
                                " m, vertical), ",
                                c.name,
                                " holds ",
                                held == 0 ? "X" : "Y",
                                "; ",
                                setup_.num_check_points,
                                " check points");
  }

  void SetUpFree() {
    if (!control_.points.empty()) {
      setup_.notes.push_back(
          "free network: the control points were not used (choose --datum "
          "control or minimum to use them)");
    }
    if (block_->images.size() < 2) {
      ThrowInputError("a free network needs two or more images");
    }
    // Turned first: the held centre coordinate below is chosen in the
    // frame the solution runs in.
    if (options_.upright) TurnUpright();
    // The first image and one centre coordinate of the image farthest from
    // it: seven parameters, the minimal datum of the solution.
    BlockImage& first = block_->images[0];
    first.rotation_fixed = true;
    first.center_fixed = {true, true, true};
    size_t farthest = 1;
    for (size_t i = 1; i < block_->images.size(); ++i) {
      if ((block_->images[i].center - first.center).norm() >
          (block_->images[farthest].center - first.center).norm()) {
        farthest = i;
      }
    }
    Eigen::Vector3d offset = block_->images[farthest].center - first.center;
    int coordinate = 0;
    offset.cwiseAbs().maxCoeff(&coordinate);
    block_->images[farthest].center_fixed[coordinate] = true;
    block_->free_network = true;
    AddManualTiePoints();
    setup_.description =
        "free network, inner constraints over the tie points (minimum "
        "trace of their covariance)";
    if (!setup_.vertical.empty()) {
      setup_.description +=
          "; z up along " + setup_.vertical + ", origin at the object's centre";
    }
  }

  // z along the photographs' up direction, the origin at the object's
  // centre, the scale kept; the held parameters above stay held at their
  // turned values.
  void TurnUpright() {
    std::vector<Rigid3d> poses;
    for (const BlockImage& image : block_->images) {
      poses.push_back(image.CamFromWorld());
    }
    std::vector<Eigen::Vector3d> points;
    for (const BlockPoint& point : block_->points) points.push_back(point.xyz);
    const std::optional<UprightFrame> frame =
        EstimateUprightFrame(poses, points);
    if (!frame) {
      setup_.notes.push_back(
          "free network: the photographs' up directions cancel; the model "
          "keeps the relative orientation's coordinates (z arbitrary)");
      return;
    }
    setup_.object_from_model = Sim3d(
        1.0, frame->new_from_old.rotation, frame->new_from_old.translation);
    TransformBlock(setup_.object_from_model, block_);
    setup_.vertical = frame->source;
  }

  const ControlData& control_;
  const DatumOptions& options_;
  AdjustmentBlock* block_;
  DatumSetup setup_;
  std::map<std::string, Measured> measured_;
  std::map<std::string, const ControlPoint*> given_;
  std::map<std::string, int> point_idxs_;
};

}  // namespace

const char* DatumTypeName(DatumType type) {
  switch (type) {
    case DatumType::kAuto:
      return "auto";
    case DatumType::kControl:
      return "control";
    case DatumType::kMinimum:
      return "minimum";
    case DatumType::kFree:
      return "free";
  }
  return "?";
}

ControlData ReadControlFolder(const std::string& folder) {
  ControlData control;
  control.folder = folder;
  if (folder.empty()) return control;
  if (!fs::is_directory(folder)) {
    ThrowInputError(folder, ": control folder not found");
  }
  const std::string points = folder + "/points.txt";
  const std::string measurements = folder + "/observations.txt";
  const std::string distances = folder + "/distances.txt";
  if (fs::exists(points)) control.points = ReadControlPoints(points);
  if (fs::exists(measurements)) {
    control.measurements = ReadImageMeasurements(measurements);
  }
  if (fs::exists(distances)) control.distances = ReadDistances(distances);
  // Points without measurements here may be coded targets, measured
  // automatically (TakeControlFromNamedTiePoints); every point's
  // measurements are checked when the datum is set up.
  return control;
}

std::set<size_t> TakeControlFromNamedTiePoints(
    const std::vector<TiePointRecord>& tie_points,
    const std::map<image_t, std::string>& image_names,
    ControlData* control) {
  std::set<std::string> control_names;
  for (const ControlPoint& point : control->points) {
    control_names.insert(point.name);
  }
  std::set<std::pair<std::string, std::string>> measured;  // name, image
  for (const ImageMeasurement& m : control->measurements) {
    measured.insert({m.point_name, m.image_name});
  }
  std::set<size_t> taken;
  for (size_t i = 0; i < tie_points.size(); ++i) {
    const TiePointRecord& tie = tie_points[i];
    if (tie.name.empty() || control_names.count(tie.name) == 0) continue;
    taken.insert(i);
    for (const TieObservation& observation : tie.observations) {
      const auto image = image_names.find(observation.image_id);
      if (image == image_names.end()) continue;
      if (measured.count({tie.name, image->second})) continue;
      ImageMeasurement m;
      m.point_name = tie.name;
      m.image_name = image->second;
      m.xy = observation.xy;
      m.sigma_px = MeasurementSigma(observation.covariance);
      control->measurements.push_back(m);
    }
  }
  return taken;
}

void DatumOptions::Register(OptionRegistry* r) {
  r->AddChoice(
      "datum",
      &datum,
      ChoicesOf<DatumType>([](DatumType t) { return DatumTypeName(t); },
                           {DatumType::kAuto,
                            DatumType::kControl,
                            DatumType::kMinimum,
                            DatumType::kFree}),
      "auto (control with 3+ control points, else minimum with a "
      "vertical bar, else free), control, minimum or free");
  r->Add("datum_point",
         &datum_point,
         "Minimum datum: the point that fixes the rotation about the vertical "
         "(default: the control point farthest from the bar)");
}

void DatumOptions::Check() const {
  CheckOption(measurement_sigma_px > 0,
              "measurement_sigma_px",
              "> 0",
              measurement_sigma_px);
  CheckOption(max_similarity_residual_m >= 0,
              "max_similarity_residual_m",
              ">= 0",
              max_similarity_residual_m);
}

DatumSetup SetUpDatum(const ControlData& control,
                      const DatumOptions& options,
                      AdjustmentBlock* block) {
  options.Check();
  return DatumBuilder(control, options, block).Build();
}

SimilarityFit FitControlSimilarity(const std::vector<std::string>& names,
                                   const std::vector<Eigen::Vector3d>& model,
                                   const std::vector<Eigen::Vector3d>& object,
                                   double max_residual_m,
                                   const std::string& what) {
  if (names.size() < 3) {
    ThrowInputError(what,
                    ": the 7-parameter similarity needs three control "
                    "points, found ",
                    names.size());
  }
  if (Collinear(object) || Collinear(model)) {
    ThrowInputError(what,
                    ": the control points ",
                    Joined(names),
                    " are collinear; the similarity needs three points "
                    "that span a plane");
  }
  RobustSim3dOptions options;
  options.max_residual = max_residual_m;
  // With three or four points a minimal sample is (nearly) the whole set;
  // least squares over all of them is all there is.
  RobustSim3dReport report;
  if (names.size() >= 5) report = EstimateSim3dRobust(model, object, options);
  SimilarityFit fit;
  if (report.success && report.num_inliers >= 3) {
    fit.object_from_model = report.dst_from_src;
  } else {
    const std::optional<Sim3d> sim = EstimateSim3d(model, object);
    if (!sim) {
      ThrowInputError(what, ": the control points do not define a similarity");
    }
    fit.object_from_model = *sim;
    report.inlier_mask.assign(names.size(), 1);
  }
  double sum = 0;
  for (size_t i = 0; i < names.size(); ++i) {
    SimilarityResidual residual;
    residual.name = names[i];
    residual.residual = object[i] - fit.object_from_model * model[i];
    residual.inlier = report.inlier_mask[i] != 0;
    sum += residual.residual.squaredNorm();
    fit.residuals.push_back(residual);
  }
  fit.rms_m = std::sqrt(sum / names.size());
  return fit;
}

void TransformBlock(const Sim3d& new_from_old, AdjustmentBlock* block) {
  for (BlockPoint& point : block->points) point.xyz = new_from_old * point.xyz;
  for (BlockImage& image : block->images) {
    image.SetCamFromWorld(new_from_old.TransformPose(image.CamFromWorld()));
  }
}

}  // namespace bayon
