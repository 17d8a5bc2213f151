// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/sparse_eval.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace bayon {
namespace {

nlohmann::ordered_json SparseToJson(const SparseEvaluation& e) {
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

void PrintSparseTable(const std::string& label, const SparseEvaluation& e) {
  std::printf("%-28s %10s %12s %12s %12s %12s\n",
              "model",
              "registered",
              "centre RMS",
              "centre max",
              "centre RMS %",
              "rot RMS deg");
  std::printf("%-28s %6d/%-3d %12.6g %12.6g %12.5f %12.5f\n",
              label.c_str(),
              e.num_registered,
              e.num_truth_images,
              e.center_rms,
              e.center_max,
              100.0 * e.center_rms_relative,
              e.rotation_rms_deg);
}

}  // namespace

int RunEvaluate(int argc, char** argv) {
  std::string input_path, ground_truth_path, output_path, label;
  bool align = true;
  CommandLine command("evaluate",
                      "Compare a sparse model with the ground truth: images "
                      "registered, camera centre and rotation errors after a "
                      "7-parameter similarity. Prints a table, writes JSON.");
  CLI::App& app = command.app();
  app.add_option("--input_path", input_path, "Model to evaluate")->required();
  app.add_option("--ground_truth_path",
                 ground_truth_path,
                 "True model (e.g. W/gt/sparse)")
      ->required();
  app.add_option("--output_path", output_path, "Write the report as JSON here");
  app.add_option(
      "--align", align, "1: fit a similarity first; 0: both share a datum");
  app.add_option("--label", label, "Name of the model in the table");
  if (!command.Parse(argc, argv)) return 0;

  const Scene model = ReadModel(input_path);
  const Scene truth = ReadModel(ground_truth_path);
  SparseEvaluationOptions options;
  options.align = align;
  const SparseEvaluation evaluation = EvaluateSparse(model, truth, options);
  PrintSparseTable(label.empty() ? input_path : label, evaluation);
  if (!output_path.empty()) {
    nlohmann::ordered_json report;
    report["input_path"] = input_path;
    report["ground_truth_path"] = ground_truth_path;
    report["sparse"] = SparseToJson(evaluation);
    WriteFileAtomically(output_path, report.dump(2) + "\n");
  }
  return 0;
}

}  // namespace bayon
