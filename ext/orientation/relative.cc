// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/relative.h"

#include "ext/colmap/scene_database.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"

#include <glog/logging.h>

#include <algorithm>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

namespace bayon {

void RelativeOptions::Register(OptionRegistry* r) {
  r->Add("assume_zero_distortion",
         &assume_zero_distortion,
         "1: camera constant and principal point only (the paper's start)");
  r->Add("use_subpixel_points",
         &use_subpixel_points,
         "1: use bayon_matches' sub-pixel conjugate points");
  estimation.Register(r);
  r->Add("overwrite",
         &overwrite,
         "1: orient pairs that were oriented before again");
  r->Add("estimate_focal_length",
         &estimate_focal_length,
         "1: a camera without calibration or EXIF focal length gets one from "
         "its strongest pairs before they are oriented");
  r->Add("focal_max_num_pairs",
         &focal_max_num_pairs,
         "Pairs that estimate an unknown focal length");
  r->Add("num_threads", &num_threads, "Threads (-1 = all cores)");
}

std::string RelativeSummaryLine(const RelativeSummary& summary) {
  int64_t num_inliers = 0, num_blunders = 0;
  double sum_sigma0 = 0;
  for (const PairOrientationReport& pair : summary.pairs) {
    if (!pair.oriented) continue;
    num_inliers += pair.num_inliers;
    num_blunders += pair.num_blunders;
    sum_sigma0 += pair.sigma0_px;
  }
  std::string focal_lengths;
  for (const FocalLengthReport& focal : summary.focal_lengths) {
    focal_lengths += StrCat(
        "camera ",
        focal.camera_id,
        focal.estimate.success
            ? StrCat(": focal length ",
                     focal.estimate.focal_length_px,
                     " px +- ",
                     100 * focal.estimate.relative_sigma,
                     " % from the photographs; ")
            : StrCat(": focal length unknown, ", focal.estimate.reason, "; "));
  }
  return StrCat(
      focal_lengths,
      summary.num_oriented,
      " pairs oriented (",
      num_inliers,
      " inliers, ",
      num_blunders,
      " blunders, mean sigma0 ",
      summary.num_oriented > 0 ? sum_sigma0 / summary.num_oriented : 0.0,
      " px), ",
      summary.num_failed,
      " not oriented, ",
      summary.num_skipped,
      " skipped, ",
      summary.seconds,
      " s");
}

void RelativeOptions::Check() const {
  estimation.Check();
  focal.Check();
  CheckOption(focal_max_num_pairs >= 1,
              "RelativeOptions.focal_max_num_pairs",
              ">= 1",
              focal_max_num_pairs);
}

ConjugatePoints PairConjugatePoints(const FeatureKeypoints& keypoints1,
                                    const FeatureKeypoints& keypoints2,
                                    const FeatureMatches& matches,
                                    const std::optional<MatchRecord>& record,
                                    const ImageVectors& vectors1,
                                    const ImageVectors& vectors2,
                                    std::vector<int>* rows) {
  const bool subpixel =
      record && record->xy1.size() == static_cast<size_t>(matches.rows());
  const bool weighted =
      subpixel && record->sigma_px.size() == record->xy1.size();
  ConjugatePoints points;
  rows->clear();
  for (int row = 0; row < matches.rows(); ++row) {
    const uint32_t idx1 = matches(row, 0), idx2 = matches(row, 1);
    if (idx1 >= keypoints1.rows() || idx2 >= keypoints2.rows()) continue;
    const Eigen::Vector2d pixel1 = subpixel ? record->xy1[row].cast<double>()
                                            : KeypointXY(keypoints1, idx1);
    const Eigen::Vector2d pixel2 = subpixel ? record->xy2[row].cast<double>()
                                            : KeypointXY(keypoints2, idx2);
    Eigen::Vector3d u1, u2;
    if (!vectors1.FromPixel(pixel1, &u1) || !vectors2.FromPixel(pixel2, &u2)) {
      continue;
    }
    points.u1.push_back(u1);
    points.u2.push_back(u2);
    points.pixel1.push_back(pixel1);
    points.pixel2.push_back(pixel2);
    if (weighted) points.sigma.push_back(record->sigma_px[row]);
    rows->push_back(row);
  }
  return points;
}

namespace {

struct PairJob {
  PairOrientationReport report;
  FeatureMatches matches;
  std::optional<MatchRecord> match_record;
  RelativeOrientation result;
  std::vector<uint8_t> row_inliers;    // per match row
  std::vector<uint8_t> row_is_target;  // per match row: two coded targets
};

ConjugatePoints SubsetOf(const ConjugatePoints& points,
                         const std::vector<int>& indices) {
  ConjugatePoints subset;
  for (int i : indices) {
    subset.u1.push_back(points.u1[i]);
    subset.u2.push_back(points.u2[i]);
    if (!points.pixel1.empty()) subset.pixel1.push_back(points.pixel1[i]);
    if (!points.pixel2.empty()) subset.pixel2.push_back(points.pixel2[i]);
    if (!points.sigma.empty()) subset.sigma.push_back(points.sigma[i]);
  }
  return subset;
}

// Where a pair shares at least this many coded targets (the linear DRT's
// eight and one to check them), they orient it first.
constexpr int kMinTargetPoints = 9;

// The points that agree with an orientation from the coded targets alone,
// targets included; all points where there are too few targets or they
// give no orientation. The targets' identities are certain (their codes),
// where correlation on repetitive masonry can give more blunders than
// LMedS's median tolerates: on the rendered tower, adjacent pairs with 9
// to 11 targets among 50 to 80 matches were not oriented without this.
std::vector<int> PointsAgreeingWithTargets(
    const ConjugatePoints& points,
    const std::vector<uint8_t>& is_target,
    const RelativeOrientationOptions& options,
    PairOrientationReport* report) {
  std::vector<int> all(points.size()), targets;
  for (int i = 0; i < points.size(); ++i) {
    all[i] = i;
    if (is_target[i]) targets.push_back(i);
  }
  report->num_target_points = static_cast<int>(targets.size());
  if (static_cast<int>(targets.size()) < kMinTargetPoints) return all;
  RelativeOrientationOptions anchor_options = options;
  anchor_options.min_num_points = kMinTargetPoints;
  anchor_options.min_num_inliers = kMinTargetPoints;
  const RelativeOrientation anchor =
      EstimateRelativeOrientation(SubsetOf(points, targets), anchor_options);
  if (!anchor.success) return all;
  // Agreement within the blunder test's bound at the largest sigma a pair
  // may have.
  const double limit = options.blunder_threshold * options.max_sigma_px;
  const std::vector<double> residuals =
      DrtResiduals(anchor.M, points.u1, points.u2, DrtResidual::kSampson);
  std::vector<int> agreeing;
  for (int i = 0; i < points.size(); ++i) {
    if (is_target[i] || std::abs(residuals[i]) <= limit) agreeing.push_back(i);
  }
  report->anchored_by_targets = true;
  return agreeing;
}

void OrientPair(const std::map<image_t, FeatureKeypoints>& keypoints,
                const std::map<image_t, ImageVectors>& vectors,
                const RelativeOptions& options,
                PairJob* job) {
  Timer timer;
  PairOrientationReport& report = job->report;
  const ImageVectors& v1 = vectors.at(report.image_id1);
  const ImageVectors& v2 = vectors.at(report.image_id2);
  report.calibrated = v1.calibrated() && v2.calibrated();
  std::optional<MatchRecord> record;
  if (options.use_subpixel_points) record = job->match_record;
  report.subpixel =
      record && record->xy1.size() == static_cast<size_t>(job->matches.rows());
  std::vector<int> rows;
  const ConjugatePoints points =
      PairConjugatePoints(keypoints.at(report.image_id1),
                          keypoints.at(report.image_id2),
                          job->matches,
                          record,
                          v1,
                          v2,
                          &rows);
  RelativeOrientationOptions estimation = options.estimation;
  estimation.calibrated = report.calibrated;
  std::vector<uint8_t> is_target(rows.size(), 0);
  if (!job->row_is_target.empty()) {
    for (size_t k = 0; k < rows.size(); ++k) {
      is_target[k] = job->row_is_target[rows[k]];
    }
  }
  const std::vector<int> kept =
      PointsAgreeingWithTargets(points, is_target, estimation, &report);
  const bool anchored = static_cast<int>(kept.size()) != points.size();
  job->result = EstimateRelativeOrientation(
      anchored ? SubsetOf(points, kept) : points, estimation);
  if (anchored && !job->result.success) {
    // The targets' orientation kept too few points to orient the pair (or
    // a wrong one, from targets on one wall): all of them, as without
    // targets.
    report.anchored_by_targets = false;
    job->result = EstimateRelativeOrientation(points, estimation);
  } else if (anchored) {
    // Back to the conjugate points' order; those left out are blunders.
    std::vector<int> kept_rows;
    std::vector<uint8_t> inliers;
    for (size_t k = 0; k < kept.size(); ++k) {
      kept_rows.push_back(rows[kept[k]]);
      if (!job->result.inliers.empty()) {
        inliers.push_back(job->result.inliers[k]);
      }
    }
    rows = std::move(kept_rows);
    job->result.inliers = std::move(inliers);
  }
  const RelativeOrientation& result = job->result;
  job->row_inliers.assign(job->matches.rows(), 0);
  if (!result.inliers.empty()) {
    for (size_t k = 0; k < rows.size(); ++k) {
      job->row_inliers[rows[k]] = result.inliers[k];
    }
  }
  report.oriented = result.success;
  report.reason = result.reason;
  report.num_inliers = result.num_inliers;
  report.num_blunders = report.num_matches - result.num_inliers;
  report.sigma0_px = result.sigma0_px;
  report.convergence_angle_deg = result.convergence_angle_deg;
  report.median_intersection_angle_deg = result.median_intersection_angle_deg;
  report.omega_phi_kappa_deg = result.omega_phi_kappa_deg;
  report.std_omega_phi_kappa_deg = result.std_omega_phi_kappa_deg;
  report.std_base_deg = result.std_base_deg;
  report.cam2_from_cam1 = result.Cam2FromCam1();
  report.seconds = timer.Seconds();
}

void WritePair(Database* database,
               const std::map<camera_t, Camera>& colmap_cameras,
               const std::map<image_t, camera_t>& camera_of_image,
               const RelativeOptions& options,
               const PairJob& job) {
  const PairOrientationReport& report = job.report;
  const RelativeOrientation& result = job.result;
  const image_t id1 = report.image_id1, id2 = report.image_id2;
  // What an earlier run found for this pair no longer stands.
  database->DeleteTwoViewGeometry(id1, id2);
  RelativeOrientationRecord record;
  record.success = result.success;
  record.reason = result.reason;
  record.calibrated = report.calibrated;
  record.assume_zero_distortion = options.assume_zero_distortion;
  record.num_matches = report.num_matches;
  record.num_inliers = result.num_inliers;
  record.num_blunders = report.num_blunders;
  record.omega_phi_kappa_deg = result.omega_phi_kappa_deg;
  record.std_omega_phi_kappa_deg = result.std_omega_phi_kappa_deg;
  record.base = result.base;
  record.std_base_deg = result.std_base_deg;
  record.sigma0_px = result.sigma0_px;
  record.robust_sigma_px = result.lmeds_sigma_px;
  record.convergence_angle_deg = result.convergence_angle_deg;
  record.median_intersection_angle_deg = result.median_intersection_angle_deg;
  record.num_iterations = result.num_iterations;
  record.L = result.L;
  record.covariance = result.covariance;
  record.cam2_from_cam1 = report.cam2_from_cam1;
  record.inliers = job.row_inliers;
  record.seconds = report.seconds;
  WriteRelativeOrientation(database, id1, id2, record);
  if (!result.success) return;

  TwoViewGeometry geometry =
      TwoViewGeometryFromPoses(colmap_cameras.at(camera_of_image.at(id1)),
                               Rigid3d(),
                               colmap_cameras.at(camera_of_image.at(id2)),
                               report.cam2_from_cam1);
  geometry.config = report.calibrated ? TwoViewConfig::kCalibrated
                                      : TwoViewConfig::kUncalibrated;
  geometry.inlier_matches.resize(result.num_inliers, 2);
  int k = 0;
  for (int row = 0; row < job.matches.rows(); ++row) {
    if (!job.row_inliers[row]) continue;
    geometry.inlier_matches.row(k++) = job.matches.row(row);
  }
  geometry.inlier_matches.conservativeResize(k, 2);
  database->WriteTwoViewGeometry(id1, id2, geometry);
}

void LogPair(const PairOrientationReport& report) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(3) << report.name1 << " - "
       << report.name2 << ": ";
  if (report.skipped) {
    line << "skipped, " << report.reason;
    LOG(INFO) << line.str();
    return;
  }
  line << report.num_matches << " matches"
       << (report.subpixel ? " (sub-pixel)" : "") << ", " << report.num_inliers
       << " inliers, " << report.num_blunders << " blunders";
  if (report.num_target_points > 0) {
    line << ", " << report.num_target_points << " coded targets"
         << (report.anchored_by_targets ? " (oriented from them first)" : "");
  }
  if (report.oriented) {
    line << ", sigma0 " << report.sigma0_px << " px, omega/phi/kappa "
         << report.omega_phi_kappa_deg.transpose() << " deg (+- "
         << report.std_omega_phi_kappa_deg.transpose() << "), base +- "
         << report.std_base_deg.norm() << " deg, convergence "
         << report.convergence_angle_deg << " deg, "
         << (report.calibrated ? "calibrated" : "uncalibrated") << ", "
         << report.seconds << " s";
    LOG(INFO) << line.str();
  } else {
    line << " -- not oriented: " << report.reason;
    LOG(WARNING) << line.str();
  }
}

// Estimates the focal length of every camera whose images' vectors are
// not calibrated and that took a pair to orient (see the header), writes it
// to the cameras table and renews those images' vectors.
std::vector<FocalLengthReport> EstimateUnknownFocalLengths(
    Database* database,
    const std::map<image_t, camera_t>& camera_of_image,
    const std::vector<PairJob>& jobs,
    const std::map<image_t, FeatureKeypoints>& keypoints,
    const RelativeOptions& options,
    std::map<camera_t, Camera>* cameras,
    std::map<image_t, ImageVectors>* vectors) {
  // Each uncalibrated camera's pairs to orient, strongest first.
  std::map<camera_t, std::vector<const PairJob*>> pairs_of_camera;
  for (const PairJob& job : jobs) {
    const image_t id1 = job.report.image_id1, id2 = job.report.image_id2;
    if (job.matches.rows() == 0 || !camera_of_image.count(id1) ||
        !camera_of_image.count(id2)) {
      continue;
    }
    const camera_t camera_id = camera_of_image.at(id1);
    if (camera_of_image.at(id2) != camera_id || vectors->at(id1).calibrated()) {
      continue;
    }
    pairs_of_camera[camera_id].push_back(&job);
  }
  std::vector<FocalLengthReport> reports;
  for (auto& [camera_id, pairs] : pairs_of_camera) {
    Timer timer;
    std::sort(pairs.begin(), pairs.end(), [](const auto* a, const auto* b) {
      return a->matches.rows() > b->matches.rows();
    });
    if (static_cast<int>(pairs.size()) > options.focal_max_num_pairs) {
      pairs.resize(options.focal_max_num_pairs);
    }
    std::vector<ConjugatePoints> points;
    for (const PairJob* job : pairs) {
      const image_t id1 = job->report.image_id1, id2 = job->report.image_id2;
      std::vector<int> rows;
      points.push_back(PairConjugatePoints(
          keypoints.at(id1),
          keypoints.at(id2),
          job->matches,
          options.use_subpixel_points ? job->match_record : std::nullopt,
          vectors->at(id1),
          vectors->at(id2),
          &rows));
    }
    Camera& camera = cameras->at(camera_id);
    FocalLengthReport report;
    report.camera_id = camera_id;
    report.guess_px = camera.MeanFocalLengthPx();
    FocalLengthOptions focal = options.focal;
    focal.num_threads = options.num_threads;
    report.estimate = EstimateFocalLength(
        points,
        static_cast<double>(std::max(camera.width, camera.height)),
        focal);
    report.seconds = timer.Seconds();
    for (const auto& [f, score] : report.estimate.grid) {
      VLOG(1) << "focal " << f << " px: score " << score;
    }
    if (report.estimate.success) {
      for (int idx : camera.ModelInfo().focal_idxs) {
        camera.params[idx] = report.estimate.focal_length_px;
      }
      camera.has_prior_focal_length = true;
      database->UpdateCamera(camera);
      // What ImageVectors::FromDatabase now reads for these images: the
      // COLMAP camera (there is no calibration row), its focal length known.
      const ImageVectors renewed(
          camera, std::nullopt, true, options.assume_zero_distortion);
      for (const auto& [image_id, image_camera] : camera_of_image) {
        if (image_camera == camera_id) vectors->at(image_id) = renewed;
      }
      LOG(INFO) << std::fixed << std::setprecision(1) << "Camera " << camera_id
                << ": focal length " << report.estimate.focal_length_px
                << " px (+- " << 100 * report.estimate.relative_sigma
                << " %) from the photographs (" << report.estimate.num_pairs
                << " pairs, " << report.estimate.num_points
                << " points; the guess was " << report.guess_px << " px), "
                << std::setprecision(2) << report.seconds << " s";
    } else {
      LOG(WARNING) << "Camera " << camera_id
                   << ": the focal length stays the guess (" << report.guess_px
                   << " px): " << report.estimate.reason;
    }
    reports.push_back(std::move(report));
  }
  return reports;
}

// Why no pair could be oriented: the pair with the most matches and what
// stopped it. With nothing oriented there is no model to build, and most
// often the photographs do not overlap.
std::string NoPairOrientedReason(
    const std::vector<PairOrientationReport>& pairs) {
  const auto best = std::max_element(
      pairs.begin(),
      pairs.end(),
      [](const PairOrientationReport& a, const PairOrientationReport& b) {
        return a.num_matches < b.num_matches;
      });
  return StrCat("none of the ",
                pairs.size(),
                " matched image pairs could be oriented; the best, ",
                best->name1,
                " - ",
                best->name2,
                ", ",
                best->num_matches,
                " matches: ",
                best->reason,
                ". Do the photographs overlap?");
}

}  // namespace

RelativeSummary OrientImagePairs(const std::string& database_path,
                                 const RelativeOptions& options) {
  options.Check();
  CheckFileExists(database_path, "database_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  database.CheckWritable("two_view_geometries");
  const std::vector<DatabaseImage> images = database.ReadAllImages();
  if (images.empty()) {
    ThrowInputError(database_path,
                    ": the database has no images (run `bayon import`, "
                    "`bayon features` and `bayon match` first)");
  }
  std::vector<std::pair<pair_t, FeatureMatches>> matched;
  for (auto& [pair_id, matches] : database.ReadAllMatches()) {
    if (matches.rows() > 0) matched.emplace_back(pair_id, std::move(matches));
  }
  if (matched.empty()) {
    ThrowInputError(database_path,
                    ": no matched image pairs (run `bayon match` first; if "
                    "it ran, no two photographs overlap)");
  }
  std::map<image_t, std::string> names;
  std::map<image_t, camera_t> camera_of_image;
  std::map<image_t, ImageVectors> vectors;
  std::map<image_t, FeatureKeypoints> keypoints;
  std::map<camera_t, Camera> colmap_cameras;
  for (const Camera& camera : database.ReadAllCameras()) {
    colmap_cameras.emplace(camera.camera_id, camera);
  }
  for (const DatabaseImage& image : images) {
    names[image.image_id] = image.name;
    camera_of_image[image.image_id] = image.camera_id;
    if (!colmap_cameras.count(image.camera_id)) {
      ThrowInputError(database_path,
                      ": image ",
                      image.name,
                      " refers to camera ",
                      image.camera_id,
                      ", which is not in the cameras table");
    }
    vectors.emplace(image.image_id,
                    ImageVectors::FromDatabase(
                        &database, image, options.assume_zero_distortion));
  }

  std::vector<PairJob> jobs;
  std::map<image_t, std::set<uint32_t>> target_rows;  // coded targets
  for (auto& [pair_id, matches] : matched) {
    const auto [id1, id2] = ImageIdsFromPairId(pair_id);
    PairJob job;
    PairOrientationReport& report = job.report;
    report.image_id1 = id1;
    report.image_id2 = id2;
    report.name1 = names.count(id1) ? names[id1] : std::to_string(id1);
    report.name2 = names.count(id2) ? names[id2] : std::to_string(id2);
    report.num_matches = static_cast<int>(matches.rows());
    if (!names.count(id1) || !names.count(id2)) {
      report.reason = "matches of an image that is not in the images table";
    } else if (!options.overwrite &&
               (database.ExistsTwoViewGeometry(id1, id2) ||
                ReadRelativeOrientation(&database, id1, id2))) {
      report.skipped = true;
      report.reason = "oriented already (--overwrite 1 orients it again)";
    } else {
      for (image_t id : {id1, id2}) {
        if (keypoints.count(id)) continue;
        keypoints[id] = database.ReadKeypoints(id);
        target_rows[id] = KeypointTargetRows(
            &database, id, static_cast<int>(keypoints[id].rows()));
      }
      job.matches = std::move(matches);
      job.match_record = ReadMatchRecord(&database, id1, id2);
      if (!target_rows[id1].empty() && !target_rows[id2].empty()) {
        job.row_is_target.assign(job.matches.rows(), 0);
        for (int r = 0; r < job.matches.rows(); ++r) {
          job.row_is_target[r] = target_rows[id1].count(job.matches(r, 0)) &&
                                 target_rows[id2].count(job.matches(r, 1));
        }
      }
    }
    jobs.push_back(std::move(job));
  }

  RelativeSummary summary;
  if (options.estimate_focal_length) {
    summary.focal_lengths = EstimateUnknownFocalLengths(&database,
                                                        camera_of_image,
                                                        jobs,
                                                        keypoints,
                                                        options,
                                                        &colmap_cameras,
                                                        &vectors);
  }

  std::vector<int> todo;
  for (int i = 0; i < static_cast<int>(jobs.size()); ++i) {
    if (!jobs[i].report.skipped && jobs[i].report.reason.empty()) {
      todo.push_back(i);
    }
  }
  Progress progress("Relative orientation", todo.size(), "pairs");
  ParallelBatches(
      static_cast<int>(todo.size()),
      options.num_threads,
      [&](int k) {
        OrientPair(keypoints, vectors, options, &jobs[todo[k]]);
        progress.Add();
      },
      [&](int begin, int end) {
        auto transaction = database.BeginTransaction();
        for (int k = begin; k < end; ++k) {
          WritePair(&database,
                    colmap_cameras,
                    camera_of_image,
                    options,
                    jobs[todo[k]]);
        }
        transaction.Commit();
      });
  progress.Finish();

  for (const PairJob& job : jobs) {
    LogPair(job.report);
    if (job.report.skipped) {
      ++summary.num_skipped;
    } else if (job.report.oriented) {
      ++summary.num_oriented;
    } else {
      ++summary.num_failed;
    }
    summary.pairs.push_back(job.report);
  }
  summary.seconds = timer.Seconds();
  if (summary.num_oriented + summary.num_skipped == 0) {
    ThrowInputError(database_path, ": ", NoPairOrientedReason(summary.pairs));
  }
  return summary;
}

}  // namespace bayon
