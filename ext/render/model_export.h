// SPDX-License-Identifier: BSD-3-Clause
//
// A textured model (a triangle mesh with per-corner texture coordinates and
// one atlas image) in the formats viewers read, and back:
//
// - OBJ + MTL + PNG: `v`, `vt` and `f v/vt` records, one material whose
//   `map_Kd` is the atlas; what MeshLab, Blender and most tools open.
// - PLY: bayon's binary PLY with the face `texcoord` list and the header
//   comment `TextureFile NAME` (MeshLab's convention).
// - VRML 2.0 (.wrl): one Shape with an IndexedFaceSet, its texCoord and
//   texCoordIndex, and an ImageTexture naming the PNG, as in the paper.
// - glTF 2.0 binary (.glb): one mesh, one primitive, positions (single
//   precision, relative to the model's centre, which is the node's
//   translation, so that a georeferenced datum keeps its precision), texture
//   coordinates and 32-bit indices, the PNG embedded in the binary chunk;
//   what web viewers (three.js) and today's tools read.
//
// Texture coordinates follow TriangleMesh: u right, v up, [0, 1] over the
// atlas. glTF counts v downwards from the top; the writer and reader flip
// it. glTF shares vertices between faces only where their texture
// coordinates agree too, so vertices on chart borders are repeated; OBJ and
// VRML index positions and texture coordinates separately, so they keep the
// mesh's vertices and repeat only texture coordinates.
//
// Every file is written atomically (temporary name, rename).
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace bayon {

struct TexturedModel {
  TriangleMesh mesh;  // with face_texcoords
  cv::Mat atlas;      // CV_8UC3, BGR
};

struct ModelExportOptions {
  // File stem inside the output folder: <stem>.obj, .mtl, .png, .ply, .wrl,
  // .glb.
  std::string stem = "model";
  bool obj = true;
  bool ply = true;
  bool vrml = true;
  bool gltf = true;
  // glTF's up axis is y, bayon's datum's is z: the .glb's node carries the
  // rotation that stands the model upright in glTF viewers (the positions
  // stay in the datum). Off: the node has no transform.
  bool gltf_y_up = true;
  // Where the model lies in the world: a crs.json (bayon import_control;
  // the CRS and the origin the model's coordinates are relative to), put
  // into the .glb as asset.extras.georeference. Empty: none.
  std::string georeference_json;
  // stem, and the formats as one list: obj, ply, wrl, glb.
  void Register(OptionRegistry* registry);
  // The stem a plain file name, at least one format.
  void Check() const;
  // The files WriteTexturedModel writes, in its order: <stem>.png, then
  // .obj and .mtl, .ply, .wrl, .glb as asked for.
  std::vector<std::string> FileNames() const;
};

// The paths written, in the order above (the PNG atlas first).
// Throws InputError if the mesh has no texture coordinates or the atlas is
// empty or a file cannot be written (naming it).
std::vector<std::string> WriteTexturedModel(const TexturedModel& model,
                                            const std::string& output_dir,
                                            const ModelExportOptions& options);

// Reads .obj (with its MTL and map_Kd), .ply (TextureFile), .wrl (the one
// IndexedFaceSet this file writes) or .glb (TRIANGLES primitives, their
// positions as stored: node transforms are not applied). A model
// without texture coordinates comes back with an empty atlas (vertex
// colours, if any, in mesh.vertices.colors). Throws InputError naming the
// file for anything it cannot read.
TexturedModel ReadTexturedModel(const std::string& path);

}  // namespace bayon
