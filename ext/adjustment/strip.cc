// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/strip.h"

#include "ext/adjustment/adjustment_block.h"
#include "ext/adjustment/adjustment_input.h"
#include "ext/adjustment/bundle_solver.h"
#include "ext/adjustment/precision.h"
#include "ext/adjustment/resection.h"
#include "ext/adjustment/triangulation.h"
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_relative.h"
#include "ext/colmap/table_tie_points.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"
#include "ext/core/union_find.h"

#include <Eigen/Dense>
#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <unordered_map>

namespace bayon {
namespace {

struct StripImage {
  DatabaseImage row;
  int camera_idx = -1;
  // The database's keypoints (none with tie points alone), then the tie
  // observations in point order, with their covariances.
  FeatureKeypoints keypoints;
  int num_keypoints = 0;
  // Keypoint rows that are coded targets: their matches oriented the pairs
  // but make no tracks, for the targets come in as named tie points (or
  // control points), once.
  std::set<uint32_t> target_rows;
  std::vector<Eigen::Matrix2d> tie_covariances;
  ImageFrame frame;
  bool placed = false;
  Rigid3d cam_from_world;
  // Normalised rays (u, v, 1) of the keypoints, computed on demand.
  std::vector<std::optional<Eigen::Vector3d>> rays;
  std::vector<bool> ray_done;
};

// Union-find over (image, keypoint) for the tracks of the verified matches.
Eigen::Quaterniond ExpRotation(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle));
}

Eigen::Vector3d LogRotation(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q.normalized());
  return aa.angle() * aa.axis();
}

class StripBuilder {
 public:
  StripBuilder(const std::string& database_path,
               const std::string& control_path,
               const StripOptions& options)
      : database_path_(database_path),
        control_path_(control_path),
        options_(options) {}

  StripResult Build() {
    Timer timer;
    ControlData control = ReadControlFolder(control_path_);
    LoadImagesAndCameras(&control);
    DropInconsistentPairs();
    BuildTracks();
    ChainModels();
    CloseRing();
    TriangulateTracks();
    MakeBlock();
    if (options_.adjust) AdjustStrip();
    if (!control.empty() && options_.datum.datum != DatumType::kFree) {
      ApplyControl(control);
    }
    MakeModel();
    result_.time_s = timer.Seconds();
    return std::move(result_);
  }

 private:
  // ---------------------------------------------------------------- input
  void LoadImagesAndCameras(ControlData* control) {
    CheckFileExists(database_path_, "database_path");
    Database database(database_path_, Database::Mode::kReadOnly);
    std::vector<DatabaseImage> rows = database.ReadAllImages();
    if (rows.size() < 2) {
      ThrowInputError(database_path_,
                      ": ",
                      rows.size(),
                      " images; a strip needs two or more");
    }
    // The sequence as photographed: images in the order of their names.
    std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
      return a.name < b.name;
    });
    std::map<camera_t, CalibrationRecord> calibrations;
    std::map<image_t, InteriorRecord> interiors;
    if (BayonTableExists(&database, kCalibrationTable.name)) {
      calibrations = ReadAllCalibrations(&database);
    }
    if (BayonTableExists(&database, kInteriorTable.name)) {
      interiors = ReadAllInteriors(&database);
    }
    std::map<camera_t, int> camera_idxs;
    for (const DatabaseImage& row : rows) {
      if (camera_idxs.count(row.camera_id) == 0) {
        const Camera colmap_camera = database.ReadCamera(row.camera_id);
        Camera camera = colmap_camera;
        auto record = calibrations.find(row.camera_id);
        if (record != calibrations.end()) {
          camera = record->second.camera;
          camera.camera_id = row.camera_id;
        } else if (!colmap_camera.has_prior_focal_length) {
          // The strip is formed with the guess; it is off in scale and
          // shape as the guess is, which the bundle, estimating the focal
          // length first (adjustment.h, step 1b), takes out.
          LOG(WARNING) << "camera " << row.camera_id
                       << ": the focal length is COLMAP's guess ("
                       << camera.MeanFocalLengthPx()
                       << " px; no EXIF, no calibration, and bayon relative "
                          "could not estimate it: its log says why); the "
                          "strip is formed with it, and bayon adjust "
                          "estimates it";
        }
        CheckCameraCalibration(camera, database_path_);
        camera_idxs[row.camera_id] = static_cast<int>(colmap_cameras_.size());
        colmap_cameras_.push_back(colmap_camera);
        cameras_.push_back(camera);
      }
      StripImage image;
      image.row = row;
      image.camera_idx = camera_idxs.at(row.camera_id);
      image.keypoints = database.ReadKeypoints(row.image_id);
      image.num_keypoints = static_cast<int>(image.keypoints.rows());
      image.target_rows =
          KeypointTargetRows(&database, row.image_id, image.num_keypoints);
      // A measured frame (film scans) replaces the camera's default; a
      // digital image's row does not, as it may hold the default frame of
      // another camera (InteriorRecord::MeasuredFrame()).
      auto interior = interiors.find(row.image_id);
      const std::optional<ImageFrame> measured =
          interior != interiors.end() ? interior->second.MeasuredFrame()
                                      : std::nullopt;
      image.frame =
          measured ? *measured : cameras_[image.camera_idx].DefaultFrame();
      image.rays.resize(image.keypoints.rows());
      image.ray_done.assign(image.keypoints.rows(), false);
      image_idxs_[row.image_id] = static_cast<int>(images_.size());
      images_.push_back(std::move(image));
    }
    for (auto& [pair_id, geometry] : database.ReadAllTwoViewGeometries()) {
      if (geometry.inlier_matches.rows() == 0) continue;
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      if (!image_idxs_.count(id1) || !image_idxs_.count(id2)) continue;
      geometries_[{image_idxs_.at(id1), image_idxs_.at(id2)}] = geometry;
    }
    if (BayonTableExists(&database, kRelativeOrientationTable.name)) {
      for (const auto& [pair_id, record] :
           ReadAllRelativeOrientations(&database)) {
        const auto [id1, id2] = ImageIdsFromPairId(pair_id);
        if (!image_idxs_.count(id1) || !image_idxs_.count(id2)) continue;
        rotation_sigma_deg_[{image_idxs_.at(id1), image_idxs_.at(id2)}] =
            record.std_omega_phi_kappa_deg.norm();
      }
    }
    if (geometries_.empty()) {
      ThrowInputError(database_path_,
                      ": no verified image pairs (two_view_geometries); run "
                      "bayon match and bayon relative, or a COLMAP matcher");
    }
    const std::vector<TiePointRecord> tie_points =
        ReadTiePointsFor(&database, options_.tie_points);
    std::map<image_t, std::string> image_names;
    for (const DatabaseImage& row : rows) image_names[row.image_id] = row.name;
    use_matches_ = options_.tie_points != TiePointSource::kAlsm;
    AppendTieObservations(
        tie_points,
        TakeControlFromNamedTiePoints(tie_points, image_names, control));
  }

  // ----------------------------------------------------------- view graph
  // The pairs whose rotation disagrees with their loops (view_graph.h) go
  // before their matches join any track, each rotation with its standard
  // deviation from bayon_relative_orientation where `bayon relative` wrote
  // one. Pairs without a stored pose (E alone) are decomposed later, with
  // the tracks, and are not tested.
  void DropInconsistentPairs() {
    std::vector<ViewGraphPair> pairs;
    std::vector<std::pair<int, int>> keys;
    for (const auto& [key, geometry] : geometries_) {
      const std::optional<Rigid3d> pose = geometry.StoredPose();
      if (!pose) continue;
      ViewGraphPair pair;
      pair.image1 = key.first;
      pair.image2 = key.second;
      pair.rotation = pose->rotation.toRotationMatrix();
      const auto sigma = rotation_sigma_deg_.find(key);
      if (sigma != rotation_sigma_deg_.end()) pair.sigma_deg = sigma->second;
      pair.weight = static_cast<double>(geometry.inlier_matches.rows());
      pairs.push_back(pair);
      keys.push_back(key);
    }
    for (const DroppedPair& dropped :
         FindInconsistentPairs(pairs, options_.view_graph)) {
      const auto [a, b] = keys[dropped.pair_idx];
      const std::string line = StrCat(images_[a].row.name,
                                      " - ",
                                      images_[b].row.name,
                                      ": ",
                                      WhyDropped(dropped, options_.view_graph));
      LOG(WARNING) << "pair dropped: " << line;
      result_.dropped_pairs.push_back(line);
      geometries_.erase(keys[dropped.pair_idx]);
    }
  }

  // The tie observations after each image's keypoints, and their tracks;
  // control points' observations keep their place among the keypoints but
  // make no track (the control adds those points).
  void AppendTieObservations(const std::vector<TiePointRecord>& tie_points,
                             const std::set<size_t>& control_points) {
    std::vector<std::vector<Eigen::Vector2d>> xy(images_.size());
    for (size_t t = 0; t < tie_points.size(); ++t) {
      const TiePointRecord& point = tie_points[t];
      std::vector<std::pair<int, int>> track;
      for (const TieObservation& observation : point.observations) {
        auto it = image_idxs_.find(observation.image_id);
        if (it == image_idxs_.end()) continue;
        StripImage& image = images_[it->second];
        const int first = use_matches_ ? image.num_keypoints : 0;
        track.push_back(
            {it->second, first + static_cast<int>(xy[it->second].size())});
        xy[it->second].push_back(observation.xy);
        image.tie_covariances.push_back(FlooredCovariance(
            observation.covariance, options_.min_tie_sigma_px));
      }
      if (track.size() >= 2 && !control_points.count(t)) {
        tie_tracks_.push_back(std::move(track));
      }
    }
    result_.num_alsm_tie_points = static_cast<int>(tie_tracks_.size());
    for (size_t i = 0; i < images_.size(); ++i) {
      StripImage& image = images_[i];
      const int first = use_matches_ ? image.num_keypoints : 0;
      FeatureKeypoints keypoints(
          first + xy[i].size(),
          std::max<Eigen::Index>(2, image.keypoints.cols()));
      keypoints.setZero();
      if (first > 0) keypoints.topRows(first) = image.keypoints;
      for (size_t k = 0; k < xy[i].size(); ++k) {
        keypoints(first + k, 0) = static_cast<float>(xy[i][k].x());
        keypoints(first + k, 1) = static_cast<float>(xy[i][k].y());
      }
      if (!use_matches_) image.num_keypoints = 0;
      image.keypoints = std::move(keypoints);
      image.rays.assign(image.keypoints.rows(), std::nullopt);
      image.ray_done.assign(image.keypoints.rows(), false);
    }
  }

  const Eigen::Vector3d* Ray(int image_idx, int keypoint) {
    StripImage& image = images_[image_idx];
    if (!image.ray_done[keypoint]) {
      Eigen::Vector3d ray;
      if (cameras_[image.camera_idx].CamFromImg(
              KeypointXY(image.keypoints, keypoint), &ray, &image.frame)) {
        image.rays[keypoint] = ray;
      }
      image.ray_done[keypoint] = true;
    }
    return image.rays[keypoint] ? &*image.rays[keypoint] : nullptr;
  }

  // --------------------------------------------------------------- tracks
  static int64_t Key(int image_idx, int keypoint) {
    return (static_cast<int64_t>(image_idx) << 32) | keypoint;
  }

  void BuildTracks() {
    UnionFind sets;
    std::unordered_map<int64_t, int> element_of;
    std::vector<std::pair<int, int>> elements;
    auto element = [&](int image_idx, int keypoint) {
      const int64_t key = Key(image_idx, keypoint);
      auto it = element_of.find(key);
      if (it != element_of.end()) return it->second;
      const int id = static_cast<int>(sets.Add());
      element_of.emplace(key, id);
      elements.push_back({image_idx, keypoint});
      return id;
    };
    for (const auto& [pair, geometry] : geometries_) {
      if (!use_matches_) break;
      const FeatureMatches& matches = geometry.inlier_matches;
      const std::set<uint32_t>& targets1 = images_[pair.first].target_rows;
      const std::set<uint32_t>& targets2 = images_[pair.second].target_rows;
      for (Eigen::Index m = 0; m < matches.rows(); ++m) {
        if (targets1.count(matches(m, 0)) || targets2.count(matches(m, 1))) {
          continue;
        }
        sets.Union(element(pair.first, matches(m, 0)),
                   element(pair.second, matches(m, 1)));
      }
    }
    std::unordered_map<int, int> track_of_root;
    for (size_t e = 0; e < elements.size(); ++e) {
      const int root = static_cast<int>(sets.Find(e));
      auto it = track_of_root.find(root);
      if (it == track_of_root.end()) {
        it =
            track_of_root.emplace(root, static_cast<int>(tracks_.size())).first;
        tracks_.emplace_back();
      }
      tracks_[it->second].push_back(elements[e]);
    }
    // A track with two keypoints in one image joins points that differ:
    // it is dropped (COLMAP keeps only a consistent part; the adjustment
    // must not see contradictions).
    std::vector<std::vector<std::pair<int, int>>> consistent;
    for (auto& track : tracks_) {
      std::sort(track.begin(), track.end());
      bool ok = track.size() >= 2;
      for (size_t i = 1; i < track.size() && ok; ++i) {
        ok = track[i].first != track[i - 1].first;
      }
      if (ok) consistent.push_back(std::move(track));
    }
    tracks_ = std::move(consistent);
    // The tie points of `bayon tiepoints` are tracks of their own (one
    // observation per image by construction).
    for (const auto& track : tie_tracks_) tracks_.push_back(track);
    track_points_.assign(tracks_.size(), std::nullopt);
    track_at_.assign(images_.size(), {});
    for (size_t t = 0; t < tracks_.size(); ++t) {
      for (const auto& [image_idx, keypoint] : tracks_[t]) {
        track_at_[image_idx][keypoint] = static_cast<int>(t);
      }
    }
    result_.num_tracks = static_cast<int>(tracks_.size());
  }

  // ------------------------------------------------------------- chaining
  // cam_b_from_cam_a with |t| = 1 from the pair's geometry, or nullopt.
  std::optional<Rigid3d> RelativeOrientation(int a,
                                             int b,
                                             const TwoViewGeometry& geometry,
                                             std::string* reason) {
    if (std::optional<Rigid3d> pose = geometry.StoredPose()) return pose;
    Eigen::Matrix3d E;
    if (geometry.E && geometry.E->norm() > 1e-12) {
      E = *geometry.E;
    } else {
      *reason = "no relative orientation (qvec/tvec or E) for the pair";
      return std::nullopt;
    }
    return DecomposeEssential(a, b, E, reason);
  }

  // E = [t]x R: the four (R, t) of the SVD, the one with most intersections
  // in front of both cameras (cheirality).
  std::optional<Rigid3d> DecomposeEssential(int a,
                                            int b,
                                            const Eigen::Matrix3d& E,
                                            std::string* reason) {
    const std::vector<std::pair<int, int>> shared = SharedObservations(a, b);
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(
        E, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
    if (U.determinant() < 0) U = -U;
    if (V.determinant() < 0) V = -V;
    Eigen::Matrix3d W;
    W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    const Eigen::Matrix3d rotations[2] = {U * W * V.transpose(),
                                          U * W.transpose() * V.transpose()};
    const Eigen::Vector3d t = U.col(2);
    int best_count = -1;
    Rigid3d best;
    for (const Eigen::Matrix3d& R : rotations) {
      for (double sign : {1.0, -1.0}) {
        const Rigid3d candidate(Eigen::Quaterniond(R).normalized(), sign * t);
        int count = 0;
        for (const auto& [keypoint_a, keypoint_b] : shared) {
          count +=
              ModelPoint(a, keypoint_a, b, keypoint_b, candidate).has_value();
        }
        if (count > best_count) {
          best_count = count;
          best = candidate;
        }
      }
    }
    if (best_count < 5) {
      *reason = "the essential matrix has no solution in front of both images";
      return std::nullopt;
    }
    return best;
  }

  // Intersection of two rays in the model of (a, b): a at the origin, b at
  // cam_b_from_cam_a; coordinates in camera a's frame.
  std::optional<Eigen::Vector3d> ModelPoint(
      int a, int keypoint_a, int b, int keypoint_b, const Rigid3d& b_from_a) {
    const Eigen::Vector3d* ray_a = Ray(a, keypoint_a);
    const Eigen::Vector3d* ray_b = Ray(b, keypoint_b);
    if (ray_a == nullptr || ray_b == nullptr) return std::nullopt;
    const std::vector<bayon::Ray> rays = {
        {Eigen::Vector3d::Zero(), ray_a->normalized()},
        {b_from_a.Inverse().translation,
         (b_from_a.rotation.inverse() * *ray_b).normalized()}};
    return IntersectRays(rays, options_.min_intersection_angle_deg);
  }

  struct ModelPoints {
    std::vector<int> tracks;
    std::vector<Eigen::Vector3d> xyz;  // camera a's frame, base 1
  };

  // The observations (keypoint in a, keypoint in b) of the tracks the two
  // images share.
  std::vector<std::pair<int, int>> SharedObservations(int a, int b) const {
    std::vector<std::pair<int, int>> shared;
    for (const auto& [keypoint_a, track] : track_at_[a]) {
      for (const auto& [image_idx, keypoint] : tracks_[track]) {
        if (image_idx == b) shared.push_back({keypoint_a, keypoint});
      }
    }
    return shared;
  }

  ModelPoints IntersectModel(int a, int b, const Rigid3d& b_from_a) {
    ModelPoints points;
    for (const auto& [keypoint_a, keypoint_b] : SharedObservations(a, b)) {
      const std::optional<Eigen::Vector3d> xyz =
          ModelPoint(a, keypoint_a, b, keypoint_b, b_from_a);
      if (!xyz) continue;
      points.tracks.push_back(track_at_[a].at(keypoint_a));
      points.xyz.push_back(*xyz);
    }
    return points;
  }

  const TwoViewGeometry* Geometry(int a, int b, bool* swapped) const {
    auto it = geometries_.find({a, b});
    if (it != geometries_.end()) {
      *swapped = false;
      return &it->second;
    }
    it = geometries_.find({b, a});
    if (it != geometries_.end()) {
      *swapped = true;
      return &it->second;
    }
    return nullptr;
  }

  // Scale of a model (strip units per model unit) from its points shared
  // with the strip: their distances from camera a's centre.
  std::optional<double> TransferScale(int a,
                                      const ModelPoints& points,
                                      StripModel* model) const {
    const Eigen::Vector3d center_a = images_[a].cam_from_world.Center();
    std::vector<double> ratios;
    for (size_t i = 0; i < points.tracks.size(); ++i) {
      const auto& world = track_points_[points.tracks[i]];
      if (!world) continue;
      const double model_distance = points.xyz[i].norm();
      if (model_distance <= 0) continue;
      ratios.push_back((*world - center_a).norm() / model_distance);
    }
    model->num_common_points = static_cast<int>(ratios.size());
    if (static_cast<int>(ratios.size()) < options_.min_common_points) {
      model->reason = StrCat("only ",
                             ratios.size(),
                             " tie points shared with the strip for the "
                             "scale transfer");
      return std::nullopt;
    }
    const double scale = Median(ratios);
    std::vector<double> deviations;
    for (double r : ratios) deviations.push_back(std::abs(r / scale - 1));
    model->scale_spread = 1.4826 * Median(deviations);
    return scale;
  }

  // The model of (a, b): its relative orientation and intersected tie
  // points, computed once per pair.
  struct PairModel {
    bool ok = false;
    std::string reason;
    int num_matches = 0;
    Rigid3d b_from_a;
    ModelPoints points;
  };

  const PairModel& Model(int a, int b) {
    auto it = models_.find({a, b});
    if (it != models_.end()) return it->second;
    PairModel& model = models_[{a, b}];
    bool swapped = false;
    const TwoViewGeometry* geometry = Geometry(a, b, &swapped);
    if (geometry == nullptr) {
      model.reason = "no verified matches";
      return model;
    }
    model.num_matches = static_cast<int>(geometry->inlier_matches.rows());
    const std::optional<Rigid3d> b_from_a = RelativeOrientation(
        a,
        b,
        swapped ? InvertTwoViewGeometry(*geometry) : *geometry,
        &model.reason);
    if (!b_from_a) return model;
    model.b_from_a = *b_from_a;
    model.points = IntersectModel(a, b, *b_from_a);
    model.ok = true;
    return model;
  }

  int NumCommonPoints(const PairModel& model) const {
    int count = 0;
    for (int track : model.points.tracks)
      count += track_points_[track].has_value();
    return count;
  }

  // Tries to attach image b to the strip through the model (a, b).
  bool Connect(int a, int b, bool first_model) {
    const PairModel& pair = Model(a, b);
    StripModel model;
    model.image1 = images_[a].row.name;
    model.image2 = images_[b].row.name;
    model.num_matches = pair.num_matches;
    model.reason = pair.reason;
    if (!pair.ok) {
      result_.models.push_back(model);
      return false;
    }
    const ModelPoints& points = pair.points;
    model.num_points = static_cast<int>(points.tracks.size());
    double scale = 1.0;
    if (!first_model) {
      const std::optional<double> transferred =
          TransferScale(a, points, &model);
      if (!transferred) {
        result_.models.push_back(model);
        return false;
      }
      scale = *transferred;
    }
    model.scale = scale;
    model.connected = true;
    const Rigid3d& a_from_world = images_[a].cam_from_world;
    const Rigid3d scaled(pair.b_from_a.rotation,
                         scale * pair.b_from_a.translation);
    images_[b].cam_from_world = scaled * a_from_world;
    images_[b].placed = true;
    const Rigid3d world_from_a = a_from_world.Inverse();
    for (size_t i = 0; i < points.tracks.size(); ++i) {
      if (!track_points_[points.tracks[i]]) {
        track_points_[points.tracks[i]] =
            world_from_a * (scale * points.xyz[i]);
      }
    }
    sequence_.push_back(b);
    result_.models.push_back(model);
    IntersectTracksOf(b);
    return true;
  }

  // The intersection, from all oriented images, of b's tracks that have
  // none yet: tie points b shares with images other than its model partner
  // carry the scale on to the next models.
  void IntersectTracksOf(int b) {
    for (const auto& [keypoint, track] : track_at_[b]) {
      if (track_points_[track]) continue;
      track_points_[track] = IntersectTrack(track);
    }
  }

  std::optional<Eigen::Vector3d> IntersectTrack(int track) {
    std::vector<bayon::Ray> rays;
    for (const auto& [image_idx, keypoint] : tracks_[track]) {
      const StripImage& image = images_[image_idx];
      if (!image.placed) continue;
      const Eigen::Vector3d* ray = Ray(image_idx, keypoint);
      if (ray == nullptr) continue;
      rays.push_back(
          {image.cam_from_world.Center(),
           (image.cam_from_world.rotation.inverse() * *ray).normalized()});
    }
    return IntersectRays(rays, options_.min_intersection_angle_deg);
  }

  // Spatial resection of image b from the tie points intersected so far,
  // the nearest placed station (in name order) as one approximation.
  bool Resect(int b) {
    std::vector<Eigen::Vector2d> xy;
    std::vector<Eigen::Vector3d> points;
    for (const auto& [keypoint, track] : track_at_[b]) {
      if (!track_points_[track]) continue;
      const Eigen::Vector3d* ray = Ray(b, keypoint);
      if (ray == nullptr) continue;
      xy.push_back(ray->hnormalized());
      points.push_back(*track_points_[track]);
    }
    const double focal = cameras_[images_[b].camera_idx].MeanFocalLengthPx();
    ResectionOptions resection;
    resection.max_error = options_.resection_max_error_px / focal;
    resection.min_inliers = options_.min_resection_points;
    resection.seed = static_cast<uint64_t>(b) + 1;
    const Rigid3d* guess = nullptr;
    int nearest = std::numeric_limits<int>::max();
    for (size_t i = 0; i < images_.size(); ++i) {
      const int distance = std::abs(static_cast<int>(i) - b);
      if (images_[i].placed && distance < nearest) {
        nearest = distance;
        guess = &images_[i].cam_from_world;
      }
    }
    const std::optional<Resection> result =
        ResectImage(xy, points, guess, resection);
    if (!result) return false;
    images_[b].cam_from_world = result->cam_from_world;
    images_[b].placed = true;
    sequence_.push_back(b);
    result_.resected_images.push_back({images_[b].row.name,
                                       result->num_inliers,
                                       static_cast<int>(xy.size()),
                                       result->rms_error * focal});
    LOG(INFO) << "strip: " << images_[b].row.name << " placed by resection ("
              << result->num_inliers << " of " << xy.size()
              << " tie points, RMS " << result->rms_error * focal << " px)";
    IntersectTracksOf(b);
    return true;
  }

  // Resects the unplaced image that sees the most intersected tie points
  // (trying the others in turn); false when none can be placed.
  bool ResectBest() {
    if (!options_.resection) return false;
    std::vector<std::pair<int, int>> candidates;  // (-count, image)
    for (size_t i = 0; i < images_.size(); ++i) {
      if (images_[i].placed) continue;
      int count = 0;
      for (const auto& [keypoint, track] : track_at_[i]) {
        count += track_points_[track].has_value();
      }
      if (count >= options_.min_resection_points) {
        candidates.push_back({-count, static_cast<int>(i)});
      }
    }
    std::sort(candidates.begin(), candidates.end());
    for (const auto& [count, image_idx] : candidates) {
      if (Resect(image_idx)) return true;
    }
    return false;
  }

  // The images in the order of their names form the strip when every
  // neighbour in that order is related to the next (or to one within the
  // gap that bridges a missing model).
  bool NameOrderIsAStrip() const {
    for (size_t b = 1; b < images_.size(); ++b) {
      bool related = false;
      for (int gap = 1; gap <= options_.max_gap && !related; ++gap) {
        const int a = static_cast<int>(b) - gap;
        bool swapped = false;
        related = a >= 0 && Geometry(a, static_cast<int>(b), &swapped);
      }
      if (!related) return false;
    }
    return true;
  }

  void ChainModels() {
    const bool by_name =
        options_.order == StripOrder::kName ||
        (options_.order == StripOrder::kAuto && NameOrderIsAStrip());
    result_.order = by_name ? "name" : "graph";
    if (by_name) {
      ChainInNameOrder();
      // Images placed out of sequence now: no ring closure along the names.
      while (ResectBest()) sequential_ = false;
    } else {
      ChainByGraph();
    }
    for (size_t i = 0; i < images_.size(); ++i) {
      if (!images_[i].placed) {
        result_.unoriented_images.push_back(images_[i].row.name);
      }
    }
  }

  void ChainInNameOrder() {
    sequential_ = true;
    images_[0].placed = true;
    images_[0].cam_from_world = Rigid3d();
    sequence_.push_back(0);
    if (!Connect(0, 1, true)) {
      throw RunFailure(StrCat("the first model (",
                              images_[0].row.name,
                              ", ",
                              images_[1].row.name,
                              ") cannot be formed: ",
                              result_.models.back().reason));
    }
    for (size_t b = 2; b < images_.size(); ++b) {
      bool connected = false;
      for (int gap = 1; gap <= options_.max_gap && !connected; ++gap) {
        const int a = static_cast<int>(b) - gap;
        if (a < 0 || !images_[a].placed) continue;
        connected = Connect(a, static_cast<int>(b), false);
      }
      if (!connected && options_.resection) connected = Resect(b);
      if (!connected) {
        LOG(WARNING) << "strip: " << images_[b].row.name
                     << " could not be connected: "
                     << result_.models.back().reason;
      }
    }
  }

  // Images whose names do not follow the strip (temple-ring's stations were
  // photographed out of order, some turned upside down): the strip grows
  // from the model with the most intersected tie points, each step adding
  // the image whose model shares the most tie points with the strip.
  void ChainByGraph() {
    std::pair<int, int> first{-1, -1};
    size_t best_points = 0;
    for (const auto& [pair, geometry] : geometries_) {
      const PairModel& model = Model(pair.first, pair.second);
      if (model.ok && model.points.tracks.size() > best_points) {
        best_points = model.points.tracks.size();
        first = pair;
      }
    }
    if (first.first < 0 ||
        static_cast<int>(best_points) < options_.min_common_points) {
      throw RunFailure(
          "no image pair forms a model (no relative "
          "orientation with intersecting tie points)");
    }
    images_[first.first].placed = true;
    images_[first.first].cam_from_world = Rigid3d();
    sequence_.push_back(first.first);
    Connect(first.first, first.second, true);
    while (true) {
      int best_a = -1, best_b = -1, best_common = 0;
      for (const auto& [pair, geometry] : geometries_) {
        for (const auto& [a, b] :
             {pair, std::make_pair(pair.second, pair.first)}) {
          if (!images_[a].placed || images_[b].placed) continue;
          const PairModel& model = Model(a, b);
          if (!model.ok) continue;
          const int common = NumCommonPoints(model);
          if (common > best_common) {
            best_common = common;
            best_a = a;
            best_b = b;
          }
        }
      }
      if (best_a >= 0 && best_common >= options_.min_common_points &&
          Connect(best_a, best_b, false)) {
        continue;
      }
      if (!ResectBest()) break;
    }
  }

  // ---------------------------------------------------------------- ring
  void CloseRing() {
    if (!sequential_ || options_.ring == RingClosure::kOpen ||
        sequence_.size() < 3) {
      return;
    }
    const int last = sequence_.back();
    const int first = sequence_.front();
    bool swapped = false;
    const TwoViewGeometry* geometry = Geometry(last, first, &swapped);
    std::string reason;
    std::optional<Rigid3d> first_from_last;
    if (geometry != nullptr) {
      first_from_last = RelativeOrientation(
          last,
          first,
          swapped ? InvertTwoViewGeometry(*geometry) : *geometry,
          &reason);
    }
    StripModel model;
    model.image1 = images_[last].row.name;
    model.image2 = images_[first].row.name;
    std::optional<double> scale;
    ModelPoints points;
    if (first_from_last) {
      points = IntersectModel(last, first, *first_from_last);
      model.num_points = static_cast<int>(points.tracks.size());
      scale = TransferScale(last, points, &model);
    } else {
      model.reason = geometry == nullptr ? "no verified matches" : reason;
    }
    if (!scale) {
      if (options_.ring == RingClosure::kClosed) {
        LOG(WARNING) << "strip: the ring cannot be closed: " << model.reason;
      }
      if (geometry != nullptr) result_.models.push_back(model);
      return;
    }
    model.connected = true;
    model.scale = *scale;
    result_.models.push_back(model);
    result_.closed_ring = true;

    // The first image as the ring predicts it, against where it is.
    const Rigid3d& last_from_world = images_[last].cam_from_world;
    const Rigid3d predicted = Rigid3d(first_from_last->rotation,
                                      *scale * first_from_last->translation) *
                              last_from_world;
    const Rigid3d& actual = images_[first].cam_from_world;
    // Path length around the ring.
    std::vector<double> path(sequence_.size(), 0.0);
    for (size_t i = 1; i < sequence_.size(); ++i) {
      path[i] =
          path[i - 1] + (images_[sequence_[i]].cam_from_world.Center() -
                         images_[sequence_[i - 1]].cam_from_world.Center())
                            .norm();
    }
    const double total =
        path.back() + (predicted.Center() - last_from_world.Center()).norm();
    const Eigen::Vector3d position_error = actual.Center() - predicted.Center();
    // R_first' = R_first W: the accumulated turn of the world, undone along
    // the ring in proportion to each image's place.
    const Eigen::Vector3d omega =
        LogRotation(actual.rotation.inverse() * predicted.rotation);
    result_.closure_rotation_deg = omega.norm() * 180.0 / M_PI;
    result_.closure_position_relative = position_error.norm() / total;
    // The scale error: distances from the first centre to the shared points,
    // as the strip has them and as the closing model has them.
    std::vector<double> ratios;
    const Rigid3d world_from_last = last_from_world.Inverse();
    for (size_t i = 0; i < points.tracks.size(); ++i) {
      const auto& world = track_points_[points.tracks[i]];
      if (!world) continue;
      const Eigen::Vector3d closing =
          world_from_last * (*scale * points.xyz[i]);
      const double d_closing = (closing - predicted.Center()).norm();
      if (d_closing > 0) {
        ratios.push_back((*world - actual.Center()).norm() / d_closing);
      }
    }
    if (!ratios.empty()) result_.closure_scale = Median(ratios);
    LOG(INFO) << "strip: ring closure error " << result_.closure_rotation_deg
              << " deg, " << 100 * result_.closure_position_relative
              << " % of the path, scale " << result_.closure_scale;
    for (size_t i = 1; i < sequence_.size(); ++i) {
      const double f = path[i] / total;
      StripImage& image = images_[sequence_[i]];
      const Eigen::Vector3d center =
          image.cam_from_world.Center() + f * position_error;
      const Eigen::Quaterniond rotation =
          (image.cam_from_world.rotation * ExpRotation(-f * omega))
              .normalized();
      image.cam_from_world = Rigid3d(rotation, -(rotation * center));
    }
  }

  // Every track from all the rays of its oriented images.
  void TriangulateTracks() {
    for (size_t t = 0; t < tracks_.size(); ++t) {
      track_points_[t] = IntersectTrack(static_cast<int>(t));
    }
  }

  // ------------------------------------------------------------ adjustment
  void MakeBlock() {
    block_.sigma0_px = options_.image_sigma_px;
    for (const Camera& camera : cameras_) {
      BlockCamera block_camera;
      block_camera.camera = camera;
      block_camera.free.assign(camera.params.size(), false);
      block_camera.source_model = camera.model_id;
      block_.cameras.push_back(block_camera);
    }
    std::vector<int> block_image(images_.size(), -1);
    for (int idx : sequence_) {
      const StripImage& image = images_[idx];
      BlockImage block_image_entry;
      block_image_entry.image_id = image.row.image_id;
      block_image_entry.name = image.row.name;
      block_image_entry.camera_idx = image.camera_idx;
      block_image_entry.SetCamFromWorld(image.cam_from_world);
      block_image_entry.frame = image.frame;
      block_image[idx] = static_cast<int>(block_.images.size());
      block_.images.push_back(block_image_entry);
    }
    for (size_t t = 0; t < tracks_.size(); ++t) {
      if (!track_points_[t]) continue;
      BlockPoint point;
      point.point3D_id = block_.points.size() + 1;
      point.xyz = *track_points_[t];
      point.color = Eigen::Matrix<uint8_t, 3, 1>(128, 128, 128);
      const int point_idx = static_cast<int>(block_.points.size());
      int count = 0;
      for (const auto& [image_idx, keypoint] : tracks_[t]) {
        if (block_image[image_idx] < 0) continue;
        BlockObservation observation;
        observation.image_idx = block_image[image_idx];
        observation.point_idx = point_idx;
        observation.point2D_idx = keypoint;
        observation.xy = KeypointXY(images_[image_idx].keypoints, keypoint);
        observation.sigma_px = options_.image_sigma_px;
        const StripImage& image = images_[image_idx];
        if (keypoint >= image.num_keypoints) {
          observation.SetCovariance(
              image.tie_covariances[keypoint - image.num_keypoints]);
        }
        block_.observations.push_back(observation);
        ++count;
      }
      if (count < 2) {
        block_.observations.resize(block_.observations.size() - count);
        continue;
      }
      block_.points.push_back(point);
    }
  }

  // The strip adjustment in model coordinates: the first image and the
  // scale of the first model held (a minimal datum), a robust solution,
  // observations above the residual limit removed, a least-squares solution.
  void AdjustStrip() {
    if (block_.points.empty()) throw RunFailure("no tie point intersected");
    BlockImage& first = block_.images[0];
    first.rotation_fixed = true;
    first.center_fixed = {true, true, true};
    BlockImage& second = block_.images[1];
    int coordinate = 0;
    (second.center - first.center).cwiseAbs().maxCoeff(&coordinate);
    second.center_fixed[coordinate] = true;
    BundleSolverOptions solver;
    solver.num_threads = options_.num_threads;
    solver.loss = RobustLoss::kHuber;
    solver.loss_scale = 2.0;
    for (BlockObservation& o : block_.observations) {
      const BlockImage& image = block_.images[o.image_idx];
      if ((image.CamFromWorld() * block_.points[o.point_idx].xyz).z() <= 0) {
        o.active = false;
      }
    }
    block_.DeactivateWeakPoints();
    SolveBundle(solver, &block_);
    const std::vector<Eigen::Vector2d> residuals = ImageResiduals(&block_);
    for (size_t o = 0; o < block_.observations.size(); ++o) {
      if (!block_.observations[o].active) continue;
      if (!(residuals[o].norm() <= options_.max_reprojection_error_px)) {
        block_.observations[o].active = false;
        ++result_.num_observations_removed;
      }
    }
    block_.DeactivateWeakPoints();
    solver.loss = RobustLoss::kNone;
    SolveBundle(solver, &block_);
    PrecisionOptions precision_options;
    precision_options.compute_residual_cofactors = false;
    try {
      const AdjustmentPrecision precision =
          ComputePrecision(&block_, precision_options);
      result_.sigma0_px = precision.sigma0;
      result_.num_observations = precision.num_image_coordinates / 2;
    } catch (const RunFailure& failure) {
      LOG(WARNING) << "strip adjustment: no statistics: " << failure.what();
    }
    for (BlockImage& image : block_.images) {
      image.rotation_fixed = false;
      image.center_fixed = {false, false, false};
    }
  }

  // ---------------------------------------------------------------- datum
  void ApplyControl(const ControlData& control) {
    DatumOptions datum = options_.datum;
    if (datum.datum == DatumType::kAuto) {
      int num_control = 0;
      bool bar = false;
      for (const ControlPoint& p : control.points) {
        num_control += p.type == ControlPointType::kControl;
      }
      for (const DistanceObservation& d : control.distances) bar |= d.vertical;
      datum.datum =
          num_control < 3 && bar ? DatumType::kMinimum : DatumType::kControl;
    }
    result_.datum = SetUpDatum(control, datum, &block_);
    result_.has_control = true;
  }

  // ----------------------------------------------------------------- model
  void MakeModel() {
    Scene& scene = result_.model;
    std::map<int, bool> used_cameras;
    for (const BlockImage& block_image : block_.images) {
      used_cameras[block_image.camera_idx] = true;
    }
    for (const auto& [camera_idx, used] : used_cameras) {
      scene.cameras.Set(colmap_cameras_[camera_idx].camera_id,
                        colmap_cameras_[camera_idx]);
    }
    std::map<image_t, int> image_of;
    for (const BlockImage& block_image : block_.images) {
      const StripImage& source = images_[image_idxs_.at(block_image.image_id)];
      Image image;
      image.image_id = block_image.image_id;
      image.name = block_image.name;
      image.camera_id = source.row.camera_id;
      image.cam_from_world = block_image.CamFromWorld();
      image.points2D.resize(source.keypoints.rows());
      for (Eigen::Index k = 0; k < source.keypoints.rows(); ++k) {
        image.points2D[k].xy = KeypointXY(source.keypoints, k);
      }
      scene.images.Set(image.image_id, std::move(image));
    }
    std::vector<std::vector<TrackElement>> tracks(block_.points.size());
    for (const BlockObservation& o : block_.observations) {
      // Manual tie points measured in control/observations.txt are tie
      // points of the block but no keypoints of the model's images.
      if (!o.active || block_.points[o.point_idx].kind != PointKind::kTie ||
          o.point2D_idx == kInvalidPoint2DIdx) {
        continue;
      }
      tracks[o.point_idx].push_back(
          {block_.images[o.image_idx].image_id, o.point2D_idx});
    }
    point3D_t next_id = 1;
    for (size_t p = 0; p < block_.points.size(); ++p) {
      const BlockPoint& block_point = block_.points[p];
      if (block_point.kind != PointKind::kTie || !block_point.active ||
          tracks[p].size() < 2) {
        continue;
      }
      Point3D point;
      point.xyz = block_point.xyz;
      point.color = block_point.color;
      point.track = tracks[p];
      const point3D_t id = next_id++;
      for (const TrackElement& e : point.track) {
        scene.images.at(e.image_id).points2D.at(e.point2D_idx).point3D_id = id;
      }
      scene.points3D.Set(id, std::move(point));
    }
    scene.UpdateReprojectionErrors();
  }

  const std::string database_path_;
  const std::string control_path_;
  const StripOptions& options_;
  StripResult result_;
  std::vector<Camera> cameras_;         // as adjusted (BROWN_BEYER if known)
  std::vector<Camera> colmap_cameras_;  // the database's rows
  std::vector<StripImage> images_;      // in sequence order
  std::map<image_t, int> image_idxs_;
  std::map<std::pair<int, int>, TwoViewGeometry> geometries_;
  // The relative rotations' standard deviations (bayon relative), degrees.
  std::map<std::pair<int, int>, double> rotation_sigma_deg_;
  std::vector<std::vector<std::pair<int, int>>> tracks_;
  std::vector<std::vector<std::pair<int, int>>> tie_tracks_;  // bayon's
  bool use_matches_ = true;  // tracks of the verified matches as well
  std::vector<std::optional<Eigen::Vector3d>> track_points_;
  std::vector<std::unordered_map<int, int>> track_at_;  // keypoint -> track
  std::vector<int> sequence_;  // placed images in the order of placing
  bool sequential_ = false;    // chained in name order (a strip or ring)
  std::map<std::pair<int, int>, PairModel> models_;
  AdjustmentBlock block_;
};

}  // namespace

void StripOptions::Register(OptionRegistry* r) {
  r->AddChoice("ring",
               &ring,
               {{"auto", RingClosure::kAuto},
                {"closed", RingClosure::kClosed},
                {"open", RingClosure::kOpen}},
               "auto (closed when the last image is related to the first), "
               "closed or open");
  r->AddChoice("order",
               &order,
               {{"auto", StripOrder::kAuto},
                {"name", StripOrder::kName},
                {"graph", StripOrder::kGraph}},
               "Models connected in the images' name order, or by the view "
               "graph (the image sharing the most tie points next); auto: "
               "names when every image is related to its predecessor");
  datum.Register(r);
  r->Add("max_gap",
         &max_gap,
         "Bridge a missing model with an image up to this many places back");
  view_graph.Register(r);
  r->Add("min_common_points",
         &min_common_points,
         "Tie points two models must share for the scale transfer");
  r->Add("image_sigma_px", &image_sigma_px, "Precision of a keypoint, px");
  r->AddChoice("tie_points",
               &tie_points,
               TiePointSourceChoices(),
               "Tie observations: model (the tracks of the verified matches), "
               "alsm (bayon tiepoints' least-squares tie points), both; auto: "
               "both where the database has tie points");
  r->Add("min_tie_sigma_px",
         &min_tie_sigma_px,
         "Tie points: floor of the least-squares standard deviations, px");
  r->Add("resection",
         &resection,
         "1: place images no model attaches by spatial resection");
  r->Add("min_resection_points",
         &min_resection_points,
         "Resection: intersected tie points needed (inliers)");
  r->Add("resection_max_error_px",
         &resection_max_error_px,
         "Resection: largest image error of an inlier, px");
  r->Add("max_reprojection_error_px",
         &max_reprojection_error_px,
         "Strip adjustment: observations above this are removed");
  r->Add("adjust", &adjust, "1: adjust the strip in model coordinates");
  r->Add("num_threads", &num_threads, "-1: all cores");
}

void StripOptions::Check() const {
  view_graph.Check();
  CheckOption(max_gap >= 1, "max_gap", ">= 1", max_gap);
  CheckOption(
      min_common_points >= 1, "min_common_points", ">= 1", min_common_points);
  CheckOption(min_intersection_angle_deg >= 0,
              "min_intersection_angle_deg",
              ">= 0",
              min_intersection_angle_deg);
  CheckOption(max_reprojection_error_px > 0,
              "max_reprojection_error_px",
              "> 0",
              max_reprojection_error_px);
  CheckOption(image_sigma_px > 0, "image_sigma_px", "> 0", image_sigma_px);
  CheckOption(
      min_tie_sigma_px > 0, "min_tie_sigma_px", "> 0", min_tie_sigma_px);
  CheckOption(min_resection_points >= 6,
              "min_resection_points",
              ">= 6",
              min_resection_points);
  CheckOption(resection_max_error_px > 0,
              "resection_max_error_px",
              "> 0",
              resection_max_error_px);
  datum.Check();
}

StripResult RunStrip(const std::string& database_path,
                     const std::string& control_path,
                     const StripOptions& options) {
  options.Check();
  return StripBuilder(database_path, control_path, options).Build();
}

std::string StripReportJson(const StripResult& result) {
  using Json = nlohmann::ordered_json;
  Json root;
  root["format"] = "bayon-strip";
  root["version"] = 1;
  root["num_images"] = result.model.images.size();
  root["num_points"] = result.model.points3D.size();
  root["num_tracks"] = result.num_tracks;
  root["order"] = result.order;
  root["num_alsm_tie_points"] = result.num_alsm_tie_points;
  Json resected = Json::array();
  for (const auto& image : result.resected_images) {
    resected.push_back({{"name", image.name},
                        {"num_inliers", image.num_inliers},
                        {"num_points", image.num_points},
                        {"rms_px", image.rms_px}});
  }
  root["resected_images"] = resected;
  root["unoriented_images"] = result.unoriented_images;
  root["dropped_pairs"] = result.dropped_pairs;
  Json models = Json::array();
  for (const StripModel& m : result.models) {
    Json model = {{"images", {m.image1, m.image2}},
                  {"connected", m.connected},
                  {"num_matches", m.num_matches},
                  {"num_points", m.num_points},
                  {"num_common_points", m.num_common_points},
                  {"scale", m.scale},
                  {"scale_spread", m.scale_spread}};
    if (!m.reason.empty()) model["reason"] = m.reason;
    models.push_back(model);
  }
  root["models"] = models;
  root["closed_ring"] = result.closed_ring;
  if (result.closed_ring) {
    root["closure"] = {
        {"rotation_deg", result.closure_rotation_deg},
        {"position_relative_to_path", result.closure_position_relative},
        {"scale", result.closure_scale}};
  }
  root["strip_adjustment"] = {
      {"sigma0_px", result.sigma0_px},
      {"num_observations", result.num_observations},
      {"num_observations_removed", result.num_observations_removed}};
  if (result.has_control) {
    const DatumSetup& datum = result.datum;
    Json residuals = Json::array();
    for (const SimilarityResidual& r : datum.similarity_residuals) {
      residuals.push_back(
          {{"name", r.name},
           {"residual_m", {r.residual.x(), r.residual.y(), r.residual.z()}},
           {"inlier", r.inlier}});
    }
    const Sim3d& sim = datum.object_from_model;
    root["similarity"] = {
        {"datum", DatumTypeName(datum.type)},
        {"description", datum.description},
        {"scale", sim.scale},
        {"qvec",
         {sim.rotation.w(),
          sim.rotation.x(),
          sim.rotation.y(),
          sim.rotation.z()}},
        {"tvec",
         {sim.translation.x(), sim.translation.y(), sim.translation.z()}},
        {"rms_m", datum.similarity_rms_m},
        {"residuals", residuals},
        {"notes", datum.notes}};
  }
  root["time_s"] = result.time_s;
  return root.dump(2) + "\n";
}

}  // namespace bayon
