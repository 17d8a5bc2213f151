// SPDX-License-Identifier: BSD-3-Clause
//
// Meshes in the formats viewers and other tools read, chosen by the file's
// extension: .ply through bayon's own PLY code (ext/colmap/ply_io.h: binary,
// double coordinates, every vertex attribute kept), .obj and .off through
// OpenMesh (positions, and vertex normals and colours where present). Written
// atomically (temporary name, rename).
//
// OpenMesh's exporters hand coordinates over in single precision (about 7
// significant digits): fine for an object in a local datum, a millimetre
// lost at 10 km from the origin. PLY keeps doubles; WriteMesh logs a warning
// when OBJ or OFF would lose more than 0.1 mm.
#pragma once

#include "ext/core/point_cloud.h"

#include <string>

namespace bayon {

// True for .ply, .obj, .off (any case).
bool IsMeshFormatSupported(const std::string& path);

// Throws InputError for an unsupported extension; RunFailure when the file
// cannot be written.
void WriteMesh(const TriangleMesh& mesh, const std::string& path);

// Throws InputError naming the file when it cannot be read or has no faces.
TriangleMesh ReadMesh(const std::string& path);

}  // namespace bayon
