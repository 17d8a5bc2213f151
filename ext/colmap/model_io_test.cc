// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/model_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/random.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "tests/testing.h"

namespace bayon {
namespace {

Scene SmallScene() {
  Scene scene;
  Camera camera =
      Camera::Create(CameraModelId::kOpenCV, 1000.123456789, 800, 600);
  camera.camera_id = 7;
  camera.params[4] = -0.0123456789012345;
  scene.cameras.Set(7, camera);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 600);
  // Ids deliberately out of order: the order must survive.
  for (image_t image_id : {5u, 2u, 9u}) {
    Image image;
    image.image_id = image_id;
    image.name = "img_" + std::to_string(image_id) + ".jpg";
    image.camera_id = 7;
    image.cam_from_world.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(
        0.1 * image_id, Eigen::Vector3d(1, 2, 3).normalized()));
    image.cam_from_world.translation =
        Eigen::Vector3d(0.1, -0.2, 3.0 + image_id);
    for (int i = 0; i < 20; ++i) {
      Point2D point;
      point.xy = RandomVector<2>(u, rng);
      image.points2D.push_back(point);
    }
    scene.images.Set(image_id, image);
  }
  for (int i = 0; i < 10; ++i) {
    scene.AddPoint3D(
        RandomVector<3>(u, rng) / 100,
        {{5, static_cast<point2D_t>(i)}, {9, static_cast<point2D_t>(i + 3)}});
  }
  scene.UpdateReprojectionErrors();
  return scene;
}

TEST(ModelIo, BinaryAndTextRoundTripsAreByteIdentical) {
  const std::string dir = testing::TempDir("model_io");
  const Scene scene = SmallScene();
  for (ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    const std::string a =
        dir + (format == ModelFormat::kBinary ? "/bin_a" : "/txt_a");
    const std::string b =
        dir + (format == ModelFormat::kBinary ? "/bin_b" : "/txt_b");
    std::filesystem::create_directories(a);
    std::filesystem::create_directories(b);
    WriteModel(scene, a, format);
    const Scene read = ReadModel(a);
    EXPECT_EQ(read.images.begin()->first, 5u);
    WriteModel(read, b, format);
    EXPECT_EQ(testing::HashTree(a), testing::HashTree(b));
  }
}

TEST(ModelIo, TruncatedBinaryIsRefusedWithTheFileName) {
  const std::string dir = testing::TempDir("model_io_truncated");
  WriteModel(SmallScene(), dir, ModelFormat::kBinary);
  const std::string images = ReadFileToString(dir + "/images.bin");
  WriteFileAtomically(dir + "/images.bin",
                      images.substr(0, images.size() - 30));
  try {
    ReadModel(dir);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("images.bin"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("truncated"), std::string::npos);
  }
}

TEST(ModelIo, WrongParameterCountInTextNamesTheLine) {
  const std::string dir = testing::TempDir("model_io_params");
  WriteModel(SmallScene(), dir, ModelFormat::kText);
  WriteFileAtomically(dir + "/cameras.txt",
                      "# header\n7 OPENCV 800 600 1000 1000 400 300 0.1\n");
  try {
    ReadModel(dir);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cameras.txt:2"),
              std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("takes 8 parameters"),
              std::string::npos);
  }
}

TEST(ModelIo, DanglingReferencesAreRefused) {
  const std::string dir = testing::TempDir("model_io_dangling");
  Scene scene = SmallScene();
  scene.points3D.begin()->second.track.push_back({42, 0});
  WriteModel(scene, dir, ModelFormat::kBinary);
  EXPECT_THROW(ReadModel(dir), InputError);
}

}  // namespace
}  // namespace bayon
