// SPDX-License-Identifier: BSD-3-Clause
//
// A workspace's results as one self-contained HTML page (`bayon report`,
// issue 10): the pipeline run, the image network, the tie-point
// distribution, the image residuals, the additional parameters and the
// precision table of the bundle adjustment (as the Bayon paper's sec. 3.2.4
// reports them), the dense cloud, the editing, the mesh, the texture,
// renders of the model, and the comparison with stock COLMAP.
//
// What it reads (W = the workspace; all optional but sparse/adjusted):
//   W/sparse/adjusted/            the adjusted model, calibration.json,
//                                 adjustment.json (bayon adjust)
//   W/database.db                 keypoint counts (tracks vs. LSM tie
//                                 observations), scanned frames
//   W/pipeline.json               stages, their status and time
//   W/sparse/initial/strip.json   the strip (ring closure)
//   W/pipeline/tiepoints.json     bayon tiepoints --report_path
//   W/dense/points.json, points.ply, edit.json; W/mesh/mesh.json;
//   W/model/texture.json, model.png; W/renders/*.png; W/viewer/index.html
//   W/colmap/comparison.json      bayon compare_colmap
//   W/evaluation.json             bayon evaluate against a truth
// A part that is missing becomes a line "not run" in its section; a part
// that cannot be read becomes a line saying why. Only a missing workspace
// or adjusted model is an error.
//
// Charts are inline SVG (ext/report/svg_plot.h), pictures JPEG data URIs;
// the page loads nothing from anywhere (the viewer is a relative link).
// Units: pixels for image residuals; the datum's metres for object
// coordinates, their precision in millimetres; a free network keeps the
// strip's model units (its "mm" are thousandths of them, as adjustment.txt
// says).
#pragma once

#include "ext/core/option_registry.h"

#include <string>
#include <vector>

namespace bayon {

struct WorkspaceReportOptions {
  // Page title; empty: "bayon report: <workspace folder name>".
  std::string title;
  // The folder the page will be written to: links into the workspace (the
  // viewer) are relative to it. Empty: the workspace itself.
  std::string report_dir;
  // Embedded renders: longest side in pixels and JPEG quality. Larger
  // pictures show more detail and make the page heavier (about 60 KB per
  // 800 px picture at quality 85).
  int max_render_size_px = 800;
  int jpeg_quality = 85;
  int max_renders = 8;
  // Sparse points drawn in the plan and side views (evenly thinned); the
  // page grows by about 40 bytes per point and view.
  int max_plot_points = 4000;
  // Tie points drawn in each image's frame, and frames drawn (every k-th
  // image beyond that).
  int max_frame_points = 800;
  int max_frames = 48;
  // Cells across the image frame for the mean residual vectors (systematic
  // image errors).
  int residual_grid_cells = 8;

  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value and rule
};

struct WorkspaceReport {
  std::string html;
  // Section ids in page order, and the titles of those shown as "not run".
  std::vector<std::string> section_ids;
  std::vector<std::string> not_run;
  // Parts that exist but could not be read or shown: "<file>: <why>".
  std::vector<std::string> problems;
  int num_images = 0;  // registered in the adjusted model
  int num_points3D = 0;
  int num_observations = 0;
  int num_charts = 0;    // inline SVG elements
  int num_pictures = 0;  // embedded JPEGs
};

// Throws InputError for a missing workspace folder or a missing
// sparse/adjusted model ("run bayon pipeline or bayon adjust first") and
// for a model that cannot be read.
WorkspaceReport BuildWorkspaceReport(const std::string& workspace_path,
                                     const WorkspaceReportOptions& options);

}  // namespace bayon
