// SPDX-License-Identifier: BSD-3-Clause
#include "ext/texture/texture_mapping.h"

#include "ext/core/errors.h"
#include "ext/render/mesh_renderer.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <iostream>
#include <random>

namespace bayon {
namespace {

// A 1 m box standing on z = 0: four sides and a top, each a grid of n x n
// squares, and a bottom that no camera above the ground can see. The sides
// and top carry texture coordinates into five columns of one atlas (the
// bottom takes the sixth).
TriangleMesh TexturedBox(int n) {
  TriangleMesh mesh;
  const Eigen::Vector3d o(-0.5, -0.5, 0.0);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(),
                        y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  // Origin and axes of each side, counter-clockwise seen from outside.
  const Eigen::Vector3d sides[6][3] = {{o, x, z},
                                       {o + x, y, z},
                                       {o + x + y, -x, z},
                                       {o + y, -y, z},
                                       {o + z, x, y},
                                       {o + y, x, -y}};
  for (int s = 0; s < 6; ++s) {
    const int base = static_cast<int>(mesh.vertices.size());
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        mesh.vertices.positions.push_back(sides[s][0] +
                                          sides[s][1] * (double(i) / n) +
                                          sides[s][2] * (double(j) / n));
      }
    }
    auto uv = [&](int i, int j) {
      return Eigen::Vector2f((s + float(i) / n) / 6.0f, float(j) / n);
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1,
                  d = c + 1;
        mesh.faces.emplace_back(a, b, d);
        mesh.face_texcoords.push_back(
            {uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
        mesh.faces.emplace_back(a, d, c);
        mesh.face_texcoords.push_back(
            {uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
      }
    }
  }
  return mesh;
}

// Smooth random colour blobs with fine detail on top, 8-bit BGR.
cv::Mat RandomTexture(int width, int height, uint32_t seed) {
  std::mt19937 random(seed);
  cv::Mat coarse(height / 16, width / 16, CV_8UC3);
  cv::Mat fine(height, width, CV_8UC3);
  cv::randu(coarse, cv::Scalar::all(40), cv::Scalar::all(215));
  cv::theRNG().state = seed;
  cv::randu(fine, cv::Scalar::all(0), cv::Scalar::all(60));
  cv::Mat texture;
  cv::resize(coarse, texture, fine.size(), 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(fine, fine, cv::Size(0, 0), 1.0);
  return texture + fine - cv::Scalar::all(30);
}

// Eight photographs around the box (the small Brown/Beyer camera with every
// additional parameter) under per-image exposure `gains`, and two held-out
// viewpoints between them.
struct BoxScene {
  TriangleMesh truth;
  cv::Mat truth_texture;
  Camera camera;
  std::vector<Image> images;
  std::vector<cv::Mat> photographs;
  std::vector<Rigid3d> heldout;
};

Rigid3d Station(double azimuth_deg, double height) {
  const double a = azimuth_deg * M_PI / 180.0;
  return LookAt(Eigen::Vector3d(3.0 * std::cos(a), 3.0 * std::sin(a), height),
                Eigen::Vector3d(0, 0, 0.5));
}

// The photograph's exposure and white balance: `exposure` applied to the
// 8-bit colours.
cv::Mat RenderBgr8(const MeshRenderer& renderer,
                   const Camera& camera,
                   const Rigid3d& pose,
                   const GainOffset& exposure = GainOffset()) {
  RenderView view;
  view.camera = camera;
  view.cam_from_world = pose;
  RenderOptions options;
  options.supersampling = 2;
  cv::Mat color = renderer.Render(view, Lighting(), options).color;
  cv::Mat bgr8;
  color.convertTo(bgr8, CV_8UC3, 255.0);
  return ApplyGainOffset(bgr8, exposure);
}

BoxScene MakeBoxScene(const std::vector<GainOffset>& exposures) {
  BoxScene scene;
  scene.truth = TexturedBox(12);
  scene.truth_texture = RandomTexture(6 * 128, 128, 7);
  SyntheticCameraOptions camera_options;
  camera_options.width = 600;
  camera_options.height = 400;
  camera_options.pixel_pitch_mm = 0.06;
  scene.camera = SyntheticCamera(camera_options);
  const MeshRenderer renderer(scene.truth, scene.truth_texture);
  for (size_t i = 0; i < exposures.size(); ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.name = "image_" + std::to_string(i) + ".png";
    image.camera_id = scene.camera.camera_id;
    image.cam_from_world = Station(10 + 45.0 * i, 1.6);
    scene.photographs.push_back(
        RenderBgr8(renderer, scene.camera, image.cam_from_world, exposures[i]));
    scene.images.push_back(image);
  }
  scene.heldout = {Station(32, 1.2), Station(190, 2.0)};
  return scene;
}

// Exposures differing by a gain alone.
BoxScene MakeBoxScene(const std::vector<float>& gains) {
  std::vector<GainOffset> exposures(gains.size());
  for (size_t i = 0; i < gains.size(); ++i) {
    exposures[i].gain.setConstant(gains[i]);
  }
  return MakeBoxScene(exposures);
}

std::vector<TextureImage> Photographs(const BoxScene& scene) {
  std::vector<TextureImage> images;
  for (size_t i = 0; i < scene.images.size(); ++i) {
    TextureImage t;
    t.name = scene.images[i].name;
    t.camera = &scene.camera;
    t.image = &scene.images[i];
    t.bgr = scene.photographs[i];
    images.push_back(t);
  }
  return images;
}

// The untextured geometry, as a mesher would give it.
TriangleMesh Untextured(const TriangleMesh& mesh) {
  TriangleMesh plain = mesh;
  plain.face_texcoords.clear();
  return plain;
}

double HeldoutPsnr(const BoxScene& scene, const TexturedMesh& model) {
  const MeshRenderer truth(scene.truth, scene.truth_texture);
  const MeshRenderer rendered(model.mesh, model.atlas);
  double sum = 0;
  for (const Rigid3d& pose : scene.heldout) {
    cv::Mat a = RenderBgr8(truth, scene.camera, pose);
    cv::Mat b = RenderBgr8(rendered, scene.camera, pose);
    sum += cv::PSNR(a, b);
  }
  return sum / scene.heldout.size();
}

TEST(TextureMapping, ReproducesTheTrueTextureFromUnseenViewpoints) {
  const BoxScene scene = MakeBoxScene(std::vector<float>(8, 1.0f));
  TextureOptions options;
  options.preprocess = TexturePreprocess::kNone;
  const TexturedMesh model =
      MapTexture(Untextured(scene.truth), Photographs(scene), options);
  const TextureReport& r = model.report;
  ASSERT_EQ(model.mesh.face_texcoords.size(), model.mesh.NumFaces());
  EXPECT_EQ(model.atlas.type(), CV_8UC3);
  // The bottom (a sixth of the faces) is hidden from every camera; every
  // other face is seen by two or more.
  EXPECT_EQ(r.num_unseen_faces, static_cast<int>(model.mesh.NumFaces() / 6));
  EXPECT_GT(r.mean_views_per_face, 2.0);
  // Texel size near the photographs' GSD: 3 m at c / pitch = 583 px.
  EXPECT_GT(r.texel_size, 0.003);
  EXPECT_LT(r.texel_size, 0.008);
  EXPECT_LE(std::max(r.atlas_width, r.atlas_height), options.max_atlas_size);
  for (const auto& corners : model.mesh.face_texcoords) {
    for (const Eigen::Vector2f& uv : corners) {
      EXPECT_TRUE(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1);
    }
  }
  const double psnr = HeldoutPsnr(scene, model);
  EXPECT_GT(psnr, 35.0) << TextureSummary(r);
}

TEST(TextureMapping, BlendingHidesTheSeamsOfDifferentExposures) {
  const BoxScene scene =
      MakeBoxScene({0.75f, 1.2f, 0.9f, 1.1f, 0.7f, 1.25f, 0.85f, 1.15f});
  TextureOptions options;
  options.preprocess = TexturePreprocess::kNone;
  options.blend = TextureBlend::kNone;
  const TexturedMesh single =
      MapTexture(Untextured(scene.truth), Photographs(scene), options);
  options.blend = TextureBlend::kViewDependent;
  const TexturedMesh blended =
      MapTexture(Untextured(scene.truth), Photographs(scene), options);
  // The same charts either way: the optimal image does not depend on the
  // blend.
  EXPECT_EQ(single.report.num_seam_edges, blended.report.num_seam_edges);
  ASSERT_GT(single.report.num_seam_edges, 10);
  EXPECT_LT(blended.report.seam_difference, 0.7 * single.report.seam_difference)
      << "single: " << TextureSummary(single.report)
      << "\nblended: " << TextureSummary(blended.report);
}

// Eight photographs, each with its own exposure and white balance (gains
// and offsets per channel whose means are 1 and 0): the balance brings the
// texture back to the true colours, which neither the photographs as they
// are nor the paper's equalisation give.
TEST(TextureMapping, BalanceRestoresTheTrueColours) {
  const float gains[8][3] = {{0.80f, 0.95f, 1.10f},
                             {1.15f, 1.05f, 0.90f},
                             {0.90f, 1.20f, 1.00f},
                             {1.10f, 0.85f, 1.05f},
                             {0.85f, 1.00f, 0.80f},
                             {1.20f, 1.10f, 1.15f},
                             {0.95f, 0.80f, 0.95f},
                             {1.05f, 1.05f, 1.05f}};
  const float offsets[8] = {8, -6, 4, -10, 10, -4, 2, -4};
  std::vector<GainOffset> exposures(8);
  for (int i = 0; i < 8; ++i) {
    exposures[i].gain = Eigen::Vector3f(gains[i][0], gains[i][1], gains[i][2]);
    exposures[i].offset.setConstant(offsets[i]);
  }
  const BoxScene scene = MakeBoxScene(exposures);
  auto texture = [&](TexturePreprocess preprocess,
                     bool seam_leveling,
                     TextureBlend blend = TextureBlend::kViewDependent) {
    TextureOptions options;
    options.preprocess = preprocess;
    options.seam_leveling = seam_leveling;
    options.blend = blend;
    return MapTexture(Untextured(scene.truth), Photographs(scene), options);
  };
  const TexturedMesh as_taken = texture(TexturePreprocess::kNone, false);
  const TexturedMesh paper =
      texture(TexturePreprocess::kHighPassEqualize, false);
  const TexturedMesh balanced = texture(TexturePreprocess::kBalance, false);
  const TexturedMesh leveled = texture(TexturePreprocess::kBalance, true);
  const double psnr_as_taken = HeldoutPsnr(scene, as_taken);
  const double psnr_paper = HeldoutPsnr(scene, paper);
  const double psnr_balanced = HeldoutPsnr(scene, balanced);
  const double psnr_leveled = HeldoutPsnr(scene, leveled);
  std::cout << "held-out PSNR: as taken " << psnr_as_taken << ", paper "
            << psnr_paper << ", balanced " << psnr_balanced
            << ", balanced and levelled " << psnr_leveled << " dB\n"
            << TextureSummary(leveled.report) << "\n";
  EXPECT_GT(psnr_balanced, psnr_as_taken + 3.0);
  EXPECT_GT(psnr_balanced, psnr_paper + 3.0);
  EXPECT_GT(psnr_leveled, psnr_as_taken + 3.0);
  EXPECT_LT(leveled.report.balance.sigma_after,
            0.3 * leveled.report.balance.sigma_before);
  // The seams of charts drawn from one photograph each.
  const TexturedMesh single =
      texture(TexturePreprocess::kNone, false, TextureBlend::kNone);
  const TexturedMesh single_leveled =
      texture(TexturePreprocess::kBalance, true, TextureBlend::kNone);
  std::cout << "seams of single photographs: as taken "
            << single.report.seam_difference << ", balanced and levelled "
            << single_leveled.report.seam_difference << " grey levels\n";
  EXPECT_LT(single_leveled.report.seam_difference,
            0.5 * single.report.seam_difference);
  // Every photograph's correction undoes its exposure up to the common
  // mean: gain_j * exposure_j is about the same for all.
  for (int i = 0; i < 8; ++i) {
    const GainOffset& c = leveled.report.corrections.at(scene.images[i].name);
    EXPECT_NEAR(c.gain.x() * gains[i][0], 1.0, 0.08) << i;
  }
}

TEST(TextureMapping, UnseenFacesTakeTheColoursAroundThem) {
  // A tent: one connected grid rising to a ridge along x at y = 0; the
  // cameras stand low on the +y side, so the far slope is hidden.
  const int n = 16;
  TriangleMesh tent;
  for (int j = 0; j <= 2 * n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double y = double(j) / n - 1.0;
      tent.vertices.positions.emplace_back(
          double(i) / n - 0.5, y, 0.5 * (1.0 - std::abs(y)));
    }
  }
  for (int j = 0; j < 2 * n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      tent.faces.emplace_back(a, b, d);
      tent.faces.emplace_back(a, d, c);
    }
  }
  SyntheticCameraOptions camera_options;
  camera_options.width = 600;
  camera_options.height = 400;
  camera_options.pixel_pitch_mm = 0.06;
  const Camera camera = SyntheticCamera(camera_options);
  // Photographs of one plain colour: what the unseen faces should take.
  std::vector<Image> poses(3);
  std::vector<TextureImage> images(3);
  for (int k = 0; k < 3; ++k) {
    poses[k].name = std::to_string(k);
    poses[k].cam_from_world =
        LookAt(Eigen::Vector3d(-1.0 + k, 3.0, 0.2), Eigen::Vector3d(0, 0, 0.2));
    images[k].name = poses[k].name;
    images[k].camera = &camera;
    images[k].image = &poses[k];
    images[k].bgr = cv::Mat(400, 600, CV_8UC3, cv::Scalar(30, 140, 220));
  }
  TextureOptions options;
  options.preprocess = TexturePreprocess::kNone;
  const TexturedMesh model = MapTexture(tent, images, options);
  ASSERT_GT(model.report.num_unseen_faces, int(tent.NumFaces() / 5));
  ASSERT_LT(model.report.num_unseen_faces, int(tent.NumFaces()));
  const MipTexture atlas(model.atlas);
  for (const auto& corners : model.mesh.face_texcoords) {
    const Eigen::Vector3f color = 255.0f * atlas.SampleLevel(corners[0], 0);
    EXPECT_NEAR(color[0], 30, 2);
    EXPECT_NEAR(color[1], 140, 2);
    EXPECT_NEAR(color[2], 220, 2);
  }
}

TEST(TextureMapping, RejectsAMeshNoPhotographSees) {
  BoxScene scene = MakeBoxScene({1.0f, 1.0f});
  TriangleMesh far = Untextured(scene.truth);
  for (auto& p : far.vertices.positions) p += Eigen::Vector3d(0, 0, -100);
  EXPECT_THROW(MapTexture(far, Photographs(scene), TextureOptions()),
               InputError);
  EXPECT_THROW(MapTexture(TriangleMesh(), Photographs(scene), TextureOptions()),
               InputError);
  // Sixteen charts with 30 texels of padding each cannot share 64 x 64.
  TextureOptions cramped;
  cramped.max_atlas_size = 64;
  cramped.padding_px = 30;
  EXPECT_THROW(MapTexture(Untextured(scene.truth), Photographs(scene), cramped),
               InputError);
}

}  // namespace
}  // namespace bayon
