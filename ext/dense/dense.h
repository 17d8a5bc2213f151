// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon dense`: a dense surface with a covariance for every point, by
// multi-photo geometrically constrained matching (MPGC, mpgc.h). Two modes:
//
// multiview (the default; DenseReconstructMultiView):
// 1. Every photograph a master; its source views are the images that see
//    the point it looks at (on its principal ray, in the middle of its
//    depth range) at the smallest angle between the rays that is still
//    min_triangulation_angle_deg (on a ring: the neighbours on both sides).
// 2. Per master, a depth and a normal for every pixel of the photograph
//    shrunk to max_image_size (patch_match.h), coarse to fine, streamed:
//    each photograph is read once and kept at the working size only.
// 3. The depth maps fused (fusion.h): a pixel whose depth and normal enough
//    other masters confirm becomes one point with them.
// 4. MPGC at full resolution for every fused point, from its position and
//    normal, over the master and the masters that confirmed it (its source
//    views first); X, Y, Z with their covariance, the precision test below
//    and a test of how far MPGC moved it (max_refine_shift_gsd).
//
// paper (--mode paper): the paper's section 3.3 from a few master images:
//
// 1. Masters and their search images by viewing geometry: every image's
//    direction from the object centre (the median of the sparse points) to
//    its projection centre; masters by farthest-point sampling of those
//    directions (a ring of 16 with 5 masters: every third or fourth image),
//    and for each master the images nearest in direction (default 6, the
//    paper's 7 in total) that are within max_search_angle_deg.
// 2. The dense pattern: the master divided into cells (7 x 7 pixels) and the
//    strongest Moravec point of each cell kept where it has texture.
// 3. Approximations by correlation along the master ray (SearchMasterRay):
//    first for a coarse subset of the cells (every coarse_step-th in each
//    direction) within the depths of the sparse points near each (or the
//    master's whole depth range where there are none), then
//    for every other cell inside the band the coarse points around it
//    span, widened by band_tolerance: the disparity-surface band of the
//    paper, built from the master's own coarse points in the adjusted
//    object system.
// 4. MPGC for every point, with blunder/occlusion removal per search image
//    (mpgc.h), and a precision test: points whose standard deviation along
//    the master ray (the depth, where the intersection is weakest) exceeds
//    max_sigma_gsd ground sampling distances of the master are rejected.
//    Then every point is tested against the plane of its neighbours in the
//    master's cell grid (inverse depth over the pixel coordinates, fitted
//    robustly); those off it are rejected as blunders.
//    Then region growing: cells still without a point, where five or more
//    accepted neighbours determine the surface around them, get their
//    approximation (depth and the search patches' shapes) from that surface
//    and MPGC starts from it; passes repeat while points are added, the
//    off-surface test after each.
//    Last, every point is tested against the other masters' surfaces
//    (visibility: a point may not hide what another master saw, nor be
//    matched in a master whose surface hides it).
// 5. Normals from the accepted neighbours in the master's cell grid (a
//    plane through them, facing the master), colours from the master.
//
// Everything is in the model's object system, so the masters' points form
// one cloud without any registration between them.
#pragma once

#include "ext/core/point_cloud.h"
#include "ext/core/scene.h"
#include "ext/dense/fusion.h"
#include "ext/dense/mpgc.h"
#include "ext/dense/patch_match.h"

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace bayon {

enum class DenseMode { kMultiView, kPaper };

struct DenseOptions {
  DenseMode mode = DenseMode::kMultiView;
  // Radiometric pre-processing of the grey values for matching: minus their
  // Gaussian blur of this sigma (pixels; 0: off), so that photographs taken
  // in different light agree (LoadDenseImages).
  double highpass_sigma_px = 3.0;
  // Masters: 0 for every photograph (multiview) or 5 (paper).
  int num_masters = 0;
  // Explicit masters (image names); overrides num_masters.
  std::vector<std::string> master_names;

  // multiview: the depth maps' size (the photographs shrunk by the smallest
  // whole factor that brings the longer side to this at most), source views
  // per master, and the smallest angle between the rays of master and
  // source to the point the master looks at.
  int max_image_size = 1200;
  int num_source_views = 4;
  double min_triangulation_angle_deg = 3;
  PatchMatchOptions patch_match;
  FusionOptions fusion;
  // MPGC for every fused point; off: the fused points as they are, without
  // covariance.
  bool refine = true;
  // A refined point further along its master ray from the fused one than
  // this many GSDs of the depth map is rejected (off_surface).
  double max_refine_shift_gsd = 2.0;
  // The smallest contrast (grey values) of a master patch MPGC refines
  // (flat_patch below it). Lower than the paper's 2 (mpgc.lsm): a fused
  // point has already been matched over a wider window, and the precision
  // test (max_sigma_gsd) judges what the patch's texture determines; on
  // fountain-P11 2 left 28 % of the fused points flat, 1 leaves 6 %.
  double refine_min_template_stddev = 1.0;
  // The points' stated precision gets the standard deviation of the errors
  // MPGC's model leaves out (resampling, shading the radiometric model
  // cannot follow, a surface that is not a plane across the patch) added
  // in quadrature: estimated from the cloud's own scatter about its local
  // surface, the variance component `bayon edit` estimates
  // (EstimateUnmodelledSigma). Rendered tower: the true errors were 1.81
  // times the stated sigmas (median), 0.99 times with it (2.6 mm added).
  // multiview only (AddUnmodelledSigma says why).
  bool add_unmodelled_sigma = true;

  // paper: search images per master (nearest viewing directions).
  int num_search_images = 6;
  // The search along the master ray correlates with the nearest this many
  // search images (the best two of them score each sample).
  int num_ray_views = 4;
  double max_search_angle_deg = 75;
  // Dense pattern: cell side, pixels; a cell's best Moravec point must
  // reach min_interest (squared grey values, moravec.h).
  int cell_size = 7;
  int moravec_window = 5;
  double min_interest = 2.0;
  // Approximations: the coarse cells, and how far the band of the other
  // cells reaches beyond the depths of the coarse points around them
  // (a share of the depth), over how many coarse cells around.
  int coarse_step = 4;
  double band_tolerance = 0.01;
  int band_radius_cells = 2;
  // The master's depth range when the model has fewer than 10 sparse points
  // in it (object units; 0: refuse).
  double min_depth = 0;
  double max_depth = 0;
  // Widening of the depth range of the sparse points (a share of it).
  double depth_margin = 0.25;
  // A coarse cell searches between the depths of the sparse points within
  // sparse_radius_px of it, widened by sparse_tolerance (a share of the
  // depth); with fewer than three such points, the master's whole range.
  double sparse_radius_px = 60;
  double sparse_tolerance = 0.05;
  EpipolarSearchOptions search;
  // The best correlation along the ray must exceed the best elsewhere on it
  // by this much (repetitive texture); 0: off.
  double min_peak_margin = 0.0;
  // Search views whose correlation at the approximation is below this are
  // left out of the point's MPGC (hidden there, or lit beyond recognition).
  double min_view_ncc = 0.5;
  MpgcOptions mpgc;
  double max_sigma_gsd = 2.0;
  // Off-surface test: a point whose depth misses the plane of its
  // neighbours within surface_radius_cells by more than off_surface_gsd
  // GSDs is a blunder.
  int surface_radius_cells = 2;
  double off_surface_gsd = 3.0;
  // Fewer accepted neighbours within surface_radius_cells: isolated.
  int min_neighbors = 3;
  // Region growing after the search along the rays: passes of MPGC from
  // the surface of the accepted neighbours for the cells still without a
  // point (0: off).
  int max_growth_passes = 8;
  // Search images a grown point needs (MPGC's min_search_views for it).
  // A grown point is confirmed by the surface it grew from, so fewer could
  // do; on the rendered tower 2 gave 14 % more points (completeness 34.0 ->
  // 37.5 %) but twice the points beyond 5 GSD (RMS 0.85 -> 0.99 GSD), so
  // the default stays with the searched points' 3.
  int growth_min_search_views = 3;
  int num_threads = -1;
  DenseOptions();      // the dense stage's own defaults for search and mpgc
  void Check() const;  // throws InputError naming field, value, rule
  // Its fields by name (option_registry.h): patch_match.*, fusion.*,
  // search.* and mpgc.* (mpgc.lsm.*) for the nested ones.
  void Register(OptionRegistry* registry);
};

struct MasterSelection {
  image_t master = kInvalidImageId;
  std::vector<image_t> search;  // nearest in viewing direction first
};

// Throws InputError when the scene has fewer than two images or a named
// master is not in it; a master without any image within the angle gets an
// empty search list (DenseReconstruct skips it and says why).
std::vector<MasterSelection> SelectMasters(const Scene& scene,
                                           const DenseOptions& options);

// Why a cell of a master gave no point.
enum class DenseReject {
  kAccepted = 0,
  kNoTexture,        // no Moravec point reaches min_interest in the cell
  kNoApproximation,  // correlation along the ray stayed below min_ncc, or
                     // no coarse point around to bound the search
  kAmbiguous,        // a second peak along the ray nearly as high
  kMpgcOutside,      // the MPGC statuses (mpgc.h)
  kMpgcFlat,
  kMpgcBehind,
  kMpgcTooFewViews,
  kMpgcNotConverged,
  kMpgcSingular,
  kImprecise,     // sigma along the ray above max_sigma_gsd
  kOffSurface,    // off the plane of its neighbours
  kIsolated,      // too few accepted neighbours to confirm it
  kInconsistent,  // in front of another master's surface, or behind it
                  // though matched in that master; multiview: too few
                  // other depth maps agree
  kMerged,        // multiview: part of a point of another master
  kDepthEdge,     // multiview: near an edge of the master's depth map
  kNumReasons
};
const char* DenseRejectName(DenseReject reason);

struct DenseMasterReport {
  image_t master = kInvalidImageId;
  std::string name;
  std::vector<image_t> search;  // those used (their images could be read)
  // Why the master was not matched (no search image, its image or all its
  // search images unreadable, no depth range); empty when it was.
  std::string skipped;
  double min_depth = 0, max_depth = 0;
  size_t num_cells = 0;
  size_t num_points = 0;
  std::array<size_t, static_cast<int>(DenseReject::kNumReasons)> rejects{};
  double median_sigma_gsd = 0;  // along the ray, master GSDs
  double seconds = 0;
  // What became of every cell (DenseReject, CV_8U, one element per cell),
  // and where the cell grid lies in the master: cell (cx, cy) covers pixels
  // border + cell_size * (cx, cy) onwards.
  cv::Mat reasons;
  int border = 0, cell_size = 1;
};

// A picture of a master's cells (RejectMap colours, the master dimmed
// underneath) with a legend: where the surface was found, and why not
// elsewhere.
cv::Mat RejectMap(const DenseMasterReport& master, const cv::Mat& color);

struct DenseReport {
  // multiview: the cells are the depth maps' pixels, the search images the
  // source views.
  DenseMode mode = DenseMode::kPaper;
  std::vector<DenseMasterReport> masters;
  size_t num_points = 0;
  size_t num_cells = 0;
  double seconds = 0;
  // multiview: the time of the depth maps, the fusion and MPGC.
  double propagation_seconds = 0, fusion_seconds = 0, mpgc_seconds = 0;
  // Added to every point's sigmas in quadrature (object units; 0: none).
  double added_sigma = 0;
  // Rates over the whole run: cells tried (every one of the pattern) and
  // points accepted.
  double CellsPerSecond() const {
    return seconds > 0 ? num_cells / seconds : 0;
  }
  double PointsPerSecond() const {
    return seconds > 0 ? num_points / seconds : 0;
  }
  std::string Summary() const;
};

// Adds the standard deviation of the errors MPGC's model leaves out
// (DenseOptions::add_unmodelled_sigma) to the cloud's sx, sy, sz and
// s_normal in quadrature, and states it in report->added_sigma. The paper
// mode's clouds, those without MPGC and those too small to judge keep
// their own.
void AddUnmodelledSigma(const DenseOptions& options,
                        PointCloud* cloud,
                        DenseReport* report);

// The images of the scene, loaded once: grey (CV_32F, 0..255) for matching,
// and colour (8-bit BGR) for the points' colours.
struct DenseImage {
  cv::Mat gray;
  cv::Mat color;
};

// The per-point attributes of both modes, one value per point each, as
// DenseReconstruct describes them; MoveInto adds them to the cloud.
struct DensePointAttributes {
  std::vector<double> sx, sy, sz, s_normal, num_images, master_ids, sigma0,
      correlation;
  void MoveInto(PointCloud* cloud);
};

// A cloud with per-point attributes sx sy sz (object units), s_normal (the
// standard deviation along the point's normal, from the full covariance),
// num_images,
// master_id, sigma0 (grey values) and correlation (mean over the search
// patches), with normals and colours; `visibility` (if not null) gets, per
// point, the image ids it was matched in (the master first). Search images
// missing from `images` are left out; a master that cannot be matched (its
// image missing, no search image, no depth range) is skipped with the
// reason in its report; InputError when no master can be matched.
PointCloud DenseReconstruct(const Scene& scene,
                            const std::map<image_t, DenseImage>& images,
                            const std::vector<MasterSelection>& masters,
                            const DenseOptions& options,
                            DenseReport* report,
                            std::vector<std::vector<image_t>>* visibility);

// multiview: every image (or the named ones, or num_masters spread as
// SelectMasters spreads them) a master, with its source views
// (MasterSelection::search): by the angle at the point the master looks
// at, or by viewing direction where its depth range is unknown; InputError
// as SelectMasters.
std::vector<MasterSelection> SelectMultiViewMasters(
    const Scene& scene, const DenseOptions& options);

// multiview: the points of the masters' depth maps, fused and refined by
// MPGC (see the top of this file), with the attributes and `visibility` of
// DenseReconstruct. The photographs are read from `image_path` as they are
// needed and kept at the depth maps' size; at full size only a master and
// its sources at a time. One that cannot be read is left out with its error
// in `unreadable` (InputError without it); masters that cannot be matched
// are skipped with the reason in their report; InputError when none can.
PointCloud DenseReconstructMultiView(
    const Scene& scene,
    const std::string& image_path,
    const std::vector<MasterSelection>& masters,
    const DenseOptions& options,
    DenseReport* report,
    std::vector<std::vector<image_t>>* visibility,
    std::map<image_t, std::string>* unreadable = nullptr);

// One image as the dense stages match it (LoadDenseImages; `color` too if
// asked); InputError when it cannot be read or has another size than its
// camera.
DenseImage LoadDenseImage(const Scene& scene,
                          image_t image_id,
                          const std::string& image_path,
                          double highpass_sigma_px,
                          bool color);

// An image's colours (8-bit BGR) as the dense stages read them, for the
// points and the reject pictures; InputError when it cannot be read.
cv::Mat LoadDenseColor(const Scene& scene,
                       image_t image_id,
                       const std::string& image_path);

// Angle between two directions, degrees.
double AngleBetweenDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// The MPGC status as a reject reason (kAccepted when converged).
DenseReject DenseRejectOf(MpgcStatus status);

// A master's depth range from the sparse points it sees (or that project
// into it), widened by depth_margin; the options' range where given;
// InputError where neither says.
std::pair<double, double> MasterDepthRange(const Scene& scene,
                                           const Image& master,
                                           const DenseOptions& options);

// Loads the images `masters` need from `image_path` (by the scene's names),
// the grey values high-pass filtered (minus their Gaussian blur of
// `highpass_sigma_px`, plus 128; 0: as read). An image that cannot be read
// (missing, corrupt, of another size than its camera) throws InputError,
// or, with `unreadable`, is left out and its error kept there, so that
// DenseReconstruct matches the masters without it.
std::map<image_t, DenseImage> LoadDenseImages(
    const Scene& scene,
    const std::vector<MasterSelection>& masters,
    const std::string& image_path,
    double highpass_sigma_px,
    std::map<image_t, std::string>* unreadable = nullptr);

// The report `bayon dense` writes beside its cloud (points.json): the
// rates, the time split and each master's cells and rejects.
nlohmann::ordered_json DenseReportJson(const DenseReport& report,
                                       const DenseOptions& options);

}  // namespace bayon
