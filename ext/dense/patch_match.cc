// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/patch_match.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace bayon {

void PatchMatchOptions::Check() const {
  CheckOption(window_radius >= 1, "window_radius", ">= 1", window_radius);
  CheckOption(window_step >= 1 && window_step <= window_radius,
              "window_step",
              "in [1, window_radius]",
              window_step);
  CheckOption(num_iterations >= 1, "num_iterations", ">= 1", num_iterations);
  CheckOption(num_levels >= 1, "patch_match_levels", ">= 1", num_levels);
  CheckOption(best_views >= 1, "best_views", ">= 1", best_views);
  CheckOption(
      num_propagation_candidates >= 1 && num_propagation_candidates <= 8,
      "patch_match_candidates",
      "in [1, 8]",
      num_propagation_candidates);
  CheckOption(min_texture >= 0, "min_texture", ">= 0", min_texture);
  CheckOption(max_normal_angle_deg > 0 && max_normal_angle_deg < 90,
              "max_normal_angle_deg",
              "in (0, 90)",
              max_normal_angle_deg);
}

void PatchMatchOptions::Register(OptionRegistry* r) {
  r->Add("window_radius",
         &window_radius,
         "Correlation window radius, depth-map px");
  r->Add("window_step", &window_step, "Every n-th pixel of the window");
  r->Add("num_iterations",
         &num_iterations,
         "Red-black propagation iterations per level");
  r->Add("num_levels",
         &num_levels,
         "Coarse-to-fine levels of halved size (1: the working size alone), "
         "each level's planes starting the next");
  r->Add("num_propagation_candidates",
         &num_propagation_candidates,
         "Neighbours' planes scored per pixel (the best-matched of 8)");
  r->Add("best_views", &best_views, "A plane's cost over its best n views");
  r->Add("min_texture",
         &min_texture,
         "Master windows with less contrast are not matched (grey values)");
  r->Add("max_normal_angle_deg",
         &max_normal_angle_deg,
         "Random normals within this angle of the master ray");
}

PinholeView MakePinholeView(const Camera& camera,
                            const ImageFrame* frame,
                            const Rigid3d& cam_from_world,
                            const cv::Mat& gray,
                            const cv::Mat& color,
                            int downscale) {
  const double s = 1.0 / downscale;
  PinholeView view;
  view.cam_from_world = cam_from_world;
  const double f = camera.MeanFocalLengthPx() * s;
  const Eigen::Vector2d c = camera.PrincipalPointPx() * s;
  view.K << f, 0, c.x(), 0, f, c.y(), 0, 0, 1;
  const int width = static_cast<int>(camera.width) / downscale;
  const int height = static_cast<int>(camera.height) / downscale;
  // Where each pinhole pixel's ray meets the photograph, in the pixels of
  // the photograph shrunk by `downscale` (area averaging: no aliasing).
  cv::Mat map_x(height, width, CV_32F), map_y(height, width, CV_32F);
  const Eigen::Matrix3d K_inv = view.K.inverse();
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(x + 0.5, y + 0.5, 1);
      Eigen::Vector2d pixel;
      if (!camera.ImgFromCam(ray, &pixel, frame)) pixel.setConstant(-1e6);
      map_x.at<float>(y, x) = static_cast<float>(pixel.x() * s - 0.5);
      map_y.at<float>(y, x) = static_cast<float>(pixel.y() * s - 0.5);
    }
  }
  const auto resample = [&](const cv::Mat& image, cv::Mat* out) {
    cv::Mat small = image;
    if (downscale > 1) {
      cv::resize(image,
                 small,
                 cv::Size(image.cols / downscale, image.rows / downscale),
                 0,
                 0,
                 cv::INTER_AREA);
    }
    cv::remap(small,
              *out,
              map_x,
              map_y,
              cv::INTER_LINEAR,
              cv::BORDER_CONSTANT,
              cv::Scalar::all(0));
  };
  resample(gray, &view.gray);
  if (!color.empty()) resample(color, &view.color);
  return view;
}

namespace {

constexpr float kInvalidCost = 2.0f;
constexpr int kMaxSources = 32;

// Random numbers from the pixel, the iteration and the draw (splitmix64):
// the same whatever thread visits the pixel.
class PixelRandom {
 public:
  PixelRandom(int x, int y, int iteration) {
    state_ = (static_cast<uint64_t>(static_cast<uint32_t>(x)) << 32) ^
             static_cast<uint64_t>(static_cast<uint32_t>(y)) ^
             (static_cast<uint64_t>(iteration) << 56) ^ 0x9E3779B97F4A7C15ull;
  }
  float Uniform() {  // [0, 1)
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<float>(z >> 40) * (1.0f / 16777216.0f);
  }

 private:
  uint64_t state_;
};

struct Source {
  Eigen::Matrix3f R;  // source_from_master
  Eigen::Vector3f t;
  Eigen::Matrix3f K;
  const float* data = nullptr;
  int width = 0, height = 0;
  size_t stride = 0;  // floats per row
};

// The master's window at one pixel, normalised: zero mean, unit norm.
struct Window {
  std::vector<float> du, dv;  // offsets, working pixels
  std::vector<float> values;
  bool Load(const cv::Mat& gray, int x, int y, float min_texture) {
    const int n = static_cast<int>(du.size());
    float sum = 0;
    for (int k = 0; k < n; ++k) {
      values[k] = gray.at<float>(y + static_cast<int>(dv[k]),
                                 x + static_cast<int>(du[k]));
      sum += values[k];
    }
    const float mean = sum / n;
    float sum_squares = 0;
    for (int k = 0; k < n; ++k) {
      values[k] -= mean;
      sum_squares += values[k] * values[k];
    }
    if (sum_squares <= min_texture * min_texture * n) return false;
    const float scale = 1.0f / std::sqrt(sum_squares);
    for (float& v : values) v *= scale;
    return true;
  }
};

// 1 - NCC of the master window with its image in `source` under the
// homography H (master continuous pixels to source homogeneous pixels).
// Over a window of a few pixels the homography is affine to far below a
// hundredth of a pixel, so it is linearised at the window's centre: no
// division per sample, and the window is inside the source when its
// corners are.
float ViewCost(const Source& source,
               const Eigen::Matrix3f& H,
               float cx,
               float cy,
               float half_width,
               const Window& window) {
  const Eigen::Vector3f h = H * Eigen::Vector3f(cx, cy, 1);
  if (h.z() <= 0) return kInvalidCost;
  const float inv = 1.0f / h.z();
  const float px = h.x() * inv, py = h.y() * inv;
  // d(px, py) / d(u, v) at the centre.
  const float a = (H(0, 0) - px * H(2, 0)) * inv;
  const float b = (H(0, 1) - px * H(2, 1)) * inv;
  const float c = (H(1, 0) - py * H(2, 0)) * inv;
  const float d = (H(1, 1) - py * H(2, 1)) * inv;
  const float reach_x = half_width * (std::abs(a) + std::abs(b));
  const float reach_y = half_width * (std::abs(c) + std::abs(d));
  // Sample positions in array indices (pixel centres at +0.5).
  const float x0 = px - 0.5f, y0 = py - 0.5f;
  if (!(x0 - reach_x >= 0 && y0 - reach_y >= 0 &&
        x0 + reach_x < source.width - 1.001f &&
        y0 + reach_y < source.height - 1.001f)) {
    return kInvalidCost;
  }
  const int n = static_cast<int>(window.du.size());
  float sum = 0, sum_squares = 0, cross = 0;
  for (int k = 0; k < n; ++k) {
    const float sx = x0 + a * window.du[k] + b * window.dv[k];
    const float sy = y0 + c * window.du[k] + d * window.dv[k];
    const int ix = static_cast<int>(sx), iy = static_cast<int>(sy);
    const float fx = sx - ix, fy = sy - iy;
    const float* row = source.data + iy * source.stride + ix;
    const float top = row[0] + fx * (row[1] - row[0]);
    const float bottom =
        row[source.stride] + fx * (row[source.stride + 1] - row[source.stride]);
    const float v = top + fy * (bottom - top);
    sum += v;
    sum_squares += v * v;
    cross += window.values[k] * v;
  }
  const float variance = sum_squares - sum * sum / n;
  if (variance <= 1e-4f * n) return kInvalidCost;
  return 1.0f - cross / std::sqrt(variance);
}

class Matcher {
 public:
  Matcher(const PinholeView& master,
          const std::vector<const PinholeView*>& sources,
          double min_depth,
          double max_depth,
          const PatchMatchOptions& options)
      : master_(master),
        options_(options),
        min_depth_(static_cast<float>(min_depth)),
        max_depth_(static_cast<float>(max_depth)) {
    K_inv_ = master.K.inverse().cast<float>();
    const Rigid3d world_from_master = master.cam_from_world.Inverse();
    for (const PinholeView* view : sources) {
      const Rigid3d source_from_master =
          view->cam_from_world * world_from_master;
      Source source;
      source.R = source_from_master.rotation.toRotationMatrix().cast<float>();
      source.t = source_from_master.translation.cast<float>();
      source.K = view->K.cast<float>();
      source.data = view->gray.ptr<float>();
      source.width = view->width();
      source.height = view->height();
      source.stride = view->gray.step1();
      sources_.push_back(source);
    }
    const int r = options.window_radius, step = options.window_step;
    for (int dy = -(r / step) * step; dy <= r; dy += step) {
      for (int dx = -(r / step) * step; dx <= r; dx += step) {
        window_template_.du.push_back(static_cast<float>(dx));
        window_template_.dv.push_back(static_cast<float>(dy));
      }
    }
    window_template_.values.resize(window_template_.du.size());
    border_ = (r / step) * step;
    half_width_ = static_cast<float>(border_);
    max_tan_ =
        static_cast<float>(std::tan(options.max_normal_angle_deg * M_PI / 180));
  }

  Window NewWindow() const { return window_template_; }
  int border() const { return border_; }

  Eigen::Vector3f Ray(int x, int y) const { return RayAt(x + 0.5f, y + 0.5f); }
  // The ray through the continuous pixel position (u, v).
  Eigen::Vector3f RayAt(float u, float v) const {
    return K_inv_ * Eigen::Vector3f(u, v, 1.0f);
  }

  // The mean cost over the best views of the plane through the point at
  // `depth` on pixel (x, y)'s ray with `normal`.
  float Cost(int x,
             int y,
             float depth,
             const Eigen::Vector3f& normal,
             const Window& window,
             float* view_costs = nullptr) const {
    const Eigen::Vector3f ray = Ray(x, y);
    const float facing = normal.dot(ray);
    std::array<float, kMaxSources> costs;
    const int n = static_cast<int>(sources_.size());
    if (facing >= -1e-3f * ray.norm()) {
      costs.fill(kInvalidCost);
    } else {
      // The plane n.X + d = 0 through X = depth * ray; a source sees it
      // through H = K_s (R - t n^T / d) K_m^-1.
      const float d = -depth * facing;
      for (int j = 0; j < n; ++j) {
        const Source& source = sources_[j];
        const Eigen::Matrix3f H =
            source.K * (source.R - source.t * normal.transpose() / d) * K_inv_;
        costs[j] = ViewCost(source, H, x + 0.5f, y + 0.5f, half_width_, window);
      }
    }
    if (view_costs != nullptr) std::copy_n(costs.begin(), n, view_costs);
    const int k = std::min(options_.best_views, n);
    std::partial_sort(costs.begin(), costs.begin() + k, costs.begin() + n);
    float sum = 0;
    for (int i = 0; i < k; ++i) sum += costs[i];
    return sum / k;
  }

  float RandomDepth(PixelRandom* random) const {
    // Uniform in inverse depth: even steps along the epipolar lines.
    const float inv =
        1.0f / max_depth_ +
        random->Uniform() * (1.0f / min_depth_ - 1.0f / max_depth_);
    return 1.0f / inv;
  }

  // A random normal facing the master, within max_normal_angle_deg of the
  // ray (scaled by `spread`) around `around` (unit, facing the master).
  Eigen::Vector3f PerturbedNormal(const Eigen::Vector3f& around,
                                  float spread,
                                  PixelRandom* random,
                                  const Eigen::Vector3f& ray) const {
    Eigen::Vector3f e1 = around.unitOrthogonal();
    Eigen::Vector3f e2 = around.cross(e1);
    float a, b;
    do {
      a = 2 * random->Uniform() - 1;
      b = 2 * random->Uniform() - 1;
    } while (a * a + b * b > 1);
    Eigen::Vector3f normal =
        (around + spread * max_tan_ * (a * e1 + b * e2)).normalized();
    if (normal.dot(ray) >= 0) normal = around;
    return normal;
  }

  float min_depth() const { return min_depth_; }
  float max_depth() const { return max_depth_; }

 private:
  const PinholeView& master_;
  const PatchMatchOptions& options_;
  float min_depth_, max_depth_;
  Eigen::Matrix3f K_inv_;
  std::vector<Source> sources_;
  Window window_template_;
  int border_ = 0;
  float half_width_ = 0;
  float max_tan_ = 1;
};

// The neighbours a pixel takes planes from: all of the other colour.
constexpr std::array<std::array<int, 2>, 8> kNeighbours = {
    {{-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-5, 0}, {5, 0}, {0, -5}, {0, 5}}};

// The plane of `coarse` (the depth map of the same camera at half the
// size) at the coarse pixel that holds pixel (x, y), as a depth on (x, y)'s
// `ray`; false where the coarse map has none there.
bool PlaneFromCoarse(const DepthMap& coarse,
                     const Matcher& matcher,
                     int x,
                     int y,
                     const Eigen::Vector3f& ray,
                     float* depth,
                     Eigen::Vector3f* normal) {
  const int cx = std::min(x / 2, coarse.width - 1);
  const int cy = std::min(y / 2, coarse.height - 1);
  const size_t c = coarse.index(cx, cy);
  if (!(coarse.depth[c] > 0) || coarse.cost[c] >= kInvalidCost) return false;
  // The coarse pixel's ray in this level's pixels: its centre
  // ((cx + 0.5) * 2, (cy + 0.5) * 2), a ray the same in the camera frame.
  const Eigen::Vector3f coarse_ray =
      matcher.RayAt(2.0f * cx + 1.0f, 2.0f * cy + 1.0f);
  const Eigen::Vector3f& n = coarse.normal[c];
  const float along = n.dot(ray);
  if (along >= 0) return false;
  *depth = coarse.depth[c] * n.dot(coarse_ray) / along;
  *normal = n;
  return *depth >= matcher.min_depth() && *depth <= matcher.max_depth();
}

// A view at half the size: grey values averaged over 2 x 2 pixels (an odd
// last row or column dropped), the pixel coordinates halved (pixel (i, j)
// covers [i, i+1) x [j, j+1)).
PinholeView HalfView(const PinholeView& view) {
  PinholeView half;
  const cv::Rect even(0, 0, view.width() / 2 * 2, view.height() / 2 * 2);
  cv::resize(view.gray(even),
             half.gray,
             cv::Size(view.width() / 2, view.height() / 2),
             0,
             0,
             cv::INTER_AREA);
  half.K = view.K;
  half.K.topRows<2>() *= 0.5;
  half.cam_from_world = view.cam_from_world;
  return half;
}

DepthMap EstimateLevel(const PinholeView& master,
                       const std::vector<const PinholeView*>& sources,
                       double min_depth,
                       double max_depth,
                       const std::vector<DepthSeed>& seeds,
                       const DepthMap* coarse,
                       const PatchMatchOptions& options,
                       int num_threads) {
  const Matcher matcher(master, sources, min_depth, max_depth, options);
  DepthMap map;
  map.width = master.width();
  map.height = master.height();
  const size_t num_pixels = static_cast<size_t>(map.width) * map.height;
  map.depth.assign(num_pixels, 0.0f);
  map.normal.assign(num_pixels, Eigen::Vector3f::Zero());
  map.cost.assign(num_pixels, kInvalidCost);
  const int border = matcher.border();
  const int x_end = map.width - border, y_end = map.height - border;
  if (x_end <= border || y_end <= border) return map;
  const float min_texture = static_cast<float>(options.min_texture);

  // Start: a random plane everywhere there is texture, or the coarse
  // level's plane where that matches better; a sparse point's depth,
  // facing the master, where one lies.
  std::vector<uint8_t> textured(num_pixels, 0);
  ParallelFor(y_end - border, num_threads, [&](int row) {
    const int y = border + row;
    Window window = matcher.NewWindow();
    for (int x = border; x < x_end; ++x) {
      if (!window.Load(master.gray, x, y, min_texture)) continue;
      const size_t i = map.index(x, y);
      textured[i] = 1;
      PixelRandom random(x, y, 0);
      const Eigen::Vector3f ray = matcher.Ray(x, y);
      const Eigen::Vector3f facing = -ray.normalized();
      map.depth[i] = matcher.RandomDepth(&random);
      map.normal[i] = matcher.PerturbedNormal(facing, 1.0f, &random, ray);
      map.cost[i] = matcher.Cost(x, y, map.depth[i], map.normal[i], window);
      float depth;
      Eigen::Vector3f normal;
      if (coarse != nullptr &&
          PlaneFromCoarse(*coarse, matcher, x, y, ray, &depth, &normal)) {
        const float cost = matcher.Cost(x, y, depth, normal, window);
        if (cost < map.cost[i]) {
          map.depth[i] = depth;
          map.normal[i] = normal;
          map.cost[i] = cost;
        }
      }
    }
  });
  {
    Window window = matcher.NewWindow();
    for (const DepthSeed& seed : seeds) {
      const int x = static_cast<int>(seed.xy.x()),
                y = static_cast<int>(seed.xy.y());
      if (x < border || y < border || x >= x_end || y >= y_end) continue;
      const float depth = static_cast<float>(seed.depth);
      if (depth < matcher.min_depth() || depth > matcher.max_depth()) continue;
      const size_t i = map.index(x, y);
      if (!textured[i] || !window.Load(master.gray, x, y, min_texture)) {
        continue;
      }
      const Eigen::Vector3f normal = -matcher.Ray(x, y).normalized();
      const float cost = matcher.Cost(x, y, depth, normal, window);
      if (cost < map.cost[i]) {
        map.depth[i] = depth;
        map.normal[i] = normal;
        map.cost[i] = cost;
      }
    }
  }

  // Red-black sweeps: propagation from the neighbours, then refinement by
  // perturbations that shrink with every iteration.
  for (int iteration = 0; iteration < options.num_iterations; ++iteration) {
    const float spread = std::pow(0.5f, static_cast<float>(iteration));
    for (int colour = 0; colour < 2; ++colour) {
      ParallelFor(y_end - border, num_threads, [&](int row) {
        const int y = border + row;
        Window window = matcher.NewWindow();
        for (int x = border + ((y + colour) & 1); x < x_end; x += 2) {
          const size_t i = map.index(x, y);
          if (!textured[i]) continue;
          window.Load(master.gray, x, y, min_texture);
          const Eigen::Vector3f ray = matcher.Ray(x, y);
          float depth = map.depth[i], cost = map.cost[i];
          Eigen::Vector3f normal = map.normal[i];
          const auto consider = [&](float d, const Eigen::Vector3f& n) {
            if (!(d >= matcher.min_depth() && d <= matcher.max_depth())) return;
            const float c = matcher.Cost(x, y, d, n, window);
            if (c < cost) {
              depth = d;
              normal = n;
              cost = c;
            }
          };
          // The neighbours' planes where this pixel's ray meets them, the
          // best-matched neighbours first (their own costs rank them); the
          // plane this pixel has already is not scored again.
          std::array<std::pair<float, int>, kNeighbours.size()> ranked;
          int num_ranked = 0;
          for (int k = 0; k < static_cast<int>(kNeighbours.size()); ++k) {
            const int qx = x + kNeighbours[k][0], qy = y + kNeighbours[k][1];
            if (qx < border || qy < border || qx >= x_end || qy >= y_end) {
              continue;
            }
            const size_t q = map.index(qx, qy);
            if (!textured[q] || map.cost[q] >= kInvalidCost) continue;
            ranked[num_ranked++] = {map.cost[q], k};
          }
          const int num_tried =
              std::min(num_ranked, options.num_propagation_candidates);
          std::partial_sort(ranked.begin(),
                            ranked.begin() + num_tried,
                            ranked.begin() + num_ranked);
          for (int c = 0; c < num_tried; ++c) {
            const int k = ranked[c].second;
            const int qx = x + kNeighbours[k][0], qy = y + kNeighbours[k][1];
            const size_t q = map.index(qx, qy);
            const Eigen::Vector3f& n = map.normal[q];
            const float along = n.dot(ray);
            if (along >= 0) continue;
            const float d = map.depth[q] * n.dot(matcher.Ray(qx, qy)) / along;
            if (n == normal && std::abs(d - depth) <= 1e-6f * depth) continue;
            consider(d, n);
          }
          PixelRandom random(x, y, 2 * iteration + colour + 1);
          const float range = matcher.max_depth() - matcher.min_depth();
          consider(depth + (2 * random.Uniform() - 1) * 0.1f * spread * range,
                   normal);
          consider(
              depth,
              matcher.PerturbedNormal(normal, 0.5f * spread, &random, ray));
          consider(
              depth * (1 + (2 * random.Uniform() - 1) * 0.02f * spread),
              matcher.PerturbedNormal(normal, 0.25f * spread, &random, ray));
          map.depth[i] = depth;
          map.normal[i] = normal;
          map.cost[i] = cost;
        }
      });
    }
  }
  return map;
}

}  // namespace

DepthMap EstimateDepthMap(const PinholeView& master,
                          const std::vector<const PinholeView*>& sources,
                          double min_depth,
                          double max_depth,
                          const std::vector<DepthSeed>& seeds,
                          const PatchMatchOptions& options,
                          int num_threads) {
  options.Check();
  for (const PinholeView* view : sources) {
    if (view->gray.type() != CV_32F || master.gray.type() != CV_32F) {
      ThrowInputError("depth maps need grey values as 32-bit floats");
    }
  }
  if (sources.empty() || sources.size() > kMaxSources) {
    ThrowInputError("a depth map needs 1 to ",
                    kMaxSources,
                    " source views; given ",
                    sources.size());
  }
  if (!(min_depth > 0 && max_depth > min_depth)) {
    ThrowInputError(
        "depth range [", min_depth, ", ", max_depth, "] is not positive");
  }
  // Coarse to fine: the planes found at half the size start this level.
  // Propagation carries a plane a few pixels per sweep, so a surface that
  // random planes hit only here and there is covered in few sweeps at the
  // coarse level, where the same window also spans twice the surface (more
  // texture where it is weak); the fine level then mostly refines.
  const int min_size = 8 * (2 * options.window_radius + 1);
  if (options.num_levels <= 1 ||
      std::min(master.width(), master.height()) / 2 < min_size) {
    return EstimateLevel(master,
                         sources,
                         min_depth,
                         max_depth,
                         seeds,
                         nullptr,
                         options,
                         num_threads);
  }
  const PinholeView half_master = HalfView(master);
  std::vector<PinholeView> half_sources;
  half_sources.reserve(sources.size());
  for (const PinholeView* view : sources) {
    half_sources.push_back(HalfView(*view));
  }
  std::vector<const PinholeView*> half_source_ptrs;
  for (const PinholeView& view : half_sources) {
    half_source_ptrs.push_back(&view);
  }
  std::vector<DepthSeed> half_seeds = seeds;
  for (DepthSeed& seed : half_seeds) seed.xy *= 0.5;
  PatchMatchOptions coarse_options = options;
  --coarse_options.num_levels;
  const DepthMap coarse = EstimateDepthMap(half_master,
                                           half_source_ptrs,
                                           min_depth,
                                           max_depth,
                                           half_seeds,
                                           coarse_options,
                                           num_threads);
  return EstimateLevel(master,
                       sources,
                       min_depth,
                       max_depth,
                       seeds,
                       &coarse,
                       options,
                       num_threads);
}

std::vector<float> PlaneCosts(const PinholeView& master,
                              const std::vector<const PinholeView*>& sources,
                              int x,
                              int y,
                              float depth,
                              const Eigen::Vector3f& normal,
                              const PatchMatchOptions& options) {
  options.Check();
  const Matcher matcher(master, sources, depth * 0.5, depth * 2, options);
  std::vector<float> costs(sources.size(), kInvalidCost);
  const int border = matcher.border();
  if (sources.size() > kMaxSources || x < border || y < border ||
      x >= master.width() - border || y >= master.height() - border) {
    return costs;
  }
  Window window = matcher.NewWindow();
  if (!window.Load(
          master.gray, x, y, static_cast<float>(options.min_texture))) {
    costs.assign(sources.size(), std::nanf(""));
    return costs;
  }
  matcher.Cost(x, y, depth, normal, window, costs.data());
  return costs;
}

}  // namespace bayon
