// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/surface_eval.h"

#include "ext/core/errors.h"
#include "ext/synth/cloud_scene.h"
#include "ext/synth/synthetic_camera.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bayon {
namespace {

// A wavy torus (closed) and a ring of eight cameras above its equator: the
// top and the outer side are seen, the underside and much of the inner
// side are not.
struct TorusScene {
  TriangleMesh surface;
  Scene cameras;
};

TorusScene MakeScene() {
  TorusScene scene;
  TorusOptions torus;
  torus.num_major = 240;
  torus.num_minor = 96;
  scene.surface = MakeTorus(torus);
  Camera camera = Camera::Create(CameraModelId::kPinhole, 500, 640, 480);
  camera.camera_id = 1;
  scene.cameras.cameras.Set(1, camera);
  for (int i = 0; i < 8; ++i) {
    const double angle = 2 * M_PI * i / 8;
    Image image;
    image.image_id = i + 1;
    image.name = "view_" + std::to_string(i) + ".png";
    image.camera_id = 1;
    image.cam_from_world =
        LookAt(Eigen::Vector3d(7 * std::cos(angle), 7 * std::sin(angle), 3),
               Eigen::Vector3d::Zero());
    scene.cameras.images.Set(image.image_id, image);
  }
  return scene;
}

const TorusScene& Scene0() {
  static const TorusScene scene = MakeScene();
  return scene;
}

const VisibleSurface& Visible() {
  static const VisibleSurface visible = [] {
    VisibleSurfaceOptions options;
    options.num_samples = 40000;
    return FindVisibleSurface(Scene0().surface, Scene0().cameras, options);
  }();
  return visible;
}

TEST(SurfaceEval, OnlyTheSurfaceSeenTwiceCounts) {
  const VisibleSurface& visible = Visible();
  EXPECT_EQ(visible.num_candidates, 40000u);
  const double share = double(visible.samples.size()) / visible.num_candidates;
  EXPECT_GT(share, 0.3);
  EXPECT_LT(share, 0.8);
  for (const Eigen::Vector3d& p : visible.samples) {
    // The cameras are 3 m up: the lowest parts of the tube stay unseen.
    EXPECT_GT(p.z(), -0.59);
  }
  // A region cuts the candidates.
  VisibleSurfaceOptions options;
  options.num_samples = 40000;
  options.region =
      Eigen::AlignedBox3d(Eigen::Vector3d(0, -3, -1), Eigen::Vector3d(3, 3, 1));
  const VisibleSurface half =
      FindVisibleSurface(Scene0().surface, Scene0().cameras, options);
  EXPECT_NEAR(double(half.num_candidates) / 40000, 0.5, 0.03);
}

TEST(SurfaceEval, NoisyCloudHasItsNoiseAsAccuracyAndIsComplete) {
  const VisibleSurface& visible = Visible();
  const MeshDistance truth(Scene0().surface);
  NoisyCloudOptions noise;
  noise.num_points = 200000;
  noise.sigma_m = 0.002;
  noise.sigma_spread = 0;
  noise.blunder_fraction = 0;
  const PointCloud cloud = SampleNoisyCloud(Scene0().surface, noise);
  SurfaceEvaluationOptions options;
  options.completeness_threshold_m = 0.02;
  options.gsd_m = 0.004;
  const SurfaceEvaluation e = EvaluateCloud(cloud, truth, visible, options);
  EXPECT_EQ(e.num_points, cloud.size());
  // The distance to the surface is the normal component of the noise.
  EXPECT_NEAR(e.accuracy.rms, 0.002, 0.0002);
  EXPECT_NEAR(e.accuracy.mean, 0.002 * std::sqrt(2 / M_PI), 0.0002);
  EXPECT_GT(e.completeness_fraction, 0.99);
  EXPECT_NE(SurfaceTableRow("cloud", e).find("(in GSD)"), std::string::npos);

  // Half the cloud gone: half the visible surface is missed.
  PointCloud half = cloud;
  std::vector<bool> keep(half.size());
  for (size_t i = 0; i < half.size(); ++i) keep[i] = half.positions[i].x() > 0;
  half.Filter(keep);
  const SurfaceEvaluation h = EvaluateCloud(half, truth, visible, options);
  EXPECT_NEAR(h.completeness_fraction, 0.5, 0.05);
  EXPECT_NEAR(h.accuracy.rms, 0.002, 0.0002);
  // Misses are counted at ten times the threshold, not as infinity.
  EXPECT_NEAR(h.completeness.max, 0.2, 1e-12);
}

TEST(SurfaceEval, CompletenessPerOrientationOfTheTrueSurface) {
  // A cloud on the torus's walls alone (normals within 45 degrees of
  // horizontal) reaches the walls and, of the tops, only a rim next to them.
  const VisibleSurface& visible = Visible();
  ASSERT_EQ(visible.normals.size(), visible.samples.size());
  const MeshDistance truth(Scene0().surface);
  NoisyCloudOptions noise;
  noise.num_points = 200000;
  noise.sigma_m = 0;
  noise.blunder_fraction = 0;
  PointCloud cloud = SampleNoisyCloud(Scene0().surface, noise);
  std::vector<bool> keep(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    keep[i] = OrientationOf(FaceNormal(
                  Scene0().surface, truth.Closest(cloud.positions[i]).face)) ==
              SurfaceOrientation::kWalls;
  }
  cloud.Filter(keep);
  SurfaceEvaluationOptions options;
  options.completeness_threshold_m = 0.02;
  const SurfaceEvaluation e = EvaluateCloud(cloud, truth, visible, options);
  const auto& walls =
      e.completeness_by_orientation[int(SurfaceOrientation::kWalls)];
  const auto& tops =
      e.completeness_by_orientation[int(SurfaceOrientation::kTops)];
  const auto& undersides =
      e.completeness_by_orientation[int(SurfaceOrientation::kUndersides)];
  EXPECT_EQ(walls.num_samples + tops.num_samples + undersides.num_samples,
            e.num_visible_samples);
  // The cameras, 3 m up, see the torus's top and outer side.
  EXPECT_GT(tops.num_samples, e.num_visible_samples / 4);
  EXPECT_GT(walls.num_samples, e.num_visible_samples / 4);
  EXPECT_GT(walls.fraction, 0.99);
  EXPECT_LT(tops.fraction, 0.2);
  EXPECT_NEAR(
      e.completeness_fraction,
      (walls.fraction * walls.num_samples + tops.fraction * tops.num_samples +
       undersides.fraction * undersides.num_samples) /
          e.num_visible_samples,
      1e-12);
  EXPECT_NE(SurfaceTableRow("cloud", e).find("walls"), std::string::npos);
}

TEST(SurfaceEval, TheTruthAsAMeshIsExactClosedAndComplete) {
  const VisibleSurface& visible = Visible();
  const MeshDistance truth(Scene0().surface);
  SurfaceEvaluationOptions options;
  options.completeness_threshold_m = 0.005;
  options.num_mesh_samples = 20000;
  const SurfaceEvaluation e =
      EvaluateMesh(Scene0().surface, Scene0().surface, truth, visible, options);
  EXPECT_LT(e.accuracy.max, 1e-9);
  EXPECT_LT(e.completeness.max, 1e-9);
  EXPECT_EQ(e.completeness_fraction, 1.0);
  EXPECT_TRUE(e.topology.IsClosed());
  EXPECT_TRUE(e.truth_topology.IsClosed());

  // An offset copy is off by its offset, both ways.
  TriangleMesh shifted = Scene0().surface;
  for (Eigen::Vector3d& p : shifted.vertices.positions) p.z() += 0.003;
  const SurfaceEvaluation s =
      EvaluateMesh(shifted, Scene0().surface, truth, visible, options);
  EXPECT_LT(s.accuracy.max, 0.0031);
  EXPECT_GT(s.accuracy.mean, 0.001);
}

TEST(SurfaceEval, RefusesWhatCannotBeEvaluated) {
  const VisibleSurface& visible = Visible();
  const MeshDistance truth(Scene0().surface);
  SurfaceEvaluationOptions options;
  options.completeness_threshold_m = 0;
  PointCloud cloud;
  cloud.positions.push_back(Eigen::Vector3d(2.1, 0, 0));
  EXPECT_THROW(EvaluateCloud(cloud, truth, visible, options), InputError);
  options.completeness_threshold_m = 0.01;
  options.region = Eigen::AlignedBox3d(Eigen::Vector3d(10, 10, 10),
                                       Eigen::Vector3d(11, 11, 11));
  EXPECT_THROW(EvaluateCloud(cloud, truth, visible, options), InputError);
  Scene no_images;
  EXPECT_THROW(FindVisibleSurface(Scene0().surface, no_images), InputError);
}

}  // namespace
}  // namespace bayon
