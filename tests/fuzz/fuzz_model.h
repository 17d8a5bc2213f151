// SPDX-License-Identifier: BSD-3-Clause
//
// The body of fuzz_model_binary and fuzz_model_text: the input is three
// files split at kSplit lines (cameras, images, points3D), written into a
// model folder and read as `bayon` reads a user's model: each file on its
// own, then ReadModel on the folder, and a model that was read is written
// back to memory (as model_converter does).
#pragma once

#include "ext/colmap/model_io.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace bayon::fuzz {

inline void FuzzModel(const uint8_t* data, size_t size, ModelFormat format) {
  const std::string folder = FreshPath("model");
  std::filesystem::create_directories(folder);
  const std::string ext = format == ModelFormat::kBinary ? ".bin" : ".txt";
  const std::vector<std::string> parts = SplitInput(data, size, 3);
  const std::string cameras = folder + "/cameras" + ext;
  const std::string images = folder + "/images" + ext;
  const std::string points = folder + "/points3D" + ext;
  WriteFile(cameras, parts[0]);
  WriteFile(images, parts[1]);
  WriteFile(points, parts[2]);
  const bool binary = format == ModelFormat::kBinary;
  Expect([&] {
    Scene scene;
    binary ? ReadCamerasBinary(cameras, &scene)
           : ReadCamerasText(cameras, &scene);
  });
  Expect([&] {
    Scene scene;
    binary ? ReadImagesBinary(images, &scene) : ReadImagesText(images, &scene);
  });
  Expect([&] {
    Scene scene;
    binary ? ReadPoints3DBinary(points, &scene)
           : ReadPoints3DText(points, &scene);
  });
  Expect([&] {
    const Scene scene = ReadModel(folder);
    CamerasBinary(scene);
    ImagesBinary(scene);
    Points3DBinary(scene);
    CamerasText(scene);
    ImagesText(scene);
    Points3DText(scene);
  });
}

}  // namespace bayon::fuzz
