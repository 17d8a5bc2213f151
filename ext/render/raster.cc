// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/raster.h"

#include "ext/core/parallel.h"

#include <algorithm>
#include <cmath>

namespace bayon {

void DepthRaster::Reset(int new_width, int new_height, bool with_ids) {
  width = new_width;
  height = new_height;
  const size_t size = size_t(width) * height;
  key.assign(size, std::numeric_limits<float>::infinity());
  if (with_ids) {
    id.assign(size, -1);
  } else {
    id.clear();
    id.shrink_to_fit();
  }
}

namespace {

constexpr int kBandHeight = 32;

// Rows [y_begin, y_end) of one triangle.
void DrawTriangle(const RasterTriangle& triangle,
                  int y_begin,
                  int y_end,
                  DepthRaster* raster) {
  const Eigen::Vector2d& p0 = triangle.position[0];
  const Eigen::Vector2d& p1 = triangle.position[1];
  const Eigen::Vector2d& p2 = triangle.position[2];
  const double area = (p1.x() - p0.x()) * (p2.y() - p0.y()) -
                      (p1.y() - p0.y()) * (p2.x() - p0.x());
  if (!(std::abs(area) > 1e-14)) return;
  const double sign = area > 0 ? 1.0 : -1.0;
  const double inv_area = 1.0 / std::abs(area);
  const double min_x = std::min({p0.x(), p1.x(), p2.x()});
  const double max_x = std::max({p0.x(), p1.x(), p2.x()});
  const double min_y = std::min({p0.y(), p1.y(), p2.y()});
  const double max_y = std::max({p0.y(), p1.y(), p2.y()});
  const int x0 = std::max(0, static_cast<int>(std::ceil(min_x - 0.5)));
  const int x1 =
      std::min(raster->width - 1, static_cast<int>(std::floor(max_x - 0.5)));
  const int y0 = std::max(y_begin, static_cast<int>(std::ceil(min_y - 0.5)));
  const int y1 = std::min(y_end - 1, static_cast<int>(std::floor(max_y - 0.5)));
  if (x0 > x1 || y0 > y1) return;
  // Edge functions w_i(x, y) = a_i x + b_i y + c_i, positive inside.
  auto edge = [sign](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const double ea = sign * (a.y() - b.y());
    const double eb = sign * (b.x() - a.x());
    const double ec = sign * (a.x() * b.y() - a.y() * b.x());
    return Eigen::Vector3d(ea, eb, ec);
  };
  const Eigen::Vector3d e0 = edge(p1, p2);  // weight of vertex 0
  const Eigen::Vector3d e1 = edge(p2, p0);
  const Eigen::Vector3d e2 = edge(p0, p1);
  const double k0 = triangle.key[0], k1 = triangle.key[1], k2 = triangle.key[2];
  for (int y = y0; y <= y1; ++y) {
    const double py = y + 0.5;
    // The span of this row inside all three half-planes w_i(x) >= 0, each
    // w_i affine in x: one division per edge instead of a test per pixel.
    double x_low = x0 + 0.5, x_high = x1 + 0.5;
    bool empty = false;
    for (const Eigen::Vector3d* e : {&e0, &e1, &e2}) {
      const double constant = e->y() * py + e->z();
      if (e->x() > 0) {
        x_low = std::max(x_low, -constant / e->x());
      } else if (e->x() < 0) {
        x_high = std::min(x_high, -constant / e->x());
      } else if (constant < 0) {
        empty = true;
      }
    }
    if (empty) continue;
    // Pixel centres x + 0.5 within [x_low, x_high]; the exact edge test
    // below settles the rounding at both ends.
    const int xa = std::max(x0, static_cast<int>(std::ceil(x_low - 0.5)) - 1);
    const int xb = std::min(x1, static_cast<int>(std::floor(x_high - 0.5)) + 1);
    if (xa > xb) continue;
    const double px0 = xa + 0.5;
    double w0 = e0.x() * px0 + e0.y() * py + e0.z();
    double w1 = e1.x() * px0 + e1.y() * py + e1.z();
    double w2 = e2.x() * px0 + e2.y() * py + e2.z();
    float* key_row = raster->key.data() + size_t(y) * raster->width;
    int32_t* id_row = raster->id.empty()
                          ? nullptr
                          : raster->id.data() + size_t(y) * raster->width;
    for (int x = xa; x <= xb; ++x) {
      if (w0 >= 0 && w1 >= 0 && w2 >= 0) {
        const float key =
            static_cast<float>((w0 * k0 + w1 * k1 + w2 * k2) * inv_area);
        if (key < key_row[x]) {
          key_row[x] = key;
          if (id_row) id_row[x] = triangle.id;
        }
      }
      w0 += e0.x();
      w1 += e1.x();
      w2 += e2.x();
    }
  }
}

}  // namespace

void RasterizeTriangles(const std::vector<RasterTriangle>& triangles,
                        int num_threads,
                        DepthRaster* raster) {
  if (raster->width <= 0 || raster->height <= 0) return;
  const int num_bands = (raster->height + kBandHeight - 1) / kBandHeight;
  // Bin the triangles by the bands their rows touch (counting sort), so
  // that each band visits only its own triangles, in input order.
  std::vector<int> band_range(2 * triangles.size(), -1);
  std::vector<int> counts(num_bands + 1, 0);
  for (size_t t = 0; t < triangles.size(); ++t) {
    const RasterTriangle& triangle = triangles[t];
    const double min_y = std::min({triangle.position[0].y(),
                                   triangle.position[1].y(),
                                   triangle.position[2].y()});
    const double max_y = std::max({triangle.position[0].y(),
                                   triangle.position[1].y(),
                                   triangle.position[2].y()});
    if (!(max_y >= 0.5) || !(min_y <= raster->height - 0.5)) continue;
    const int first =
        std::max(0, static_cast<int>(std::ceil(min_y - 0.5)) / kBandHeight);
    const int last = std::min(
        num_bands - 1,
        std::max(0, static_cast<int>(std::floor(max_y - 0.5))) / kBandHeight);
    if (first > last) continue;
    band_range[2 * t] = first;
    band_range[2 * t + 1] = last;
    for (int b = first; b <= last; ++b) ++counts[b + 1];
  }
  for (int b = 0; b < num_bands; ++b) counts[b + 1] += counts[b];
  std::vector<int> members(counts[num_bands]);
  std::vector<int> fill(counts.begin(), counts.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t) {
    if (band_range[2 * t] < 0) continue;
    for (int b = band_range[2 * t]; b <= band_range[2 * t + 1]; ++b) {
      members[fill[b]++] = static_cast<int>(t);
    }
  }
  ParallelFor(num_bands, num_threads, [&](int band) {
    const int y_begin = band * kBandHeight;
    const int y_end = std::min(raster->height, y_begin + kBandHeight);
    for (int m = counts[band]; m < counts[band + 1]; ++m) {
      DrawTriangle(triangles[members[m]], y_begin, y_end, raster);
    }
  });
}

}  // namespace bayon
