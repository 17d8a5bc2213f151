// SPDX-License-Identifier: BSD-3-Clause
//
// A textured model against the true textured surface, seen from viewpoints
// that were not photographed (gt/heldout/ of a synthetic tower): both are
// rendered unlit (their texture as it is) through the same cameras with
// ext/render, and compared by PSNR and SSIM (ext/eval/image_metrics.h) over
// the pixels where the true surface fills the pixel. Where the model has a
// hole the background shows and counts as an error.
//
// The photographs were taken under changing light and the texture stage
// equalises them, so the model's colours need not match the truth's
// albedo in level: each view is also compared after the best per-channel
// gain and offset (least squares over the mask), which judges detail and
// seams rather than exposure.
#pragma once

#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"
#include "ext/eval/image_metrics.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace bayon {

struct TextureEvaluationOptions {
  int supersampling = 2;
  int num_threads = -1;
  // Where renders are written as model_NAME.png / truth_NAME.png (for
  // looking at them); empty: not written.
  std::string render_dir;
};

struct ViewComparison {
  std::string name;
  ImageComparison raw;
  ImageComparison normalized;  // after a per-channel gain and offset
};

struct TextureEvaluation {
  std::vector<ViewComparison> views;
  double mean_psnr_db = 0;
  double mean_ssim = 0;
  double mean_normalized_psnr_db = 0;
  double mean_normalized_ssim = 0;
};

// `model_texture` / `truth_texture`: the atlases of meshes with texture
// coordinates (empty for per-vertex colours). Throws InputError if the
// viewpoints see none of the true surface.
TextureEvaluation EvaluateTexturedModel(
    const TriangleMesh& model,
    const cv::Mat& model_texture,
    const TriangleMesh& truth,
    const cv::Mat& truth_texture,
    const Scene& viewpoints,
    const TextureEvaluationOptions& options);

// A textured model against photographs it was not made from (leave one
// out): the model rendered unlit through each photograph's camera, and
// compared with the photograph over the pixels the model fills entirely,
// as it is (`raw`) and after a per-channel gain and offset (`normalized`).
// `photographs`: 8-bit BGR, by image name in `scene`. Throws InputError
// for a name the scene lacks, a size that differs from its camera's, or a
// photograph the model does not appear in.
TextureEvaluation EvaluateAgainstPhotographs(
    const TriangleMesh& model,
    const cv::Mat& model_texture,
    const Scene& scene,
    const std::vector<std::pair<std::string, cv::Mat>>& photographs,
    const TextureEvaluationOptions& options);

std::string TextureTable(const TextureEvaluation& evaluation);

// The evaluation as `bayon evaluate` reports it: the means and each view.
nlohmann::ordered_json TextureEvaluationJson(const TextureEvaluation& e);

}  // namespace bayon
