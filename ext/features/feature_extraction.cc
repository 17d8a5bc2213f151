// SPDX-License-Identifier: BSD-3-Clause
#include "ext/features/feature_extraction.h"

#include "ext/colmap/control_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_features.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>

#include <filesystem>
#include <limits>
#include <map>

namespace fs = std::filesystem;

namespace bayon {

const char* FeatureDetectorName(FeatureDetector detector) {
  switch (detector) {
    case FeatureDetector::kMoravec:
      return "moravec";
    case FeatureDetector::kSift:
      return "sift";
    case FeatureDetector::kBoth:
      return "both";
  }
  return "?";
}

void FeatureExtractionOptions::Register(OptionRegistry* r) {
  r->AddChoice("detector",
               &detector,
               ChoicesOf<FeatureDetector>(
                   [](FeatureDetector d) { return FeatureDetectorName(d); },
                   {FeatureDetector::kMoravec,
                    FeatureDetector::kSift,
                    FeatureDetector::kBoth}),
               "moravec, sift or both");
  r->AddNested("moravec", &moravec);
  r->AddNested("sift", &sift);
  r->Add("overwrite",
         &overwrite,
         "1: replace existing keypoints (drops their matches)");
  r->Add("targets_path",
         &targets_path,
         "Coded targets of `bayon targets`, appended as keypoints that match "
         "pairs by name");
  r->Add("num_threads", &num_threads, "Images in parallel (-1 = all)");
}

void FeatureExtractionOptions::Check() const {
  if (detector != FeatureDetector::kSift) CheckNested("moravec", moravec);
  if (detector != FeatureDetector::kMoravec) CheckNested("sift", sift);
}

ImageFeatures DetectImageFeatures(const std::string& image_file,
                                  const FeatureExtractionOptions& options) {
  const cv::Mat gray = ReadImageGrayFloat(image_file);
  ImageFeatures features;
  std::vector<Eigen::Vector2d> moravec_xy;
  if (options.detector != FeatureDetector::kSift) {
    for (const InterestPoint& point :
         DetectMoravecPoints(gray, options.moravec)) {
      moravec_xy.push_back(point.xy.cast<double>());
      features.interest.push_back(point.interest);
    }
  }
  if (options.detector == FeatureDetector::kMoravec) {
    features.keypoints = KeypointsFromXY(moravec_xy);
    return features;
  }
  const SiftFeatures sift = DetectSiftFeatures(gray, options.sift);
  features.num_sift = static_cast<int>(sift.keypoints.rows());
  const int num_moravec = static_cast<int>(moravec_xy.size());
  const int n = num_moravec + features.num_sift;
  features.keypoints.resize(n, 6);
  features.descriptors.resize(n, 128);
  if (num_moravec > 0) {
    features.keypoints.topRows(num_moravec) = KeypointsFromXY(moravec_xy);
    features.descriptors.topRows(num_moravec) =
        ComputeUprightSiftDescriptors(gray, moravec_xy, options.sift);
  }
  features.keypoints.bottomRows(features.num_sift) = sift.keypoints;
  features.descriptors.bottomRows(features.num_sift) = sift.descriptors;
  features.interest.resize(n, std::numeric_limits<float>::quiet_NaN());
  return features;
}

namespace {

struct Job {
  DatabaseImage image;
  std::string path;
  ImageFeatureResult result;
  ImageFeatures features;
  std::vector<ImageMeasurement> targets;  // targets_path's, of this image
};

// The targets file's measurements, by image; one that names an image the
// database does not have is refused (a file of another project).
void AssignTargets(const std::string& targets_path,
                   const std::string& database_path,
                   std::vector<Job>* jobs) {
  if (targets_path.empty()) return;
  CheckFileExists(targets_path, "targets_path");
  std::map<std::string, Job*> by_name;
  for (Job& job : *jobs) by_name[job.image.name] = &job;
  for (const ImageMeasurement& m : ReadImageMeasurements(targets_path)) {
    const auto job = by_name.find(m.image_name);
    if (job == by_name.end()) {
      ThrowInputError(targets_path,
                      ": target ",
                      m.point_name,
                      " is measured in ",
                      m.image_name,
                      ", which is not in ",
                      database_path);
    }
    job->second->targets.push_back(m);
  }
}

// The targets as keypoints after the detector's (no interest value, zero
// descriptors: neither correlation nor descriptors match them).
std::vector<KeypointTarget> AppendTargets(
    const std::vector<ImageMeasurement>& targets, ImageFeatures* features) {
  const int first = static_cast<int>(features->keypoints.rows());
  const int n = static_cast<int>(targets.size());
  std::vector<Eigen::Vector2d> xy;
  std::vector<KeypointTarget> rows;
  for (int i = 0; i < n; ++i) {
    xy.push_back(targets[i].xy);
    rows.push_back({static_cast<uint32_t>(first + i),
                    targets[i].point_name,
                    static_cast<float>(targets[i].sigma_px)});
  }
  features->keypoints.conservativeResize(first + n, 6);
  features->keypoints.bottomRows(n) = KeypointsFromXY(xy);
  if (features->descriptors.rows() > 0) {
    features->descriptors.conservativeResize(first + n, 128);
    features->descriptors.bottomRows(n).setZero();
  }
  features->interest.resize(first + n, std::numeric_limits<float>::quiet_NaN());
  return rows;
}

// Every image must be on disk with the size its camera row claims, checked
// from the file headers before any work.
std::vector<Job> PlanJobs(Database* database,
                          const std::string& image_path,
                          const FeatureExtractionOptions& options) {
  const std::vector<DatabaseImage> images = database->ReadAllImages();
  if (images.empty()) {
    ThrowInputError(database->path(),
                    ": the database has no images (run `bayon import` or "
                    "`colmap feature_extractor` first)");
  }
  const std::map<image_t, Camera> cameras = ReadImageCameras(database, images);
  std::vector<ExpectedImage> expected;
  std::vector<Job> jobs;
  for (const DatabaseImage& image : images) {
    const Camera& camera = cameras.at(image.image_id);
    Job job;
    job.image = image;
    job.path = (fs::path(image_path) / image.name).string();
    job.result.image_id = image.image_id;
    job.result.name = image.name;
    job.result.width = static_cast<int>(camera.width);
    job.result.height = static_cast<int>(camera.height);
    expected.push_back({image.name, job.result.width, job.result.height});
    if (!options.overwrite && database->ExistsKeypoints(image.image_id) &&
        database->ReadKeypoints(image.image_id).rows() > 0) {
      job.result.skipped = true;
      job.result.reason = "has keypoints (--overwrite 1 replaces them)";
    }
    jobs.push_back(std::move(job));
  }
  CheckImagesOnDisk(image_path, expected, database->path());
  return jobs;
}

}  // namespace

FeatureExtractionSummary ExtractFeatures(
    const std::string& database_path,
    const std::string& image_path,
    const FeatureExtractionOptions& options) {
  options.Check();
  CheckFileExists(database_path, "database_path");
  CheckDirectoryExists(image_path, "image_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  database.CheckWritable("keypoints");
  std::vector<Job> jobs = PlanJobs(&database, image_path, options);
  AssignTargets(options.targets_path, database_path, &jobs);

  std::vector<int> todo;
  for (int i = 0; i < static_cast<int>(jobs.size()); ++i) {
    if (!jobs[i].result.skipped) todo.push_back(i);
  }
  Progress progress(
      StrCat("Extracting ", FeatureDetectorName(options.detector), " points"),
      todo.size(),
      "images");
  ParallelFor(todo.size(), options.num_threads, [&](int k) {
    Job& job = jobs[todo[k]];
    Timer image_timer;
    job.features = DetectImageFeatures(job.path, options);
    job.result.num_targets = static_cast<int>(job.targets.size());
    job.result.num_sift = job.features.num_sift;
    if (options.detector != FeatureDetector::kSift) {
      job.result.patch_size = ThinningPatchSize(
          options.moravec, job.result.width, job.result.height);
    }
    job.result.seconds = image_timer.Seconds();
    progress.Add();
  });
  progress.Finish();

  FeatureExtractionSummary summary;
  {
    auto transaction = database.BeginTransaction();
    EnsureBayonTable(&database, kKeypointInterestTable);
    for (Job& job : jobs) {
      if (job.result.skipped) {
        LOG(INFO) << job.result.name << ": skipped, " << job.result.reason;
        ++summary.num_skipped;
        summary.images.push_back(job.result);
        continue;
      }
      summary.num_pairs_invalidated +=
          DeleteKeypointDependents(&database, job.image.image_id);
      KeypointInterestRecord record;
      record.detector = FeatureDetectorName(options.detector);
      record.window_size = options.moravec.window_size;
      record.patch_size = job.result.patch_size;
      const std::vector<KeypointTarget> targets =
          AppendTargets(job.targets, &job.features);
      job.result.num_features = static_cast<int>(job.features.keypoints.rows());
      record.interest = std::move(job.features.interest);
      database.WriteKeypoints(job.image.image_id, job.features.keypoints);
      DeleteKeypointTargets(&database, job.image.image_id);
      if (!targets.empty()) {
        WriteKeypointTargets(
            &database, job.image.image_id, job.result.num_features, targets);
      }
      if (job.features.descriptors.rows() > 0) {
        database.WriteDescriptors(job.image.image_id, job.features.descriptors);
      }
      WriteKeypointInterest(&database, job.image.image_id, record);
      LOG(INFO) << job.result.name << ": " << job.result.num_features
                << " points, " << job.result.num_sift << " of them SIFT ("
                << job.result.width << "x" << job.result.height << ", patch "
                << job.result.patch_size << " px) in " << job.result.seconds
                << " s";
      ++summary.num_extracted;
      summary.num_features += job.result.num_features;
      summary.num_sift += job.result.num_sift;
      summary.num_targets += job.result.num_targets;
      summary.images.push_back(job.result);
    }
    transaction.Commit();
  }
  summary.seconds = timer.Seconds();
  return summary;
}

}  // namespace bayon
