// SPDX-License-Identifier: BSD-3-Clause
#include "ext/targets/find_targets.h"

#include "ext/colmap/database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"
#include "ext/image/image_io.h"

#include <filesystem>
#include <set>

namespace bayon {
namespace {

std::string PathOf(const std::string& image_path, const std::string& name) {
  return (std::filesystem::path(image_path) / name).string();
}

}  // namespace

std::string CodedTargetSummary::Summary() const {
  int seen_in = 0;
  for (const CodedTargetImageReport& image : images) {
    seen_in += image.detection.num_measured > 0;
  }
  return StrCat(num_targets,
                " coded targets measured ",
                measurements.size(),
                " times in ",
                seen_in,
                " of ",
                images.size(),
                " photographs, median sigma ",
                median_sigma_px,
                " px; ",
                num_refused,
                " decoded but not measured, ",
                seconds,
                " s");
}

CodedTargetSummary FindCodedTargets(const std::string& database_path,
                                    const std::string& image_path,
                                    const CodedTargetOptions& options,
                                    int num_threads) {
  options.Check();
  const Timer timer;
  CodedTargetSummary summary;
  std::vector<std::string> names;
  {
    Database database(database_path, Database::Mode::kReadOnly);
    for (const DatabaseImage& image : database.ReadAllImages()) {
      names.push_back(image.name);
    }
  }
  if (names.empty()) {
    ThrowInputError(database_path, ": no images (run `bayon import`)");
  }
  for (const std::string& name : names) {
    CheckFileExists(PathOf(image_path, name), "photograph");
  }
  std::vector<std::vector<CodedTarget>> found(names.size());
  summary.images.resize(names.size());
  Progress progress("Coded targets", names.size(), "images");
  ParallelFor(static_cast<int>(names.size()), num_threads, [&](int i) {
    const std::string path = PathOf(image_path, names[i]);
    summary.images[i].image_name = names[i];
    found[i] = DetectCodedTargets(
        ReadImageColor8(path), options, path, &summary.images[i].detection);
    progress.Add();
  });
  progress.Finish();
  std::set<std::string> distinct;
  std::vector<double> sigmas;
  for (size_t i = 0; i < names.size(); ++i) {
    summary.num_refused +=
        static_cast<int>(summary.images[i].detection.refused.size());
    for (const CodedTarget& target : found[i]) {
      ImageMeasurement& m = summary.measurements.emplace_back();
      m.point_name = target.name;
      m.image_name = names[i];
      m.xy = target.centre;
      m.sigma_px = MeasurementSigma(target.covariance);
      sigmas.push_back(m.sigma_px);
      distinct.insert(target.name);
    }
  }
  summary.num_targets = static_cast<int>(distinct.size());
  summary.median_sigma_px = sigmas.empty() ? 0 : Median(sigmas);
  summary.seconds = timer.Seconds();
  return summary;
}

nlohmann::ordered_json CodedTargetReportJson(
    const CodedTargetSummary& summary, const CodedTargetOptions& options) {
  nlohmann::ordered_json json;
  json["dictionary"] = options.dictionary;
  json["num_targets"] = summary.num_targets;
  json["num_measurements"] = summary.measurements.size();
  json["num_refused"] = summary.num_refused;
  json["median_sigma_px"] = summary.median_sigma_px;
  json["seconds"] = summary.seconds;
  json["images"] = nlohmann::ordered_json::array();
  for (const CodedTargetImageReport& image : summary.images) {
    json["images"].push_back({{"name", image.image_name},
                              {"num_decoded", image.detection.num_decoded},
                              {"num_measured", image.detection.num_measured},
                              {"refused", image.detection.refused}});
  }
  return json;
}

}  // namespace bayon
