// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_bal: a Bundle Adjustment in the Large problem file, read as
// `bayon import_bal` reads it (bal_io.h).
#include "ext/adjustment/bal_io.h"

#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = bayon::fuzz::FreshPath("problem.txt");
  bayon::fuzz::WriteFile(
      path, std::string(reinterpret_cast<const char*>(data), size));
  bayon::fuzz::Expect([&] { bayon::ReadBalProblem(path); });
  return 0;
}
