// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/model_export.h"

#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"
#include "ext/render/model_formats.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace bayon {
namespace internal {

cv::Mat ToAtlas(cv::Mat image) {
  if (image.depth() == CV_16U) image.convertTo(image, CV_8U, 1.0 / 257.0);
  if (image.depth() != CV_8U) image.convertTo(image, CV_8U, 255.0);
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  return image;
}

cv::Mat ReadAtlasFile(const std::string& model_path,
                      const std::string& image_path) {
  try {
    return ToAtlas(ReadImage(image_path, ImageReadMode::kColor));
  } catch (const InputError& error) {
    ThrowInputError(model_path, ": its texture image: ", error.what());
  }
}

std::string ResolveBeside(const std::string& file, const std::string& name) {
  const fs::path path(name);
  return path.is_absolute() ? name
                            : (fs::path(file).parent_path() / path).string();
}

}  // namespace internal

namespace {

using internal::ReadAtlasFile;
using internal::Wedges;

Wedges SplitWedges(const TriangleMesh& mesh) {
  Wedges wedges;
  // The wedges of each vertex so far; a vertex rarely has more than a few.
  std::vector<std::vector<int>> of_vertex(mesh.NumVertices());
  wedges.faces.resize(mesh.NumFaces());
  for (size_t f = 0; f < mesh.NumFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      const Eigen::Vector2f& uv = mesh.face_texcoords[f][k];
      int found = -1;
      for (int w : of_vertex[v]) {
        if (wedges.uv[w] == uv) {
          found = w;
          break;
        }
      }
      if (found < 0) {
        found = static_cast<int>(wedges.vertex.size());
        wedges.vertex.push_back(v);
        wedges.uv.push_back(uv);
        of_vertex[v].push_back(found);
      }
      wedges.faces[f][k] = found;
    }
  }
  return wedges;
}

void CheckModel(const TexturedModel& model) {
  model.mesh.Check("textured model");
  if (model.mesh.faces.empty()) {
    ThrowInputError("textured model: the mesh has no faces");
  }
  if (!model.mesh.HasTexcoords()) {
    ThrowInputError("textured model: the mesh has no texture coordinates");
  }
  if (model.atlas.empty()) {
    ThrowInputError("textured model: the texture atlas is empty");
  }
  if (model.atlas.depth() != CV_8U ||
      (model.atlas.channels() != 3 && model.atlas.channels() != 1)) {
    ThrowInputError("textured model: the atlas must be 8-bit grey or BGR");
  }
}

TexturedModel ReadTexturedPly(const std::string& path) {
  TexturedModel model;
  model.mesh = ReadMeshPly(path);
  if (model.mesh.HasTexcoords()) {
    const std::string texture = PlyTextureFile(path);
    if (texture.empty()) {
      ThrowInputError(path,
                      ": has texture coordinates but no 'comment TextureFile' "
                      "header line naming the atlas");
    }
    model.atlas = ReadAtlasFile(path, texture);
  }
  return model;
}

std::string LowerExtension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

}  // namespace

void ModelExportOptions::Register(OptionRegistry* r) {
  r->Add("stem", &stem, "File name of the model files");
  r->AddSwitches("formats",
                 {{"obj", &obj}, {"ply", &ply}, {"wrl", &vrml}, {"glb", &gltf}},
                 "Model formats: obj, ply, wrl, glb");
}

void ModelExportOptions::Check() const {
  if (stem.empty() || stem.find_first_of("/\\ \t\"") != std::string::npos ||
      stem == "." || stem == "..") {
    ThrowInputError("stem must be a plain file name (got '", stem, "')");
  }
  if (!obj && !ply && !vrml && !gltf) {
    ThrowInputError("formats: none given (obj, ply, wrl, glb)");
  }
}

std::vector<std::string> ModelExportOptions::FileNames() const {
  std::vector<std::string> names = {stem + ".png"};
  if (obj) names.insert(names.end(), {stem + ".obj", stem + ".mtl"});
  if (ply) names.push_back(stem + ".ply");
  if (vrml) names.push_back(stem + ".wrl");
  if (gltf) names.push_back(stem + ".glb");
  return names;
}

std::vector<std::string> WriteTexturedModel(const TexturedModel& model,
                                            const std::string& output_dir,
                                            const ModelExportOptions& options) {
  CheckModel(model);
  options.Check();
  std::error_code error;
  fs::create_directories(output_dir, error);
  if (!fs::is_directory(output_dir)) {
    throw RunFailure(StrCat(output_dir, ": cannot create the output folder"));
  }
  auto file = [&](const std::string& extension) {
    return (fs::path(output_dir) / (options.stem + extension)).string();
  };
  const std::string png_name = options.stem + ".png";
  std::vector<uchar> png_bytes;
  if (!cv::imencode(".png", model.atlas, png_bytes)) {
    throw RunFailure(StrCat(file(".png"), ": cannot encode the atlas"));
  }
  const std::string png(png_bytes.begin(), png_bytes.end());
  std::vector<std::string> written;
  WriteFileAtomically(file(".png"), png);
  written.push_back(file(".png"));

  const TriangleMesh& mesh = model.mesh;
  const Wedges wedges = SplitWedges(mesh);
  if (options.obj) {
    WriteFileAtomically(file(".mtl"), internal::MtlText(png_name));
    WriteFileAtomically(file(".obj"),
                        internal::ObjText(mesh, wedges, options.stem + ".mtl"));
    written.push_back(file(".obj"));
    written.push_back(file(".mtl"));
  }
  if (options.ply) {
    PlyWriteOptions ply_options;
    ply_options.comment = "TextureFile " + png_name;
    WriteMeshPly(mesh, file(".ply"), ply_options);
    written.push_back(file(".ply"));
  }
  if (options.vrml) {
    WriteFileAtomically(file(".wrl"),
                        internal::VrmlText(mesh, wedges, png_name));
    written.push_back(file(".wrl"));
  }
  if (options.gltf) {
    WriteFileAtomically(
        file(".glb"),
        internal::GlbBytes(
            mesh, wedges, png, options.gltf_y_up, options.georeference_json));
    written.push_back(file(".glb"));
  }
  return written;
}

TexturedModel ReadTexturedModel(const std::string& path) {
  CheckFileExists(path, "model");
  const std::string extension = LowerExtension(path);
  if (extension == ".obj") return internal::ReadObj(path);
  if (extension == ".ply") return ReadTexturedPly(path);
  if (extension == ".wrl") return internal::ReadVrml(path);
  if (extension == ".glb") return internal::ReadGlb(path);
  ThrowInputError(path,
                  ": unknown model format '",
                  extension,
                  "' (use .obj, .ply, .wrl or .glb)");
}

}  // namespace bayon
