// SPDX-License-Identifier: BSD-3-Clause
//
// The formats behind model_export.h, one file each (model_export_obj.cc,
// model_export_vrml.cc, model_export_glb.cc), and what they share. For
// model_export's own files only; other code uses model_export.h.
#pragma once

#include "ext/render/model_export.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace bayon {
namespace internal {

// ---------------------------------------------------------------------------
// Wedges: a vertex together with one texture coordinate. Formats with a
// single index per corner (glTF) need one vertex per wedge; OBJ and VRML
// index positions and texture coordinates separately and list each wedge's
// texture coordinate once.

struct Wedges {
  std::vector<int> vertex;             // per wedge: the mesh vertex
  std::vector<Eigen::Vector2f> uv;     // per wedge
  std::vector<Eigen::Vector3i> faces;  // per face: wedge indices
};

// Appends printf-formatted text (numbers in the C locale's format).
template <typename... Args>
void Append(std::string* out, const char* format, Args... args) {
  char buffer[160];
  const int n = std::snprintf(buffer, sizeof(buffer), format, args...);
  out->append(buffer, static_cast<size_t>(std::max(0, n)));
}

// An atlas as TexturedModel holds it: 8-bit BGR.
cv::Mat ToAtlas(cv::Mat image);

// The atlas file a model names; errors name the model too.
cv::Mat ReadAtlasFile(const std::string& model_path,
                      const std::string& image_path);

// `name` as a file named in `file`: relative names are beside it.
std::string ResolveBeside(const std::string& file, const std::string& name);

// OBJ (with its MTL) and VRML 2.0 index positions and texture coordinates
// separately; glTF binary gives every wedge its own vertex.
std::string ObjText(const TriangleMesh& mesh,
                    const Wedges& wedges,
                    const std::string& mtl_name);
std::string MtlText(const std::string& png_name);
TexturedModel ReadObj(const std::string& path);

std::string VrmlText(const TriangleMesh& mesh,
                     const Wedges& wedges,
                     const std::string& png_name);
TexturedModel ReadVrml(const std::string& path);

std::string GlbBytes(const TriangleMesh& mesh,
                     const Wedges& wedges,
                     const std::string& png,
                     bool y_up,
                     const std::string& georeference_json);
TexturedModel ReadGlb(const std::string& path);

}  // namespace internal
}  // namespace bayon
