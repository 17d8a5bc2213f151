// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_model_text: a sparse model in COLMAP's text format (cameras, images and
// points3D files split at "=====" lines; see fuzz_model.h), seeded from
// small real models.
#include "tests/fuzz/fuzz_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  bayon::fuzz::FuzzModel(data, size, bayon::ModelFormat::kText);
  return 0;
}
