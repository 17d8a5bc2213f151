// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_georef: a survey's control file as `bayon import_control` reads it
// (control_import.h). The first byte picks the format (odm, metashape,
// csv) and whether --crs is given (EPSG:32648); the rest is the file.
#include "ext/georef/control_import.h"

#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  if (size == 0) return 0;
  static const char* kFormats[] = {"odm", "metashape", "csv"};
  ControlImportOptions options;
  options.format = kFormats[data[0] % 3];
  if ((data[0] / 3) % 2 == 1) options.crs = "EPSG:32648";
  const std::string path = fuzz::FreshPath("survey.txt");
  fuzz::WriteFile(
      path, std::string(reinterpret_cast<const char*>(data) + 1, size - 1));
  fuzz::Expect([&] { ImportControl(path, options, {"a.jpg", "b.jpg"}); });
  return 0;
}
