// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon dense` as one call: the masters chosen and matched as the options'
// mode says (dense.h), and the cloud written with COLMAP's fused.ply, the
// report and a picture per master of what became of its cells.
#pragma once

#include "ext/dense/dense.h"

#include <map>
#include <string>
#include <vector>

namespace bayon {

struct DenseResult {
  PointCloud cloud;
  DenseReport report;
  // Per point, the images that saw it, the master first.
  std::vector<std::vector<image_t>> seen;
  // Photographs that could not be read, left out with why: the masters
  // match without them.
  std::map<image_t, std::string> unreadable;
  // paper: the images matched (their colours draw the reject pictures).
  std::map<image_t, DenseImage> images;
};

// Selects the masters (logging each with its search images or source
// views), matches them, and adds the unmodelled sigma. RunFailure when no
// point was matched.
DenseResult RunDense(const Scene& scene,
                     const std::string& image_path,
                     const DenseOptions& options);

struct DenseOutputPaths {
  std::string cloud;   // PLY with every attribute
  std::string fused;   // COLMAP's fused.ply, with fused.ply.vis beside it
  std::string report;  // DenseReportJson
  // <cloud's folder>/rejects: a picture per matched master (RejectMap).
  std::string RejectsFolder() const;
};

// Writes what `paths` names; the .vis indices are positions in the model's
// image list, as COLMAP's meshers read them.
void WriteDenseOutputs(const Scene& scene,
                       const std::string& image_path,
                       const DenseResult& result,
                       const DenseOptions& options,
                       const DenseOutputPaths& paths);

}  // namespace bayon
