// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/sparse_eval.h"

#include "ext/core/alignment.h"
#include "ext/core/errors.h"
#include "ext/core/string_printf.h"

#include <cmath>
#include <map>

namespace bayon {

SparseEvaluation EvaluateSparse(const Scene& model,
                                const Scene& truth,
                                const SparseEvaluationOptions& options) {
  SparseEvaluation evaluation;
  evaluation.num_truth_images = static_cast<int>(truth.images.size());
  evaluation.num_model_points = static_cast<int>(model.points3D.size());

  std::map<std::string, const Image*> model_by_name;
  for (const auto& [image_id, image] : model.images) {
    model_by_name[image.name] = &image;
  }
  std::vector<Eigen::Vector3d> model_centers, truth_centers;
  std::vector<std::pair<const Image*, const Image*>> common;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& [image_id, image] : truth.images) {
    centroid += image.cam_from_world.Center();
    auto it = model_by_name.find(image.name);
    if (it == model_by_name.end()) continue;
    common.emplace_back(it->second, &image);
    model_centers.push_back(it->second->cam_from_world.Center());
    truth_centers.push_back(image.cam_from_world.Center());
  }
  if (!truth.images.empty()) centroid /= truth.images.size();
  for (const auto& [image_id, image] : truth.images) {
    evaluation.mean_camera_distance +=
        (image.cam_from_world.Center() - centroid).norm();
  }
  if (!truth.images.empty())
    evaluation.mean_camera_distance /= truth.images.size();
  evaluation.num_registered = static_cast<int>(common.size());

  const size_t min_common = options.align ? 3 : 1;
  if (common.size() < min_common) {
    ThrowInputError("the model shares only ",
                    common.size(),
                    " image names with the truth; at least ",
                    min_common,
                    " are needed to compare them");
  }
  if (options.align) {
    const auto similarity = EstimateSim3d(model_centers, truth_centers);
    if (!similarity) {
      ThrowInputError(
          "the registered camera centres are collinear; no "
          "similarity can be fitted");
    }
    evaluation.truth_from_model = *similarity;
  }

  std::map<std::string, ImageEvaluation> by_name;
  double center_sum_sq = 0, rotation_sum_sq = 0;
  for (const auto& [model_image, truth_image] : common) {
    ImageEvaluation image;
    image.name = truth_image->name;
    image.registered = true;
    const Rigid3d aligned =
        evaluation.truth_from_model.TransformPose(model_image->cam_from_world);
    image.center_error =
        (aligned.Center() - truth_image->cam_from_world.Center()).norm();
    image.rotation_error_deg =
        RotationAngleBetween(aligned.rotation,
                             truth_image->cam_from_world.rotation) *
        180.0 / M_PI;
    center_sum_sq += image.center_error * image.center_error;
    rotation_sum_sq += image.rotation_error_deg * image.rotation_error_deg;
    evaluation.center_max = std::max(evaluation.center_max, image.center_error);
    evaluation.rotation_max_deg =
        std::max(evaluation.rotation_max_deg, image.rotation_error_deg);
    by_name[image.name] = image;
  }
  evaluation.center_rms = std::sqrt(center_sum_sq / common.size());
  evaluation.rotation_rms_deg = std::sqrt(rotation_sum_sq / common.size());
  if (evaluation.mean_camera_distance > 0) {
    evaluation.center_rms_relative =
        evaluation.center_rms / evaluation.mean_camera_distance;
    evaluation.center_max_relative =
        evaluation.center_max / evaluation.mean_camera_distance;
  }
  for (const auto& [image_id, image] : truth.images) {
    auto it = by_name.find(image.name);
    if (it != by_name.end()) {
      evaluation.images.push_back(it->second);
    } else {
      ImageEvaluation missing;
      missing.name = image.name;
      evaluation.images.push_back(missing);
    }
  }
  return evaluation;
}

nlohmann::ordered_json SparseEvaluationJson(const SparseEvaluation& e) {
  nlohmann::ordered_json json;
  json["num_truth_images"] = e.num_truth_images;
  json["num_registered"] = e.num_registered;
  json["num_model_points"] = e.num_model_points;
  json["similarity"] = {{"scale", e.truth_from_model.scale},
                        {"qvec",
                         {e.truth_from_model.rotation.w(),
                          e.truth_from_model.rotation.x(),
                          e.truth_from_model.rotation.y(),
                          e.truth_from_model.rotation.z()}},
                        {"tvec",
                         {e.truth_from_model.translation.x(),
                          e.truth_from_model.translation.y(),
                          e.truth_from_model.translation.z()}}};
  json["mean_camera_distance"] = e.mean_camera_distance;
  json["center_rms"] = e.center_rms;
  json["center_max"] = e.center_max;
  json["center_rms_relative"] = e.center_rms_relative;
  json["center_max_relative"] = e.center_max_relative;
  json["rotation_rms_deg"] = e.rotation_rms_deg;
  json["rotation_max_deg"] = e.rotation_max_deg;
  json["images"] = nlohmann::ordered_json::array();
  for (const ImageEvaluation& image : e.images) {
    json["images"].push_back(
        {{"name", image.name},
         {"registered", image.registered},
         {"center_error", image.center_error},
         {"rotation_error_deg", image.rotation_error_deg}});
  }
  return json;
}

std::string SparseEvaluationTable(const std::string& label,
                                  const SparseEvaluation& e) {
  return StringPrintf("%-28s %10s %12s %12s %12s %12s\n",
                      "model",
                      "registered",
                      "centre RMS",
                      "centre max",
                      "centre RMS %",
                      "rot RMS deg") +
         StringPrintf("%-28s %6d/%-3d %12.6g %12.6g %12.5f %12.5f\n",
                      label.c_str(),
                      e.num_registered,
                      e.num_truth_images,
                      e.center_rms,
                      e.center_max,
                      100.0 * e.center_rms_relative,
                      e.rotation_rms_deg);
}

}  // namespace bayon
