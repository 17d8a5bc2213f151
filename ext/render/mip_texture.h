// SPDX-License-Identifier: BSD-3-Clause
//
// A texture atlas with a mip pyramid, sampled bilinearly within a level and
// linearly between levels (trilinear filtering), so that a renderer can
// match the texture's detail to the footprint of each sample instead of
// aliasing it into noise.
//
// Texture coordinates are those of TriangleMesh::face_texcoords: u to the
// right, v up, both in [0, 1] over the whole atlas; texel (column i, row j
// counted from the top) covers u in [i, i + 1] / W and v in
// [H - j - 1, H - j] / H, its centre at ((i + 0.5) / W, 1 - (j + 0.5) / H).
// Positions outside [0, 1] are clamped to the border texels.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace bayon {

class MipTexture {
 public:
  MipTexture() = default;
  // `image`: 8-bit, 1 or 3 channels (BGR as OpenCV reads it), or float
  // 3-channel. Colours are returned as given, 8-bit scaled to [0, 1].
  // Levels halve the size (area averaging) down to 1 texel or `max_levels`.
  explicit MipTexture(const cv::Mat& image, int max_levels = 16);

  bool empty() const { return levels_.empty(); }
  int width() const { return empty() ? 0 : levels_[0].cols; }
  int height() const { return empty() ? 0 : levels_[0].rows; }
  int num_levels() const { return static_cast<int>(levels_.size()); }

  // BGR colour at `uv`. `lod` is log2 of the texels of level 0 per sample:
  // 0 or less samples level 0, fractional values blend two levels.
  Eigen::Vector3f Sample(const Eigen::Vector2f& uv, float lod) const;
  // Bilinear sample of one level.
  Eigen::Vector3f SampleLevel(const Eigen::Vector2f& uv, int level) const;

 private:
  std::vector<cv::Mat> levels_;  // CV_8UC3 or CV_32FC3 each
  float scale_ = 1.0f;           // to [0, 1]
};

}  // namespace bayon
