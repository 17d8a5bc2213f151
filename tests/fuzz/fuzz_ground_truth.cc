// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_ground_truth: the truth formats `bayon import_ground_truth` reads
// (ground_truth_import.h). The first byte picks Middlebury (*_par.txt),
// one Strecha .camera file, or a folder of two .camera files (split at a
// "=====" line); the views read are then built into a scene, with a size
// given to views whose format has none (as the image folder would).
// COLMAP-format truth models are sparse models: fuzz_model_*.
#include "ext/eval/ground_truth_import.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  if (size == 0) return 0;
  const int kind = data[0] % 3;
  ++data;
  --size;
  GroundTruthImportOptions options;
  std::vector<GroundTruthView> views;
  if (kind == 0) {
    options.format = GroundTruthFormat::kMiddlebury;
    const std::string path = fuzz::FreshPath("truth_par.txt");
    fuzz::WriteFile(path,
                    std::string(reinterpret_cast<const char*>(data), size));
    fuzz::Expect([&] { views = ReadMiddleburyCameras(path, options); });
  } else {
    options.format = GroundTruthFormat::kStrecha;
    const std::string folder = fuzz::FreshPath("cameras");
    std::filesystem::create_directories(folder);
    const std::vector<std::string> parts =
        fuzz::SplitInput(data, size, kind == 1 ? 1 : 2);
    for (size_t i = 0; i < parts.size(); ++i) {
      fuzz::WriteFile(folder + "/" + std::to_string(i) + ".png.camera",
                      parts[i]);
    }
    const std::string input = kind == 1 ? folder + "/0.png.camera" : folder;
    fuzz::Expect([&] { views = ReadStrechaCameras(input, options); });
  }
  for (GroundTruthView& view : views) {
    if (view.width <= 0 || view.height <= 0) {
      view.width = 640;
      view.height = 480;
    }
  }
  fuzz::Expect([&] { GroundTruthScene(views); });
  return 0;
}
