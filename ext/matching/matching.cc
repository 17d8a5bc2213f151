// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/matching.h"

#include "ext/colmap/database.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

void MatchingOptions::Register(OptionRegistry* r) {
  r->AddNested("pairing", &pairing);
  r->AddNested("retrieval", &retrieval);
  r->AddNested("patches", &patches);
  r->AddNested("correlation", &correlation);
  r->AddNested("descriptors", &descriptors);
  r->Add("lsm_refinement",
         &lsm_refinement,
         "1: conjugate points refined by least-squares matching");
  r->AddNested("refinement", &refinement);
  r->Add("min_num_matches",
         &min_num_matches,
         "Pairs with fewer matches are not written");
  r->Add("overwrite", &overwrite, "1: replace existing matches of a pair");
  r->Add("num_threads", &num_threads, "Threads (-1 = all cores)");
}

void MatchingOptions::Check() const {
  CheckNested("pairing", pairing);
  CheckNested("retrieval", retrieval);
  CheckNested("patches", patches);
  CheckNested("correlation", correlation);
  CheckNested("descriptors", descriptors);
  CheckNested("refinement", refinement);
  const std::string shift_rule =
      StrCat("< patches.refine_radius (", patches.refine_radius, ")");
  CheckOption(correlation.max_keypoint_shift_px < patches.refine_radius,
              "correlation.max_keypoint_shift_px",
              shift_rule.c_str(),
              correlation.max_keypoint_shift_px);
  CheckOption(min_num_matches >= 8,
              "min_num_matches",
              ">= 8 (the relative orientation needs 8 points)",
              min_num_matches);
}

namespace {

struct ImageData {
  DatabaseImage image;
  std::string path;
  FeatureKeypoints keypoints;
  // Of the images a pair needs: which keypoint rows are matched by
  // correlation (their windows in `patches`) and which by descriptor.
  std::vector<uint8_t> by_correlation;
  FeatureDescriptors descriptors;  // empty, or a row per keypoint
  std::vector<int> descriptor_rows;
  std::vector<KeypointTarget> targets;  // matched by name
  std::unique_ptr<ImagePatches> patches;
  cv::Mat gray;  // for the least-squares refinement
};

// A keypoint with a Moravec interest value is matched by correlation; one
// without (NaN in bayon_keypoint_interest: bayon's SIFT keypoints) by its
// descriptor. An image without an interest record (another detector's
// keypoints) is matched by descriptor if it has descriptors, else by
// correlation.
void ClassifyKeypoints(Database* database, ImageData* entry) {
  const image_t image_id = entry->image.image_id;
  const int n = static_cast<int>(entry->keypoints.rows());
  if (database->ExistsDescriptors(image_id)) {
    FeatureDescriptors descriptors = database->ReadDescriptors(image_id);
    if (descriptors.rows() == n && descriptors.cols() == 128) {
      entry->descriptors = std::move(descriptors);
    }
  }
  const bool has_descriptors = entry->descriptors.rows() > 0;
  const std::optional<KeypointInterestRecord> record =
      ReadKeypointInterest(database, image_id);
  const bool has_interest =
      record && record->interest.size() == static_cast<size_t>(n);
  entry->targets = ReadKeypointTargets(database, image_id, n);
  std::vector<uint8_t> is_target(n, 0);
  for (const KeypointTarget& target : entry->targets) {
    is_target[target.point2D_idx] = 1;
  }
  entry->by_correlation.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    if (is_target[i]) continue;
    const bool correlate =
        has_interest ? std::isfinite(record->interest[i]) : !has_descriptors;
    if (correlate) {
      entry->by_correlation[i] = 1;
    } else if (has_descriptors) {
      entry->descriptor_rows.push_back(i);
    }
  }
}

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
      entry.keypoints = database->ReadKeypoints(image.image_id);
    }
    num_with_keypoints += entry.keypoints.rows() > 0;
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

// A SIFT keypoint is located to about a correlation peak's precision at
// the pyramid's base scale (sigma 1.6 px), and proportionally less
// precisely at coarser scales, whose samples are proportionally farther
// apart.
constexpr double kSiftBaseScale = 1.6;

void AddDescriptorMatches(const ImageData& image1,
                          const ImageData& image2,
                          const MatchingOptions& options,
                          PairMatches* matches) {
  const std::vector<DescriptorMatch> found =
      MatchDescriptors(image1.descriptors,
                       image1.descriptor_rows,
                       image2.descriptors,
                       image2.descriptor_rows,
                       options.descriptors);
  const int first = static_cast<int>(matches->matches.rows());
  matches->matches.conservativeResize(first + found.size(), 2);
  for (size_t k = 0; k < found.size(); ++k) {
    const DescriptorMatch& match = found[k];
    matches->matches(first + k, 0) = static_cast<uint32_t>(match.idx1);
    matches->matches(first + k, 1) = static_cast<uint32_t>(match.idx2);
    matches->reference_xy1.push_back(KeypointXY(image1.keypoints, match.idx1));
    matches->refined_xy2.push_back(KeypointXY(image2.keypoints, match.idx2));
    // The descriptors' cosine in place of a correlation coefficient.
    matches->ncc.push_back(std::cos(match.distance));
    const double scale = std::max(KeypointScale(image1.keypoints, match.idx1),
                                  KeypointScale(image2.keypoints, match.idx2));
    matches->sigma_px.push_back(
        static_cast<float>(options.correlation.peak_sigma_px *
                           std::max(1.0, scale / kSiftBaseScale)));
  }
}

// The coded targets both images show, matched by name: their decoding is
// their identification. Their sigma is the less precise measurement's.
void AddTargetMatches(const ImageData& image1,
                      const ImageData& image2,
                      PairMatches* matches) {
  std::map<std::string, const KeypointTarget*> in_image2;
  for (const KeypointTarget& target : image2.targets) {
    in_image2[target.name] = &target;
  }
  for (const KeypointTarget& target1 : image1.targets) {
    const auto found = in_image2.find(target1.name);
    if (found == in_image2.end()) continue;
    const KeypointTarget& target2 = *found->second;
    const int row = static_cast<int>(matches->matches.rows());
    matches->matches.conservativeResize(row + 1, 2);
    matches->matches(row, 0) = target1.point2D_idx;
    matches->matches(row, 1) = target2.point2D_idx;
    matches->reference_xy1.push_back(
        KeypointXY(image1.keypoints, target1.point2D_idx));
    matches->refined_xy2.push_back(
        KeypointXY(image2.keypoints, target2.point2D_idx));
    matches->ncc.push_back(1);
    matches->sigma_px.push_back(std::max(target1.sigma_px, target2.sigma_px));
  }
}

void MatchPair(const std::map<image_t, ImageData>& data,
               const MatchingOptions& options,
               PairJob* job) {
  Timer timer;
  PairMatchReport& report = job->report;
  const ImageData& data1 = data.at(report.image_id1);
  const ImageData& data2 = data.at(report.image_id2);
  const ImagePatches& image1 = *data1.patches;
  const ImagePatches& image2 = *data2.patches;
  const int valid1 = image1.NumValid(), valid2 = image2.NumValid();
  const int described1 = static_cast<int>(data1.descriptor_rows.size());
  const int described2 = static_cast<int>(data2.descriptor_rows.size());
  const bool correlate = std::min(valid1, valid2) >= options.min_num_matches;
  const bool describe =
      std::min(described1, described2) >= options.min_num_matches;
  if (!correlate && !describe && data1.targets.empty()) {
    report.reason =
        StrCat("too few points to match (",
               valid1,
               " and ",
               valid2,
               " usable keypoints",
               described1 + described2 > 0 ? StrCat(" for correlation, ",
                                                    described1,
                                                    " and ",
                                                    described2,
                                                    " with descriptors")
                                           : std::string(),
               ", ",
               options.min_num_matches,
               " needed)");
    report.seconds = timer.Seconds();
    return;
  }
  if (correlate) {
    job->matches = MatchImagePatches(image1, image2, options.correlation);
  }
  if (correlate && options.lsm_refinement) {
    report.refinement = RefineConjugatePoints(data.at(report.image_id1).gray,
                                              data.at(report.image_id2).gray,
                                              image1.xy,
                                              image2.xy,
                                              options.refinement,
                                              &job->matches);
  }
  if (describe) {
    const int before = static_cast<int>(job->matches.matches.rows());
    AddDescriptorMatches(data1, data2, options, &job->matches);
    report.num_descriptor_matches =
        static_cast<int>(job->matches.matches.rows()) - before;
  }
  const int before_targets = static_cast<int>(job->matches.matches.rows());
  AddTargetMatches(data1, data2, &job->matches);
  report.num_target_matches =
      static_cast<int>(job->matches.matches.rows()) - before_targets;
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
    line << report.num_points1 << "/" << report.num_points2 << " points, ";
    // Correlation's steps, where it ran.
    if (report.num_candidates > 0 || report.num_descriptor_matches == 0) {
      line << "rotation " << report.rotation_deg << " deg ("
           << (report.mapping_found ? "" : "no ") << "global mapping, "
           << report.mapping_inliers << " votes), " << report.num_candidates
           << " candidates, " << report.num_relaxed << " after relaxation, ";
    }
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
    if (report.num_descriptor_matches > 0) {
      line << report.num_descriptor_matches << " by descriptor, ";
    }
    if (report.num_target_matches > 0) {
      line << report.num_target_matches << " coded targets, ";
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
  CheckFileExists(database_path, "database_path");
  CheckDirectoryExists(image_path, "image_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  database.CheckWritable("matches");
  std::map<image_t, ImageData> data = ReadImageList(&database, image_path);
  std::vector<DatabaseImage> images;
  for (const auto& [image_id, entry] : data) images.push_back(entry.image);
  std::optional<Eigen::MatrixXd> similarity;
  if (UsesRetrieval(options.pairing, static_cast<int>(images.size()))) {
    std::set<image_t> all;
    std::vector<std::string> files;
    for (const DatabaseImage& image : images) {
      all.insert(image.image_id);
      files.push_back(data.at(image.image_id).path);
    }
    CheckImageFiles(&database, image_path, data, all);
    RetrievalOptions retrieval = options.retrieval;
    retrieval.num_threads = options.num_threads;
    similarity = ImageSimilarities(files, retrieval);
  }
  const std::vector<std::pair<image_t, image_t>> pairs = SelectImagePairs(
      images, options.pairing, similarity ? &*similarity : nullptr);
  LOG(INFO) << pairs.size() << " pairs of " << images.size() << " images ("
            << PairingModeName(options.pairing.mode)
            << (similarity ? ", chosen by similarity" : "") << ")";

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
    report.num_points1 = static_cast<int>(data.at(id1).keypoints.rows());
    report.num_points2 = static_cast<int>(data.at(id2).keypoints.rows());
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
    for (image_t image_id : needed_ids) {
      ClassifyKeypoints(&database, &data.at(image_id));
    }
    Progress progress("Reading images", needed_ids.size(), "images");
    ParallelFor(needed_ids.size(), options.num_threads, [&](int k) {
      ImageData& entry = data.at(needed_ids[k]);
      std::vector<Eigen::Vector2d> xy(entry.keypoints.rows());
      for (int i = 0; i < entry.keypoints.rows(); ++i) {
        xy[i] = KeypointXY(entry.keypoints, i);
      }
      entry.patches = std::make_unique<ImagePatches>();
      const bool correlates =
          std::count(
              entry.by_correlation.begin(), entry.by_correlation.end(), 1) > 0;
      if (correlates) {
        cv::Mat gray = ReadImageGrayFloat(entry.path);
        *entry.patches = ExtractImagePatches(gray, xy, options.patches);
        if (options.lsm_refinement) entry.gray = std::move(gray);
      } else {
        entry.patches->xy = xy;
        entry.patches->valid.assign(xy.size(), 0);
      }
      // Keypoints matched by descriptor take no part in the correlation.
      for (size_t i = 0; i < xy.size(); ++i) {
        if (!entry.by_correlation[i]) entry.patches->valid[i] = 0;
      }
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
