// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/disparity.h"

#include "ext/colmap/table_disparity.h"
#include "ext/colmap/table_matches.h"
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

void DisparityOptions::Register(OptionRegistry* r) {
  r->Add("use_subpixel_points",
         &use_subpixel_points,
         "1: use bayon_matches' sub-pixel conjugate points");
  surface.Register(r);
  r->Add("overwrite",
         &overwrite,
         "1: fit pairs that have a current surface again");
  r->Add("num_threads", &num_threads, "Threads (-1 = all cores)");
}

void DisparityOptions::Check() const { surface.Check(); }

std::string DisparitySummaryLine(const DisparitySummary& summary) {
  std::vector<double> bands, shares;
  int64_t num_used = 0, num_blunders = 0;
  for (const DisparityReport& report : summary.surfaces) {
    if (!report.fitted) continue;
    num_used += report.num_used;
    num_blunders += report.num_blunders;
    bands.push_back(report.median_band_px);
    if (report.median_range_px > 0) {
      shares.push_back(100 * report.median_band_px / report.median_range_px);
    }
  }
  const auto median = [](std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::nth_element(
        values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  return StrCat(summary.num_fitted,
                " surfaces fitted for ",
                summary.num_pairs,
                " oriented pairs (",
                num_used,
                " points used, ",
                num_blunders,
                " blunders; median band ",
                median(bands),
                " px, ",
                median(shares),
                " % of the epipolar line), ",
                summary.num_failed,
                " not fitted, ",
                summary.num_skipped,
                " skipped, ",
                summary.seconds,
                " s");
}

namespace {

struct SurfaceJob {
  DisparityReport report;
  ConjugatePoints points;
  Rigid3d cam2_from_cam1;
  bool assume_zero_distortion = false;
  const ImageVectors* vectors1 = nullptr;
  const ImageVectors* vectors2 = nullptr;
  DisparitySurfaceRecord record;
};

// The pair's inlier conjugate points in canonical order (image_id1 <
// image_id2): the two-view geometry's inlier matches, at the sub-pixel
// positions of bayon_matches where there are any.
ConjugatePoints InlierPoints(Database* database,
                             image_t id1,
                             image_t id2,
                             const FeatureKeypoints& keypoints1,
                             const FeatureKeypoints& keypoints2,
                             const ImageVectors& vectors1,
                             const ImageVectors& vectors2,
                             bool use_subpixel_points,
                             bool* subpixel) {
  const TwoViewGeometry geometry = database->ReadTwoViewGeometry(id1, id2);
  std::map<std::pair<uint32_t, uint32_t>, int> match_row;
  std::optional<MatchRecord> record;
  if (use_subpixel_points) record = ReadMatchRecord(database, id1, id2);
  if (record) {
    const FeatureMatches matches = database->ReadMatches(id1, id2);
    if (record->xy1.size() == static_cast<size_t>(matches.rows())) {
      for (int row = 0; row < matches.rows(); ++row) {
        match_row[{matches(row, 0), matches(row, 1)}] = row;
      }
    }
  }
  *subpixel = !match_row.empty();
  ConjugatePoints points;
  const FeatureMatches& inliers = geometry.inlier_matches;
  for (int k = 0; k < inliers.rows(); ++k) {
    const uint32_t idx1 = inliers(k, 0), idx2 = inliers(k, 1);
    if (idx1 >= keypoints1.rows() || idx2 >= keypoints2.rows()) continue;
    Eigen::Vector2d pixel1 = KeypointXY(keypoints1, idx1);
    Eigen::Vector2d pixel2 = KeypointXY(keypoints2, idx2);
    if (const auto it = match_row.find({idx1, idx2}); it != match_row.end()) {
      pixel1 = record->xy1[it->second].cast<double>();
      pixel2 = record->xy2[it->second].cast<double>();
    }
    Eigen::Vector3d u1, u2;
    if (!vectors1.FromPixel(pixel1, &u1) || !vectors2.FromPixel(pixel2, &u2)) {
      continue;
    }
    points.u1.push_back(u1);
    points.u2.push_back(u2);
    points.pixel1.push_back(pixel1);
    points.pixel2.push_back(pixel2);
  }
  return points;
}

ConjugatePoints Reversed(const ConjugatePoints& points) {
  ConjugatePoints reversed;
  reversed.u1 = points.u2;
  reversed.u2 = points.u1;
  reversed.pixel1 = points.pixel2;
  reversed.pixel2 = points.pixel1;
  return reversed;
}

bool SameOrientation(const Rigid3d& a, const Rigid3d& b) {
  return RotationAngleBetween(a.rotation, b.rotation) <= 1e-9 &&
         (a.translation - b.translation).norm() <= 1e-9;
}

void FitJob(const DisparitySurfaceOptions& options, SurfaceJob* job) {
  const DisparitySurface surface = DisparitySurface::Fit(job->points,
                                                         job->cam2_from_cam1,
                                                         *job->vectors1,
                                                         *job->vectors2,
                                                         options);
  job->record = surface.record();
  job->record.assume_zero_distortion = job->assume_zero_distortion;
  const DisparitySurfaceRecord& r = job->record;
  DisparityReport& report = job->report;
  report.fitted = r.success;
  report.reason = r.reason;
  report.num_used = r.num_used;
  report.num_blunders = r.num_blunders;
  report.robust_sigma_px = r.robust_sigma_px;
  report.cv_sigma_px = r.cv_sigma_px;
  report.cv_coverage = r.cv_coverage;
  report.median_band_px = r.median_band_px;
  report.median_range_px = r.median_range_px;
  report.cols = r.cols;
  report.rows = r.rows;
  report.smoothness = r.smoothness;
  report.seconds = r.seconds;
}

void LogSurface(const DisparityReport& report) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(2) << report.name1 << " -> "
       << report.name2 << ": ";
  if (report.skipped) {
    line << "skipped, " << report.reason;
    LOG(INFO) << line.str();
    return;
  }
  line << report.num_points << " points"
       << (report.subpixel ? " (sub-pixel)" : "");
  if (!report.fitted) {
    line << " -- no surface: " << report.reason;
    LOG(WARNING) << line.str();
    return;
  }
  line << ", " << report.num_used << " used, " << report.num_blunders
       << " blunders, sigma " << report.robust_sigma_px << " px (predicted "
       << report.cv_sigma_px << " px), band " << report.median_band_px
       << " px of " << report.median_range_px << " px ("
       << (report.median_range_px > 0
               ? 100 * report.median_band_px / report.median_range_px
               : 0.0)
       << " %), " << report.cols << " x " << report.rows
       << " cells, smoothness " << report.smoothness << ", " << report.seconds
       << " s";
  LOG(INFO) << line.str();
}

struct OrientedPair {
  image_t id1 = kInvalidImageId;
  image_t id2 = kInvalidImageId;
  PairOrientation orientation;
};

// The oriented pairs: bayon's orientations, and COLMAP's posed geometries,
// each as it was oriented; InputError when there are none.
std::vector<OrientedPair> OrientedPairs(
    Database* database,
    const std::map<image_t, const DatabaseImage*>& image_of,
    const std::string& database_path) {
  std::set<pair_t> pair_ids;
  for (const auto& [pair_id, record] : ReadAllRelativeOrientations(database)) {
    if (record.success) pair_ids.insert(pair_id);
  }
  for (const auto& [pair_id, geometry] : database->ReadAllTwoViewGeometries()) {
    if (geometry.inlier_matches.rows() > 0 && geometry.qvec && geometry.tvec) {
      pair_ids.insert(pair_id);
    }
  }
  std::vector<OrientedPair> pairs;
  for (pair_t pair_id : pair_ids) {
    const auto [id1, id2] = ImageIdsFromPairId(pair_id);
    if (!image_of.count(id1) || !image_of.count(id2)) continue;
    if (!database->ExistsTwoViewGeometry(id1, id2)) continue;
    const auto orientation = ReadPairOrientation(database, id1, id2);
    if (!orientation) continue;
    pairs.push_back({id1, id2, *orientation});
  }
  if (pairs.empty()) {
    ThrowInputError(database_path,
                    ": no oriented image pairs (two_view_geometries with a "
                    "relative pose; run `bayon relative` first)");
  }
  return pairs;
}

// Each surface logged and counted.
DisparitySummary Summarize(const std::vector<SurfaceJob>& jobs) {
  DisparitySummary summary;
  for (const SurfaceJob& job : jobs) {
    LogSurface(job.report);
    if (job.report.skipped) {
      ++summary.num_skipped;
    } else if (job.report.fitted) {
      ++summary.num_fitted;
    } else {
      ++summary.num_failed;
    }
    summary.surfaces.push_back(job.report);
  }
  return summary;
}

}  // namespace

DisparitySummary FitDisparitySurfaces(const std::string& database_path,
                                      const DisparityOptions& options) {
  options.Check();
  CheckFileExists(database_path, "database_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  const std::vector<DatabaseImage> images = database.ReadAllImages();
  if (images.empty()) {
    ThrowInputError(database_path,
                    ": the database has no images (run `bayon import`, "
                    "`bayon features`, `bayon match` and `bayon relative` "
                    "first)");
  }
  std::map<image_t, const DatabaseImage*> image_of;
  for (const DatabaseImage& image : images) image_of[image.image_id] = &image;

  const std::vector<OrientedPair> pairs =
      OrientedPairs(&database, image_of, database_path);

  // Interior orientations, as each pair was oriented.
  std::map<std::pair<image_t, bool>, ImageVectors> vectors;
  const auto vectors_of = [&](image_t id, bool zero) -> const ImageVectors& {
    auto it = vectors.find({id, zero});
    if (it == vectors.end()) {
      it = vectors
               .emplace(std::make_pair(id, zero),
                        ImageVectors::FromDatabase(
                            &database, *image_of.at(id), zero))
               .first;
    }
    return it->second;
  };
  std::map<image_t, FeatureKeypoints> keypoints;
  const auto keypoints_of = [&](image_t id) -> const FeatureKeypoints& {
    auto it = keypoints.find(id);
    if (it == keypoints.end()) {
      it = keypoints.emplace(id, database.ReadKeypoints(id)).first;
    }
    return it->second;
  };
  const auto existing = ReadAllDisparitySurfaces(&database);

  std::vector<SurfaceJob> jobs;
  for (size_t p = 0; p < pairs.size(); ++p) {
    const image_t id1 = pairs[p].id1, id2 = pairs[p].id2;
    const PairOrientation& orientation = pairs[p].orientation;
    const bool zero = orientation.assume_zero_distortion;
    const ImageVectors& v1 = vectors_of(id1, zero);
    const ImageVectors& v2 = vectors_of(id2, zero);
    // Both directions; points are read only when one is to be fitted.
    std::optional<ConjugatePoints> points;
    bool subpixel = false;
    for (const bool reverse : {false, true}) {
      SurfaceJob job;
      DisparityReport& report = job.report;
      report.image_id1 = reverse ? id2 : id1;
      report.image_id2 = reverse ? id1 : id2;
      report.name1 = image_of.at(report.image_id1)->name;
      report.name2 = image_of.at(report.image_id2)->name;
      job.cam2_from_cam1 = orientation.cam2_from_cam1;
      if (reverse) {
        job.cam2_from_cam1 = job.cam2_from_cam1.Inverse();
        job.cam2_from_cam1.translation.normalize();
      }
      job.assume_zero_distortion = zero;
      job.vectors1 = reverse ? &v2 : &v1;
      job.vectors2 = reverse ? &v1 : &v2;
      const auto before = existing.find({report.image_id1, report.image_id2});
      if (!options.overwrite && before != existing.end() &&
          before->second.assume_zero_distortion == zero &&
          SameOrientation(before->second.cam2_from_cam1, job.cam2_from_cam1)) {
        report.skipped = true;
        report.num_points = before->second.num_points;
        report.reason = before->second.success
                            ? "fitted already (--overwrite 1 fits it again)"
                            : StrCat("failed before (",
                                     before->second.reason,
                                     "; --overwrite 1 tries again)");
        jobs.push_back(std::move(job));
        continue;
      }
      if (!points) {
        points = InlierPoints(&database,
                              id1,
                              id2,
                              keypoints_of(id1),
                              keypoints_of(id2),
                              v1,
                              v2,
                              options.use_subpixel_points,
                              &subpixel);
      }
      job.points = reverse ? Reversed(*points) : *points;
      report.subpixel = subpixel;
      report.num_points = job.points.size();
      jobs.push_back(std::move(job));
    }
  }

  std::vector<int> todo;
  for (int i = 0; i < static_cast<int>(jobs.size()); ++i) {
    if (!jobs[i].report.skipped) todo.push_back(i);
  }
  Progress progress("Disparity surfaces", todo.size(), "surfaces");
  ParallelBatches(
      static_cast<int>(todo.size()),
      options.num_threads,
      [&](int k) {
        FitJob(options.surface, &jobs[todo[k]]);
        progress.Add();
      },
      [&](int begin, int end) {
        auto transaction = database.BeginTransaction();
        for (int k = begin; k < end; ++k) {
          SurfaceJob& job = jobs[todo[k]];
          WriteDisparitySurface(&database,
                                job.report.image_id1,
                                job.report.image_id2,
                                job.record);
          job.points = ConjugatePoints();
        }
        transaction.Commit();
      });
  progress.Finish();

  DisparitySummary summary = Summarize(jobs);
  summary.num_pairs = static_cast<int>(pairs.size());
  summary.seconds = timer.Seconds();
  return summary;
}

}  // namespace bayon
