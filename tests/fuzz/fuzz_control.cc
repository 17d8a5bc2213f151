// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_control: a control/ folder (control_io.h): points.txt,
// observations.txt (control and manual tie point measurements) and
// distances.txt, split at "=====" lines; an empty part leaves its file out.
// Each file is read on its own, then the folder as `bayon adjust` and
// `bayon strip` read it (ReadControlFolder).
#include "ext/adjustment/datum.h"
#include "ext/colmap/control_io.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  const std::string folder = fuzz::FreshPath("control");
  std::filesystem::create_directories(folder);
  const std::vector<std::string> parts = fuzz::SplitInput(data, size, 3);
  const std::string points = folder + "/points.txt";
  const std::string measurements = folder + "/observations.txt";
  const std::string distances = folder + "/distances.txt";
  if (!parts[0].empty()) fuzz::WriteFile(points, parts[0]);
  if (!parts[1].empty()) fuzz::WriteFile(measurements, parts[1]);
  if (!parts[2].empty()) fuzz::WriteFile(distances, parts[2]);
  if (!parts[0].empty()) fuzz::Expect([&] { ReadControlPoints(points); });
  if (!parts[1].empty()) {
    fuzz::Expect([&] { ReadImageMeasurements(measurements); });
  }
  if (!parts[2].empty()) fuzz::Expect([&] { ReadDistances(distances); });
  fuzz::Expect([&] { ReadControlFolder(folder); });
  return 0;
}
