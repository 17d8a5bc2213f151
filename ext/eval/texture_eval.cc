// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/texture_eval.h"

#include "ext/core/errors.h"
#include "ext/image/image_io.h"
#include "ext/render/mesh_renderer.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace bayon {
namespace {

// The image with each channel mapped by the gain and offset that fit it to
// the reference best (least squares) over the mask.
cv::Mat FitChannels(const cv::Mat& image,
                    const cv::Mat& reference,
                    const cv::Mat& mask) {
  std::vector<cv::Mat> channels, references;
  cv::split(image, channels);
  cv::split(reference, references);
  for (size_t c = 0; c < channels.size(); ++c) {
    cv::Scalar mean_x, std_x, mean_y, std_y;
    cv::meanStdDev(channels[c], mean_x, std_x, mask);
    cv::meanStdDev(references[c], mean_y, std_y, mask);
    const cv::Mat centred_x = channels[c] - mean_x[0];
    const cv::Mat centred_y = references[c] - mean_y[0];
    const double covariance = cv::mean(centred_x.mul(centred_y), mask)[0];
    const double variance = std_x[0] * std_x[0];
    const double gain = variance > 0 ? covariance / variance : 0.0;
    channels[c] = centred_x * gain + mean_y[0];
  }
  cv::Mat fitted;
  cv::merge(channels, fitted);
  return fitted;
}

void WriteRender(const std::string& path, const cv::Mat& bgr) {
  cv::Mat bytes;
  bgr.convertTo(bytes, CV_8UC3, 255.0);
  WriteImage(path, bytes);
}

// The views' means.
void Summarize(TextureEvaluation* evaluation) {
  for (const ViewComparison& v : evaluation->views) {
    evaluation->mean_psnr_db += v.raw.psnr_db;
    evaluation->mean_ssim += v.raw.ssim;
    evaluation->mean_normalized_psnr_db += v.normalized.psnr_db;
    evaluation->mean_normalized_ssim += v.normalized.ssim;
  }
  const double n = static_cast<double>(evaluation->views.size());
  evaluation->mean_psnr_db /= n;
  evaluation->mean_ssim /= n;
  evaluation->mean_normalized_psnr_db /= n;
  evaluation->mean_normalized_ssim /= n;
}

ViewComparison Compare(const std::string& name,
                       const cv::Mat& image,
                       const cv::Mat& reference,
                       const cv::Mat& mask) {
  ViewComparison comparison;
  comparison.name = name;
  comparison.raw = CompareImages(image, reference, mask);
  comparison.normalized =
      CompareImages(FitChannels(image, reference, mask), reference, mask);
  return comparison;
}

RenderOptions UnlitRenderOptions(const TextureEvaluationOptions& options) {
  RenderOptions render;
  render.supersampling = options.supersampling;
  render.geometry_buffers = false;
  render.num_threads = options.num_threads;
  return render;
}

RenderView ViewOf(const Scene& scene, const Image& image) {
  RenderView view;
  view.camera = scene.cameras.at(image.camera_id);
  view.cam_from_world = image.cam_from_world;
  view.frame = image.frame;
  return view;
}

}  // namespace

TextureEvaluation EvaluateAgainstPhotographs(
    const TriangleMesh& model,
    const cv::Mat& model_texture,
    const Scene& scene,
    const std::vector<std::pair<std::string, cv::Mat>>& photographs,
    const TextureEvaluationOptions& options) {
  if (photographs.empty()) ThrowInputError("no photographs to compare with");
  const MeshRenderer renderer(model, model_texture);
  const RenderOptions render = UnlitRenderOptions(options);
  if (!options.render_dir.empty()) {
    std::filesystem::create_directories(options.render_dir);
  }
  TextureEvaluation evaluation;
  for (const auto& [name, bgr] : photographs) {
    const Image* image = scene.FindImageByName(name);
    if (image == nullptr) {
      ThrowInputError("the model has no image '", name, "'");
    }
    const RenderView view = ViewOf(scene, *image);
    if (bgr.cols != static_cast<int>(view.camera.width) ||
        bgr.rows != static_cast<int>(view.camera.height)) {
      ThrowInputError(name,
                      ": is ",
                      bgr.cols,
                      " x ",
                      bgr.rows,
                      " pixels but its camera is ",
                      view.camera.width,
                      " x ",
                      view.camera.height);
    }
    const RenderResult rendered = renderer.Render(view, Lighting(), render);
    const cv::Mat mask = rendered.coverage >= 0.999f;
    if (cv::countNonZero(mask) == 0) {
      ThrowInputError(name, ": the model does not appear in it");
    }
    cv::Mat photograph;
    bgr.convertTo(photograph, CV_32FC3, 1.0 / 255.0);
    evaluation.views.push_back(Compare(name, rendered.color, photograph, mask));
    if (!options.render_dir.empty()) {
      const std::string stem = std::filesystem::path(name).stem().string();
      WriteRender(options.render_dir + "/model_" + stem + ".png",
                  rendered.color);
      cv::Mat masked = cv::Mat::zeros(photograph.size(), photograph.type());
      photograph.copyTo(masked, mask);
      WriteRender(options.render_dir + "/photograph_" + stem + ".png", masked);
    }
  }
  Summarize(&evaluation);
  return evaluation;
}

TextureEvaluation EvaluateTexturedModel(
    const TriangleMesh& model,
    const cv::Mat& model_texture,
    const TriangleMesh& truth,
    const cv::Mat& truth_texture,
    const Scene& viewpoints,
    const TextureEvaluationOptions& options) {
  if (viewpoints.images.empty()) {
    ThrowInputError("no viewpoints to render the textured model from");
  }
  const MeshRenderer model_renderer(model, model_texture);
  const MeshRenderer truth_renderer(truth, truth_texture);
  const RenderOptions render = UnlitRenderOptions(options);
  const Lighting unlit;
  if (!options.render_dir.empty()) {
    std::filesystem::create_directories(options.render_dir);
  }

  TextureEvaluation evaluation;
  for (const auto& [image_id, image] : viewpoints.images) {
    const RenderView view = ViewOf(viewpoints, image);
    const RenderResult truth_render =
        truth_renderer.Render(view, unlit, render);
    const RenderResult model_render =
        model_renderer.Render(view, unlit, render);
    // Pixels entirely on the true surface: edges of the silhouette mix
    // in the background and would judge the anti-aliasing.
    const cv::Mat mask = truth_render.coverage >= 0.999f;
    if (cv::countNonZero(mask) == 0) continue;
    evaluation.views.push_back(
        Compare(image.name, model_render.color, truth_render.color, mask));
    if (!options.render_dir.empty()) {
      const std::string stem =
          std::filesystem::path(image.name).stem().string();
      WriteRender(options.render_dir + "/model_" + stem + ".png",
                  model_render.color);
      WriteRender(options.render_dir + "/truth_" + stem + ".png",
                  truth_render.color);
    }
  }
  if (evaluation.views.empty()) {
    ThrowInputError("none of the ",
                    viewpoints.images.size(),
                    " viewpoints sees the true surface");
  }
  Summarize(&evaluation);
  return evaluation;
}

std::string TextureTable(const TextureEvaluation& evaluation) {
  std::string table;
  char line[256];
  std::snprintf(line,
                sizeof(line),
                "%-20s %10s %8s %12s %10s %8s\n",
                "view",
                "pixels",
                "PSNR dB",
                "SSIM",
                "PSNR* dB",
                "SSIM*");
  table += line;
  for (const ViewComparison& v : evaluation.views) {
    std::snprintf(line,
                  sizeof(line),
                  "%-20s %10zu %8.2f %12.4f %10.2f %8.4f\n",
                  v.name.c_str(),
                  v.raw.num_pixels,
                  v.raw.psnr_db,
                  v.raw.ssim,
                  v.normalized.psnr_db,
                  v.normalized.ssim);
    table += line;
  }
  std::snprintf(line,
                sizeof(line),
                "%-20s %10s %8.2f %12.4f %10.2f %8.4f\n",
                "mean",
                "",
                evaluation.mean_psnr_db,
                evaluation.mean_ssim,
                evaluation.mean_normalized_psnr_db,
                evaluation.mean_normalized_ssim);
  table += line;
  table += "(* after a per-channel gain and offset)\n";
  return table;
}

nlohmann::ordered_json TextureEvaluationJson(const TextureEvaluation& e) {
  nlohmann::ordered_json json = {
      {"mean_psnr_db", e.mean_psnr_db},
      {"mean_ssim", e.mean_ssim},
      {"mean_normalized_psnr_db", e.mean_normalized_psnr_db},
      {"mean_normalized_ssim", e.mean_normalized_ssim}};
  json["views"] = nlohmann::ordered_json::array();
  for (const ViewComparison& v : e.views) {
    json["views"].push_back({{"name", v.name},
                             {"pixels", v.raw.num_pixels},
                             {"psnr_db", v.raw.psnr_db},
                             {"ssim", v.raw.ssim},
                             {"normalized_psnr_db", v.normalized.psnr_db},
                             {"normalized_ssim", v.normalized.ssim}});
  }
  return json;
}

}  // namespace bayon
