// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment_input.h"

#include "ext/adjustment/triangulation.h"
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/statistics.h"

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace bayon {
namespace {

// The database row of a model image (by name).
DatabaseImage DatabaseRowOf(const std::string& input_path,
                            Database* database,
                            const Image& image) {
  std::optional<DatabaseImage> row = database->ReadImageWithName(image.name);
  if (!row) {
    ThrowInputError(input_path,
                    ": image '",
                    image.name,
                    "' is not in the database ",
                    database->path(),
                    " (the model must come from this database)");
  }
  return *row;
}

// Replaces each image's 2D points by the database's keypoints (same rows:
// a COLMAP model's 2D points are its database's keypoints in order). A model
// of bayon strip or adjust with tie points has each image's tie
// observations after its keypoints, or (tie points alone) instead of them:
// those 2D points are dropped with the track elements on them (the tie
// points are read again from the database).
void TakeKeypointsFromDatabase(const std::string& input_path,
                               const std::map<image_t, size_t>& tie_counts,
                               Database* database,
                               Scene* scene) {
  // Per image: the model's 2D points below this index are keypoints.
  std::map<image_t, size_t> keypoint_limit;
  bool dropped = false;
  for (auto& [image_id, image] : scene->images) {
    const DatabaseImage row = DatabaseRowOf(input_path, database, image);
    const FeatureKeypoints keypoints = database->ReadKeypoints(row.image_id);
    const size_t num_keypoints = static_cast<size_t>(keypoints.rows());
    auto ties = tie_counts.find(row.image_id);
    const size_t num_ties = ties == tie_counts.end() ? 0 : ties->second;
    const size_t num_points = image.points2D.size();
    if (num_points == num_keypoints) {
      keypoint_limit[image_id] = num_keypoints;
    } else if (num_ties > 0 && num_points == num_keypoints + num_ties) {
      keypoint_limit[image_id] = num_keypoints;
    } else if (num_ties > 0 && num_points == num_ties) {
      keypoint_limit[image_id] = 0;
    } else {
      ThrowInputError(input_path,
                      ": image '",
                      image.name,
                      "' has ",
                      num_points,
                      " 2D points, but the database has ",
                      keypoints.rows(),
                      " keypoints",
                      num_ties > 0
                          ? StrCat(" and ", num_ties, " tie observations")
                          : std::string(),
                      " for it (the model must come from this database)");
    }
    dropped |= keypoint_limit[image_id] < num_points;
    image.points2D.resize(num_keypoints);
    for (size_t k = 0; k < num_keypoints; ++k) {
      image.points2D[k].xy = KeypointXY(keypoints, static_cast<int>(k));
    }
  }
  if (!dropped) return;
  OrderedMap<point3D_t, Point3D> kept;
  for (auto& [point3D_id, point] : scene->points3D) {
    std::vector<TrackElement>& track = point.track;
    track.erase(std::remove_if(track.begin(),
                               track.end(),
                               [&](const TrackElement& element) {
                                 return element.point2D_idx >=
                                        keypoint_limit.at(element.image_id);
                               }),
                track.end());
    if (track.size() >= 2) kept.Set(point3D_id, std::move(point));
  }
  scene->points3D = std::move(kept);
  for (auto& [image_id, image] : scene->images) {
    for (Point2D& point2D : image.points2D) {
      point2D.point3D_id = kInvalidPoint3DId;
    }
  }
  for (const auto& [point3D_id, point] : scene->points3D) {
    for (const TrackElement& element : point.track) {
      scene->images.at(element.image_id)
          .points2D.at(element.point2D_idx)
          .point3D_id = point3D_id;
    }
  }
}

using ObservationKey = std::pair<image_t, point2D_t>;

// Adds bayon's tie points to the model, or replaces the model's tracks by
// them (`replace`): the tie observations are appended to each image's 2D
// points in point order, and every tie point observed in two or more of the
// model's images is intersected from the model's orientations
// (approximations; the adjustment refines them) as 3D point id = tie point
// id (+ the largest model id when added). Returns the covariance of every
// tie observation.
std::map<ObservationKey, Eigen::Matrix2d> TakeTiePointsFromDatabase(
    const std::string& input_path,
    const std::vector<TiePointRecord>& tie_points,
    const std::set<size_t>& control_points,
    bool replace,
    Database* database,
    double min_sigma_px,
    Scene* scene) {
  std::map<image_t, image_t> model_image_of;  // database id -> model id
  for (auto& [image_id, image] : scene->images) {
    const DatabaseImage row = DatabaseRowOf(input_path, database, image);
    model_image_of[row.image_id] = image_id;
    if (replace) image.points2D.clear();
  }
  point3D_t id_offset = 0;
  if (replace) {
    scene->points3D.clear();
  } else {
    for (const auto& [id, point] : scene->points3D) {
      id_offset = std::max(id_offset, id);
    }
  }
  std::map<ObservationKey, Eigen::Matrix2d> covariances;
  for (size_t t = 0; t < tie_points.size(); ++t) {
    const TiePointRecord& tie = tie_points[t];
    Point3D point;
    std::vector<Ray> rays;
    for (const TieObservation& observation : tie.observations) {
      auto it = model_image_of.find(observation.image_id);
      if (it == model_image_of.end()) continue;  // not in the model
      Image& image = scene->images.at(it->second);
      const point2D_t idx = static_cast<point2D_t>(image.points2D.size());
      Point2D point2D;
      point2D.xy = observation.xy;
      image.points2D.push_back(point2D);
      covariances[{it->second, idx}] =
          FlooredCovariance(observation.covariance, min_sigma_px);
      point.track.push_back({it->second, idx});
      const std::optional<Ray> ray =
          RayThroughPixel(scene->cameras.at(image.camera_id),
                          image.cam_from_world,
                          observation.xy);
      if (ray) rays.push_back(*ray);
    }
    // A control point's observations keep their 2D points (the keypoints'
    // order) but make no tie point: the datum adds the point.
    if (point.track.size() < 2 || control_points.count(t)) continue;
    const std::optional<Eigen::Vector3d> xyz = IntersectRays(rays);
    if (!xyz) continue;
    point.xyz = *xyz;
    point.color = Eigen::Matrix<uint8_t, 3, 1>(128, 128, 128);
    const point3D_t id = id_offset + static_cast<point3D_t>(tie.point_id);
    for (const TrackElement& element : point.track) {
      scene->images.at(element.image_id)
          .points2D.at(element.point2D_idx)
          .point3D_id = id;
    }
    scene->points3D.Set(id, std::move(point));
  }
  if (covariances.empty() || scene->points3D.empty()) {
    ThrowInputError(database->path(),
                    ": no tie point of bayon_tie_points is seen in two or "
                    "more images of the model ",
                    input_path,
                    " (run bayon tiepoints, or --tie_points model)");
  }
  return covariances;
}

// Whether a model's camera still has the focal length COLMAP guessed at
// import (1.2 x the long side): the database's camera has no prior focal
// length (no EXIF, none given, none estimated by bayon relative) and the
// model's is the same, so no mapper has refined it either.
bool FocalLengthIsTheGuess(const Camera& camera, Database* database) {
  if (!database->ExistsCamera(camera.camera_id)) return false;
  const Camera imported = database->ReadCamera(camera.camera_id);
  const double focal = camera.MeanFocalLengthPx();
  return !imported.has_prior_focal_length &&
         std::abs(imported.MeanFocalLengthPx() - focal) <= 1e-9 * focal;
}

}  // namespace

std::vector<TiePointRecord> ReadTiePointsFor(Database* database,
                                             TiePointSource source) {
  if (source == TiePointSource::kModel) return {};
  std::vector<TiePointRecord> points = ReadTiePoints(database);
  if (points.empty() &&
      (source == TiePointSource::kAlsm || source == TiePointSource::kBoth)) {
    ThrowInputError(database->path(),
                    ": tie_points ",
                    source == TiePointSource::kAlsm ? "alsm" : "both",
                    ", but the database has no tie points (bayon_tie_points; "
                    "run bayon tiepoints first, or tie_points model)");
  }
  return points;
}

std::string TiePointSourceName(TiePointSource source) {
  switch (source) {
    case TiePointSource::kAuto:
      return "auto";
    case TiePointSource::kModel:
      return "model";
    case TiePointSource::kAlsm:
      return "alsm";
    case TiePointSource::kBoth:
      break;
  }
  return "both";
}

Eigen::Matrix2d FlooredCovariance(const Eigen::Matrix2d& covariance,
                                  double min_sigma) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
  const Eigen::Vector2d values =
      eigen.eigenvalues().cwiseMax(min_sigma * min_sigma);
  return eigen.eigenvectors() * values.asDiagonal() *
         eigen.eigenvectors().transpose();
}

std::vector<std::pair<std::string, TiePointSource>> TiePointSourceChoices() {
  return ChoicesOf<TiePointSource>(TiePointSourceName,
                                   {TiePointSource::kAuto,
                                    TiePointSource::kAlsm,
                                    TiePointSource::kModel,
                                    TiePointSource::kBoth});
}

void AdjustmentInputOptions::Register(OptionRegistry* r) {
  datum.Register(r);
  r->Add("upright",
         &datum.upright,
         "Free network: 1 = z along the photographs' up direction, origin at "
         "the object's centre (0 = the relative orientation's coordinates)");
  r->AddChoice("camera_model",
               &camera_model,
               {{"brown_beyer", CameraModelChoice::kBrownBeyer},
                {"colmap", CameraModelChoice::kColmap}},
               "brown_beyer (the ten additional parameters) or colmap (the "
               "model's own COLMAP cameras)");
  r->Add("image_sigma_px",
         &image_sigma_px,
         "A priori standard deviation of an image coordinate, px");
  r->AddChoice("tie_points",
               &tie_points,
               TiePointSourceChoices(),
               "Tie observations: model (the model's tracks), alsm (bayon "
               "tiepoints' least-squares tie points), both; auto: both where "
               "the database has tie points, else model");
  r->Add("min_tie_sigma_px",
         &min_tie_sigma_px,
         "Tie points: floor of the least-squares standard deviations, px");
}

void AdjustmentInputOptions::Check() const {
  CheckOption(image_sigma_px > 0, "image_sigma_px", "> 0", image_sigma_px);
  CheckOption(
      min_tie_sigma_px > 0, "min_tie_sigma_px", "> 0", min_tie_sigma_px);
  datum.Check();
}

void CheckCameraCalibration(const Camera& camera, const std::string& what) {
  try {
    camera.Check();
  } catch (const InputError& error) {
    ThrowInputError(what, ": ", error.what());
  }
  const double focal = camera.MeanFocalLengthPx();
  if (!(focal > 0) || !std::isfinite(focal)) {
    ThrowInputError(what,
                    ": camera ",
                    camera.camera_id,
                    " (",
                    camera.ModelName(),
                    ") has no calibration: focal length ",
                    focal,
                    " px");
  }
}

AdjustmentInput LoadAdjustmentInput(const std::string& database_path,
                                    const std::string& input_path,
                                    const std::string& control_path,
                                    const AdjustmentInputOptions& options) {
  options.Check();
  CheckFileExists(database_path, "database_path");
  CheckDirectoryExists(input_path, "input_path");
  AdjustmentInput input;
  input.scene = ReadModel(input_path);
  Scene& scene = input.scene;
  if (scene.images.size() < 2) {
    ThrowInputError(input_path,
                    ": a model with ",
                    scene.images.size(),
                    " images cannot be adjusted (two or more needed)");
  }
  if (scene.points3D.empty()) {
    ThrowInputError(input_path, ": the model has no 3D points (tie points)");
  }
  for (const auto& [camera_id, camera] : scene.cameras) {
    CheckCameraCalibration(camera, input_path);
  }
  // Read everything needed first; the control is read before any work.
  ControlData control = ReadControlFolder(control_path);

  Database database(database_path, Database::Mode::kReadOnly);
  const std::vector<TiePointRecord> tie_points =
      ReadTiePointsFor(&database, options.tie_points);
  std::map<image_t, std::string> image_names;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    image_names[image.image_id] = image.name;
  }
  const std::set<size_t> control_points =
      TakeControlFromNamedTiePoints(tie_points, image_names, &control);
  if (!control_points.empty()) {
    input.notes.push_back(StrCat(control_points.size(),
                                 " control or check points measured as named "
                                 "tie points (coded targets)"));
  }
  const bool use_tie_points = !tie_points.empty();
  const bool replace = options.tie_points == TiePointSource::kAlsm;
  if (!replace) {
    std::map<image_t, size_t> tie_counts;
    for (const TiePointRecord& point : tie_points) {
      for (const TieObservation& observation : point.observations) {
        ++tie_counts[observation.image_id];
      }
    }
    TakeKeypointsFromDatabase(input_path, tie_counts, &database, &scene);
  }
  std::map<ObservationKey, Eigen::Matrix2d> covariances;
  if (use_tie_points) {
    covariances = TakeTiePointsFromDatabase(input_path,
                                            tie_points,
                                            control_points,
                                            replace,
                                            &database,
                                            options.min_tie_sigma_px,
                                            &scene);
  }
  const std::map<camera_t, Camera> beside =
      ReadCalibrationsBesideModel(input_path);
  std::map<camera_t, CalibrationRecord> calibrations;
  if (BayonTableExists(&database, kCalibrationTable.name)) {
    calibrations = ReadAllCalibrations(&database);
  }

  // The cameras the block adjusts.
  Scene block_scene = scene;
  std::set<camera_t> unknown_focal;
  for (auto& [camera_id, camera] : block_scene.cameras) {
    CameraSource source;
    source.camera_id = camera_id;
    source.input_model = camera.ModelName();
    // The input model's camera, not a calibration: its focal length may
    // still be the guess.
    bool from_model = true;
    if (options.camera_model == CameraModelChoice::kColmap) {
      source.source = "the input model";
    } else if (auto it = beside.find(camera_id);
               it != beside.end() &&
               it->second.model_id == CameraModelId::kBrownBeyer) {
      camera = it->second;
      source.source = input_path + "/calibration.json";
      from_model = false;
    } else if (auto record = calibrations.find(camera_id);
               record != calibrations.end() &&
               record->second.camera.model_id == CameraModelId::kBrownBeyer) {
      camera = record->second.camera;
      camera.camera_id = camera_id;
      source.source = "the database (bayon_calibration)";
      from_model = false;
    } else {
      const CameraConversion conversion =
          ConvertCamera(camera, CameraModelId::kBrownBeyer);
      source.source = StrCat(source.input_model,
                             " of the input model, converted to BROWN_BEYER");
      source.conversion_rms_px = conversion.rms_residual_px;
      camera = conversion.camera;
    }
    if (camera.width != scene.cameras.at(camera_id).width ||
        camera.height != scene.cameras.at(camera_id).height) {
      ThrowInputError(source.source,
                      ": camera ",
                      camera_id,
                      " is ",
                      camera.width,
                      "x",
                      camera.height,
                      " but the model's camera is ",
                      scene.cameras.at(camera_id).width,
                      "x",
                      scene.cameras.at(camera_id).height);
    }
    CheckCameraCalibration(camera, source.source);
    input.cameras.push_back(source);
    const Camera& model_camera = scene.cameras.at(camera_id);
    if (from_model && FocalLengthIsTheGuess(model_camera, &database)) {
      unknown_focal.insert(camera_id);
      input.notes.push_back(
          StrCat("camera ",
                 camera_id,
                 ": the focal length is COLMAP's guess (",
                 model_camera.MeanFocalLengthPx(),
                 " px); the self-calibration estimates it first"));
      LOG(WARNING) << input.notes.back();
    }
  }
  // Interior orientations of scanned film frames. Digital images use the
  // default frame of the camera just chosen, not their bayon_interior row,
  // which holds the default frame of the database's camera (pitch 1 for a
  // COLMAP camera, where the conversion above assumes 36 mm / width).
  SetInteriorFrames(&database, &block_scene);

  input.block = BlockFromScene(block_scene, options.image_sigma_px);
  for (BlockObservation& observation : input.block.observations) {
    auto it =
        covariances.find({input.block.images[observation.image_idx].image_id,
                          observation.point2D_idx});
    if (it != covariances.end()) observation.SetCovariance(it->second);
  }
  if (use_tie_points) {
    // The reference precision: the median tie observation's, so that
    // sigma0 a posteriori in pixels reads as the precision of a typical
    // observation and the variance factor as how far the matching
    // covariances are off.
    std::vector<double> sigmas;
    for (const BlockObservation& observation : input.block.observations) {
      if (!observation.covariance.isZero()) {
        sigmas.push_back(observation.sigma_px);
      }
    }
    input.block.sigma0_px = Median(sigmas);
    input.notes.push_back(
        StrCat(tie_points.size(),
               " tie points from bayon_tie_points",
               replace ? "" : " beside the model's tracks",
               ", weighted by their least-squares covariance; a priori "
               "sigma0 = the median tie observation's ",
               input.block.sigma0_px,
               " px"));
    LOG(INFO) << input.notes.back();
  }
  for (size_t c = 0; c < input.block.cameras.size(); ++c) {
    const camera_t camera_id = input.block.cameras[c].camera.camera_id;
    input.block.cameras[c].source_model = scene.cameras.at(camera_id).model_id;
    input.block.cameras[c].focal_unknown = unknown_focal.count(camera_id) > 0;
  }
  if (input.block.points.empty()) {
    ThrowInputError(input_path, ": no 3D point is seen in two or more images");
  }
  input.datum = SetUpDatum(control, options.datum, &input.block);
  for (const std::string& note : input.datum.notes) {
    LOG(WARNING) << note;
    input.notes.push_back(note);
  }
  return input;
}

}  // namespace bayon
