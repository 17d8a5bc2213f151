// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon evaluate`: every product of a run against the truth. The truth is a
// COLMAP model, or a synthetic workspace's gt/ folder (sparse/, surface.ply,
// ground.ply, its texture, heldout/, calibration.json, synth.json), from
// which the other truth files default. Dense clouds, meshes and textured
// models made from the evaluated sparse model are brought into the truth's
// datum by the same similarity as the cameras (with align and input_path);
// without a sparse model they are taken to be in the truth's datum already.
//
// Two evaluations need no truth: a mesh's silhouettes against photographs of
// an object on a dark background, and a textured model against photographs
// it was not made from (leave one out).
#pragma once

#include "ext/core/option_registry.h"
#include "ext/eval/silhouette_eval.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace bayon {

struct EvaluationOptions {
  // The truth: a model folder or a synthetic workspace's gt/ folder.
  std::string ground_truth_path;
  // The sparse model to evaluate, and its calibration.json (default: the
  // one beside it).
  std::string input_path;
  std::string calibration_path;
  // A database whose pair orientations (`bayon relative`) to evaluate; with
  // adjacent_pairs only neighbouring images in its order, last with first.
  std::string database_path;
  bool adjacent_pairs = false;
  // A dense cloud; where to write it in the truth's frame with each point's
  // distance to the true surface; the cloud before `bayon edit` (blunders
  // flagged), when cloud_path is the edited one.
  std::string cloud_path;
  std::string cloud_errors_path;
  std::string edit_input_path;
  // With edit_input_path: unflagged points farther than this from the truth
  // (the input's own blunders) are counted apart. synth_cloud's smallest
  // blunder offset: an unflagged point as far off is as much a blunder as an
  // injected one.
  double off_surface_m = 0.01;
  std::string mesh_path;
  // A textured model (PLY with texcoords and a TextureFile, or vertex
  // colours) and its atlas (default: the PLY's TextureFile).
  std::string textured_mesh_path;
  std::string texture_path;
  // Default: the truth folder's surface.ply and heldout/.
  std::string surface_path;
  std::string heldout_path;
  // Default: synth.json's GSD.
  double gsd_m = 0;
  // The truth counts as reached within this distance; 0: within
  // completeness_threshold_gsd GSDs.
  double completeness_threshold_m = 0;
  double completeness_threshold_gsd = 2;
  int num_samples = 200000;  // of the true surface and of meshes
  std::string render_path;   // the texture evaluation's renders
  // Silhouettes of mesh_path through input_path's cameras against these
  // photographs; no truth needed.
  std::string silhouette_image_path;
  SilhouetteOptions silhouette;
  // Leave one out: textured_mesh_path rendered through input_path's cameras
  // of these photographs and compared with them; no truth needed.
  std::string image_path;
  std::vector<std::string> image_names;
  bool align = true;  // fit a similarity first; false: one datum
  std::string label;  // the model's name in the tables
  int num_threads = -1;

  // Refuses, with one line, what is missing or inconsistent.
  // Every field, under `bayon evaluate`'s flags.
  void Register(OptionRegistry* registry);
  void Check() const;
};

// The evaluation the options ask for, its tables printed to `tables` as each
// is done; returns the report. Reads the inputs only.
nlohmann::ordered_json RunEvaluation(const EvaluationOptions& options,
                                     std::FILE* tables);

}  // namespace bayon
