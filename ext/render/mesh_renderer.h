// SPDX-License-Identifier: BSD-3-Clause
//
// A software renderer for triangle meshes seen through bayon's cameras,
// shared by the synthetic scenes (ground truth), the texture stage
// (visibility, view selection), the render stage (shaded and textured
// views) and the dense stage (depth and visibility maps).
//
// What it draws: a TriangleMesh (ext/core/point_cloud.h) coloured by a
// texture atlas (face_texcoords + an image), by per-vertex colours, or a
// uniform grey; unlit (the colour itself) or lit by a directional sun and an
// ambient sky, with cast shadows from a shadow map seen from the sun.
//
// How the camera model is honoured exactly (distortion included): the image
// is not rasterised in distorted space. For each sample position in the
// output image the renderer computes the exact ray through that position
// (PixelRays: Camera::CamFromImg on a coarse grid, refined by Newton steps
// on Camera::ImgFromCam to 1e-6 px) and intersects it exactly with the mesh.
// To find which triangles to intersect, an ideal pinhole image covering all
// rays of the distorted frame is first rasterised (a z-buffer of triangle
// ids, with pixels no larger than half an image pixel anywhere); each ray
// is intersected with the triangles found at the 2 x 2 raster pixels around
// it (4 x 4 when none of them contains it, then their neighbours sharing a
// vertex) and the nearest hit is kept. Depths, barycentric coordinates and
// hence every projected point are therefore exact to rounding, not to a
// raster's resolution; only where a triangle narrower than a raster pixel
// lies in front of another can the farther one show through.
//
// Anti-aliasing: s x s samples on a regular grid in every output pixel
// (supersampling), averaged with equal weights (a box filter). Depth,
// triangle id and barycentric coordinates are those of the ray through the
// pixel centre (the middle sample when s is odd, an extra ray otherwise).
//
// Colours are BGR floats (OpenCV's channel order). Texture colours are used
// as they are stored (8-bit scaled to [0, 1]); lighting multiplies them, so
// lit colours can exceed 1 and the caller decides the tone curve.
//
// Frames: world coordinates in metres; cam_from_world as everywhere in
// bayon (x right, y down, z forward); pixels in COLMAP's convention (the
// centre of the upper-left pixel is (0.5, 0.5)).
#pragma once

#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/point_cloud.h"
#include "ext/core/rigid3.h"
#include "ext/render/mip_texture.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace bayon {

// One image to render: a camera, its pose and, for BROWN_BEYER cameras, the
// image's own frame (a film scan's affine frame in the scan).
struct RenderView {
  Camera camera;
  Rigid3d cam_from_world;
  std::optional<ImageFrame> frame;
  // BROWN_BEYER only: image coordinates (mm) outside this box are not part
  // of the photograph (the film border of a scan); they get
  // RenderOptions::border_bgr and no geometry.
  std::optional<Eigen::AlignedBox2d> frame_window_mm;
};

// Directional sun and ambient sky. Off: every surface shows its own colour.
struct Lighting {
  bool enabled = false;
  // World direction towards the sun (normalised on use).
  Eigen::Vector3d sun_direction = Eigen::Vector3d(0.3, -0.4, 0.866);
  // Irradiance of a surface facing the sun, and of the sky (ambient).
  double sun_intensity = 1.0;
  double ambient_intensity = 0.35;
  // Share of the ambient light that depends on the surface's orientation:
  // a face looking up gets ambient * 1, one looking down ambient * (1 - w).
  double ambient_up_weight = 0.4;
  // Colour balance of the sun and the sky (BGR multipliers).
  Eigen::Vector3f sun_bgr = Eigen::Vector3f(0.92f, 0.98f, 1.05f);
  Eigen::Vector3f ambient_bgr = Eigen::Vector3f(1.08f, 1.0f, 0.95f);
  // Cast shadows (a shadow map from the sun); without them only the
  // orientation towards the sun shades a surface.
  bool shadows = true;
  void Check() const;
};

struct ShadowMapOptions {
  // Texels along each side. The map covers `region` seen from the sun; its
  // texel size bounds how sharp shadow edges are.
  int size = 4096;
  // World box of the shadow casters; empty: the mesh's bounding box. Keep
  // it tight (the object, not a large ground plane) for sharp shadows;
  // points outside its shadow volume are lit.
  Eigen::AlignedBox3d region;
  int num_threads = -1;
  void Check() const;
};

// Depth of the scene seen from the sun (orthographic).
struct ShadowMap {
  Eigen::Vector3d sun_direction = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axis_x = Eigen::Vector3d::UnitX();  // map columns
  Eigen::Vector3d axis_y = Eigen::Vector3d::UnitY();  // map rows
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();   // (x, y) of texel 0
  double texel_size = 0;
  int size = 0;
  // -(sun_direction . X) of the surface nearest the sun, +inf where none.
  std::vector<float> depth;

  // Share of the sun that reaches `point` (0 in shadow, 1 lit, between on
  // shadow edges), with a bias along `normal` against self-shadowing.
  double Visibility(const Eigen::Vector3d& point,
                    const Eigen::Vector3d& normal) const;
};

struct RenderOptions {
  // Samples per pixel along each axis (s x s per pixel).
  int supersampling = 3;
  // Also produce depth, triangle id and barycentric buffers.
  bool geometry_buffers = true;
  // Colour where rays hit nothing: a sky from the horizon colour (looking
  // along the world's horizontal) to the zenith colour (looking up); below
  // the horizon the horizon colour.
  Eigen::Vector3f background_horizon_bgr = Eigen::Vector3f(0.85f, 0.80f, 0.75f);
  Eigen::Vector3f background_zenith_bgr = Eigen::Vector3f(0.80f, 0.55f, 0.35f);
  // Colour outside RenderView::frame_window_mm (film border).
  Eigen::Vector3f border_bgr = Eigen::Vector3f(0.02f, 0.02f, 0.025f);
  // Triangle parts nearer to the camera than this (metres) are cut away.
  double near_clip = 0.01;
  // Used when lighting casts shadows and no shadow map is passed in.
  ShadowMapOptions shadow_map;
  int num_threads = -1;
  void Check() const;
};

struct RenderStats {
  int64_t num_samples = 0;      // rays traced
  int64_t num_hits = 0;         // rays that hit the mesh
  int64_t num_missed_rays = 0;  // rays the camera model could not invert
  // Largest re-projection miss of the pixel-centre rays: how exactly the
  // camera model was followed (pixels).
  double max_ray_residual_px = 0;
  int raster_width = 0;  // the pinhole visibility raster
  int raster_height = 0;
  double seconds = 0;
};

struct RenderResult {
  cv::Mat color;     // CV_32FC3, BGR
  cv::Mat coverage;  // CV_32F, share of the pixel's samples on the mesh
  // Geometry of the pixel-centre ray (when requested):
  cv::Mat depth;        // CV_32F, camera-frame z in metres, 0 = no hit
  cv::Mat triangle_id;  // CV_32S, face index, -1 = no hit
  cv::Mat barycentric;  // CV_32FC2, weights of the face's vertices 1 and 2
  RenderStats stats;
};

class MeshRenderer {
 public:
  // Takes the mesh (and its texture atlas, used when the mesh has texture
  // coordinates). Throws InputError if the mesh is invalid or has texture
  // coordinates but no texture.
  explicit MeshRenderer(TriangleMesh mesh, const cv::Mat& texture = cv::Mat());

  const TriangleMesh& mesh() const { return mesh_; }
  const MipTexture& texture() const { return texture_; }
  // The mesh's bounding box.
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }

  // Faces drawn with their own colour even when lighting is on (light
  // sources, retro-reflective targets). One flag per face; empty: none.
  void SetUnlitFaces(std::vector<bool> unlit);
  // Faces that cast no shadow. One flag per face; empty: all cast.
  void SetNonCasterFaces(std::vector<bool> non_caster);

  // The shadow map for a sun direction, to share between views.
  ShadowMap BuildShadowMap(const Eigen::Vector3d& sun_direction,
                           const ShadowMapOptions& options = {}) const;

  // Renders one view. With lighting.shadows and no `shadow_map`, one is
  // built from options.shadow_map.
  RenderResult Render(const RenderView& view,
                      const Lighting& lighting,
                      const RenderOptions& options,
                      const ShadowMap* shadow_map = nullptr) const;

 private:
  struct ViewContext;
  struct Hit;
  bool Trace(const ViewContext& context,
             const Eigen::Vector2d& uv,
             Hit* hit) const;
  Eigen::Vector3f Shade(const ViewContext& context,
                        const Eigen::Vector2d& uv,
                        const Hit& hit) const;

  TriangleMesh mesh_;
  MipTexture texture_;
  Eigen::AlignedBox3d bounds_;
  std::vector<Eigen::Vector3d> face_normals_;  // world, unit
  // log2 of texture texels per metre on each face (texture detail level).
  std::vector<float> face_texel_density_log2_;
  std::vector<bool> unlit_;
  std::vector<bool> non_caster_;
  // The faces around each vertex: vertex_faces_[vertex_face_offsets_[v] ..
  // vertex_face_offsets_[v + 1]).
  std::vector<int> vertex_face_offsets_;
  std::vector<int> vertex_faces_;
};

}  // namespace bayon
