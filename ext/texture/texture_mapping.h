// SPDX-License-Identifier: BSD-3-Clause
//
// View-dependent texture mapping (the Bayon paper's sec. 3.5): a mesh and
// the oriented photographs give a texture atlas and per-corner texture
// coordinates.
//
// 1. Pre-processing of every photograph: by default the photographs'
//    exposures and white balances are balanced (a gain and offset per
//    photograph and channel, solved over their overlaps; color_balance.h),
//    which keeps the object's colours. The paper's high pass and histogram
//    equalisation per channel (ext/image/radiometry.h; equalisation counts
//    only the pixels the mesh covers, so that a dark background does not
//    wash the object out), a Wallis filter, or none are the alternatives.
//    The photographs on disk are never changed.
// 2. Visibility of every triangle in every photograph: the mesh rendered
//    through the photograph's camera (ext/render, the full camera model
//    with distortion) gives a depth map; a triangle is seen when its
//    centroid and three points just inside its corners project into the
//    frame and are not behind the depth map (occlusion by the mesh itself).
//    Triangles seen edge-on (the view ray within `min_view_angle_deg` of
//    the face's plane) count as unseen.
// 3. For each triangle its geometrically optimal image: the one where its
//    projected area is largest.
// 4. Charts: the connected sets of triangles drawn in one image: their
//    optimal image, or (`chart_merge_ratio`) the image of most of their
//    edge neighbours where that sees them nearly as large. A chart's
//    texture coordinates are its projection into that image, scaled to the
//    atlas's texel size, so every texel of the image is kept where the
//    texel size allows; charts are packed into one atlas (shelves, tallest
//    first) with `padding_px` texels between them, filled outwards from
//    each chart against bleeding under mip-mapping.
// 5. Texture weighted averaging (equations 6 and 7): every texel of a
//    triangle takes the weighted mean of all photographs that see the
//    triangle, weights area_j / area_max; the position in photograph j is
//    the affine transformation fixed by the triangle's three projected
//    corners (from the optimal image's geometry into image j's). With
//    `blend = kNone` only the chart's image is used (for comparison): the
//    optimal image, or its neighbours' where step 4 merged the face.
//
// 6. Seam levelling (`seam_leveling`, color_balance.h): an additive colour
//    per vertex and chart, interpolated over each face, levels what is left
//    at the chart borders.
//
// Texel size: `texel_size` metres, or by default the median ground sampling
// distance of the triangles in their optimal images, so that the atlas keeps
// the photographs' resolution where most of the model is seen.
//
// The seam measure judges what the user sees at chart borders: for every
// mesh edge whose two triangles come from different optimal images, the
// atlas colour at the edge's midpoint seen from each side (the same 3D
// point, two texels); the mean absolute difference over the channels, in
// 8-bit grey levels.
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"
#include "ext/texture/color_balance.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <map>
#include <string>
#include <vector>

namespace bayon {

enum class TexturePreprocess { kNone, kBalance, kHighPassEqualize, kWallis };
enum class TextureBlend { kNone, kViewDependent };

const char* TexturePreprocessName(TexturePreprocess preprocess);
const char* TextureBlendName(TextureBlend blend);

struct TextureOptions {
  TexturePreprocess preprocess = TexturePreprocess::kBalance;
  // High-pass radius and Wallis window (Gaussian sigma), pixels.
  double filter_radius_px = 50;
  TextureBlend blend = TextureBlend::kViewDependent;
  bool seam_leveling = true;
  // Photographs not to texture from, by name (for leaving one out).
  std::vector<std::string> exclude_images;
  // A face is drawn in the image most of its edge neighbours are drawn in
  // when that image sees it with at least this share of its largest
  // projected area (fewer, larger charts); 1: always its optimal image.
  double chart_merge_ratio = 0.7;
  // Atlas texel size in metres; 0: the median GSD of the optimal images.
  double texel_size = 0;
  // Largest atlas side; a larger atlas gets a coarser texel size.
  int max_atlas_size = 8192;
  int padding_px = 3;
  // A triangle counts as seen only when the view ray makes at least this
  // angle with its plane.
  double min_view_angle_deg = 5;
  // A point is occluded when the depth map is nearer by more than this
  // share of its depth.
  double depth_tolerance = 0.01;
  // Colour of texels no photograph sees (BGR).
  cv::Vec3b unseen_bgr = cv::Vec3b(128, 128, 128);
  int num_threads = -1;
  void Check() const;
  // Its fields by name (option_registry.h).
  void Register(OptionRegistry* registry);
};

// A photograph with its orientation, loaded and pre-processed.
struct TextureImage {
  std::string name;
  const Camera* camera = nullptr;
  const Image* image = nullptr;  // pose and frame
  cv::Mat bgr;                   // CV_8UC3, as photographed
};

struct TextureReport {
  int num_images = 0;
  int num_faces = 0;
  int num_unseen_faces = 0;  // seen in no photograph
  int num_charts = 0;
  int atlas_width = 0;
  int atlas_height = 0;
  double texel_size = 0;  // metres
  // Share of the atlas written from the photographs: the triangles, a texel
  // ring around them, and the unseen block (the rest is padding).
  double atlas_fill = 0;
  double mean_views_per_face = 0;
  // Faces by optimal image, by image name.
  std::map<std::string, int> faces_per_image;
  int num_seam_edges = 0;
  double seam_difference = 0;  // mean absolute, 8-bit grey levels
  // With --preprocess balance: every photograph's correction, by name,
  // and the overlaps' differences before and after.
  std::map<std::string, GainOffset> corrections;
  ColorBalanceReport balance;
  SeamLevelingReport seam_leveling;  // with seam_leveling
  double seconds_load = 0;           // reading the photographs (the caller's)
  double seconds_preprocess = 0;
  double seconds_visibility = 0;
  double seconds_atlas = 0;
};

struct TexturedMesh {
  TriangleMesh mesh;  // the input with face_texcoords
  cv::Mat atlas;      // CV_8UC3
  TextureReport report;
};

// Loads the scene's images from `image_path` (by name) but those excluded.
// Throws InputError naming a missing or unreadable image or one whose size
// differs from its camera's, or an excluded name the scene does not have.
std::vector<TextureImage> LoadTextureImages(const Scene& scene,
                                            const std::string& image_path,
                                            const TextureOptions& options);

// Throws InputError for a mesh without faces, no images, or a mesh no image
// sees.
TexturedMesh MapTexture(const TriangleMesh& mesh,
                        const std::vector<TextureImage>& images,
                        const TextureOptions& options);

std::string TextureSummary(const TextureReport& report);

// texture.json: the options that shaped the atlas, its figures, the
// balance and seam levelling applied, times and the files written.
nlohmann::ordered_json TextureReportJson(const TextureReport& r,
                                         const TextureOptions& options,
                                         const std::string& mesh_path,
                                         const std::vector<std::string>& files);

}  // namespace bayon
