// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/mesh_renderer.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/render/pixel_rays.h"
#include "ext/render/raster.h"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace bayon {

void Lighting::Check() const {
  CheckOption(sun_direction.allFinite() && sun_direction.norm() > 0,
              "Lighting.sun_direction",
              "a non-zero vector",
              sun_direction.transpose());
  CheckOption(
      sun_intensity >= 0, "Lighting.sun_intensity", ">= 0", sun_intensity);
  CheckOption(ambient_intensity >= 0,
              "Lighting.ambient_intensity",
              ">= 0",
              ambient_intensity);
  CheckOption(ambient_up_weight >= 0 && ambient_up_weight <= 1,
              "Lighting.ambient_up_weight",
              "in [0, 1]",
              ambient_up_weight);
}

void ShadowMapOptions::Check() const {
  CheckOption(size >= 16 && size <= 32768,
              "ShadowMapOptions.size",
              "in [16, 32768]",
              size);
}

void RenderOptions::Check() const {
  CheckOption(supersampling >= 1 && supersampling <= 16,
              "RenderOptions.supersampling",
              "in [1, 16]",
              supersampling);
  CheckOption(near_clip > 0, "RenderOptions.near_clip", "> 0", near_clip);
  shadow_map.Check();
}

// ---------------------------------------------------------------------------
// Shadow map.

double ShadowMap::Visibility(const Eigen::Vector3d& point,
                             const Eigen::Vector3d& normal) const {
  if (size <= 0) return 1.0;
  const double cos_sun = normal.dot(sun_direction);
  if (cos_sun <= 0) return 0.0;
  // Normal offset plus a slope-scaled bias: a lit plane must not shadow
  // itself between the texel centres where its depth was stored.
  const Eigen::Vector3d offset_point = point + normal * (1.5 * texel_size);
  const double tan_angle =
      std::min(8.0, std::sqrt(std::max(0.0, 1 - cos_sun * cos_sun)) / cos_sun);
  const double bias = texel_size * (0.5 + tan_angle);
  const double key = -sun_direction.dot(offset_point);
  const double x = (axis_x.dot(offset_point) - origin.x()) / texel_size - 0.5;
  const double y = (axis_y.dot(offset_point) - origin.y()) / texel_size - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  if (x0 < 0 || y0 < 0 || x0 + 1 >= size || y0 + 1 >= size) return 1.0;
  const double ax = x - fx, ay = y - fy;
  auto lit = [&](int xi, int yi) {
    return key <= depth[size_t(yi) * size + xi] + bias ? 1.0 : 0.0;
  };
  // Percentage-closer filtering over the four nearest texels.
  return (1 - ay) * ((1 - ax) * lit(x0, y0) + ax * lit(x0 + 1, y0)) +
         ay * ((1 - ax) * lit(x0, y0 + 1) + ax * lit(x0 + 1, y0 + 1));
}

// ---------------------------------------------------------------------------
// Renderer.

MeshRenderer::MeshRenderer(TriangleMesh mesh, const cv::Mat& texture)
    : mesh_(std::move(mesh)) {
  mesh_.Check("mesh to render");
  if (mesh_.HasTexcoords()) {
    if (texture.empty()) {
      ThrowInputError(
          "mesh to render: has texture coordinates but no texture image");
    }
    texture_ = MipTexture(texture);
  }
  // Faces around each vertex (compressed rows), for Trace's fallback.
  vertex_face_offsets_.assign(mesh_.NumVertices() + 1, 0);
  for (const Eigen::Vector3i& face : mesh_.faces) {
    for (int k = 0; k < 3; ++k) ++vertex_face_offsets_[face[k] + 1];
  }
  for (size_t v = 0; v < mesh_.NumVertices(); ++v) {
    vertex_face_offsets_[v + 1] += vertex_face_offsets_[v];
  }
  vertex_faces_.resize(vertex_face_offsets_.back());
  {
    std::vector<int> fill(vertex_face_offsets_.begin(),
                          vertex_face_offsets_.end() - 1);
    for (size_t f = 0; f < mesh_.NumFaces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        vertex_faces_[fill[mesh_.faces[f][k]]++] = static_cast<int>(f);
      }
    }
  }
  bounds_.setEmpty();
  for (const Eigen::Vector3d& position : mesh_.vertices.positions) {
    bounds_.extend(position);
  }
  face_normals_.resize(mesh_.NumFaces());
  face_texel_density_log2_.assign(mesh_.NumFaces(), 0.0f);
  const auto& positions = mesh_.vertices.positions;
  for (size_t f = 0; f < mesh_.NumFaces(); ++f) {
    const Eigen::Vector3i& face = mesh_.faces[f];
    const Eigen::Vector3d cross =
        (positions[face[1]] - positions[face[0]])
            .cross(positions[face[2]] - positions[face[0]]);
    const double area = 0.5 * cross.norm();
    face_normals_[f] = area > 0 ? Eigen::Vector3d(cross / (2 * area))
                                : Eigen::Vector3d::Zero();
    if (!texture_.empty() && area > 0) {
      const auto& tc = mesh_.face_texcoords[f];
      const Eigen::Vector2f d1 = tc[1] - tc[0], d2 = tc[2] - tc[0];
      const double texel_area = 0.5 *
                                std::abs(d1.x() * d2.y() - d1.y() * d2.x()) *
                                texture_.width() * texture_.height();
      if (texel_area > 0) {
        face_texel_density_log2_[f] =
            static_cast<float>(0.5 * std::log2(texel_area / area));
      }
    }
  }
}

void MeshRenderer::SetUnlitFaces(std::vector<bool> unlit) {
  if (!unlit.empty() && unlit.size() != mesh_.NumFaces()) {
    ThrowInputError("unlit face flags: ",
                    unlit.size(),
                    " flags for ",
                    mesh_.NumFaces(),
                    " faces");
  }
  unlit_ = std::move(unlit);
}

void MeshRenderer::SetNonCasterFaces(std::vector<bool> non_caster) {
  if (!non_caster.empty() && non_caster.size() != mesh_.NumFaces()) {
    ThrowInputError("non-caster face flags: ",
                    non_caster.size(),
                    " flags for ",
                    mesh_.NumFaces(),
                    " faces");
  }
  non_caster_ = std::move(non_caster);
}

ShadowMap MeshRenderer::BuildShadowMap(const Eigen::Vector3d& sun_direction,
                                       const ShadowMapOptions& options) const {
  options.Check();
  ShadowMap map;
  map.sun_direction = sun_direction.normalized();
  const Eigen::Vector3d& d = map.sun_direction;
  map.axis_x = std::abs(d.z()) < 0.9 ? d.cross(Eigen::Vector3d::UnitZ())
                                     : d.cross(Eigen::Vector3d::UnitX());
  map.axis_x.normalize();
  map.axis_y = d.cross(map.axis_x).normalized();
  const Eigen::AlignedBox3d region =
      options.region.isEmpty() ? bounds_ : options.region;
  Eigen::AlignedBox2d extent;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d point =
        region.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner));
    extent.extend(
        Eigen::Vector2d(map.axis_x.dot(point), map.axis_y.dot(point)));
  }
  map.size = options.size;
  // Two texels of margin so that the filter never reads outside.
  map.texel_size = extent.sizes().maxCoeff() / (options.size - 4);
  map.origin = extent.min() - Eigen::Vector2d::Constant(2 * map.texel_size);

  std::vector<RasterTriangle> triangles;
  triangles.reserve(mesh_.NumFaces());
  const auto& positions = mesh_.vertices.positions;
  for (size_t f = 0; f < mesh_.NumFaces(); ++f) {
    if (!non_caster_.empty() && non_caster_[f]) continue;
    RasterTriangle triangle;
    triangle.id = static_cast<int32_t>(f);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& point = positions[mesh_.faces[f][k]];
      triangle.position[k] = Eigen::Vector2d(
          (map.axis_x.dot(point) - map.origin.x()) / map.texel_size,
          (map.axis_y.dot(point) - map.origin.y()) / map.texel_size);
      triangle.key[k] = static_cast<float>(-d.dot(point));
    }
    triangles.push_back(triangle);
  }
  DepthRaster raster;
  raster.Reset(map.size, map.size, /*with_ids=*/false);
  RasterizeTriangles(triangles, options.num_threads, &raster);
  map.depth = std::move(raster.key);
  return map;
}

struct MeshRenderer::Hit {
  int face = -1;
  double depth = 0;  // camera-frame z
  double b1 = 0;     // barycentric weights of vertices 1 and 2
  double b2 = 0;
};

struct MeshRenderer::ViewContext {
  const RenderView* view = nullptr;
  const Lighting* lighting = nullptr;
  const RenderOptions* options = nullptr;
  const ShadowMap* shadow_map = nullptr;
  Eigen::Matrix3d world_from_cam_rotation;
  Eigen::Vector3d center;  // projection centre in the world
  std::vector<Eigen::Vector3d> vertices_in_cam;
  // The pinhole visibility raster: raster pixel = scale * (uv - uv_min).
  DepthRaster raster;
  double raster_scale = 0;
  Eigen::Vector2d uv_min;
  // Samples per unit of normalized image coordinates (texture detail).
  double samples_per_uv = 0;
};

namespace {

// Intersects the ray (u, v, 1) from the origin with a triangle given in the
// camera frame (Moller and Trumbore 1997). On a hit, `t` is the camera-frame
// z of the intersection (the ray's z component is 1).
bool IntersectRay(const Eigen::Vector2d& uv,
                  const Eigen::Vector3d& v0,
                  const Eigen::Vector3d& v1,
                  const Eigen::Vector3d& v2,
                  double* t,
                  double* b1,
                  double* b2) {
  const Eigen::Vector3d direction(uv.x(), uv.y(), 1.0);
  const Eigen::Vector3d e1 = v1 - v0;
  const Eigen::Vector3d e2 = v2 - v0;
  const Eigen::Vector3d p = direction.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return false;
  const double inv_det = 1.0 / det;
  const Eigen::Vector3d s = -v0;
  const double u = s.dot(p) * inv_det;
  // A tiny tolerance so that rays through a shared edge hit one of the two
  // faces instead of slipping between them.
  constexpr double kEps = 1e-10;
  if (u < -kEps || u > 1 + kEps) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = direction.dot(q) * inv_det;
  if (v < -kEps || u + v > 1 + kEps) return false;
  *t = e2.dot(q) * inv_det;
  *b1 = u;
  *b2 = v;
  return true;
}

// Cuts a camera-frame triangle at z = near and appends the screen-space
// pieces (one or two triangles) to `out`.
void ClipAndProject(const Eigen::Vector3d (&vertices)[3],
                    int32_t id,
                    double near,
                    double scale,
                    const Eigen::Vector2d& uv_min,
                    std::vector<RasterTriangle>* out) {
  Eigen::Vector3d polygon[4];
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& a = vertices[k];
    const Eigen::Vector3d& b = vertices[(k + 1) % 3];
    const bool a_in = a.z() >= near, b_in = b.z() >= near;
    if (a_in) polygon[count++] = a;
    if (a_in != b_in) {
      const double t = (near - a.z()) / (b.z() - a.z());
      polygon[count++] = a + t * (b - a);
    }
  }
  if (count < 3) return;
  auto project =
      [&](const Eigen::Vector3d& point, RasterTriangle* triangle, int k) {
        triangle->position[k] = scale * (point.head<2>() / point.z() - uv_min);
        triangle->key[k] = static_cast<float>(-1.0 / point.z());
      };
  for (int k = 1; k + 1 < count; ++k) {
    RasterTriangle triangle;
    triangle.id = id;
    project(polygon[0], &triangle, 0);
    project(polygon[k], &triangle, 1);
    project(polygon[k + 1], &triangle, 2);
    out->push_back(triangle);
  }
}

}  // namespace

bool MeshRenderer::Trace(const ViewContext& context,
                         const Eigen::Vector2d& uv,
                         Hit* hit) const {
  const DepthRaster& raster = context.raster;
  const Eigen::Vector2d q = context.raster_scale * (uv - context.uv_min);
  const int x0 = static_cast<int>(std::floor(q.x() - 0.5));
  const int y0 = static_cast<int>(std::floor(q.y() - 0.5));
  int tested[16];
  int num_tested = 0;
  bool found = false;
  double best_depth = std::numeric_limits<double>::infinity();
  auto test_window = [&](int x_begin, int x_end, int y_begin, int y_end) {
    for (int y = std::max(0, y_begin); y <= std::min(raster.height - 1, y_end);
         ++y) {
      for (int x = std::max(0, x_begin); x <= std::min(raster.width - 1, x_end);
           ++x) {
        const int face = raster.Id(x, y);
        if (face < 0) continue;
        if (std::find(tested, tested + num_tested, face) !=
            tested + num_tested) {
          continue;
        }
        if (num_tested < 16) tested[num_tested++] = face;
        const Eigen::Vector3i& f = mesh_.faces[face];
        double t, b1, b2;
        if (!IntersectRay(uv,
                          context.vertices_in_cam[f[0]],
                          context.vertices_in_cam[f[1]],
                          context.vertices_in_cam[f[2]],
                          &t,
                          &b1,
                          &b2)) {
          continue;
        }
        if (t < context.options->near_clip || t >= best_depth) continue;
        best_depth = t;
        hit->face = face;
        hit->depth = t;
        hit->b1 = b1;
        hit->b2 = b2;
        found = true;
      }
    }
  };
  test_window(x0, x0 + 1, y0, y0 + 1);
  if (!found) {
    // The ray lies in a triangle narrower than a raster pixel, or at a
    // silhouette: look one pixel further.
    test_window(x0 - 1, x0 + 2, y0 - 1, y0 + 2);
  }
  if (!found && num_tested > 0) {
    // Still nothing: the ray may pass through the thin tip of a sliver
    // triangle that covers no raster pixel centre nearby. Such a triangle
    // shares a vertex with one that does; try those.
    const int num_window = num_tested;
    for (int c = 0; c < num_window; ++c) {
      const Eigen::Vector3i& candidate = mesh_.faces[tested[c]];
      for (int k = 0; k < 3; ++k) {
        const int vertex = candidate[k];
        for (int n = vertex_face_offsets_[vertex];
             n < vertex_face_offsets_[vertex + 1];
             ++n) {
          const int face = vertex_faces_[n];
          const Eigen::Vector3i& f = mesh_.faces[face];
          double t, b1, b2;
          if (!IntersectRay(uv,
                            context.vertices_in_cam[f[0]],
                            context.vertices_in_cam[f[1]],
                            context.vertices_in_cam[f[2]],
                            &t,
                            &b1,
                            &b2)) {
            continue;
          }
          if (t < context.options->near_clip || t >= best_depth) continue;
          best_depth = t;
          hit->face = face;
          hit->depth = t;
          hit->b1 = b1;
          hit->b2 = b2;
          found = true;
        }
      }
    }
  }
  return found;
}

Eigen::Vector3f MeshRenderer::Shade(const ViewContext& context,
                                    const Eigen::Vector2d& uv,
                                    const Hit& hit) const {
  const Eigen::Vector3i& face = mesh_.faces[hit.face];
  const double b0 = 1.0 - hit.b1 - hit.b2;
  const Eigen::Vector3d ray(uv.x(), uv.y(), 1.0);
  const Eigen::Vector3d ray_world = context.world_from_cam_rotation * ray;
  Eigen::Vector3d normal = face_normals_[hit.face];
  const double cos_view = std::abs(normal.dot(ray_world)) / ray_world.norm();

  Eigen::Vector3f albedo(0.7f, 0.7f, 0.7f);
  if (!texture_.empty()) {
    const auto& tc = mesh_.face_texcoords[hit.face];
    const Eigen::Vector2f texcoord =
        float(b0) * tc[0] + float(hit.b1) * tc[1] + float(hit.b2) * tc[2];
    // Footprint of one sample on the surface: its size across the ray at
    // this distance, stretched by the obliquity of the surface.
    const double across = hit.depth * ray.norm() / context.samples_per_uv;
    const double lod = std::log2(across) -
                       0.5 * std::log2(std::max(cos_view, 0.05)) +
                       face_texel_density_log2_[hit.face];
    albedo = texture_.Sample(texcoord, static_cast<float>(lod));
  } else if (mesh_.vertices.HasColors()) {
    const auto& colors = mesh_.vertices.colors;
    Eigen::Vector3f rgb = float(b0) * colors[face[0]].cast<float>() +
                          float(hit.b1) * colors[face[1]].cast<float>() +
                          float(hit.b2) * colors[face[2]].cast<float>();
    albedo = Eigen::Vector3f(rgb.z(), rgb.y(), rgb.x()) / 255.0f;
  }
  const Lighting& lighting = *context.lighting;
  if (!lighting.enabled || (!unlit_.empty() && unlit_[hit.face])) {
    return albedo;
  }
  // Two-sided: a face seen from behind is lit as if it faced the camera.
  Eigen::Vector3d geometric_normal = normal;
  if (geometric_normal.dot(ray_world) > 0) geometric_normal = -normal;
  if (mesh_.vertices.HasNormals()) {
    const auto& normals = mesh_.vertices.normals;
    const Eigen::Vector3d interpolated =
        (b0 * normals[face[0]] + hit.b1 * normals[face[1]] +
         hit.b2 * normals[face[2]])
            .cast<double>();
    if (interpolated.norm() > 1e-9) {
      normal = interpolated.normalized();
      if (normal.dot(geometric_normal) < 0) normal = -normal;
    } else {
      normal = geometric_normal;
    }
  } else {
    normal = geometric_normal;
  }
  const Eigen::Vector3d sun = lighting.sun_direction.normalized();
  const double cos_sun = std::max(0.0, normal.dot(sun));
  double sun_visible = cos_sun > 0 ? 1.0 : 0.0;
  if (cos_sun > 0 && context.shadow_map) {
    const Eigen::Vector3d point =
        context.world_from_cam_rotation *
        (hit.depth * ray - context.view->cam_from_world.translation);
    sun_visible = context.shadow_map->Visibility(point, geometric_normal);
  }
  const double w = lighting.ambient_up_weight;
  const double ambient =
      lighting.ambient_intensity * ((1 - w) + w * (0.5 + 0.5 * normal.z()));
  const double direct = lighting.sun_intensity * cos_sun * sun_visible;
  const Eigen::Vector3f light =
      float(ambient) * lighting.ambient_bgr + float(direct) * lighting.sun_bgr;
  return albedo.cwiseProduct(light);
}

RenderResult MeshRenderer::Render(const RenderView& view,
                                  const Lighting& lighting,
                                  const RenderOptions& options,
                                  const ShadowMap* shadow_map) const {
  options.Check();
  lighting.Check();
  const Timer timer;
  const Camera& camera = view.camera;
  const PixelRays rays(camera, view.frame);
  const int width = static_cast<int>(camera.width);
  const int height = static_cast<int>(camera.height);
  const int s = options.supersampling;

  ViewContext context;
  context.view = &view;
  context.lighting = &lighting;
  context.options = &options;
  context.world_from_cam_rotation =
      view.cam_from_world.rotation.toRotationMatrix().transpose();
  context.center = view.cam_from_world.Center();
  ShadowMap own_shadow_map;
  if (lighting.enabled && lighting.shadows) {
    if (!shadow_map) {
      own_shadow_map =
          BuildShadowMap(lighting.sun_direction, options.shadow_map);
      shadow_map = &own_shadow_map;
    }
    context.shadow_map = shadow_map;
  }

  // The pinhole visibility raster.
  const Eigen::AlignedBox2d& bounds = rays.bounds();
  context.uv_min = bounds.min();
  // Twice the pixel density is enough for finding candidates (Trace looks
  // around); denser rasters only cost time.
  context.samples_per_uv = s * rays.max_magnification();
  context.raster_scale = std::min(s, 2) * rays.max_magnification();
  // A very wide field of view would need a huge raster: cap it (only tiny
  // triangles can then be missed, never positions).
  constexpr double kMaxRasterSide = 16384;
  const double raster_side =
      bounds.sizes().maxCoeff() * context.raster_scale + 2;
  if (raster_side > kMaxRasterSide) {
    context.raster_scale *= kMaxRasterSide / raster_side;
  }
  const int raster_width =
      static_cast<int>(std::ceil(bounds.sizes().x() * context.raster_scale)) +
      1;
  const int raster_height =
      static_cast<int>(std::ceil(bounds.sizes().y() * context.raster_scale)) +
      1;
  context.raster.Reset(raster_width, raster_height);

  const auto& positions = mesh_.vertices.positions;
  context.vertices_in_cam.resize(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    context.vertices_in_cam[i] = view.cam_from_world * positions[i];
  }
  std::vector<RasterTriangle> triangles;
  triangles.reserve(mesh_.NumFaces());
  for (size_t f = 0; f < mesh_.NumFaces(); ++f) {
    const Eigen::Vector3i& face = mesh_.faces[f];
    const Eigen::Vector3d vertices[3] = {context.vertices_in_cam[face[0]],
                                         context.vertices_in_cam[face[1]],
                                         context.vertices_in_cam[face[2]]};
    if (vertices[0].z() < options.near_clip &&
        vertices[1].z() < options.near_clip &&
        vertices[2].z() < options.near_clip) {
      continue;
    }
    ClipAndProject(vertices,
                   static_cast<int32_t>(f),
                   options.near_clip,
                   context.raster_scale,
                   context.uv_min,
                   &triangles);
  }
  RasterizeTriangles(triangles, options.num_threads, &context.raster);
  triangles.clear();
  triangles.shrink_to_fit();

  RenderResult result;
  result.color.create(height, width, CV_32FC3);
  result.coverage.create(height, width, CV_32F);
  if (options.geometry_buffers) {
    result.depth = cv::Mat::zeros(height, width, CV_32F);
    result.triangle_id = cv::Mat(height, width, CV_32S, cv::Scalar(-1));
    result.barycentric = cv::Mat::zeros(height, width, CV_32FC2);
  }
  RenderStats& stats = result.stats;
  stats.raster_width = raster_width;
  stats.raster_height = raster_height;
  std::mutex stats_mutex;

  const ImageFrame frame = view.frame ? *view.frame : camera.DefaultFrame();
  const bool use_window =
      view.frame_window_mm && camera.model_id == CameraModelId::kBrownBeyer;
  auto background = [&](const Eigen::Vector2d& uv) {
    const Eigen::Vector3d direction =
        (context.world_from_cam_rotation * Eigen::Vector3d(uv.x(), uv.y(), 1))
            .normalized();
    const float t =
        static_cast<float>(std::sqrt(std::clamp(direction.z(), 0.0, 1.0)));
    return Eigen::Vector3f((1 - t) * options.background_horizon_bgr +
                           t * options.background_zenith_bgr);
  };

  constexpr int kBandRows = 4;
  const int num_bands = (height + kBandRows - 1) / kBandRows;
  const bool odd = s % 2 == 1;
  ParallelFor(num_bands, options.num_threads, [&](int band) {
    RenderStats local;
    const int y_end = std::min(height, (band + 1) * kBandRows);
    for (int y = band * kBandRows; y < y_end; ++y) {
      cv::Vec3f* color_row = result.color.ptr<cv::Vec3f>(y);
      float* coverage_row = result.coverage.ptr<float>(y);
      for (int x = 0; x < width; ++x) {
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        int hits = 0;
        // The exact ray through the pixel centre; the samples around it
        // follow from its derivative (within half a pixel the second-order
        // term stays below 1e-4 px, PixelRays' tests), which saves the
        // camera model's inversion at all but one ray per pixel.
        const Eigen::Vector2d center_pixel(x + 0.5, y + 0.5);
        Eigen::Vector2d center_uv;
        Eigen::Matrix2d uv_from_pixel;
        double center_residual = 0;
        const bool center_ok = rays.Ray(
            center_pixel, &center_uv, &center_residual, &uv_from_pixel);
        const bool extrapolate = center_ok && uv_from_pixel.allFinite();
        if (center_ok) {
          local.max_ray_residual_px =
              std::max(local.max_ray_residual_px, center_residual);
        }
        auto trace_sample = [&](const Eigen::Vector2d& pixel,
                                bool is_center,
                                Hit* hit,
                                bool* has_hit,
                                Eigen::Vector3f* color) {
          *has_hit = false;
          if (use_window &&
              !view.frame_window_mm->contains(frame.FrameFromPixel(pixel))) {
            *color = options.border_bgr;
            return;
          }
          Eigen::Vector2d uv;
          ++local.num_samples;
          bool ok = true;
          if (is_center) {
            uv = center_uv;
            ok = center_ok;
          } else if (extrapolate) {
            uv = center_uv + uv_from_pixel * (pixel - center_pixel);
          } else {
            ok = rays.Ray(pixel, &uv);
          }
          if (!ok) {
            ++local.num_missed_rays;
            *color = options.border_bgr;
            return;
          }
          if (Trace(context, uv, hit)) {
            *has_hit = true;
            ++local.num_hits;
            *color = Shade(context, uv, *hit);
          } else {
            *color = background(uv);
          }
        };
        Hit center_hit;
        bool center_has_hit = false;
        for (int j = 0; j < s; ++j) {
          for (int i = 0; i < s; ++i) {
            const Eigen::Vector2d pixel(x + (i + 0.5) / s, y + (j + 0.5) / s);
            const bool is_center = odd && i == s / 2 && j == s / 2;
            Hit hit;
            bool has_hit;
            Eigen::Vector3f color;
            trace_sample(pixel, is_center, &hit, &has_hit, &color);
            sum += color;
            hits += has_hit;
            if (is_center) {
              center_hit = hit;
              center_has_hit = has_hit;
            }
          }
        }
        if (!odd && options.geometry_buffers) {
          Eigen::Vector3f unused;
          trace_sample(
              center_pixel, true, &center_hit, &center_has_hit, &unused);
        }
        sum /= float(s * s);
        color_row[x] = cv::Vec3f(sum.x(), sum.y(), sum.z());
        coverage_row[x] = float(hits) / float(s * s);
        if (options.geometry_buffers && center_has_hit) {
          result.depth.at<float>(y, x) = static_cast<float>(center_hit.depth);
          result.triangle_id.at<int32_t>(y, x) = center_hit.face;
          result.barycentric.at<cv::Vec2f>(y, x) =
              cv::Vec2f(static_cast<float>(center_hit.b1),
                        static_cast<float>(center_hit.b2));
        }
      }
    }
    std::lock_guard<std::mutex> lock(stats_mutex);
    stats.num_samples += local.num_samples;
    stats.num_hits += local.num_hits;
    stats.num_missed_rays += local.num_missed_rays;
    stats.max_ray_residual_px =
        std::max(stats.max_ray_residual_px, local.max_ray_residual_px);
  });
  stats.seconds = timer.Seconds();
  return result;
}

}  // namespace bayon
