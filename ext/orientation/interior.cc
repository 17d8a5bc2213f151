// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/interior.h"

#include "ext/colmap/database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

void InteriorOptions::Register(OptionRegistry* r) {
  r->Add("film_scan",
         &film_scan,
         "1: scanned film frames (virtual fiducials); 0: digital");
  fiducials.Register(r);
  r->Add("overwrite", &overwrite, "1: replace existing bayon_interior rows");
  r->Add("num_threads", &num_threads, "Images in parallel (-1 = all)");
}

std::string InteriorSummaryLine(const InteriorSummary& summary,
                                const InteriorOptions& options) {
  double sum_rms = 0, max_rotation = 0;
  for (const ImageInteriorReport& image : summary.images) {
    if (image.status != InteriorStatus::kDone || !options.film_scan) continue;
    sum_rms += image.fiducials.rms_px;
    max_rotation =
        std::max(max_rotation, std::abs(image.fiducials.rotation_deg));
  }
  const std::string film = options.film_scan && summary.num_done > 0
                               ? StrCat(" (mean edge RMS ",
                                        sum_rms / summary.num_done,
                                        " px, largest rotation ",
                                        max_rotation,
                                        " deg)")
                               : "";
  return StrCat(summary.num_done,
                options.film_scan ? " film frames measured" : " digital frames",
                film,
                ", ",
                summary.num_kept,
                " kept, ",
                summary.num_failed,
                " failed, ",
                summary.seconds,
                " s");
}

void InteriorOptions::Check() const { fiducials.Check(); }

VirtualFiducialResult MeasureFilmFrame(const std::string& image_file,
                                       const VirtualFiducialOptions& options) {
  const cv::Mat image = ReadImage(image_file, ImageReadMode::kUnchanged);
  LinearScan scan;
  try {
    scan = MakeLinearScan(image, options.decode_srgb, options.clip_level);
  } catch (const InputError& error) {
    ThrowInputError(image_file, ": ", error.what());
  }
  return FindVirtualFiducials(scan, options);
}

InteriorRecord InteriorFromFiducials(const VirtualFiducialResult& result) {
  CHECK(result.success) << "InteriorFromFiducials of a failed measurement";
  InteriorRecord record;
  record.frame = result.frame;
  record.method = "virtual_fiducials";
  record.rms_residual_px = result.rms_px;
  record.frame_rotation_deg = result.rotation_deg;
  return record;
}

std::string DescribeInterior(const ImageInteriorReport& report) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(3) << report.name << ": ";
  if (report.status == InteriorStatus::kKept) {
    line << "kept, " << report.reason;
    return line.str();
  }
  const VirtualFiducialResult& f = report.fiducials;
  if (report.status == InteriorStatus::kDone &&
      report.record.method == kDigitalInteriorMethod) {
    const ImageFrame& frame = report.record.frame;
    line << "digital, pixel " << 1000 * frame.MeanPitchMm()
         << " um, frame centre (" << frame.pixel_from_frame(0, 2) << ", "
         << frame.pixel_from_frame(1, 2) << ") px";
    return line.str();
  }
  if (report.status == InteriorStatus::kFailed) line << "FAILED, ";
  line << f.num_edges << " edges (";
  bool first = true;
  for (const FrameEdge& edge : f.edges) {
    line << (first ? "" : ", ") << FrameSideName(edge.side) << " ";
    first = false;
    if (edge.found) {
      line << edge.num_inliers << "/" << edge.num_points << " points, RMS "
           << edge.rms_px << " px";
    } else {
      line << "not found";
    }
  }
  line << "), " << f.num_points << " points (" << f.num_rejected
       << " rejected), residual RMS " << f.rms_px << " px (max " << f.max_px
       << ")";
  if (f.num_corners > 0) {
    line << ", corner angles";
    for (int k = 0; k < 4; ++k) {
      if (f.has_corner[k]) line << " " << f.corner_angles_deg[k];
    }
    line << " deg";
  }
  if (report.status == InteriorStatus::kDone) {
    line << ", rotation " << f.rotation_deg << " deg, pixel "
         << f.pixel_size_um.x() << " x " << f.pixel_size_um.y() << " um ("
         << f.scale_source << ")";
  } else {
    line << " -- " << report.reason;
  }
  line << ", " << std::setprecision(2) << report.seconds << " s";
  return line.str();
}

namespace {

struct Job {
  DatabaseImage image;
  std::string path;
  Camera camera;  // the calibration's where there is one
  ImageInteriorReport report;
  bool todo = true;
};

std::vector<Job> PlanJobs(Database* database,
                          const std::string& image_path,
                          const std::map<image_t, InteriorRecord>& existing,
                          const InteriorOptions& options) {
  const std::vector<DatabaseImage> images = database->ReadAllImages();
  if (images.empty()) {
    ThrowInputError(database->path(),
                    ": the database has no images (run `bayon import` or "
                    "`colmap feature_extractor` first)");
  }
  const std::map<image_t, Camera> cameras = ReadImageCameras(database, images);
  std::map<camera_t, CalibrationRecord> calibrations;
  if (BayonTableExists(database, kCalibrationTable.name)) {
    calibrations = ReadAllCalibrations(database);
  }
  std::vector<ExpectedImage> expected;
  std::vector<Job> jobs;
  for (const DatabaseImage& image : images) {
    Job job;
    job.image = image;
    job.path = (fs::path(image_path) / image.name).string();
    job.camera = cameras.at(image.image_id);
    const auto calibration = calibrations.find(image.camera_id);
    if (calibration != calibrations.end()) {
      job.camera = calibration->second.camera;
    }
    if (options.film_scan &&
        job.camera.model_id != CameraModelId::kBrownBeyer) {
      ThrowInputError(database->path(),
                      ": image ",
                      image.name,
                      ": camera ",
                      image.camera_id,
                      " is ",
                      job.camera.ModelName(),
                      "; the image frame of a film scan (millimetres) needs "
                      "a BROWN_BEYER camera (bayon import --camera_model "
                      "BROWN_BEYER --focal_length_mm F --pixel_size_um P)");
    }
    job.report.image_id = image.image_id;
    job.report.name = image.name;
    expected.push_back({image.name,
                        static_cast<int>(job.camera.width),
                        static_cast<int>(job.camera.height)});
    const auto row = existing.find(image.image_id);
    if (row != existing.end() && !options.overwrite) {
      job.todo = false;
      job.report.status = InteriorStatus::kKept;
      job.report.record = row->second;
      job.report.reason = StrCat("has a bayon_interior row (method ",
                                 row->second.method,
                                 "; --overwrite 1 replaces it)");
    }
    jobs.push_back(std::move(job));
  }
  CheckImagesOnDisk(image_path, expected, database->path());
  return jobs;
}

void OrientJob(const InteriorOptions& options, Job* job) {
  Timer timer;
  ImageInteriorReport& report = job->report;
  if (!options.film_scan) {
    report.record.frame = job->camera.DefaultFrame();
    report.record.method = kDigitalInteriorMethod;
    report.status = InteriorStatus::kDone;
  } else {
    report.fiducials = MeasureFilmFrame(job->path, options.fiducials);
    if (report.fiducials.success) {
      report.record = InteriorFromFiducials(report.fiducials);
      report.status = InteriorStatus::kDone;
    } else {
      report.status = InteriorStatus::kFailed;
      report.reason = report.fiducials.reason;
    }
  }
  report.seconds = timer.Seconds();
}

}  // namespace

InteriorSummary OrientInteriors(const std::string& database_path,
                                const std::string& image_path,
                                const InteriorOptions& options) {
  options.Check();
  CheckFileExists(database_path, "database_path");
  CheckDirectoryExists(image_path, "image_path");
  Timer timer;
  Database database(database_path, Database::Mode::kReadWrite);
  CheckBayonSchema(&database);
  // Existing rows: kept without `overwrite`; a failure never removes one.
  const std::map<image_t, InteriorRecord> existing =
      ReadAllInteriors(&database);
  std::vector<Job> jobs = PlanJobs(&database, image_path, existing, options);

  std::vector<int> todo;
  for (int i = 0; i < static_cast<int>(jobs.size()); ++i) {
    if (jobs[i].todo) todo.push_back(i);
  }
  Progress progress(options.film_scan ? "Virtual fiducials" : "Image frames",
                    todo.size(),
                    "images");
  ParallelFor(todo.size(), options.num_threads, [&](int k) {
    OrientJob(options, &jobs[todo[k]]);
    progress.Add();
  });
  progress.Finish();

  InteriorSummary summary;
  for (Job& job : jobs) {
    ImageInteriorReport& report = job.report;
    const auto row = existing.find(job.image.image_id);
    if (report.status == InteriorStatus::kFailed && row != existing.end()) {
      report.reason += StrCat(
          " (its existing row, method ", row->second.method, ", is kept)");
    }
  }
  const bool any_done =
      std::any_of(jobs.begin(), jobs.end(), [](const Job& job) {
        return job.report.status == InteriorStatus::kDone;
      });
  if (any_done) {
    auto transaction = database.BeginTransaction();
    EnsureBayonTable(&database, kInteriorTable);
    for (const Job& job : jobs) {
      if (job.report.status == InteriorStatus::kDone) {
        WriteInterior(&database, job.image.image_id, job.report.record);
      }
    }
    transaction.Commit();
  }
  for (const Job& job : jobs) {
    const ImageInteriorReport& report = job.report;
    switch (report.status) {
      case InteriorStatus::kDone:
        ++summary.num_done;
        LOG(INFO) << DescribeInterior(report);
        break;
      case InteriorStatus::kKept:
        ++summary.num_kept;
        LOG(INFO) << DescribeInterior(report);
        break;
      case InteriorStatus::kFailed:
        ++summary.num_failed;
        LOG(WARNING) << DescribeInterior(report);
        break;
    }
    summary.images.push_back(report);
  }
  summary.seconds = timer.Seconds();
  return summary;
}

}  // namespace bayon
