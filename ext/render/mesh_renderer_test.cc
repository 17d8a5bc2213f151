// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/mesh_renderer.h"

#include "ext/core/errors.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

// A grid of (n x n) squares, two triangles each, on the plane through
// `origin` spanned by `axis_u` and `axis_v`, facing axis_u x axis_v.
TriangleMesh GridMesh(const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& axis_u,
                      const Eigen::Vector3d& axis_v,
                      int n) {
  TriangleMesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.vertices.positions.push_back(origin + axis_u * (double(i) / n) +
                                        axis_v * (double(j) / n));
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.faces.emplace_back(a, b, d);
      mesh.faces.emplace_back(a, d, c);
    }
  }
  return mesh;
}

void AppendMesh(const TriangleMesh& part, TriangleMesh* mesh) {
  const int offset = static_cast<int>(mesh->vertices.size());
  for (const auto& p : part.vertices.positions) {
    mesh->vertices.positions.push_back(p);
  }
  for (const auto& f : part.faces) {
    mesh->faces.push_back(f + Eigen::Vector3i::Constant(offset));
  }
}

// The small Brown/Beyer camera of the tests: 600 x 400 pixels of 60 um on
// the 36 x 24 mm frame, c = 35 mm, every additional parameter set.
Camera SmallCamera() {
  SyntheticCameraOptions options;
  options.width = 600;
  options.height = 400;
  options.pixel_pitch_mm = 0.06;
  return SyntheticCamera(options);
}

TEST(MeshRenderer, DepthAndHitPointsAreExactWithDistortion) {
  // The ground z = 0 seen from 1.6 m height: it passes under and behind the
  // camera (near-plane clipping) and fills the lower image.
  const TriangleMesh ground = GridMesh(Eigen::Vector3d(-40, -40, 0),
                                       Eigen::Vector3d(80, 0, 0),
                                       Eigen::Vector3d(0, 80, 0),
                                       40);
  const MeshRenderer renderer(ground);
  RenderView view;
  view.camera = SmallCamera();
  view.cam_from_world = LookAt(Eigen::Vector3d(0.3, -0.2, 1.6),
                               Eigen::Vector3d(5, 3, 0.0),
                               Eigen::Vector3d::UnitZ(),
                               0.1);
  RenderOptions options;
  options.supersampling = 1;
  const RenderResult result = renderer.Render(view, Lighting(), options);
  EXPECT_LT(result.stats.max_ray_residual_px, 1e-6);
  const Rigid3d world_from_cam = view.cam_from_world.Inverse();
  const Eigen::Vector3d center = view.cam_from_world.Center();
  int num_hits = 0;
  double max_depth_error = 0, max_reprojection = 0;
  for (int y = 0; y < 400; y += 3) {
    for (int x = 0; x < 600; x += 3) {
      const Eigen::Vector2d pixel(x + 0.5, y + 0.5);
      const Eigen::Vector3d ray = view.camera.CamFromImg(pixel);
      const Eigen::Vector3d direction =
          world_from_cam.rotation * ray;  // z component 1 in the camera
      const double t = -center.z() / direction.z();
      const int face = result.triangle_id.at<int>(y, x);
      if (!(t > 0.01) || t * 1.0 > 500) {
        EXPECT_EQ(face, -1);
        continue;
      }
      const Eigen::Vector3d point = center + t * direction;
      if (std::abs(point.x()) > 39.9 || std::abs(point.y()) > 39.9) continue;
      ASSERT_GE(face, 0) << x << " " << y << " t " << t << " "
                         << point.transpose();
      ++num_hits;
      // Camera-frame z of the hit is t (the ray's z is 1).
      max_depth_error = std::max(
          max_depth_error, std::abs(result.depth.at<float>(y, x) - t) / t);
      const cv::Vec2f b = result.barycentric.at<cv::Vec2f>(y, x);
      const Eigen::Vector3i& f = renderer.mesh().faces[face];
      const auto& p = renderer.mesh().vertices.positions;
      const Eigen::Vector3d hit =
          (1 - b[0] - b[1]) * p[f[0]] + b[0] * p[f[1]] + b[1] * p[f[2]];
      const Eigen::Vector2d back =
          view.camera.ImgFromCam(view.cam_from_world * hit);
      max_reprojection = std::max(max_reprojection, (back - pixel).norm());
    }
  }
  EXPECT_GT(num_hits, 5000);
  EXPECT_LT(max_depth_error, 1e-6);   // float storage of the depth
  EXPECT_LT(max_reprojection, 2e-3);  // float barycentrics on 2 m faces
}

TEST(MeshRenderer, SupersamplingCoverageIsTheProjectedArea) {
  // A fronto-parallel 1 m square at 10 m through a pinhole: 60 x 60 px.
  const Camera camera = Camera::Create(CameraModelId::kPinhole, 600, 320, 240);
  const TriangleMesh square = GridMesh(Eigen::Vector3d(-0.437, -0.291, 10),
                                       Eigen::Vector3d(1, 0, 0),
                                       Eigen::Vector3d(0, 1, 0),
                                       3);
  const MeshRenderer renderer(square);
  RenderView view;
  view.camera = camera;
  RenderOptions options;
  options.supersampling = 4;
  const RenderResult result = renderer.Render(view, Lighting(), options);
  EXPECT_NEAR(cv::sum(result.coverage)[0], 3600.0, 3600 * 0.004);
  // Inside the square every sample hits; the edge pixels are fractions.
  EXPECT_EQ(result.coverage.at<float>(120, 160), 1.0f);
  const float edge = result.coverage.at<float>(120, 160 - 27);  // x = 133.5
  // The left edge is at x = 160 - 0.437 * 60 = 133.78: 3/4 of the pixel
  // [133, 134) lies right of it at 4 x 4 samples.
  EXPECT_NEAR(edge, 0.25, 1e-6);
}

TEST(MeshRenderer, TexturedFacesShowTheirTexels) {
  TriangleMesh square = GridMesh(Eigen::Vector3d(-0.5, -0.5, 5),
                                 Eigen::Vector3d(1, 0, 0),
                                 Eigen::Vector3d(0, 1, 0),
                                 1);
  // Texture coordinates: u along x, v along -y (camera y points down, so
  // v up is image up).
  for (const Eigen::Vector3i& face : square.faces) {
    std::array<Eigen::Vector2f, 3> tc;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = square.vertices.positions[face[k]];
      tc[k] = Eigen::Vector2f(float(p.x() + 0.5), float(0.5 - p.y()));
    }
    square.face_texcoords.push_back(tc);
  }
  cv::Mat texture(4, 4, CV_8UC3);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) {
      texture.at<cv::Vec3b>(y, x) = cv::Vec3b(40 * x, 40 * y, 200);
    }
  }
  const MeshRenderer renderer(square, texture);
  RenderView view;
  view.camera = Camera::Create(CameraModelId::kPinhole, 400, 200, 200);
  RenderOptions options;
  options.supersampling = 1;
  const RenderResult result = renderer.Render(view, Lighting(), options);
  // The square spans pixels [60, 140), 20 pixels per texel: texel (1, 2)
  // is centred at (90, 110), and the centre of pixel (90, 110) lies 0.025
  // texels right of and below it, so the bilinear value is 2.5 % of the
  // way to the next texel in each direction.
  const cv::Vec3f value = result.color.at<cv::Vec3f>(110, 90);
  EXPECT_NEAR(value[0], 41 / 255.0, 1e-4);
  EXPECT_NEAR(value[1], 81 / 255.0, 1e-4);
  EXPECT_NEAR(value[2], 200 / 255.0, 1e-3);
}

TEST(MeshRenderer, SunAmbientAndCastShadows) {
  // A 1 m cube on a ground plane, sun 45 degrees up from +x.
  TriangleMesh scene = GridMesh(Eigen::Vector3d(-10, -10, 0),
                                Eigen::Vector3d(20, 0, 0),
                                Eigen::Vector3d(0, 20, 0),
                                10);
  const Eigen::Vector3d ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  AppendMesh(GridMesh(Eigen::Vector3d(0, 0, 1), ex, ey, 2), &scene);  // top
  AppendMesh(GridMesh(Eigen::Vector3d(0, 0, 0), ex, ez, 2), &scene);
  AppendMesh(GridMesh(Eigen::Vector3d(0, 1, 0), ex, ez, 2), &scene);
  AppendMesh(GridMesh(Eigen::Vector3d(0, 0, 0), ey, ez, 2), &scene);
  AppendMesh(GridMesh(Eigen::Vector3d(1, 0, 0), ey, ez, 2), &scene);
  scene.vertices.colors.assign(scene.vertices.size(),
                               Eigen::Matrix<uint8_t, 3, 1>(255, 255, 255));
  const MeshRenderer renderer(scene);
  Lighting lighting;
  lighting.enabled = true;
  lighting.sun_direction = Eigen::Vector3d(1, 0, 1).normalized();
  lighting.sun_intensity = 1.0;
  lighting.ambient_intensity = 0.3;
  lighting.ambient_up_weight = 0;
  lighting.sun_bgr = lighting.ambient_bgr = Eigen::Vector3f::Ones();
  RenderView view;
  view.camera = Camera::Create(CameraModelId::kPinhole, 500, 400, 400);
  view.cam_from_world = LookAt(Eigen::Vector3d(0.5, 0.5, 12),
                               Eigen::Vector3d(0.5, 0.5, 0),
                               Eigen::Vector3d::UnitY());
  RenderOptions options;
  options.supersampling = 1;
  options.shadow_map.size = 1024;
  options.shadow_map.region =
      Eigen::AlignedBox3d(Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(3, 3, 1));
  const RenderResult result = renderer.Render(view, lighting, options);
  auto value_at = [&](const Eigen::Vector3d& point) {
    const Eigen::Vector2d pixel =
        view.camera.ImgFromCam(view.cam_from_world * point);
    return result.color.at<cv::Vec3f>(int(pixel.y()), int(pixel.x()))[1];
  };
  const double lit_ground = 0.3 + std::sqrt(0.5);
  // The shadow of the cube falls on x in [-1, 0] (sun from +x at 45 deg).
  EXPECT_NEAR(value_at({-0.5, 0.5, 0}), 0.3, 1e-3);
  EXPECT_NEAR(value_at({-1.5, 0.5, 0}), lit_ground, 1e-3);
  EXPECT_NEAR(value_at({2.0, 0.5, 0}), lit_ground, 1e-3);
  EXPECT_NEAR(value_at({0.5, 0.5, 1}), lit_ground, 1e-3);  // cube top
  // Without shadows the ground behind the cube is lit.
  lighting.shadows = false;
  const RenderResult unshadowed = renderer.Render(view, lighting, options);
  const Eigen::Vector2d pixel = view.camera.ImgFromCam(
      view.cam_from_world * Eigen::Vector3d(-0.5, 0.5, 0));
  EXPECT_NEAR(unshadowed.color.at<cv::Vec3f>(int(pixel.y()), int(pixel.x()))[1],
              lit_ground,
              1e-3);
}

TEST(MeshRenderer, FilmBorderOutsideTheFrameWindow) {
  const TriangleMesh wall = GridMesh(Eigen::Vector3d(-20, -20, 8),
                                     Eigen::Vector3d(40, 0, 0),
                                     Eigen::Vector3d(0, 40, 0),
                                     2);
  const MeshRenderer renderer(wall);
  RenderView view;
  view.camera = SmallCamera();
  view.frame_window_mm =
      Eigen::AlignedBox2d(Eigen::Vector2d(-12, -8), Eigen::Vector2d(12, 8));
  RenderOptions options;
  options.supersampling = 2;
  const RenderResult result = renderer.Render(view, Lighting(), options);
  // 24 mm of the 36 mm frame is 400 of 600 pixels: columns [100, 500).
  EXPECT_EQ(result.coverage.at<float>(200, 99), 0.0f);
  EXPECT_EQ(result.coverage.at<float>(200, 100), 1.0f);
  EXPECT_EQ(result.coverage.at<float>(200, 499), 1.0f);
  EXPECT_EQ(result.coverage.at<float>(200, 500), 0.0f);
  EXPECT_NEAR(
      result.color.at<cv::Vec3f>(200, 50)[0], options.border_bgr.x(), 1e-6);
}

TEST(MeshRenderer, SameImageOnOneOrTwoThreads) {
  const TriangleMesh wall = GridMesh(Eigen::Vector3d(-2, -2, 6),
                                     Eigen::Vector3d(4, 0, 1),
                                     Eigen::Vector3d(0, 4, 0.5),
                                     7);
  const MeshRenderer renderer(wall);
  RenderView view;
  view.camera = SmallCamera();
  Lighting lighting;
  lighting.enabled = true;
  RenderOptions options;
  options.supersampling = 2;
  options.num_threads = 1;
  const RenderResult one = renderer.Render(view, lighting, options);
  options.num_threads = 2;
  const RenderResult two = renderer.Render(view, lighting, options);
  EXPECT_EQ(cv::norm(one.color, two.color, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(one.depth, two.depth, cv::NORM_INF), 0.0);
}

TEST(MeshRenderer, RejectsBadInput) {
  TriangleMesh mesh = GridMesh(Eigen::Vector3d::Zero(),
                               Eigen::Vector3d::UnitX(),
                               Eigen::Vector3d::UnitY(),
                               1);
  mesh.face_texcoords.resize(mesh.NumFaces());
  EXPECT_THROW(MeshRenderer renderer(mesh), InputError);
  mesh.face_texcoords.clear();
  const MeshRenderer renderer(mesh);
  RenderOptions options;
  options.supersampling = 0;
  RenderView view;
  view.camera = Camera::Create(CameraModelId::kPinhole, 100, 64, 64);
  EXPECT_THROW(renderer.Render(view, Lighting(), options), InputError);
  EXPECT_THROW(MeshRenderer(mesh).SetUnlitFaces({true}), InputError);
}

}  // namespace
}  // namespace bayon
