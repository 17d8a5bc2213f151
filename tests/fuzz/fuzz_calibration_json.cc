// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_calibration_json: calibration.json, the full calibrations that sit
// beside a sparse model (calibration_json.h), read directly and as the
// dense and texture stages find it beside a model.
#include "ext/colmap/calibration_json.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  const std::string folder = fuzz::FreshPath("model");
  std::filesystem::create_directories(folder);
  const std::string path = folder + "/calibration.json";
  fuzz::WriteFile(path, std::string(reinterpret_cast<const char*>(data), size));
  fuzz::Expect([&] { ReadCalibrationJson(path); });
  fuzz::Expect([&] { ReadCalibrationsBesideModel(folder); });
  return 0;
}
