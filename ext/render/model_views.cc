// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/model_views.h"

#include "ext/core/errors.h"
#include "ext/core/progress.h"
#include "ext/render/mesh_renderer.h"

#include <glog/logging.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace bayon {
namespace {

constexpr double kDegree = M_PI / 180.0;

bool Has(const std::vector<RenderMode>& modes, RenderMode mode) {
  return std::find(modes.begin(), modes.end(), mode) != modes.end();
}

// The sun for a view: `sun_azimuth_deg` to the left of the horizontal
// direction from the model back towards the camera, `sun_elevation_deg`
// above the horizontal. Lit from the viewer's side, every view shows its
// surfaces lit and the shadows falling away from the viewer.
Eigen::Vector3d SunDirection(const RenderView& view,
                             const ModelRenderOptions& options) {
  const Eigen::Vector3d up = options.up.normalized();
  const Eigen::Matrix3d rotation =
      view.cam_from_world.rotation.toRotationMatrix();
  Eigen::Vector3d back = -rotation.row(2).transpose();
  back -= up * up.dot(back);
  if (back.norm() < 1e-6) {
    // Looking straight down or up: the image's up direction instead.
    back = -rotation.row(1).transpose();
    back -= up * up.dot(back);
  }
  back.normalize();
  const Eigen::Vector3d left = back.cross(up);
  const double azimuth = options.sun_azimuth_deg * kDegree;
  const double elevation = options.sun_elevation_deg * kDegree;
  return (std::cos(elevation) *
              (std::cos(azimuth) * back + std::sin(azimuth) * left) +
          std::sin(elevation) * up)
      .normalized();
}

struct ModeImages {
  cv::Mat wireframe, shaded, textured;  // CV_8UC3 where rendered
};

class ModelViewRenderer {
 public:
  ModelViewRenderer(const TexturedModel& model,
                    const ModelRenderOptions& options)
      : options_(options), grey_(GreyMesh(model.mesh)) {
    if (!model.atlas.empty() && model.mesh.HasTexcoords()) {
      textured_.emplace(model.mesh, model.atlas);
    }
    base_.background_horizon_bgr = options.background_bgr;
    base_.background_zenith_bgr = options.background_bgr;
    base_.num_threads = options.num_threads;
    base_.shadow_map.size = 2048;
    base_.shadow_map.num_threads = options.num_threads;
  }

  // The view in `modes`; the sun for the shaded ones given.
  ModeImages Render(const RenderView& view,
                    const std::vector<RenderMode>& modes,
                    const Eigen::Vector3d& sun) const {
    ModeImages images;
    const int s = options_.supersampling;
    const cv::Size size(int(view.camera.width), int(view.camera.height));
    const bool wireframe = Has(modes, RenderMode::kWireframe);
    if (wireframe || Has(modes, RenderMode::kShaded)) {
      // One pass at s times the size, one sample per pixel: the shaded
      // image box-filtered down is what s x s supersampling gives, and the
      // fine triangle ids draw the wireframe's lines.
      Lighting lighting;
      lighting.enabled = true;
      lighting.sun_direction = sun;
      // Neutral white light, and more sky than outdoors, so that faces
      // turned from the sun keep their form instead of going black.
      lighting.sun_intensity = 0.8;
      lighting.ambient_intensity = 0.55;
      lighting.sun_bgr = Eigen::Vector3f::Ones();
      lighting.ambient_bgr = Eigen::Vector3f::Ones();
      RenderOptions render_options = base_;
      render_options.supersampling = 1;
      render_options.geometry_buffers = wireframe;
      const RenderResult fine =
          grey_.Render(ScaleView(view, s), lighting, render_options);
      cv::Mat shaded;
      cv::resize(fine.color, shaded, size, 0, 0, cv::INTER_AREA);
      if (Has(modes, RenderMode::kShaded)) images.shaded = ToneMap8(shaded);
      if (wireframe) {
        const cv::Mat background =
            options_.wireframe_on_shaded
                ? shaded
                : cv::Mat(size,
                          CV_32FC3,
                          cv::Scalar(options_.background_bgr.x(),
                                     options_.background_bgr.y(),
                                     options_.background_bgr.z()));
        images.wireframe = ToneMap8(PaintLines(
            WireframeCoverage(
                fine.triangle_id, s, WireframeLineWidth(fine.triangle_id, s)),
            background,
            options_.line_bgr));
      }
    }
    if (Has(modes, RenderMode::kTextured)) {
      CHECK(textured_.has_value());
      RenderOptions render_options = base_;
      render_options.supersampling = s;
      render_options.geometry_buffers = false;
      images.textured =
          ToneMap8(textured_->Render(view, Lighting(), render_options).color);
    }
    return images;
  }

 private:
  static TriangleMesh GreyMesh(TriangleMesh mesh) {
    mesh.face_texcoords.clear();
    mesh.vertices.colors.clear();
    return mesh;
  }

  const ModelRenderOptions& options_;
  MeshRenderer grey_;
  std::optional<MeshRenderer> textured_;
  RenderOptions base_;
};

const cv::Mat& ImageOf(const ModeImages& images, RenderMode mode) {
  switch (mode) {
    case RenderMode::kWireframe:
      return images.wireframe;
    case RenderMode::kShaded:
      return images.shaded;
    case RenderMode::kTextured:
      break;
  }
  return images.textured;
}

}  // namespace

std::string RenderModeName(RenderMode mode) {
  switch (mode) {
    case RenderMode::kWireframe:
      return "wireframe";
    case RenderMode::kShaded:
      return "shaded";
    case RenderMode::kTextured:
      break;
  }
  return "textured";
}

void ModelRenderOptions::Register(OptionRegistry* r) {
  const auto render_modes = ChoicesOf<RenderMode>(
      RenderModeName,
      {RenderMode::kWireframe, RenderMode::kShaded, RenderMode::kTextured});
  r->AddChoices("modes",
                &modes,
                render_modes,
                "Comma-separated: wireframe, shaded, textured (textured is "
                "left out by default for a model without texture)");
  r->Add("wireframe_on_shaded",
         &wireframe_on_shaded,
         "1: wireframe lines on the shaded view instead of white");
  r->AddSwitches("stereo",
                 {{"anaglyph", &anaglyph},
                  {"side_by_side", &side_by_side},
                  {"interleaved", &interleaved}},
                 "Comma-separated: anaglyph, side_by_side, interleaved "
                 "(default none)");
  r->AddChoice("stereo_mode",
               &stereo_mode,
               render_modes,
               "Mode of the stereo images (default textured, shaded for a "
               "model without texture)");
  r->Add("stereo_base",
         &stereo.base_m,
         "Stereo base in metres (0 = 1/30 of the nearest model distance)");
  r->AddChoice("anaglyph_type",
               &anaglyph_type,
               {{"color", AnaglyphType::kColor}, {"gray", AnaglyphType::kGray}},
               "color or gray");
  r->Add("supersampling",
         &supersampling,
         "Samples per pixel along each axis (anti-aliasing)");
  r->Add("sun_elevation_deg",
         &sun_elevation_deg,
         "shaded: sun above the horizontal (degrees)");
  r->Add("sun_azimuth_deg",
         &sun_azimuth_deg,
         "shaded: sun to the left of the viewer's direction (degrees)");
  r->Add("up",
         &up,
         "World vertical x,y,z (bayon's datum: z; with stations viewpoints "
         "and no up given, the cameras' mean image up)");
  r->Add("num_threads", &num_threads, "-1 = all cores");
}

void ModelRenderOptions::FitToModel(const std::string& model_path,
                                    bool has_atlas,
                                    bool modes_given,
                                    bool stereo_mode_given) {
  if (!stereo_mode_given) {
    stereo_mode = has_atlas ? RenderMode::kTextured : RenderMode::kShaded;
  }
  if (has_atlas) return;
  auto textured = std::find(modes.begin(), modes.end(), RenderMode::kTextured);
  if (textured != modes.end()) {
    if (modes_given) {
      ThrowInputError(model_path,
                      ": the model has no texture, so there is no textured "
                      "mode (choose modes wireframe,shaded)");
    }
    LOG(INFO) << model_path << " has no texture: textured mode left out";
    modes.erase(textured);
  }
  if (HasStereo() && stereo_mode == RenderMode::kTextured) {
    ThrowInputError(model_path,
                    ": the model has no texture, so no textured stereo "
                    "(choose stereo_mode shaded or wireframe)");
  }
}

void ModelRenderOptions::Check(bool has_atlas) const {
  if (modes.empty() && !HasStereo()) {
    ThrowInputError("modes: nothing to render (no mode and no stereo)");
  }
  CheckOption(supersampling >= 1 && supersampling <= 8,
              "supersampling",
              "1 to 8",
              supersampling);
  CheckOption(sun_elevation_deg > 0 && sun_elevation_deg <= 90,
              "sun_elevation_deg",
              "in (0, 90]",
              sun_elevation_deg);
  CheckOption(up.allFinite() && up.norm() > 1e-9,
              "up",
              "a non-zero vector",
              up.transpose());
  if (HasStereo()) stereo.Check();
  const bool wants_texture =
      Has(modes, RenderMode::kTextured) ||
      (HasStereo() && stereo_mode == RenderMode::kTextured);
  if (wants_texture && !has_atlas) {
    ThrowInputError(
        "the model has no texture atlas, so it cannot be "
        "rendered in textured mode");
  }
}

ModelRenderSummary RenderModelViews(
    const TexturedModel& model,
    const std::vector<Viewpoint>& viewpoints,
    const ModelRenderOptions& options,
    const std::function<void(const std::string&, const cv::Mat&)>& sink) {
  options.Check(!model.atlas.empty() && model.mesh.HasTexcoords());
  // Each view is rendered at supersampling times its size (three floats a
  // sample, for the shaded and wireframe modes): refuse before any work
  // what would not fit in memory (2^28 samples, 3 GB).
  for (const Viewpoint& viewpoint : viewpoints) {
    const double samples = double(viewpoint.view.camera.width) *
                           double(viewpoint.view.camera.height) *
                           options.supersampling * options.supersampling;
    if (samples > double(1 << 28)) {
      ThrowInputError("view ",
                      viewpoint.name,
                      ": ",
                      viewpoint.view.camera.width,
                      " x ",
                      viewpoint.view.camera.height,
                      " pixels at supersampling ",
                      options.supersampling,
                      " is too large to render (lower supersampling, "
                      "max_image_size or width/height)");
    }
  }
  Timer timer;
  ModelRenderSummary summary;
  const ModelViewRenderer renderer(model, options);
  Progress progress("render", viewpoints.size(), "views");
  for (const Viewpoint& viewpoint : viewpoints) {
    const Eigen::Vector3d sun = SunDirection(viewpoint.view, options);
    const ModeImages images =
        renderer.Render(viewpoint.view, options.modes, sun);
    for (RenderMode mode : options.modes) {
      sink(StrCat(RenderModeName(mode), "_", viewpoint.name, ".png"),
           ImageOf(images, mode));
      ++summary.num_images;
    }
    if (options.HasStereo()) {
      const StereoPair pair = MakeStereoPair(viewpoint, options.stereo);
      summary.stereo_base_m = pair.base_m;
      const std::vector<RenderMode> mode = {options.stereo_mode};
      const cv::Mat left =
          ImageOf(renderer.Render(pair.left, mode, sun), options.stereo_mode);
      const cv::Mat right =
          ImageOf(renderer.Render(pair.right, mode, sun), options.stereo_mode);
      auto emit = [&](const char* kind, const cv::Mat& image) {
        sink(StrCat(kind, "_", viewpoint.name, ".png"), image);
        ++summary.num_images;
      };
      if (options.anaglyph) {
        emit("anaglyph", Anaglyph(left, right, options.anaglyph_type));
      }
      if (options.side_by_side) emit("side_by_side", SideBySide(left, right));
      if (options.interleaved) emit("interleaved", RowInterleaved(left, right));
    }
    ++summary.num_views;
    progress.Add();
  }
  progress.Finish();
  summary.seconds = timer.Seconds();
  return summary;
}

}  // namespace bayon
