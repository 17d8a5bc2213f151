// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/silhouette_eval.h"

#include "ext/core/errors.h"
#include "ext/image/image_io.h"
#include "ext/render/mesh_renderer.h"
#include "ext/render/views.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/testing.h"

namespace bayon {
namespace {

// A 1 m square in the plane x = 0, centred at (0, dy, 0).
TriangleMesh Square(double dy) {
  TriangleMesh mesh;
  for (const auto& [y, z] : {std::pair{-0.5, -0.5},
                             std::pair{0.5, -0.5},
                             std::pair{0.5, 0.5},
                             std::pair{-0.5, 0.5}}) {
    mesh.vertices.positions.emplace_back(0, y + dy, z);
  }
  mesh.faces.emplace_back(0, 1, 2);
  mesh.faces.emplace_back(0, 2, 3);
  return mesh;
}

// One 600 x 400 photograph from 4 m, the square grey 200 on black (10).
Scene PhotographedSquare(const std::string& image_path) {
  Scene scene;
  Camera camera = Camera::Create(CameraModelId::kPinhole, 500, 600, 400);
  camera.camera_id = 1;
  scene.cameras.Set(1, camera);
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "square.png";
  image.cam_from_world =
      LookAt({4, 0.2, 0.1}, {0, 0, 0}, Eigen::Vector3d::UnitZ());
  scene.images.Set(1, image);
  RenderView view;
  view.camera = camera;
  view.cam_from_world = image.cam_from_world;
  RenderOptions options;
  options.supersampling = 4;
  const RenderResult result =
      MeshRenderer(Square(0)).Render(view, Lighting(), options);
  cv::Mat photograph;
  result.coverage.convertTo(photograph, CV_8U, 190, 10);
  std::filesystem::create_directories(image_path);
  WriteImage(image_path + "/square.png", photograph);
  return scene;
}

TEST(Silhouettes, IoUOfTheModelCarriedIntoThePhotographs) {
  const std::string dir = testing::TempDir("silhouette_eval");
  const Scene scene = PhotographedSquare(dir + "/images");
  SilhouetteOptions options;
  options.mask_dir = dir + "/masks";
  const SilhouetteEvaluation same =
      EvaluateSilhouettes(Square(0), scene, dir + "/images", options);
  ASSERT_EQ(same.views.size(), 1u);
  EXPECT_GT(same.mean_iou, 0.99);
  EXPECT_EQ(same.worst, "square.png");
  EXPECT_TRUE(std::filesystem::exists(dir + "/masks/square.png"));
  // Moved sideways by a quarter of its width: the two squares overlap by
  // 3/4 of one and unite to 5/4, IoU 0.6 (seen nearly square on).
  const SilhouetteEvaluation moved =
      EvaluateSilhouettes(Square(0.25), scene, dir + "/images", options);
  EXPECT_NEAR(moved.mean_iou, 0.6, 0.03);
  EXPECT_NEAR(moved.views[0].model_only, 0.2, 0.02);
  EXPECT_NEAR(moved.views[0].photograph_only, 0.2, 0.02);
  EXPECT_EQ(moved.views[0].best_iou, 1.0);
  // A square the model misses altogether is clutter: the best a model can
  // do is cover the rest.
  const SilhouetteEvaluation other =
      EvaluateSilhouettes(Square(3), scene, dir + "/images", options);
  EXPECT_EQ(other.views[0].iou, 0.0);
  EXPECT_EQ(other.views[0].best_iou, 0.0);
}

TEST(Silhouettes, RefusesMissingPhotographsAndEmptyMeshes) {
  const std::string dir = testing::TempDir("silhouette_eval_bad");
  const Scene scene = PhotographedSquare(dir + "/images");
  EXPECT_THROW(EvaluateSilhouettes(Square(0), scene, dir + "/nowhere", {}),
               InputError);
  EXPECT_THROW(EvaluateSilhouettes(TriangleMesh(), scene, dir + "/images", {}),
               InputError);
  SilhouetteOptions bad;
  bad.grey_threshold = 300;
  EXPECT_THROW(EvaluateSilhouettes(Square(0), scene, dir + "/images", bad),
               InputError);
}

}  // namespace
}  // namespace bayon
