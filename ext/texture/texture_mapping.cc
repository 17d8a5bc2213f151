// SPDX-License-Identifier: BSD-3-Clause
#include "ext/texture/texture_mapping.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/union_find.h"
#include "ext/image/image_io.h"
#include "ext/image/interpolation.h"
#include "ext/image/radiometry.h"
#include "ext/render/mesh_renderer.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <sstream>

namespace bayon {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// One photograph that sees a face: its index and the face's projected area.
struct FaceView {
  int image = -1;
  float area_px = 0;
};

// Projected corners of a face in one image (pixels); false when a corner is
// behind the camera.
bool ProjectFace(const TriangleMesh& mesh,
                 int face,
                 const TextureImage& image,
                 Eigen::Vector2d corners[3]) {
  const ImageFrame* frame = image.image->frame ? &*image.image->frame : nullptr;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& x = mesh.vertices.positions[mesh.faces[face][k]];
    if (!image.camera->ImgFromCam(
            image.image->cam_from_world * x, &corners[k], frame)) {
      return false;
    }
  }
  return true;
}

double TriangleArea(const Eigen::Vector2d& a,
                    const Eigen::Vector2d& b,
                    const Eigen::Vector2d& c) {
  return 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

double TriangleArea3(const TriangleMesh& mesh, int face) {
  const auto& p = mesh.vertices.positions;
  const Eigen::Vector3i& f = mesh.faces[face];
  return 0.5 * (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]).norm();
}

// Areas of every face in one photograph, 0 where the face is not seen (see
// the header: centroid and three inner points in front of the depth map,
// not edge-on).
// `covered`: the pixels the mesh covers (CV_8U, 255).
std::vector<float> VisibleAreas(const TriangleMesh& mesh,
                                const MeshRenderer& renderer,
                                const TextureImage& image,
                                const TextureOptions& options,
                                cv::Mat* covered) {
  RenderView view;
  view.camera = *image.camera;
  view.cam_from_world = image.image->cam_from_world;
  view.frame = image.image->frame;
  RenderOptions render_options;
  render_options.supersampling = 1;
  render_options.geometry_buffers = true;
  render_options.num_threads = options.num_threads;
  const cv::Mat depth = renderer.Render(view, Lighting(), render_options).depth;
  *covered = depth > 0;

  const Rigid3d& cam_from_world = image.image->cam_from_world;
  const Eigen::Vector3d center = cam_from_world.Center();
  const ImageFrame* frame = image.image->frame ? &*image.image->frame : nullptr;
  const double min_sin = std::sin(options.min_view_angle_deg * kDegToRad);
  const int num_faces = static_cast<int>(mesh.NumFaces());
  std::vector<float> areas(num_faces, 0.0f);
  ParallelFor(num_faces, options.num_threads, [&](int face) {
    const auto& p = mesh.vertices.positions;
    const Eigen::Vector3i& f = mesh.faces[face];
    const Eigen::Vector3d centroid = (p[f[0]] + p[f[1]] + p[f[2]]) / 3.0;
    const Eigen::Vector3d normal =
        (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]).normalized();
    const Eigen::Vector3d ray = (centroid - center).normalized();
    if (!(std::abs(normal.dot(ray)) >= min_sin)) return;
    Eigen::Vector2d corners[3];
    if (!ProjectFace(mesh, face, image, corners)) return;
    // The centroid and points a fifth of the way from each corner to it:
    // inside the face, so that a neighbour in front of a shared edge does
    // not hide it.
    Eigen::Vector3d samples[4] = {centroid,
                                  0.8 * p[f[0]] + 0.2 * centroid,
                                  0.8 * p[f[1]] + 0.2 * centroid,
                                  0.8 * p[f[2]] + 0.2 * centroid};
    for (const Eigen::Vector3d& sample : samples) {
      const Eigen::Vector3d in_cam = cam_from_world * sample;
      Eigen::Vector2d pixel;
      if (!image.camera->ImgFromCam(in_cam, &pixel, frame)) return;
      const int x = static_cast<int>(std::floor(pixel.x()));
      const int y = static_cast<int>(std::floor(pixel.y()));
      if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) return;
      const float seen = depth.at<float>(y, x);
      // 0: the pixel's central ray slips past the mesh (a silhouette).
      if (seen > 0 && seen < in_cam.z() * (1.0 - options.depth_tolerance)) {
        return;
      }
    }
    areas[face] =
        static_cast<float>(TriangleArea(corners[0], corners[1], corners[2]));
  });
  return areas;
}

// A photograph after the radiometric pre-processing; `covered` (the pixels
// the mesh covers) is the population whose histogram is equalised.
cv::Mat Preprocess(const cv::Mat& bgr,
                   const cv::Mat& covered,
                   const TextureOptions& options) {
  switch (options.preprocess) {
    case TexturePreprocess::kNone:
    case TexturePreprocess::kBalance:  // over all photographs, later
      return bgr;
    case TexturePreprocess::kHighPassEqualize:
      return HighPassEqualize(
          bgr,
          options.filter_radius_px,
          cv::countNonZero(covered) > 0 ? covered : cv::Mat());
    case TexturePreprocess::kWallis: {
      WallisOptions wallis;
      wallis.radius_px = options.filter_radius_px;
      return WallisFilter(bgr, wallis);
    }
  }
  return bgr;
}

// The mesh's edges as (smaller vertex, larger vertex, face), sorted, so
// that the faces sharing an edge are neighbours in the list.
struct EdgeFace {
  int a, b, face;
  bool operator<(const EdgeFace& o) const {
    return a != o.a ? a < o.a : (b != o.b ? b < o.b : face < o.face);
  }
  bool SameEdge(const EdgeFace& o) const { return a == o.a && b == o.b; }
};

std::vector<EdgeFace> SortedEdges(const TriangleMesh& mesh) {
  std::vector<EdgeFace> edges;
  edges.reserve(3 * mesh.NumFaces());
  for (int face = 0; face < static_cast<int>(mesh.NumFaces()); ++face) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[face][k];
      const int b = mesh.faces[face][(k + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b), face});
    }
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

std::vector<TwoFaceEdge> TwoFaceEdges(const std::vector<EdgeFace>& sorted) {
  std::vector<TwoFaceEdge> pairs;
  for (size_t i = 0; i + 1 < sorted.size(); ++i) {
    if (sorted[i].SameEdge(sorted[i + 1]) &&
        !(i > 0 && sorted[i - 1].SameEdge(sorted[i])) &&
        !(i + 2 < sorted.size() && sorted[i + 2].SameEdge(sorted[i]))) {
      pairs.push_back(
          {sorted[i].a, sorted[i].b, sorted[i].face, sorted[i + 1].face});
    }
  }
  return pairs;
}

struct Chart {
  int image = -1;  // the optimal image; -1: the faces no photograph sees
  std::vector<int> faces;
  double pixels_per_metre = 0;
  // Bounding box of the scaled projection (texels), and where that box's
  // minimum lands in the atlas (texels, y down).
  Eigen::Vector2d min = Eigen::Vector2d::Zero();
  Eigen::Vector2d max = Eigen::Vector2d::Zero();
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  int width = 0;  // with padding on both sides
  int height = 0;
};

// Shelf packing, tallest charts first; returns the atlas size.
cv::Size PackCharts(std::vector<Chart>* charts) {
  double area = 0;
  int widest = 0;
  for (const Chart& c : *charts) {
    area += double(c.width) * c.height;
    widest = std::max(widest, c.width);
  }
  const int atlas_width =
      std::max(widest, static_cast<int>(std::ceil(std::sqrt(area * 1.1))));
  std::vector<int> order(charts->size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return (*charts)[a].height > (*charts)[b].height;
  });
  int x = 0, y = 0, shelf_height = 0;
  for (int i : order) {
    Chart& c = (*charts)[i];
    if (x + c.width > atlas_width) {
      x = 0;
      y += shelf_height;
      shelf_height = 0;
    }
    c.offset = Eigen::Vector2d(x, y);
    x += c.width;
    shelf_height = std::max(shelf_height, c.height);
  }
  return cv::Size(atlas_width, y + shelf_height);
}

// Bilinear colour at a pixel position (COLMAP's convention); false outside.
bool SampleColor(const cv::Mat& image,
                 const Eigen::Vector2d& pixel,
                 Eigen::Vector3f* color) {
  return SampleBilinear(image, pixel.x(), pixel.y(), color);
}

// A photograph blended into a face: its colours, the face's corners in it,
// and its weight (projected area over the largest, equation 7).
struct BlendSource {
  const cv::Mat* bgr;
  Eigen::Vector2d p[3];
  float weight;
};

// The photographs whose colours a face takes: all that see it, or with
// `blend = kNone` only its chart's image.
std::vector<BlendSource> BlendSources(const TriangleMesh& mesh,
                                      int face,
                                      const std::vector<FaceView>& views,
                                      int chart_image,
                                      float best_area,
                                      const std::vector<TextureImage>& images,
                                      const std::vector<cv::Mat>& colors,
                                      const TextureOptions& options) {
  std::vector<BlendSource> sources;
  for (const FaceView& v : views) {
    if (options.blend == TextureBlend::kNone && v.image != chart_image) {
      continue;
    }
    BlendSource s;
    s.bgr = &colors[v.image];
    if (!ProjectFace(mesh, face, images[v.image], s.p)) continue;
    s.weight = v.area_px / best_area;
    sources.push_back(s);
  }
  return sources;
}

// The weighted mean colour at barycentric coordinates `b` (the affine map
// fixed by the three corners carries the point into each photograph,
// equations 6 and 7); false where no photograph has it.
bool BlendAt(const std::vector<BlendSource>& sources,
             const Eigen::Vector3d& b,
             Eigen::Vector3f* color) {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  float weight = 0;
  for (const BlendSource& s : sources) {
    Eigen::Vector3f c;
    if (SampleColor(
            *s.bgr, b[0] * s.p[0] + b[1] * s.p[1] + b[2] * s.p[2], &c)) {
      sum += s.weight * c;
      weight += s.weight;
    }
  }
  if (weight <= 0) return false;
  *color = sum / weight;
  return true;
}

// A face's mean colour in a photograph: seven points spread over it.
bool FaceMeanColor(const TriangleMesh& mesh,
                   int face,
                   const TextureImage& image,
                   Eigen::Vector3f* color) {
  Eigen::Vector2d p[3];
  if (!ProjectFace(mesh, face, image, p)) return false;
  static const double kPoints[7][3] = {{1 / 3.0, 1 / 3.0, 1 / 3.0},
                                       {0.6, 0.2, 0.2},
                                       {0.2, 0.6, 0.2},
                                       {0.2, 0.2, 0.6},
                                       {0.1, 0.45, 0.45},
                                       {0.45, 0.1, 0.45},
                                       {0.45, 0.45, 0.1}};
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const auto& b : kPoints) {
    Eigen::Vector3f c;
    if (!SampleColor(image.bgr, b[0] * p[0] + b[1] * p[1] + b[2] * p[2], &c)) {
      return false;
    }
    sum += c;
  }
  *color = sum / 7.0f;
  return true;
}

// A face smaller than this in a photograph (pixels) is too few samples for
// the exposure balance.
constexpr float kMinBalanceArea = 10.0f;

// The photographs with their exposures and white balances balanced over
// their overlaps (color_balance.h).
std::vector<cv::Mat> BalancedColors(
    const TriangleMesh& mesh,
    const std::vector<std::vector<FaceView>>& views,
    const std::vector<TextureImage>& images,
    const TextureOptions& options,
    TextureReport* report) {
  const int num_faces = static_cast<int>(mesh.NumFaces());
  std::vector<std::vector<FaceColor>> face_colors(num_faces);
  ParallelFor(num_faces, options.num_threads, [&](int face) {
    if (views[face].size() < 2) return;
    for (const FaceView& v : views[face]) {
      FaceColor c;
      c.image = v.image;
      if (v.area_px >= kMinBalanceArea &&
          FaceMeanColor(mesh, face, images[v.image], &c.color)) {
        face_colors[face].push_back(c);
      }
    }
  });
  const std::vector<GainOffset> corrections =
      BalanceExposures(face_colors,
                       static_cast<int>(images.size()),
                       ColorBalanceOptions(),
                       &report->balance);
  std::vector<cv::Mat> colors(images.size());
  ParallelFor(static_cast<int>(images.size()), options.num_threads, [&](int j) {
    colors[j] = ApplyGainOffset(images[j].bgr, corrections[j]);
  });
  for (size_t j = 0; j < images.size(); ++j) {
    report->corrections[images[j].name] = corrections[j];
  }
  return colors;
}

// Each face no photograph sees has a cell of this many texels square in the
// unseen block, one colour, its three texture coordinates at the centre.
constexpr int kUnseenCell = 3;

Eigen::Vector2d UnseenCellCenter(const Chart& unseen,
                                 int pad,
                                 int columns,
                                 size_t i) {
  return unseen.offset + Eigen::Vector2d::Constant(pad + 0.5 * kUnseenCell) +
         kUnseenCell *
             Eigen::Vector2d(double(i % columns), double(i / columns));
}

// Colours the cells of the faces no photograph sees (the unseen block, grey
// so far) from the faces around them: breadth first from the seen faces,
// each unseen face the mean of its already coloured edge neighbours. A
// region that touches no seen face keeps the grey.
void ColorUnseenFaces(const std::vector<std::array<int, 3>>& neighbors,
                      const std::vector<std::array<Eigen::Vector2d, 3>>& texel,
                      const Chart& unseen,
                      int pad,
                      int columns,
                      cv::Mat* atlas) {
  const int num_faces = static_cast<int>(neighbors.size());
  std::vector<int> cell(num_faces, -1);
  for (size_t i = 0; i < unseen.faces.size(); ++i) {
    cell[unseen.faces[i]] = static_cast<int>(i);
  }
  std::vector<Eigen::Vector3f> color(num_faces, Eigen::Vector3f::Zero());
  std::vector<bool> known(num_faces, false);
  for (int face = 0; face < num_faces; ++face) {
    if (cell[face] >= 0) continue;
    const Eigen::Vector2d centroid =
        (texel[face][0] + texel[face][1] + texel[face][2]) / 3.0;
    known[face] = SampleColor(*atlas, centroid, &color[face]);
  }
  std::vector<int> front = unseen.faces;
  while (!front.empty()) {
    std::vector<std::pair<int, Eigen::Vector3f>> found;
    std::vector<int> next;
    for (int face : front) {
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      int n = 0;
      for (int g : neighbors[face]) {
        if (g >= 0 && known[g]) {
          sum += color[g];
          ++n;
        }
      }
      if (n > 0) {
        found.emplace_back(face, sum / n);
      } else {
        next.push_back(face);
      }
    }
    if (found.empty()) break;
    for (const auto& [face, c] : found) {
      color[face] = c;
      known[face] = true;
      const Eigen::Vector2d center =
          UnseenCellCenter(unseen, pad, columns, cell[face]);
      const cv::Rect rect(static_cast<int>(center.x() - 0.5 * kUnseenCell),
                          static_cast<int>(center.y() - 0.5 * kUnseenCell),
                          kUnseenCell,
                          kUnseenCell);
      (*atlas)(rect).setTo(cv::Scalar(c[0], c[1], c[2]));
    }
    front.swap(next);
  }
}

// Fills texels that no triangle covered from their covered neighbours,
// ring by ring, `rings` times (padding against bleeding).
void DilateAtlas(int rings, cv::Mat* atlas, cv::Mat* covered) {
  for (int ring = 0; ring < rings; ++ring) {
    cv::Mat color_sum, count;
    cv::Mat atlas_f;
    atlas->convertTo(atlas_f, CV_32FC3);
    cv::Mat mask_f;
    covered->convertTo(mask_f, CV_32F, 1.0 / 255.0);
    cv::Mat masked;
    cv::Mat mask3;
    cv::merge(std::vector<cv::Mat>{mask_f, mask_f, mask_f}, mask3);
    masked = atlas_f.mul(mask3);
    cv::boxFilter(masked,
                  color_sum,
                  -1,
                  cv::Size(3, 3),
                  cv::Point(-1, -1),
                  false,
                  cv::BORDER_CONSTANT);
    cv::boxFilter(mask_f,
                  count,
                  -1,
                  cv::Size(3, 3),
                  cv::Point(-1, -1),
                  false,
                  cv::BORDER_CONSTANT);
    bool changed = false;
    for (int y = 0; y < atlas->rows; ++y) {
      uint8_t* m = covered->ptr<uint8_t>(y);
      const float* n = count.ptr<float>(y);
      const cv::Vec3f* s = color_sum.ptr<cv::Vec3f>(y);
      cv::Vec3b* a = atlas->ptr<cv::Vec3b>(y);
      for (int x = 0; x < atlas->cols; ++x) {
        if (m[x] || n[x] < 0.5f) continue;
        for (int c = 0; c < 3; ++c) {
          a[x][c] = cv::saturate_cast<uint8_t>(s[x][c] / n[x]);
        }
        m[x] = 128;  // filled now; counts for the next ring
        changed = true;
      }
    }
    if (!changed) break;
  }
}

}  // namespace

const char* TexturePreprocessName(TexturePreprocess preprocess) {
  switch (preprocess) {
    case TexturePreprocess::kNone:
      return "none";
    case TexturePreprocess::kBalance:
      return "balance";
    case TexturePreprocess::kHighPassEqualize:
      return "highpass_equalize";
    case TexturePreprocess::kWallis:
      return "wallis";
  }
  return "?";
}

const char* TextureBlendName(TextureBlend blend) {
  return blend == TextureBlend::kNone ? "none" : "view_dependent";
}

void TextureOptions::Check() const {
  if (!(filter_radius_px >= 1)) {
    ThrowInputError("filter_radius_px must be at least 1");
  }
  if (!(texel_size >= 0)) ThrowInputError("texel_size must not be negative");
  if (!(chart_merge_ratio > 0 && chart_merge_ratio <= 1)) {
    ThrowInputError("chart_merge_ratio must lie in (0, 1]");
  }
  if (max_atlas_size < 64 || max_atlas_size > 32768) {
    ThrowInputError("max_atlas_size must lie in [64, 32768]");
  }
  if (padding_px < 1) ThrowInputError("padding_px must be at least 1");
  if (!(min_view_angle_deg >= 0 && min_view_angle_deg < 90)) {
    ThrowInputError("min_view_angle_deg must lie in [0, 90)");
  }
  if (!(depth_tolerance > 0 && depth_tolerance < 1)) {
    ThrowInputError("depth_tolerance must lie in (0, 1)");
  }
}

void TextureOptions::Register(OptionRegistry* r) {
  r->AddChoice(
      "preprocess",
      &preprocess,
      ChoicesOf<TexturePreprocess>(TexturePreprocessName,
                                   {TexturePreprocess::kBalance,
                                    TexturePreprocess::kHighPassEqualize,
                                    TexturePreprocess::kWallis,
                                    TexturePreprocess::kNone}),
      "Radiometric pre-processing: balance (true colours), "
      "highpass_equalize (the paper's), wallis, none");
  r->Add("seam_leveling",
         &seam_leveling,
         "1: level the colours across chart borders");
  r->Add("exclude_images",
         &exclude_images,
         "Photographs not to texture from (names, comma separated)");
  r->Add("filter_radius_px",
         &filter_radius_px,
         "High-pass radius / Wallis window (Gaussian sigma), px");
  r->AddChoice("blend",
               &blend,
               ChoicesOf<TextureBlend>(
                   TextureBlendName,
                   {TextureBlend::kViewDependent, TextureBlend::kNone}),
               "view_dependent (weighted by projected area) or none (the "
               "chart's image alone: the optimal one, see chart_merge_ratio)");
  r->Add("chart_merge_ratio",
         &chart_merge_ratio,
         "A face joins its neighbours' image when that sees it with at least "
         "this share of its largest area (1: always the optimal image)");
  r->Add("texel_size",
         &texel_size,
         "Atlas texel size, metres (0: median GSD of the optimal images)");
  r->Add("max_atlas_size", &max_atlas_size, "Largest atlas side");
  r->Add("padding_px", &padding_px, "Texels between charts");
  r->Add("min_view_angle_deg",
         &min_view_angle_deg,
         "A face is unseen when the view ray is nearer its plane");
  r->Add("depth_tolerance",
         &depth_tolerance,
         "Occlusion test: share of the depth");
  r->Add("num_threads", &num_threads, "-1 = all cores");
}

std::vector<TextureImage> LoadTextureImages(const Scene& scene,
                                            const std::string& image_path,
                                            const TextureOptions& options) {
  options.Check();
  for (const std::string& name : options.exclude_images) {
    if (scene.FindImageByName(name) == nullptr) {
      ThrowInputError("exclude_images: the model has no image '", name, "'");
    }
  }
  std::vector<TextureImage> images;
  for (const auto& [image_id, image] : scene.images) {
    if (std::find(options.exclude_images.begin(),
                  options.exclude_images.end(),
                  image.name) != options.exclude_images.end()) {
      continue;
    }
    TextureImage t;
    t.name = image.name;
    if (!scene.cameras.contains(image.camera_id)) {
      ThrowInputError("image ",
                      image.name,
                      ": its camera ",
                      image.camera_id,
                      " is not in the model");
    }
    t.camera = &scene.cameras.at(image.camera_id);
    t.image = &image;
    images.push_back(t);
  }
  if (images.empty()) {
    ThrowInputError(options.exclude_images.empty()
                        ? "the model has no images"
                        : "exclude_images leaves no image");
  }
  Progress progress("loading", images.size(), "images");
  ParallelFor(static_cast<int>(images.size()), options.num_threads, [&](int i) {
    TextureImage& t = images[i];
    const std::string path = image_path + "/" + t.name;
    const cv::Mat bgr = ReadImageColor8(path);
    if (bgr.cols != static_cast<int>(t.camera->width) ||
        bgr.rows != static_cast<int>(t.camera->height)) {
      ThrowInputError(path,
                      ": is ",
                      bgr.cols,
                      " x ",
                      bgr.rows,
                      " pixels but its camera is ",
                      t.camera->width,
                      " x ",
                      t.camera->height);
    }
    t.bgr = bgr;
    progress.Add();
  });
  progress.Finish();
  return images;
}

namespace {

// 2. Visibility and projected areas of every face in every photograph; 1.
// the pre-processing, which equalises the histogram of the pixels the mesh
// covers (or balances the photographs' colours), into `colors`.
std::vector<std::vector<FaceView>> FindFaceViews(
    const TriangleMesh& mesh,
    const std::vector<TextureImage>& images,
    const TextureOptions& options,
    std::vector<cv::Mat>* colors,
    TextureReport* report) {
  const int num_faces = static_cast<int>(mesh.NumFaces());
  const int num_images = static_cast<int>(images.size());
  const Timer timer;
  std::vector<std::vector<FaceView>> views(num_faces);
  colors->assign(num_images, cv::Mat());
  {
    MeshRenderer renderer(mesh);
    Progress progress("visibility", images.size(), "images");
    for (int j = 0; j < num_images; ++j) {
      cv::Mat covered;
      const std::vector<float> areas =
          VisibleAreas(mesh, renderer, images[j], options, &covered);
      for (int face = 0; face < num_faces; ++face) {
        if (areas[face] > 0) views[face].push_back({j, areas[face]});
      }
      const Timer preprocess;
      (*colors)[j] = Preprocess(images[j].bgr, covered, options);
      report->seconds_preprocess += preprocess.Seconds();
      progress.Add();
    }
    progress.Finish();
  }
  report->seconds_visibility = timer.Seconds() - report->seconds_preprocess;
  if (options.preprocess == TexturePreprocess::kBalance) {
    const Timer balance;
    *colors = BalancedColors(mesh, views, images, options, report);
    report->seconds_preprocess += balance.Seconds();
  }
  return views;
}

// 3. The optimal image of each face, where it appears largest (-1: none
// sees it), and that area.
void ChooseOptimalImages(const std::vector<std::vector<FaceView>>& views,
                         std::vector<int>* best,
                         std::vector<float>* best_area,
                         TextureReport* report) {
  const int num_faces = static_cast<int>(views.size());
  best->assign(num_faces, -1);
  best_area->assign(num_faces, 0.0f);
  size_t num_views = 0;
  for (int face = 0; face < num_faces; ++face) {
    for (const FaceView& v : views[face]) {
      if (v.area_px > (*best_area)[face]) {
        (*best_area)[face] = v.area_px;
        (*best)[face] = v.image;
      }
    }
    num_views += views[face].size();
    if ((*best)[face] < 0) ++report->num_unseen_faces;
  }
  if (report->num_unseen_faces == num_faces) {
    ThrowInputError(
        "no photograph sees the mesh (check that the mesh and "
        "the model share one coordinate system)");
  }
  report->mean_views_per_face = double(num_views) / num_faces;
}

// The faces across each face's manifold edges (-1: none).
std::vector<std::array<int, 3>> FaceNeighbors(
    const std::vector<TwoFaceEdge>& two_face_edges, int num_faces) {
  std::vector<std::array<int, 3>> neighbors(num_faces, {-1, -1, -1});
  for (const TwoFaceEdge& e : two_face_edges) {
    for (const auto& [f, g] :
         {std::make_pair(e.f, e.g), std::make_pair(e.g, e.f)}) {
      for (int& slot : neighbors[f]) {
        if (slot < 0) {
          slot = g;
          break;
        }
      }
    }
  }
  return neighbors;
}

// The image each face's texture is drawn in (its chart): the optimal one,
// except where most of its edge neighbours use another image that sees the
// face nearly as large; that merges the speckle of single faces whose
// optimal image differs from their neighbours' by a few per cent of area
// into larger charts (fewer seams, a fuller atlas).
void MergeSpeckle(const std::vector<std::array<int, 3>>& neighbors,
                  const std::vector<std::vector<FaceView>>& views,
                  const std::vector<float>& best_area,
                  const TextureOptions& options,
                  std::vector<int>* source,
                  std::vector<float>* source_area) {
  if (options.chart_merge_ratio >= 1) return;
  const int num_faces = static_cast<int>(views.size());
  for (int iteration = 0; iteration < 5; ++iteration) {
    int changed = 0;
    for (int face = 0; face < num_faces; ++face) {
      if ((*source)[face] < 0) continue;
      const auto& n = neighbors[face];
      for (int k = 0; k < 3; ++k) {
        if (n[k] < 0 || (*source)[n[k]] < 0 ||
            (*source)[n[k]] == (*source)[face]) {
          continue;
        }
        const int label = (*source)[n[k]];
        int votes = 0;
        for (int m = 0; m < 3; ++m) {
          votes += n[m] >= 0 && (*source)[n[m]] == label;
        }
        if (votes < 2) continue;
        for (const FaceView& v : views[face]) {
          if (v.image == label &&
              v.area_px >= options.chart_merge_ratio * best_area[face]) {
            (*source)[face] = label;
            (*source_area)[face] = v.area_px;
            ++changed;
          }
        }
        break;
      }
    }
    if (changed == 0) break;
  }
}

// Texel size: the median ground sampling distance of the faces in their
// source images, weighted by the faces' areas.
double MedianTexelSize(const std::vector<double>& face_area,
                       const std::vector<int>& source,
                       const std::vector<float>& source_area) {
  std::vector<std::pair<double, double>> gsd;  // (gsd, weight)
  double total = 0;
  for (size_t face = 0; face < face_area.size(); ++face) {
    if (source[face] < 0 || face_area[face] <= 0 || source_area[face] <= 0) {
      continue;
    }
    gsd.emplace_back(std::sqrt(face_area[face] / source_area[face]),
                     face_area[face]);
    total += face_area[face];
  }
  std::sort(gsd.begin(), gsd.end());
  double texel_size = 0, sum = 0;
  for (const auto& [value, weight] : gsd) {
    texel_size = value;
    sum += weight;
    if (sum >= 0.5 * total) break;
  }
  return texel_size;
}

// 4. Charts: faces joined across edges where they share the source image;
// the faces no photograph sees, apart.
struct ChartLayout {
  std::vector<Chart> charts;
  std::vector<int> chart_of_face;  // -1: unseen
  Chart unseen;
};

ChartLayout BuildCharts(const std::vector<EdgeFace>& edges,
                        const std::vector<int>& source) {
  const int num_faces = static_cast<int>(source.size());
  UnionFind joined(num_faces);
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    for (size_t k = i + 1; k < edges.size() && edges[k].SameEdge(edges[i]);
         ++k) {
      const int f = edges[i].face, g = edges[k].face;
      if (source[f] >= 0 && source[f] == source[g]) {
        joined.Union(f, g);
      }
    }
  }
  ChartLayout layout;
  std::vector<int> chart_of_root(num_faces, -1);
  layout.chart_of_face.assign(num_faces, -1);
  for (int face = 0; face < num_faces; ++face) {
    if (source[face] < 0) {
      layout.unseen.faces.push_back(face);
      continue;
    }
    int& chart = chart_of_root[joined.Find(face)];
    if (chart < 0) {
      chart = static_cast<int>(layout.charts.size());
      layout.charts.emplace_back();
      layout.charts.back().image = source[face];
    }
    layout.charts[chart].faces.push_back(face);
    layout.chart_of_face[face] = chart;
  }
  return layout;
}

// Each chart scaled to the texel size (its pixels per metre from its faces'
// areas in the source image and in the object) and packed; a larger texel
// size when the atlas would exceed its largest side. Returns the atlas size
// and sets the texel size used.
cv::Size PackAtlas(const std::vector<std::array<Eigen::Vector2d, 3>>& corners,
                   const std::vector<float>& source_area,
                   const std::vector<double>& face_area,
                   const TextureOptions& options,
                   ChartLayout* layout,
                   double* texel_size) {
  std::vector<Chart>& charts = layout->charts;
  for (Chart& chart : charts) {
    double px = 0, m2 = 0;
    for (int face : chart.faces) {
      px += source_area[face];
      m2 += face_area[face];
    }
    chart.pixels_per_metre = m2 > 0 ? std::sqrt(px / m2) : 1.0;
  }
  Chart& unseen = layout->unseen;
  const int pad = options.padding_px;
  for (int attempt = 0;; ++attempt) {
    if (attempt == 30) {
      ThrowInputError("the atlas does not fit into --max_atlas_size ",
                      options.max_atlas_size,
                      " with --padding_px ",
                      pad,
                      " around each of ",
                      charts.size(),
                      " charts (raise max_atlas_size or lower "
                      "chart_merge_ratio)");
    }
    // Chart sides in doubles first: a tiny --texel_size must not overflow.
    double largest_side = 0;
    for (Chart& chart : charts) {
      const double scale = 1.0 / (*texel_size * chart.pixels_per_metre);
      chart.min = Eigen::Vector2d::Constant(1e300);
      chart.max = Eigen::Vector2d::Constant(-1e300);
      for (int face : chart.faces) {
        for (const Eigen::Vector2d& c : corners[face]) {
          chart.min = chart.min.cwiseMin(scale * c);
          chart.max = chart.max.cwiseMax(scale * c);
        }
      }
      largest_side = std::max(largest_side, (chart.max - chart.min).maxCoeff());
    }
    if (largest_side + 2 * pad + 1 > options.max_atlas_size) {
      *texel_size *=
          1.02 * (largest_side + 2 * pad + 1) / options.max_atlas_size;
      continue;
    }
    for (Chart& chart : charts) {
      chart.width = static_cast<int>(std::ceil(chart.max.x() - chart.min.x())) +
                    2 * pad + 1;
      chart.height =
          static_cast<int>(std::ceil(chart.max.y() - chart.min.y())) + 2 * pad +
          1;
    }
    // The faces no photograph sees get a cell of kUnseenCell x kUnseenCell
    // texels each in one block, coloured later from their neighbours.
    const int unseen_columns = static_cast<int>(
        std::ceil(std::sqrt(static_cast<double>(unseen.faces.size()))));
    unseen.width = unseen.height =
        unseen.faces.empty() ? 0 : unseen_columns * kUnseenCell + 2 * pad;
    if (!unseen.faces.empty()) charts.push_back(unseen);
    const cv::Size atlas_size = PackCharts(&charts);
    if (!unseen.faces.empty()) {
      unseen = charts.back();
      charts.pop_back();
    }
    const int side = std::max(atlas_size.width, atlas_size.height);
    if (side <= options.max_atlas_size) return atlas_size;
    *texel_size *= 1.02 * side / options.max_atlas_size;
  }
}

// Texture coordinates in atlas texels (x right, y down) per face corner;
// the unseen faces at the centres of their cells.
std::vector<std::array<Eigen::Vector2d, 3>> AtlasTexels(
    const ChartLayout& layout,
    const std::vector<std::array<Eigen::Vector2d, 3>>& corners,
    double texel_size,
    int pad,
    int unseen_columns) {
  std::vector<std::array<Eigen::Vector2d, 3>> texel(corners.size());
  for (const Chart& chart : layout.charts) {
    const double scale = 1.0 / (texel_size * chart.pixels_per_metre);
    const Eigen::Vector2d shift =
        chart.offset + Eigen::Vector2d::Constant(pad + 0.5) - chart.min;
    for (int face : chart.faces) {
      for (int k = 0; k < 3; ++k) {
        texel[face][k] = scale * corners[face][k] + shift;
      }
    }
  }
  for (size_t i = 0; i < layout.unseen.faces.size(); ++i) {
    texel[layout.unseen.faces[i]].fill(
        UnseenCellCenter(layout.unseen, pad, unseen_columns, i));
  }
  return texel;
}

// 5. One chart's texels (charts own disjoint rectangles, so that they fill
// in parallel). Each face first writes the texels whose centres lie inside
// it, then those within a texel outside its edges that are still empty, so
// that bilinear lookups at chart borders find texture, not background.
void FillChart(
    const Chart& chart,
    const std::vector<std::array<Eigen::Vector2d, 3>>& texel,
    const std::function<std::vector<BlendSource>(int)>& face_sources,
    const std::vector<std::array<Eigen::Vector3f, 3>>& corner_adjustment,
    const TextureOptions& options,
    cv::Mat* atlas,
    cv::Mat* covered) {
  for (int pass = 0; pass < 2; ++pass) {
    for (int face : chart.faces) {
      const auto& t = texel[face];
      const Eigen::Vector2d e1 = t[1] - t[0], e2 = t[2] - t[0];
      const double det = e1.x() * e2.y() - e1.y() * e2.x();
      if (std::abs(det) < 1e-12) continue;
      // Distance of a texel centre outside edge k, in texels, is
      // -b_k * |det| / |edge opposite k|.
      const double margin[3] = {
          pass == 0 ? 0.0 : (t[2] - t[1]).norm() / std::abs(det),
          pass == 0 ? 0.0 : (t[2] - t[0]).norm() / std::abs(det),
          pass == 0 ? 0.0 : (t[1] - t[0]).norm() / std::abs(det)};
      const std::vector<BlendSource> sources = face_sources(face);
      const auto& adjust = corner_adjustment[face];
      // Clamped to the chart's own rectangle: charts are filled in parallel
      // and must not touch each other's texels.
      const int cx0 = static_cast<int>(chart.offset.x());
      const int cy0 = static_cast<int>(chart.offset.y());
      const int x0 = std::max(
          cx0,
          static_cast<int>(
              std::floor(std::min({t[0].x(), t[1].x(), t[2].x()}) - 1.0)));
      const int y0 = std::max(
          cy0,
          static_cast<int>(
              std::floor(std::min({t[0].y(), t[1].y(), t[2].y()}) - 1.0)));
      const int x1 = std::min(
          cx0 + chart.width - 1,
          static_cast<int>(
              std::ceil(std::max({t[0].x(), t[1].x(), t[2].x()}) + 1.0)));
      const int y1 = std::min(
          cy0 + chart.height - 1,
          static_cast<int>(
              std::ceil(std::max({t[0].y(), t[1].y(), t[2].y()}) + 1.0)));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector2d d = Eigen::Vector2d(x + 0.5, y + 0.5) - t[0];
          const double b1 = (d.x() * e2.y() - d.y() * e2.x()) / det;
          const double b2 = (e1.x() * d.y() - e1.y() * d.x()) / det;
          const double b0 = 1.0 - b1 - b2;
          if (b0 < -margin[0] || b1 < -margin[1] || b2 < -margin[2]) {
            continue;
          }
          uint8_t& mark = covered->at<uint8_t>(y, x);
          if (pass == 1 && mark) continue;
          Eigen::Vector3f color;
          cv::Vec3b& out = atlas->at<cv::Vec3b>(y, x);
          if (BlendAt(sources, Eigen::Vector3d(b0, b1, b2), &color)) {
            color += float(b0) * adjust[0] + float(b1) * adjust[1] +
                     float(b2) * adjust[2];
            for (int ch = 0; ch < 3; ++ch) {
              out[ch] = cv::saturate_cast<uint8_t>(color[ch]);
            }
          } else {
            out = options.unseen_bgr;
          }
          mark = 255;
        }
      }
    }
  }
}

// The seam measure: the atlas at each chart-border edge's midpoint, seen
// from both sides; the mean absolute difference over the edges measured.
double SeamDifference(const TriangleMesh& mesh,
                      const std::vector<TwoFaceEdge>& two_face_edges,
                      const std::vector<int>& source,
                      const std::vector<std::array<Eigen::Vector2d, 3>>& texel,
                      const cv::Mat& atlas,
                      int* num_seam_edges) {
  double seam_sum = 0;
  for (const TwoFaceEdge& e : two_face_edges) {
    if (source[e.f] < 0 || source[e.g] < 0 || source[e.f] == source[e.g]) {
      continue;
    }
    auto midpoint = [&](int face) {
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.faces[face][k];
        if (v == e.a || v == e.b) sum += texel[face][k];
      }
      return Eigen::Vector2d(0.5 * sum);
    };
    Eigen::Vector3f a, b;
    if (!SampleColor(atlas, midpoint(e.f), &a) ||
        !SampleColor(atlas, midpoint(e.g), &b)) {
      continue;
    }
    seam_sum += (a - b).cwiseAbs().mean();
    ++*num_seam_edges;
  }
  return *num_seam_edges > 0 ? seam_sum / *num_seam_edges : 0.0;
}

}  // namespace

TexturedMesh MapTexture(const TriangleMesh& input,
                        const std::vector<TextureImage>& images,
                        const TextureOptions& options) {
  options.Check();
  if (input.NumFaces() == 0) ThrowInputError("the mesh has no faces");
  if (images.empty()) ThrowInputError("no images to texture the mesh from");
  TexturedMesh result;
  result.mesh = input;
  result.mesh.face_texcoords.clear();
  const TriangleMesh& mesh = result.mesh;
  TextureReport& report = result.report;
  const int num_faces = static_cast<int>(mesh.NumFaces());
  report.num_images = static_cast<int>(images.size());
  report.num_faces = num_faces;

  std::vector<cv::Mat> colors;
  const std::vector<std::vector<FaceView>> views =
      FindFaceViews(mesh, images, options, &colors, &report);
  const Timer timer;
  std::vector<int> best;
  std::vector<float> best_area;
  ChooseOptimalImages(views, &best, &best_area, &report);
  const std::vector<EdgeFace> edges = SortedEdges(mesh);
  const std::vector<TwoFaceEdge> two_face_edges = TwoFaceEdges(edges);
  const std::vector<std::array<int, 3>> neighbors =
      FaceNeighbors(two_face_edges, num_faces);
  std::vector<int> source = best;
  std::vector<float> source_area = best_area;
  MergeSpeckle(neighbors, views, best_area, options, &source, &source_area);
  for (int face = 0; face < num_faces; ++face) {
    if (source[face] >= 0) ++report.faces_per_image[images[source[face]].name];
  }
  std::vector<double> face_area(num_faces);
  for (int face = 0; face < num_faces; ++face) {
    face_area[face] = TriangleArea3(mesh, face);
  }
  double texel_size = options.texel_size > 0
                          ? options.texel_size
                          : MedianTexelSize(face_area, source, source_area);
  ChartLayout layout = BuildCharts(edges, source);
  report.num_charts = static_cast<int>(layout.charts.size());

  // 6. Seam levelling: corner adjustments from the colours the faces would
  // take on both sides of each chart border.
  const auto face_sources = [&](int face) {
    return BlendSources(mesh,
                        face,
                        views[face],
                        source[face],
                        best_area[face],
                        images,
                        colors,
                        options);
  };
  std::vector<std::array<Eigen::Vector3f, 3>> corner_adjustment(
      num_faces,
      {Eigen::Vector3f::Zero(),
       Eigen::Vector3f::Zero(),
       Eigen::Vector3f::Zero()});
  if (options.seam_leveling) {
    corner_adjustment = LevelSeams(
        mesh,
        layout.chart_of_face,
        two_face_edges,
        [&](int face, const Eigen::Vector3d& b, Eigen::Vector3f* color) {
          return BlendAt(face_sources(face), b, color);
        },
        SeamLevelingOptions(),
        &report.seam_leveling);
  }

  // Projected corners of every face in its source image; the charts packed
  // into the atlas, and each corner's place in it.
  std::vector<std::array<Eigen::Vector2d, 3>> corners(num_faces);
  for (int face = 0; face < num_faces; ++face) {
    if (source[face] >= 0) {
      ProjectFace(mesh, face, images[source[face]], corners[face].data());
    }
  }
  const cv::Size atlas_size =
      PackAtlas(corners, source_area, face_area, options, &layout, &texel_size);
  report.texel_size = texel_size;
  report.atlas_width = atlas_size.width;
  report.atlas_height = atlas_size.height;

  const int pad = options.padding_px;
  const Chart& unseen = layout.unseen;
  const int unseen_columns =
      (unseen.width - 2 * pad) / std::max(1, kUnseenCell);
  const std::vector<std::array<Eigen::Vector2d, 3>> texel =
      AtlasTexels(layout, corners, texel_size, pad, unseen_columns);

  // The atlas, chart by chart in parallel; the unseen faces' block, then
  // their colours from their neighbours.
  cv::Mat atlas(atlas_size, CV_8UC3, cv::Scalar::all(0));
  cv::Mat covered(atlas_size, CV_8U, cv::Scalar(0));
  if (!unseen.faces.empty()) {
    const cv::Rect block(static_cast<int>(unseen.offset.x()),
                         static_cast<int>(unseen.offset.y()),
                         unseen.width,
                         unseen.height);
    atlas(block).setTo(cv::Scalar(
        options.unseen_bgr[0], options.unseen_bgr[1], options.unseen_bgr[2]));
    covered(block).setTo(255);
  }
  Progress progress("atlas", layout.charts.size(), "charts");
  ParallelFor(
      static_cast<int>(layout.charts.size()), options.num_threads, [&](int c) {
        FillChart(layout.charts[c],
                  texel,
                  face_sources,
                  corner_adjustment,
                  options,
                  &atlas,
                  &covered);
        progress.Add();
      });
  progress.Finish();
  ColorUnseenFaces(neighbors, texel, unseen, pad, unseen_columns, &atlas);
  report.atlas_fill =
      double(cv::countNonZero(covered)) / (double(atlas.cols) * atlas.rows);
  DilateAtlas(pad, &atlas, &covered);

  result.mesh.face_texcoords.resize(num_faces);
  for (int face = 0; face < num_faces; ++face) {
    for (int k = 0; k < 3; ++k) {
      result.mesh.face_texcoords[face][k] = Eigen::Vector2f(
          static_cast<float>(texel[face][k].x() / atlas.cols),
          static_cast<float>(1.0 - texel[face][k].y() / atlas.rows));
    }
  }
  report.seam_difference = SeamDifference(
      mesh, two_face_edges, source, texel, atlas, &report.num_seam_edges);
  report.seconds_atlas = timer.Seconds();
  result.atlas = atlas;
  return result;
}

std::string TextureSummary(const TextureReport& r) {
  std::ostringstream out;
  out.precision(4);
  out << r.num_faces << " faces from " << r.num_images << " images ("
      << r.mean_views_per_face << " views per face, " << r.num_unseen_faces
      << " unseen), " << r.num_charts << " charts in a " << r.atlas_width
      << " x " << r.atlas_height << " atlas (texel " << r.texel_size * 1000
      << " mm, " << 100 * r.atlas_fill
      << " % filled); seams: " << r.num_seam_edges << " edges, mean difference "
      << r.seam_difference << " grey levels";
  if (r.balance.num_pairs > 0) {
    out << "; exposure balance over " << r.balance.num_faces
        << " faces: overlap differences " << r.balance.sigma_before << " -> "
        << r.balance.sigma_after << " grey levels (robust sigma)";
  }
  if (r.seam_leveling.num_seam_edges > 0) {
    out << "; seam levelling: border differences "
        << r.seam_leveling.difference_before << " -> "
        << r.seam_leveling.difference_after << " grey levels";
  }
  out << "; "
      << r.seconds_load + r.seconds_preprocess + r.seconds_visibility +
             r.seconds_atlas
      << " s";
  return out.str();
}

nlohmann::ordered_json TextureReportJson(
    const TextureReport& r,
    const TextureOptions& options,
    const std::string& mesh_path,
    const std::vector<std::string>& files) {
  nlohmann::ordered_json json;
  json["mesh_path"] = mesh_path;
  json["preprocess"] = TexturePreprocessName(options.preprocess);
  json["filter_radius_px"] = options.filter_radius_px;
  json["blend"] = TextureBlendName(options.blend);
  json["num_images"] = r.num_images;
  json["num_faces"] = r.num_faces;
  json["num_unseen_faces"] = r.num_unseen_faces;
  json["mean_views_per_face"] = r.mean_views_per_face;
  json["num_charts"] = r.num_charts;
  json["atlas_width"] = r.atlas_width;
  json["atlas_height"] = r.atlas_height;
  json["texel_size"] = r.texel_size;
  json["atlas_fill"] = r.atlas_fill;
  json["num_seam_edges"] = r.num_seam_edges;
  json["seam_difference"] = r.seam_difference;
  json["faces_per_image"] = r.faces_per_image;
  json["seam_leveling"] = options.seam_leveling;
  if (options.seam_leveling) {
    json["seam_leveling_report"] = {
        {"num_seam_edges", r.seam_leveling.num_seam_edges},
        {"num_unknowns", r.seam_leveling.num_unknowns},
        {"difference_before", r.seam_leveling.difference_before},
        {"difference_after", r.seam_leveling.difference_after},
        {"solver_iterations", r.seam_leveling.solver_iterations},
        {"solver_error", r.seam_leveling.solver_error}};
  }
  if (options.preprocess == TexturePreprocess::kBalance) {
    nlohmann::ordered_json balance = {
        {"num_faces", r.balance.num_faces},
        {"num_pairs", r.balance.num_pairs},
        {"num_groups", r.balance.num_groups},
        {"sigma_before", r.balance.sigma_before},
        {"sigma_after", r.balance.sigma_after},
        {"images", nlohmann::ordered_json::object()}};
    for (const auto& [name, c] : r.corrections) {
      balance["images"][name] = {
          {"gain_bgr", {c.gain[0], c.gain[1], c.gain[2]}},
          {"offset_bgr", {c.offset[0], c.offset[1], c.offset[2]}}};
    }
    json["balance"] = balance;
  }
  json["exclude_images"] = options.exclude_images;
  json["seconds"] = {{"load", r.seconds_load},
                     {"preprocess", r.seconds_preprocess},
                     {"visibility", r.seconds_visibility},
                     {"atlas", r.seconds_atlas}};
  json["files"] = files;
  return json;
}

}  // namespace bayon
