// SPDX-License-Identifier: BSD-3-Clause
//
// A model carried back into its photographs: the mesh's silhouette,
// rendered through each station's camera (ext/render, with the camera's
// distortion), against the photograph's object region, for objects
// photographed against a dark background (temple-ring's black cloth). The
// object region is where the photograph's grey value exceeds a threshold;
// the figure is the intersection over union of the two regions per
// photograph. The background's own clutter (a fold of cloth, a stand) that
// passes the threshold counts against the model: the masks written for
// looking show where. What the clutter leaves possible is estimated too:
// the parts of the object region (8-connected) that the model's silhouette
// does not touch at all are taken as clutter, and the best IoU is that of
// a model covering exactly the rest.
#pragma once

#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace bayon {

struct SilhouetteOptions {
  // Grey value (0..255) above which a photograph's pixel is the object's.
  double grey_threshold = 40;
  // Share of a pixel's render samples on the mesh for it to count as the
  // model's.
  double min_coverage = 0.5;
  int supersampling = 2;
  int num_threads = -1;
  // Where NAME.png masks are written (white: both, red: the model only,
  // blue: the photograph only); empty: not written.
  std::string mask_dir;
  void Check() const;  // throws InputError naming field, value, rule
};

struct SilhouetteView {
  std::string name;  // the image's
  double iou = 0;
  // Shares of the union: the model's pixels outside the photograph's
  // object region, and the object's pixels the model leaves out.
  double model_only = 0;
  double photograph_only = 0;
  // The IoU of a model covering exactly the object region less the clutter
  // (the region's parts the model does not touch).
  double best_iou = 1;
};

struct SilhouetteEvaluation {
  std::vector<SilhouetteView> views;
  double mean_iou = 0;
  double min_iou = 0;
  double mean_best_iou = 0;
  std::string worst;  // the view of min_iou
};

// Every image of `scene` read from image_path. Throws InputError where an
// image cannot be read or the mesh is empty.
SilhouetteEvaluation EvaluateSilhouettes(const TriangleMesh& mesh,
                                         const Scene& scene,
                                         const std::string& image_path,
                                         const SilhouetteOptions& options);

// The per-view table and the mean and worst, for the console.
std::string SilhouetteTable(const SilhouetteEvaluation& evaluation);

// The evaluation as `bayon evaluate` reports it ("silhouettes"), with the
// grey threshold it used.
nlohmann::ordered_json SilhouetteEvaluationJson(
    const SilhouetteEvaluation& e, const SilhouetteOptions& options);

}  // namespace bayon
