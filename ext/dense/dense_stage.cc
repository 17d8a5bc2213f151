// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/dense_stage.h"

#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::vector<MasterSelection> ChooseMasters(const Scene& scene,
                                           const DenseOptions& options) {
  const bool paper = options.mode == DenseMode::kPaper;
  const std::vector<MasterSelection> masters =
      paper ? SelectMasters(scene, options)
            : SelectMultiViewMasters(scene, options);
  for (const MasterSelection& selection : masters) {
    std::string search;
    for (image_t id : selection.search) {
      search += (search.empty() ? "" : ", ") + scene.images.at(id).name;
    }
    LOG(INFO) << "master " << scene.images.at(selection.master).name
              << (paper ? ", search images " : ", source views ") << search;
  }
  return masters;
}

// .vis indices: positions in the model's image list.
std::vector<std::vector<uint32_t>> VisibilityIndices(
    const Scene& scene, const std::vector<std::vector<image_t>>& seen) {
  std::map<image_t, uint32_t> index_of;
  for (const auto& [image_id, image] : scene.images) {
    index_of.emplace(image_id, static_cast<uint32_t>(index_of.size()));
  }
  std::vector<std::vector<uint32_t>> visibility;
  visibility.reserve(seen.size());
  for (const std::vector<image_t>& ids : seen) {
    std::vector<uint32_t>& indices = visibility.emplace_back();
    for (image_t id : ids) indices.push_back(index_of.at(id));
  }
  return visibility;
}

}  // namespace

DenseResult RunDense(const Scene& scene,
                     const std::string& image_path,
                     const DenseOptions& options) {
  const std::vector<MasterSelection> masters = ChooseMasters(scene, options);
  DenseResult result;
  if (options.mode == DenseMode::kPaper) {
    result.images = LoadDenseImages(scene,
                                    masters,
                                    image_path,
                                    options.highpass_sigma_px,
                                    &result.unreadable);
    for (const auto& [id, error] : result.unreadable) {
      LOG(WARNING) << "left out: " << error;
    }
    result.cloud = DenseReconstruct(
        scene, result.images, masters, options, &result.report, &result.seen);
  } else {
    result.cloud = DenseReconstructMultiView(scene,
                                             image_path,
                                             masters,
                                             options,
                                             &result.report,
                                             &result.seen,
                                             &result.unreadable);
  }
  if (result.cloud.empty()) {
    throw RunFailure(StrCat("no dense point was matched in ",
                            masters.size(),
                            " master images:\n",
                            result.report.Summary()));
  }
  AddUnmodelledSigma(options, &result.cloud, &result.report);
  return result;
}

std::string DenseOutputPaths::RejectsFolder() const {
  return (fs::absolute(cloud).parent_path() / "rejects").string();
}

void WriteDenseOutputs(const Scene& scene,
                       const std::string& image_path,
                       const DenseResult& result,
                       const DenseOptions& options,
                       const DenseOutputPaths& paths) {
  fs::create_directories(fs::absolute(paths.cloud).parent_path());
  fs::create_directories(fs::absolute(paths.fused).parent_path());
  PlyWriteOptions write_options;
  write_options.comment = "bayon dense";
  WritePointCloudPly(result.cloud, paths.cloud, write_options);
  const std::vector<std::vector<uint32_t>> visibility =
      VisibilityIndices(scene, result.seen);
  WriteColmapFusedPly(result.cloud, paths.fused, "bayon dense", &visibility);
  WriteFileAtomically(paths.report,
                      DenseReportJson(result.report, options).dump(2) + "\n");
  const fs::path rejects_folder = paths.RejectsFolder();
  fs::create_directories(rejects_folder);
  for (const DenseMasterReport& master : result.report.masters) {
    if (!master.skipped.empty()) continue;
    const cv::Mat color =
        options.mode == DenseMode::kPaper
            ? result.images.at(master.master).color
            : LoadDenseColor(scene, master.master, image_path);
    WriteImage(
        (rejects_folder / fs::path(master.name).stem()).string() + ".png",
        RejectMap(master, color));
  }
}

}  // namespace bayon
