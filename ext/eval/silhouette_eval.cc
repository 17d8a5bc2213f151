// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/silhouette_eval.h"

#include "ext/core/errors.h"
#include "ext/image/image_io.h"
#include "ext/render/mesh_renderer.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {

void SilhouetteOptions::Check() const {
  CheckOption(grey_threshold >= 0 && grey_threshold < 255,
              "silhouette_threshold",
              "in [0, 255)",
              grey_threshold);
  CheckOption(min_coverage > 0 && min_coverage <= 1,
              "SilhouetteOptions.min_coverage",
              "in (0, 1]",
              min_coverage);
  CheckOption(supersampling >= 1 && supersampling <= 8,
              "SilhouetteOptions.supersampling",
              "in [1, 8]",
              supersampling);
}

namespace {

// Clutter: the pixels of the object region's parts (8-connected) that the
// model's silhouette does not touch at all.
double ClutterPixels(const cv::Mat& object, const cv::Mat& model) {
  cv::Mat labels, stats, centroids;
  const int num_labels =
      cv::connectedComponentsWithStats(object, labels, stats, centroids, 8);
  std::vector<bool> touched(num_labels, false);
  for (int y = 0; y < labels.rows; ++y) {
    const int* label = labels.ptr<int>(y);
    const uint8_t* covered = model.ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (covered[x] != 0) touched[label[x]] = true;
    }
  }
  double clutter = 0;
  for (int l = 1; l < num_labels; ++l) {
    if (!touched[l]) clutter += stats.at<int>(l, cv::CC_STAT_AREA);
  }
  return clutter;
}

}  // namespace

SilhouetteEvaluation EvaluateSilhouettes(const TriangleMesh& mesh,
                                         const Scene& scene,
                                         const std::string& image_path,
                                         const SilhouetteOptions& options) {
  options.Check();
  if (mesh.faces.empty()) ThrowInputError("silhouettes: the mesh has no faces");
  // Every photograph's size from its header first: a missing one, or one
  // of another size than its camera, stops before any rendering; the pixels
  // are read one photograph at a time.
  const auto path_of = [&](const Image& image) {
    return (fs::path(image_path) / image.name).string();
  };
  for (const auto& [image_id, image] : scene.images) {
    const ImageSize size = ReadImageSize(path_of(image));
    const Camera& camera = scene.cameras.at(image.camera_id);
    if (static_cast<uint64_t>(size.width) != camera.width ||
        static_cast<uint64_t>(size.height) != camera.height) {
      ThrowInputError(path_of(image),
                      ": ",
                      size.width,
                      " x ",
                      size.height,
                      " pixels, but its camera has ",
                      camera.width,
                      " x ",
                      camera.height);
    }
  }
  if (!options.mask_dir.empty()) fs::create_directories(options.mask_dir);
  const MeshRenderer renderer(mesh);
  RenderOptions render;
  render.supersampling = options.supersampling;
  render.geometry_buffers = false;
  render.num_threads = options.num_threads;
  SilhouetteEvaluation evaluation;
  evaluation.min_iou = 1;
  for (const auto& [image_id, image] : scene.images) {
    RenderView view;
    view.camera = scene.cameras.at(image.camera_id);
    view.cam_from_world = image.cam_from_world;
    view.frame = image.frame;
    const RenderResult rendered = renderer.Render(view, Lighting(), render);
    // OpenCV's own grey conversion (ReadImageGrayFloat's luminance would
    // move pixels at the threshold).
    const cv::Mat photograph = ReadImage(path_of(image), ImageReadMode::kGray);
    cv::Mat grey;
    photograph.convertTo(
        grey, CV_32F, photograph.depth() == CV_16U ? 1.0 / 257 : 1.0);
    const cv::Mat object = grey > options.grey_threshold;
    const cv::Mat model = rendered.coverage >= options.min_coverage;
    const double both = cv::countNonZero(object & model);
    const double model_only = cv::countNonZero(model & ~object);
    const double photograph_only = cv::countNonZero(object & ~model);
    const double united = both + model_only + photograph_only;
    const double object_pixels = both + photograph_only;
    SilhouetteView& result = evaluation.views.emplace_back();
    result.best_iou =
        object_pixels > 0
            ? (object_pixels - ClutterPixels(object, model)) / object_pixels
            : 0;
    result.name = image.name;
    result.iou = united > 0 ? both / united : 0;
    result.model_only = united > 0 ? model_only / united : 0;
    result.photograph_only = united > 0 ? photograph_only / united : 0;
    if (result.iou < evaluation.min_iou || evaluation.worst.empty()) {
      evaluation.min_iou = result.iou;
      evaluation.worst = result.name;
    }
    evaluation.mean_iou += result.iou;
    evaluation.mean_best_iou += result.best_iou;
    if (!options.mask_dir.empty()) {
      // BGR: both white, the model alone red, the photograph alone blue.
      cv::Mat mask(object.size(), CV_8UC3, cv::Scalar(0, 0, 0));
      mask.setTo(cv::Scalar(255, 255, 255), object & model);
      mask.setTo(cv::Scalar(0, 0, 255), model & ~object);
      mask.setTo(cv::Scalar(255, 0, 0), object & ~model);
      std::string stem = fs::path(image.name).stem().string();
      std::replace(stem.begin(), stem.end(), '/', '_');
      WriteImage((fs::path(options.mask_dir) / (stem + ".png")).string(), mask);
    }
  }
  if (!evaluation.views.empty()) {
    evaluation.mean_iou /= static_cast<double>(evaluation.views.size());
    evaluation.mean_best_iou /= static_cast<double>(evaluation.views.size());
  }
  return evaluation;
}

std::string SilhouetteTable(const SilhouetteEvaluation& evaluation) {
  std::string table;
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "%-24s %8s %12s %16s %9s\n",
                "silhouette",
                "IoU",
                "model only",
                "photograph only",
                "best IoU");
  table += line;
  for (const SilhouetteView& v : evaluation.views) {
    std::snprintf(line,
                  sizeof(line),
                  "%-24s %8.3f %11.1f%% %15.1f%% %9.3f\n",
                  v.name.c_str(),
                  v.iou,
                  100 * v.model_only,
                  100 * v.photograph_only,
                  v.best_iou);
    table += line;
  }
  std::snprintf(line,
                sizeof(line),
                "%-24s %8.3f   (worst %s, %.3f; best possible %.3f: the "
                "clutter)\n",
                "mean",
                evaluation.mean_iou,
                evaluation.worst.c_str(),
                evaluation.min_iou,
                evaluation.mean_best_iou);
  table += line;
  return table;
}

nlohmann::ordered_json SilhouetteEvaluationJson(
    const SilhouetteEvaluation& e, const SilhouetteOptions& options) {
  nlohmann::ordered_json json = {{"threshold", options.grey_threshold},
                                 {"mean_iou", e.mean_iou},
                                 {"min_iou", e.min_iou},
                                 {"mean_best_iou", e.mean_best_iou},
                                 {"worst", e.worst},
                                 {"views", nlohmann::ordered_json::array()}};
  for (const SilhouetteView& v : e.views) {
    json["views"].push_back({{"name", v.name},
                             {"iou", v.iou},
                             {"model_only", v.model_only},
                             {"photograph_only", v.photograph_only},
                             {"best_iou", v.best_iou}});
  }
  return json;
}

}  // namespace bayon
