// SPDX-License-Identifier: BSD-3-Clause
//
// The render stage: pictures of a textured model from given viewpoints
// (ext/render/views.h), in three modes and as stereo pairs.
//
// - wireframe: hidden-line drawing, the visible triangle edges and the
//   silhouette as dark lines on white (or on the shaded view);
// - shaded: the surface in uniform grey, lit by a sun above and to the left
//   behind the viewer and an ambient sky, with cast shadows, so that the
//   form reads without the photographs' texture;
// - textured: the atlas as it is, unlit (the photographs carry their light).
//
// Stereo pairs (MakeStereoPair) in one of those modes, composed as red-cyan
// anaglyphs, side by side, or row-interleaved.
#pragma once

#include "ext/render/image_compose.h"
#include "ext/render/model_export.h"
#include "ext/render/views.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <functional>
#include <string>
#include <vector>

namespace bayon {

enum class RenderMode { kWireframe, kShaded, kTextured };
// "wireframe", "shaded", "textured".
std::string RenderModeName(RenderMode mode);

struct ModelRenderOptions {
  // Modes rendered for every viewpoint, each as <mode>_<view>.png.
  std::vector<RenderMode> modes = {
      RenderMode::kWireframe, RenderMode::kShaded, RenderMode::kTextured};
  // Wireframe lines on the shaded view instead of on white.
  bool wireframe_on_shaded = false;
  // Stereo images per viewpoint: anaglyph_<view>.png,
  // side_by_side_<view>.png, interleaved_<view>.png.
  bool anaglyph = false;
  bool side_by_side = false;
  bool interleaved = false;
  AnaglyphType anaglyph_type = AnaglyphType::kColor;
  // The mode the stereo images are drawn in.
  RenderMode stereo_mode = RenderMode::kTextured;
  StereoOptions stereo;
  // Samples per pixel along each axis (anti-aliasing); also the factor by
  // which wireframes are drawn finer before filtering.
  int supersampling = 3;
  // The sun for shaded views: degrees above the horizontal, and to the left
  // of the direction from the model towards the viewer.
  double sun_elevation_deg = 45;
  double sun_azimuth_deg = 40;
  // World vertical (for the sun's elevation).
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Vector3f background_bgr = Eigen::Vector3f(1, 1, 1);
  Eigen::Vector3f line_bgr = Eigen::Vector3f(0.1f, 0.1f, 0.1f);
  int num_threads = -1;
  bool HasStereo() const { return anaglyph || side_by_side || interleaved; }
  // Every field but the colours; the stereo forms as one list, `stereo`.
  void Register(OptionRegistry* registry);
  // The modes a model has: where it has no texture, the textured mode is
  // left out of the modes and the stereo is shaded, unless they were
  // asked for (`*_given`), which is refused.
  void FitToModel(const std::string& model_path,
                  bool has_atlas,
                  bool modes_given,
                  bool stereo_mode_given);
  // Throws InputError naming the option; also when a textured mode is asked
  // of a model without an atlas (has_atlas false).
  void Check(bool has_atlas) const;
};

struct ModelRenderSummary {
  int num_views = 0;
  int num_images = 0;
  double stereo_base_m = 0;  // of the last pair (for the summary)
  double seconds = 0;
};

// Renders every viewpoint in the requested modes and stereo forms and hands
// each finished 8-bit BGR image to `sink` with its file name, as soon as it
// exists. Shows progress per view.
ModelRenderSummary RenderModelViews(
    const TexturedModel& model,
    const std::vector<Viewpoint>& viewpoints,
    const ModelRenderOptions& options,
    const std::function<void(const std::string& file_name,
                             const cv::Mat& image)>& sink);

}  // namespace bayon
