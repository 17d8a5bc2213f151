// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/matching.h"

#include "ext/colmap/database.h"
#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

void MatchingOptions::Check() const {
  pairing.Check();
  patches.Check();
  correlation.Check();
  refinement.Check();
  const std::string shift_rule =
      StrCat("< patches.refine_radius (", patches.refine_radius, ")");
  CheckOption(correlation.max_keypoint_shift_px < patches.refine_radius,
              "MatchingOptions.correlation.max_keypoint_shift_px",
              shift_rule.c_str(),
              correlation.max_keypoint_shift_px);
  CheckOption(min_num_matches >= 8,
              "MatchingOptions.min_num_matches",
              ">= 8 (the relative orientation needs 8 points)",
              min_num_matches);
}

namespace {

struct ImageData {
  DatabaseImage image;
  std::string path;
  int num_keypoints = 0;
  std::unique_ptr<ImagePatches> patches;
  cv::Mat gray;  // for the least-squares refinement
};

std::map<image_t, ImageData> ReadImageList(Database* database,
                                           const std::string& image_path) {
  const std::vector<DatabaseImage> images = database->ReadAllImages();
  if (images.empty()) {
    ThrowInputError(database->path(),
                    ": the database has no images (run `bayon import` and "
                    "`bayon features` first)");
  }
  std::map<image_t, ImageData> data;
  int num_with_keypoints = 0;
  for (const DatabaseImage& image : images) {
    ImageData& entry = data[image.image_id];
    entry.image = image;
    entry.path = (fs::path(image_path) / image.name).string();
    if (database->ExistsKeypoints(image.image_id)) {
      entry.num_keypoints =
          static_cast<int>(database->ReadKeypoints(image.image_id).rows());
    }
    num_with_keypoints += entry.num_keypoints > 0;
  }
  if (num_with_keypoints == 0) {
    ThrowInputError(database->path(),
                    ": no image has keypoints (run `bayon features` first)");
  }
  return data;
}

// Every image a pair needs must be on disk with its camera's size.
void CheckImageFiles(Database* database,
                     const std::string& image_path,
                     const std::map<image_t, ImageData>& data,
                     const std::set<image_t>& needed) {
  std::map<camera_t, Camera> cameras;
  for (const Camera& camera : database->ReadAllCameras()) {
    cameras.emplace(camera.camera_id, camera);
  }
  std::vector<ExpectedImage> expected;
  for (image_t image_id : needed) {
    const DatabaseImage& image = data.at(image_id).image;
    const auto camera = cameras.find(image.camera_id);
    expected.push_back(
        {image.name,
         camera == cameras.end() ? 0 : static_cast<int>(camera->second.width),
         camera == cameras.end() ? 0
                                 : static_cast<int>(camera->second.height)});
  }
  CheckImagesOnDisk(image_path, expected, database->path());
}

struct PairJob {
  PairMatchReport report;
  PairMatches matches;
};

void MatchPair(const std::map<image_t, ImageData>& data,
               const MatchingOptions& options,
               PairJob* job) {
  Timer timer;
  PairMatchReport& report = job->report;
  const ImagePatches& image1 = *data.at(report.image_id1).patches;
  const ImagePatches& image2 = *data.at(report.image_id2).patches;
  const int valid1 = image1.NumValid(), valid2 = image2.NumValid();
  if (std::min(valid1, valid2) < options.min_num_matches) {
    report.reason = StrCat("too few points to match (",
                           valid1,
                           " and ",
                           valid2,
                           " usable keypoints, ",
                           options.min_num_matches,
                           " needed)");
    report.seconds = timer.Seconds();
    return;
  }
  job->matches = MatchImagePatches(image1, image2, options.correlation);
  if (options.lsm_refinement) {
    report.refinement = RefineConjugatePoints(data.at(report.image_id1).gray,
                                              data.at(report.image_id2).gray,
                                              image1.xy,
                                              image2.xy,
                                              options.refinement,
                                              &job->matches);
  }
  const PairMatches& matches = job->matches;
  report.rotation_deg = matches.mapping.RotationDeg();
  report.mapping_found = matches.mapping.found;
  report.mapping_inliers = matches.mapping.num_inliers;
  report.num_candidates = matches.num_candidates;
  report.num_relaxed = matches.num_relaxed;
  report.num_matches = static_cast<int>(matches.matches.rows());
  if (report.num_matches < options.min_num_matches) {
    report.reason = StrCat("too few matches (",
                           report.num_matches,
                           " < ",
                           options.min_num_matches,
                           ")");
  }
  report.seconds = timer.Seconds();
}

void WritePair(Database* database,
               const MatchingOptions& options,
               const PairJob& job) {
  const PairMatchReport& report = job.report;
  if (options.overwrite) {
    DeletePairResults(database, report.image_id1, report.image_id2);
  }
  database->WriteMatches(
      report.image_id1, report.image_id2, job.matches.matches);
  MatchRecord record;
  record.rotation_deg = report.rotation_deg;
  record.mapping_found = report.mapping_found;
  record.affine = job.matches.mapping.affine;
  record.num_candidates = report.num_candidates;
  record.seconds = report.seconds;
  for (size_t k = 0; k < job.matches.refined_xy2.size(); ++k) {
    record.xy1.push_back(job.matches.reference_xy1[k].cast<float>());
    record.xy2.push_back(job.matches.refined_xy2[k].cast<float>());
    record.ncc.push_back(job.matches.ncc[k]);
    record.sigma_px.push_back(job.matches.sigma_px[k]);
  }
  WriteMatchRecord(database, report.image_id1, report.image_id2, record);
}

void LogPair(const MatchingOptions& options, const PairMatchReport& report) {
  std::ostringstream line;
  line << report.name1 << " - " << report.name2 << ": ";
  if (report.skipped) {
    line << "skipped, " << report.reason;
  } else {
    line << report.num_points1 << "/" << report.num_points2 << " points, "
         << "rotation " << report.rotation_deg << " deg ("
         << (report.mapping_found ? "" : "no ") << "global mapping, "
         << report.mapping_inliers << " votes), " << report.num_candidates
         << " candidates, " << report.num_relaxed << " after relaxation, ";
    if (options.lsm_refinement) {
      const ConjugateRefinementReport& lsm = report.refinement;
      line << lsm.NumRejected() << " not refined by LSM (";
      for (int k = 0; k < kNumObservationOutcomes; ++k) {
        if (lsm.num_rejected[k] == 0) continue;
        line << ObservationOutcomeName(static_cast<ObservationOutcome>(k))
             << " " << lsm.num_rejected[k] << ", ";
      }
      line << "median move " << lsm.median_shift_px << " px), "
           << lsm.num_propagated << " propagated, ";
    }
    line << report.num_matches << " matches, " << report.seconds << " s";
    if (!report.written) line << " -- not written: " << report.reason;
  }
  if (report.written || report.skipped) {
    LOG(INFO) << line.str();
  } else {
    LOG(WARNING) << line.str();
  }
}

}  // namespace

MatchingSummary MatchImages(const std::string& database_path,
                            const std::string& image_path,
                            const MatchingOptions& options) {
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  database.CheckWritable("matches");
  std::map<image_t, ImageData> data = ReadImageList(&database, image_path);
  std::vector<DatabaseImage> images;
  for (const auto& [image_id, entry] : data) images.push_back(entry.image);
  const std::vector<std::pair<image_t, image_t>> pairs =
      SelectImagePairs(images, options.pairing);

  MatchingSummary summary;
  std::vector<PairJob> jobs;
  std::set<image_t> needed;
  for (const auto& [id1, id2] : pairs) {
    PairJob job;
    PairMatchReport& report = job.report;
    report.image_id1 = id1;
    report.image_id2 = id2;
    report.name1 = data.at(id1).image.name;
    report.name2 = data.at(id2).image.name;
    report.num_points1 = data.at(id1).num_keypoints;
    report.num_points2 = data.at(id2).num_keypoints;
    if (!options.overwrite && database.ExistsMatches(id1, id2)) {
      report.skipped = true;
      report.reason = "has matches (--overwrite 1 replaces them)";
    } else if (report.num_points1 == 0 || report.num_points2 == 0) {
      report.reason =
          StrCat("no keypoints in ",
                 report.num_points1 == 0 ? report.name1 : report.name2,
                 " (run `bayon features`)");
    } else {
      needed.insert(id1);
      needed.insert(id2);
    }
    jobs.push_back(std::move(job));
  }
  CheckImageFiles(&database, image_path, data, needed);

  // Every image is read once and cut into windows; the pairs then share them.
  const std::vector<image_t> needed_ids(needed.begin(), needed.end());
  {
    std::vector<FeatureKeypoints> keypoints;
    for (image_t image_id : needed_ids) {
      keypoints.push_back(database.ReadKeypoints(image_id));
    }
    Progress progress("Reading images", needed_ids.size(), "images");
    ParallelFor(needed_ids.size(), options.num_threads, [&](int k) {
      ImageData& entry = data.at(needed_ids[k]);
      std::vector<Eigen::Vector2d> xy(keypoints[k].rows());
      for (int i = 0; i < keypoints[k].rows(); ++i) {
        xy[i] = KeypointXY(keypoints[k], i);
      }
      cv::Mat gray = ReadImageGrayFloat(entry.path);
      entry.patches = std::make_unique<ImagePatches>(
          ExtractImagePatches(gray, xy, options.patches));
      if (options.lsm_refinement) entry.gray = std::move(gray);
      progress.Add();
    });
    progress.Finish();
  }

  std::vector<int> todo;
  for (int i = 0; i < static_cast<int>(jobs.size()); ++i) {
    if (!jobs[i].report.skipped && jobs[i].report.reason.empty()) {
      todo.push_back(i);
    }
  }
  Progress progress("Matching image pairs", todo.size(), "pairs");
  ParallelBatches(
      static_cast<int>(todo.size()),
      options.num_threads,
      [&](int k) {
        MatchPair(data, options, &jobs[todo[k]]);
        progress.Add();
      },
      [&](int begin, int end) {
        auto transaction = database.BeginTransaction();
        for (int k = begin; k < end; ++k) {
          PairJob& job = jobs[todo[k]];
          if (!job.report.reason.empty()) {
            // What an earlier run found for this pair no longer stands.
            if (options.overwrite) {
              DeletePairResults(
                  &database, job.report.image_id1, job.report.image_id2);
            }
            continue;
          }
          WritePair(&database, options, job);
          job.report.written = true;
        }
        transaction.Commit();
      });
  progress.Finish();

  for (const PairJob& job : jobs) {
    LogPair(options, job.report);
    if (job.report.skipped) {
      ++summary.num_skipped;
    } else if (job.report.written) {
      ++summary.num_written;
      summary.num_matches += job.report.num_matches;
    } else {
      ++summary.num_failed;
    }
    summary.pairs.push_back(job.report);
  }
  summary.seconds = timer.Seconds();
  return summary;
}

}  // namespace bayon
