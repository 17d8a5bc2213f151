// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_mesh: the mesh and textured-model files bayon reads besides PLY
// (fuzz_ply): the first byte picks OBJ, PLY, VRML, glTF binary or OFF; the
// rest is split at "=====" lines into the model file, model.mtl and the
// texture image model.png, which an OBJ (mtllib, map_Kd), a PLY
// (comment TextureFile) or a VRML file (ImageTexture) may name. The model is
// read as a textured model (render/model_export.h: `bayon viewer`,
// `bayon texture`) and as a mesh (mesh/mesh_io.h: OpenMesh for OBJ and OFF).
#include "ext/mesh/mesh_io.h"
#include "ext/render/model_export.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  if (size == 0) return 0;
  static const char* kExtensions[] = {".obj", ".ply", ".wrl", ".glb", ".off"};
  const std::string extension = kExtensions[data[0] % 5];
  const std::vector<std::string> parts =
      fuzz::SplitInput(data + 1, size - 1, 3);
  const std::string folder = fuzz::FreshPath("mesh");
  std::filesystem::create_directories(folder);
  const std::string path = folder + "/model" + extension;
  fuzz::WriteFile(path, parts[0]);
  if (!parts[1].empty()) fuzz::WriteFile(folder + "/model.mtl", parts[1]);
  if (!parts[2].empty()) fuzz::WriteFile(folder + "/model.png", parts[2]);
  if (extension != ".off") fuzz::Expect([&] { ReadTexturedModel(path); });
  if (extension != ".wrl" && extension != ".glb") {
    fuzz::Expect([&] { ReadMesh(path); });
  }
  return 0;
}
