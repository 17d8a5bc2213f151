// SPDX-License-Identifier: BSD-3-Clause
//
// COLMAP sparse models (cameras, images, points3D) in binary and text
// (colmap-interop.md, section 2). Records keep the order in which they were
// read, so a model read and written again is byte-identical to COLMAP's.
// Readers check every count against the bytes left and name the file, the
// record and what was expected when something does not fit.
#pragma once

#include "ext/core/scene.h"

#include <string>

namespace bayon {

enum class ModelFormat { kBinary, kText };

// Reads the model in `path`: the .bin files when all three exist, otherwise
// the .txt files. Throws InputError when neither set is complete or a file is
// malformed. rigs/frames files of COLMAP 3.12+ are ignored: images.bin still
// holds each image's pose.
Scene ReadModel(const std::string& path);
// Which format ReadModel would use, or throws InputError.
ModelFormat DetectModelFormat(const std::string& path);

void ReadCamerasBinary(const std::string& path, Scene* scene);
void ReadImagesBinary(const std::string& path, Scene* scene);
void ReadPoints3DBinary(const std::string& path, Scene* scene);
void ReadCamerasText(const std::string& path, Scene* scene);
void ReadImagesText(const std::string& path, Scene* scene);
void ReadPoints3DText(const std::string& path, Scene* scene);

// Writes cameras, images and points3D into the folder `path` (which must
// exist), each file atomically. BROWN_BEYER cameras must have been converted
// to a COLMAP model first (camera_conversion.h); they are refused here.
void WriteModel(const Scene& scene,
                const std::string& path,
                ModelFormat format);

std::string CamerasBinary(const Scene& scene);
std::string ImagesBinary(const Scene& scene);
std::string Points3DBinary(const Scene& scene);
std::string CamerasText(const Scene& scene);
std::string ImagesText(const Scene& scene);
std::string Points3DText(const Scene& scene);

// The 3D points as a PLY point cloud (binary little-endian, x y z as double,
// red green blue as uchar), as `colmap model_converter --output_type PLY`.
void WritePointsPly(const Scene& scene, const std::string& path);

}  // namespace bayon
