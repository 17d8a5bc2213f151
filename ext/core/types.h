// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstdint>
#include <limits>
#include <utility>

namespace bayon {

// Identifier types, as in COLMAP: ids are never indices (image_id vs
// image_idx).
using camera_t = uint32_t;
using image_t = uint32_t;
using point2D_t = uint32_t;
using point3D_t = uint64_t;
using pair_t = uint64_t;

constexpr camera_t kInvalidCameraId = std::numeric_limits<camera_t>::max();
constexpr image_t kInvalidImageId = std::numeric_limits<image_t>::max();
constexpr point2D_t kInvalidPoint2DIdx = std::numeric_limits<point2D_t>::max();
constexpr point3D_t kInvalidPoint3DId = std::numeric_limits<point3D_t>::max();

// COLMAP's kMaxNumImages: pair_id = kMaxNumImages * min(id1, id2) + max(...).
constexpr uint64_t kMaxNumImages = 2147483647;

inline pair_t PairIdFromImageIds(image_t image_id1, image_t image_id2) {
  if (image_id1 > image_id2) std::swap(image_id1, image_id2);
  return kMaxNumImages * image_id1 + image_id2;
}

inline std::pair<image_t, image_t> ImageIdsFromPairId(pair_t pair_id) {
  const image_t image_id2 = static_cast<image_t>(pair_id % kMaxNumImages);
  const image_t image_id1 =
      static_cast<image_t>((pair_id - image_id2) / kMaxNumImages);
  return {image_id1, image_id2};
}

// True when the canonical order of the pair swaps the two images, in which
// case COLMAP swaps match columns and inverts two-view geometries.
inline bool SwapImagePair(image_t image_id1, image_t image_id2) {
  return image_id1 > image_id2;
}

}  // namespace bayon
