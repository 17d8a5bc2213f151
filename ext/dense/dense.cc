// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/dense.h"

#include "ext/adjustment/triangulation.h"
#include "ext/cloud/cloud_edit.h"
#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"
#include "ext/features/moravec.h"
#include "ext/image/image_io.h"

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

namespace bayon {

DenseOptions::DenseOptions() {
  // 11 x 11 patches: enough texture for the eight parameters per search
  // patch on the tower's stone, a quarter of the arithmetic of lsm.h's 15.
  // (9 x 9: on the rendered tower a fifth less MPGC time, median 0.331
  // against 0.34 GSD at the same RMS and completeness, but on a flat
  // textured plane MPGC then ends less precise than the fused points it
  // starts from, dense_multi_view_test: 0.22 against 0.19 mm, 11 x 11 0.17.)
  mpgc.lsm.patch_radius = 5;
  // A step that lowers the sum of squares by less than sigma0^2 has moved
  // the point by less than one of its standard deviations: converged.
  // MpgcOptions' 0.3 lets the iterations creep on in steps that change
  // little (the radiometry and shape following the alignment).
  mpgc.convergence_sigma = 1.0;
  // A point needs four images: on the rendered tower 39 % of the
  // three-image points were blunders (beyond 5 GSD), 13 % of the
  // four-image ones, 2 % of those in five or more.
  mpgc.min_search_views = 3;
  // The two best views: a ring has a neighbour on each side, and a point
  // hidden on one side is still seen on the other.
  search.best_views = 2;
  // One-pixel steps along the epipolar lines: the parabola through the
  // best sample and its neighbours is as good a start for MPGC as half-pixel
  // steps give (rendered tower: 3510 points at RMS 1.00 GSD against 3571 at
  // 0.97), in half the time.
  search.step_px = 1.0;
  // Every second sample first, then around the three best peaks: on the
  // rendered tower 22 % less time for the whole command and 0.3 % more
  // points at the same accuracy; on stereo-gt's cones and teddy as many
  // points and blunders as every sample gives (every third sample: 29 %
  // less time, but 8 % fewer points and twice the blunders on stereo-gt).
  search.stride = 2;
  // Patch centres that move less than this between iterations have
  // converged: a fifth of the precision dense points reach.
  mpgc.convergence_px = 0.02;
}

void DenseOptions::Check() const {
  CheckOption(
      highpass_sigma_px >= 0, "highpass_sigma_px", ">= 0", highpass_sigma_px);
  CheckOption(num_masters >= 0, "num_masters", ">= 0", num_masters);
  CheckOption(max_image_size >= 16, "max_image_size", ">= 16", max_image_size);
  CheckOption(num_source_views >= 1 && num_source_views <= 32,
              "num_source_views",
              "in [1, 32]",
              num_source_views);
  CheckOption(
      min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 90,
      "min_triangulation_angle_deg",
      "in [0, 90)",
      min_triangulation_angle_deg);
  CheckOption(refine_min_template_stddev >= 0,
              "refine_min_template_stddev",
              ">= 0",
              refine_min_template_stddev);
  CheckOption(max_refine_shift_gsd > 0,
              "max_refine_shift_gsd",
              "> 0",
              max_refine_shift_gsd);
  CheckNested("patch_match", patch_match);
  CheckNested("fusion", fusion);
  CheckOption(
      num_search_images >= 1, "num_search_images", ">= 1", num_search_images);
  CheckOption(max_search_angle_deg > 0 && max_search_angle_deg < 180,
              "max_search_angle_deg",
              "in (0, 180)",
              max_search_angle_deg);
  CheckOption(cell_size >= 1, "cell_size", ">= 1", cell_size);
  CheckOption(moravec_window >= 3 && moravec_window % 2 == 1,
              "moravec_window",
              "odd and >= 3",
              moravec_window);
  CheckOption(min_interest >= 0, "min_interest", ">= 0", min_interest);
  CheckOption(coarse_step >= 1, "coarse_step", ">= 1", coarse_step);
  CheckOption(band_tolerance >= 0, "band_tolerance", ">= 0", band_tolerance);
  CheckOption(
      band_radius_cells >= 1, "band_radius_cells", ">= 1", band_radius_cells);
  CheckOption(min_depth >= 0 && max_depth >= 0 &&
                  (max_depth == 0 || max_depth > min_depth),
              "max_depth",
              "0 (from the sparse points) or > min_depth >= 0",
              max_depth);
  CheckOption(depth_margin >= 0, "depth_margin", ">= 0", depth_margin);
  CheckOption(
      sparse_radius_px > 0, "sparse_radius_px", "> 0", sparse_radius_px);
  CheckOption(
      sparse_tolerance >= 0, "sparse_tolerance", ">= 0", sparse_tolerance);
  CheckOption(max_sigma_gsd > 0, "max_sigma_gsd", "> 0", max_sigma_gsd);
  CheckOption(min_peak_margin >= 0, "min_peak_margin", ">= 0", min_peak_margin);
  CheckOption(min_view_ncc > -1 && min_view_ncc < 1,
              "min_view_ncc",
              "in (-1, 1)",
              min_view_ncc);
  CheckOption(surface_radius_cells >= 1,
              "surface_radius_cells",
              ">= 1",
              surface_radius_cells);
  CheckOption(off_surface_gsd > 0, "off_surface_gsd", "> 0", off_surface_gsd);
  CheckOption(
      max_growth_passes >= 0, "max_growth_passes", ">= 0", max_growth_passes);
  CheckNested("search", search);
  CheckNested("mpgc", mpgc);
}

void DenseOptions::Register(OptionRegistry* r) {
  r->AddChoice(
      "mode",
      &mode,
      {{"multiview", DenseMode::kMultiView}, {"paper", DenseMode::kPaper}},
      "multiview (depth maps) or paper");
  r->Add("highpass_sigma_px",
         &highpass_sigma_px,
         "Matching on grey values minus their Gaussian blur of this sigma, px "
         "(0 = off): different light between photographs");
  r->Add("num_masters",
         &num_masters,
         "Master images (0: every one, multiview; 5, paper)");
  r->Add("master_names",
         &master_names,
         "Master images by name, comma-separated (overrides num_masters)");
  r->Add("max_image_size",
         &max_image_size,
         "multiview: depth maps of the photographs shrunk by a whole factor "
         "to this longer side at most, px");
  r->Add("num_source_views",
         &num_source_views,
         "multiview: source views per master (smallest angle at what it "
         "looks at, from min_triangulation_angle_deg)");
  r->Add("min_triangulation_angle_deg",
         &min_triangulation_angle_deg,
         "multiview: smallest angle between master and source rays");
  r->AddNested("patch_match", &patch_match);
  r->AddNested("fusion", &fusion);
  r->Add("refine",
         &refine,
         "multiview: MPGC for every fused point (0: the fused points, "
         "without covariance)");
  r->Add("max_refine_shift_gsd",
         &max_refine_shift_gsd,
         "multiview: reject points MPGC moves further, depth-map GSDs");
  r->Add("refine_min_template_stddev",
         &refine_min_template_stddev,
         "multiview: MPGC refines master patches with this contrast at "
         "least (flat_patch), grey values");
  r->Add("add_unmodelled_sigma",
         &add_unmodelled_sigma,
         "Add the errors MPGC's model leaves out, estimated from the cloud's "
         "scatter about its local surface, to the points' sigmas in "
         "quadrature");
  r->Add("num_search_images",
         &num_search_images,
         "Search images per master (nearest viewing directions)");
  r->Add("num_ray_views",
         &num_ray_views,
         "Approximations: search in the nearest n search images");
  r->Add("max_search_angle_deg",
         &max_search_angle_deg,
         "Largest angle between master and search directions");
  r->Add("cell_size",
         &cell_size,
         "Dense pattern: one Moravec point per cell of this side, px");
  r->Add("moravec_window",
         &moravec_window,
         "Dense pattern: Moravec window side, px");
  r->Add("min_interest",
         &min_interest,
         "Smallest Moravec interest of a cell's point");
  r->Add("coarse_step",
         &coarse_step,
         "Coarse cells (full depth range): every n-th in x and y");
  r->Add("band_tolerance",
         &band_tolerance,
         "Band beyond the coarse points' depths, share of the depth");
  r->Add("band_radius_cells",
         &band_radius_cells,
         "Coarse cells around a cell that bound its band");
  r->Add("min_depth",
         &min_depth,
         "Depth range when the model has too few sparse points");
  r->Add("max_depth", &max_depth, "(see min_depth)");
  r->Add("depth_margin",
         &depth_margin,
         "Widening of the sparse points' depth range, share");
  r->Add("sparse_radius_px",
         &sparse_radius_px,
         "Sparse points within this radius bound a coarse cell's depths, px");
  r->Add("sparse_tolerance",
         &sparse_tolerance,
         "Widening of those depths, share of the depth");
  r->AddNested("search", &search);
  r->Add("min_peak_margin",
         &min_peak_margin,
         "Approximations: best minus second peak along the ray");
  r->Add("min_view_ncc",
         &min_view_ncc,
         "Views correlating less at the approximation stay out of the "
         "point's MPGC");
  r->AddNested("mpgc", &mpgc);
  r->Add("max_sigma_gsd",
         &max_sigma_gsd,
         "Reject points with a larger sigma along the master ray, in ground "
         "sampling distances");
  r->Add("surface_radius_cells",
         &surface_radius_cells,
         "Neighbours of the off-surface test: cells around");
  r->Add("off_surface_gsd",
         &off_surface_gsd,
         "Reject points off the plane of their neighbours by more than this "
         "many GSDs");
  r->Add("min_neighbors",
         &min_neighbors,
         "Reject points with fewer accepted neighbours (isolated)");
  r->Add("max_growth_passes",
         &max_growth_passes,
         "Region growing: passes of MPGC from the surface of the accepted "
         "neighbours (0 = off)");
  r->Add("growth_min_search_views",
         &growth_min_search_views,
         "Region growing: search images a grown point needs");
  r->Add("num_threads", &num_threads, "-1 = all cores");
}

const char* DenseRejectName(DenseReject reason) {
  switch (reason) {
    case DenseReject::kAccepted:
      return "accepted";
    case DenseReject::kNoTexture:
      return "no_texture";
    case DenseReject::kNoApproximation:
      return "no_approximation";
    case DenseReject::kAmbiguous:
      return "ambiguous";
    case DenseReject::kMpgcOutside:
      return "outside_image";
    case DenseReject::kMpgcFlat:
      return "flat_patch";
    case DenseReject::kMpgcBehind:
      return "behind_camera";
    case DenseReject::kMpgcTooFewViews:
      return "too_few_views";
    case DenseReject::kMpgcNotConverged:
      return "not_converged";
    case DenseReject::kMpgcSingular:
      return "singular";
    case DenseReject::kImprecise:
      return "imprecise";
    case DenseReject::kOffSurface:
      return "off_surface";
    case DenseReject::kIsolated:
      return "isolated";
    case DenseReject::kInconsistent:
      return "inconsistent";
    case DenseReject::kMerged:
      return "merged";
    case DenseReject::kDepthEdge:
      return "depth_edge";
    case DenseReject::kNumReasons:
      break;
  }
  return "unknown";
}

DenseReject DenseRejectOf(MpgcStatus status) {
  switch (status) {
    case MpgcStatus::kConverged:
      return DenseReject::kAccepted;
    case MpgcStatus::kOutsideImage:
      return DenseReject::kMpgcOutside;
    case MpgcStatus::kFlatPatch:
      return DenseReject::kMpgcFlat;
    case MpgcStatus::kBehindCamera:
      return DenseReject::kMpgcBehind;
    case MpgcStatus::kTooFewViews:
      return DenseReject::kMpgcTooFewViews;
    case MpgcStatus::kNotConverged:
      return DenseReject::kMpgcNotConverged;
    case MpgcStatus::kSingular:
      return DenseReject::kMpgcSingular;
  }
  return DenseReject::kMpgcSingular;
}

namespace {

const Camera& CameraOf(const Scene& scene, const Image& image) {
  return scene.cameras.at(image.camera_id);
}

// The object centre: the component-wise median of the sparse points, or,
// with too few of them, the point nearest to all optical axes.
Eigen::Vector3d ObjectCentre(const Scene& scene) {
  if (scene.points3D.size() >= 10) {
    std::vector<double> coordinates[3];
    for (const auto& [id, point] : scene.points3D) {
      for (int k = 0; k < 3; ++k) coordinates[k].push_back(point.xyz(k));
    }
    return Eigen::Vector3d(
        Median(coordinates[0]), Median(coordinates[1]), Median(coordinates[2]));
  }
  std::vector<Ray> axes;
  for (const auto& [id, image] : scene.images) {
    const Camera& camera = CameraOf(scene, image);
    const std::optional<Ray> axis = RayThroughPixel(
        camera,
        image.cam_from_world,
        Eigen::Vector2d(camera.width / 2.0, camera.height / 2.0),
        image.frame ? &*image.frame : nullptr);
    if (axis) axes.push_back(*axis);
  }
  const std::optional<Eigen::Vector3d> centre = IntersectRays(axes, 0.0);
  if (!centre) {
    ThrowInputError(
        "the model has fewer than 10 sparse points and its optical axes do "
        "not meet in front of the cameras: no object centre for choosing "
        "master images");
  }
  return *centre;
}

}  // namespace

std::vector<MasterSelection> SelectMasters(const Scene& scene,
                                           const DenseOptions& options) {
  options.Check();
  if (scene.images.size() < 2) {
    ThrowInputError(
        "dense matching needs two or more oriented images; the "
        "model has ",
        scene.images.size());
  }
  const Eigen::Vector3d centre = ObjectCentre(scene);
  std::vector<image_t> ids;
  std::vector<Eigen::Vector3d> directions;
  for (const auto& [id, image] : scene.images) {
    ids.push_back(id);
    directions.push_back((image.cam_from_world.Center() - centre).normalized());
  }
  const int n = static_cast<int>(ids.size());
  std::vector<int> masters;
  if (!options.master_names.empty()) {
    for (const std::string& name : options.master_names) {
      const Image* image = scene.FindImageByName(name);
      if (image == nullptr) {
        ThrowInputError(
            "master_names: the model has no image named '", name, "'");
      }
      masters.push_back(static_cast<int>(
          std::find(ids.begin(), ids.end(), image->image_id) - ids.begin()));
    }
  } else {
    // Farthest-point sampling of the viewing directions, from the image
    // that sees most sparse points.
    int first = 0;
    for (int i = 1; i < n; ++i) {
      if (scene.images.at(ids[i]).NumPoints3D() >
          scene.images.at(ids[first]).NumPoints3D()) {
        first = i;
      }
    }
    masters.push_back(first);
    std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
    while (static_cast<int>(masters.size()) <
           std::min(options.num_masters > 0 ? options.num_masters : 5, n)) {
      int farthest = -1;
      for (int i = 0; i < n; ++i) {
        nearest[i] = std::min(
            nearest[i],
            AngleBetweenDeg(directions[i], directions[masters.back()]));
        if (nearest[i] > 0 &&
            (farthest < 0 || nearest[i] > nearest[farthest])) {
          farthest = i;
        }
      }
      if (farthest < 0) break;
      masters.push_back(farthest);
    }
  }
  std::vector<MasterSelection> selections;
  for (int m : masters) {
    MasterSelection selection;
    selection.master = ids[m];
    std::vector<std::pair<double, int>> by_angle;
    for (int i = 0; i < n; ++i) {
      if (i == m) continue;
      const double angle = AngleBetweenDeg(directions[i], directions[m]);
      if (angle <= options.max_search_angle_deg) by_angle.push_back({angle, i});
    }
    std::sort(by_angle.begin(), by_angle.end());
    for (size_t k = 0;
         k < by_angle.size() && static_cast<int>(k) < options.num_search_images;
         ++k) {
      selection.search.push_back(ids[by_angle[k].second]);
    }
    selections.push_back(std::move(selection));
  }
  return selections;
}

DenseImage LoadDenseImage(const Scene& scene,
                          image_t image_id,
                          const std::string& image_path,
                          double highpass_sigma_px,
                          bool color) {
  DenseImage image;
  const Image& record = scene.images.at(image_id);
  const std::string path = image_path + "/" + record.name;
  image.gray = ReadImageGrayFloat(path);
  const Camera& camera = CameraOf(scene, record);
  if (image.gray.cols != static_cast<int>(camera.width) ||
      image.gray.rows != static_cast<int>(camera.height)) {
    ThrowInputError(path,
                    ": ",
                    image.gray.cols,
                    " x ",
                    image.gray.rows,
                    " pixels, but its camera in the model is ",
                    camera.width,
                    " x ",
                    camera.height);
  }
  if (highpass_sigma_px > 0) {
    // Shading and exposure change slowly across the image; texture does
    // not. What the photographs' different light leaves of a patch is
    // then mostly its texture, which least-squares matching's linear
    // radiometric terms can follow (the paper's high-pass pre-processing
    // for texture, sec. 3.5, applied here to the matching).
    cv::Mat blurred;
    cv::GaussianBlur(image.gray, blurred, cv::Size(), highpass_sigma_px);
    image.gray = image.gray - blurred + 128.0f;
  }
  if (color) image.color = ReadImageColor8(path);
  return image;
}

double AngleBetweenDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
}

cv::Mat LoadDenseColor(const Scene& scene,
                       image_t image_id,
                       const std::string& image_path) {
  return ReadImageColor8(image_path + "/" + scene.images.at(image_id).name);
}

std::map<image_t, DenseImage> LoadDenseImages(
    const Scene& scene,
    const std::vector<MasterSelection>& masters,
    const std::string& image_path,
    double highpass_sigma_px,
    std::map<image_t, std::string>* unreadable) {
  std::map<image_t, DenseImage> images;
  const auto read = [&](image_t id, bool color) {
    DenseImage& image = images[id];
    if (image.gray.empty()) {
      image = LoadDenseImage(scene, id, image_path, highpass_sigma_px, color);
    } else if (color && image.color.empty()) {
      image.color = LoadDenseColor(scene, id, image_path);
    }
  };
  const auto load = [&](image_t id, bool color) {
    if (unreadable == nullptr) return read(id, color);
    if (unreadable->count(id) > 0) return;
    try {
      read(id, color);
    } catch (const InputError& error) {
      images.erase(id);
      unreadable->emplace(id, error.what());
    }
  };
  for (const MasterSelection& selection : masters) {
    load(selection.master, true);
    for (image_t id : selection.search) load(id, false);
  }
  return images;
}

namespace {

// One cell of a master's dense pattern and what became of it.
struct Cell {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  DenseReject reason = DenseReject::kNoTexture;
  double depth = std::numeric_limits<double>::quiet_NaN();
  double sigma_gsd = 0;
  MpgcResult mpgc;
};

// What the sparse model says about a master's depths: its whole range
// (from the sparse points it sees, or that project into it, widened by the
// margin; the options' range where there are too few), and the points
// themselves, bucketed by their master pixel, to bound the search of the
// coarse cells near them.
class SparseDepths {
 public:
  SparseDepths(const Scene& scene,
               const Image& master,
               const DenseOptions& options) {
    const Camera& camera = CameraOf(scene, master);
    std::vector<Eigen::Vector2d> seen_xy, inside_xy;
    std::vector<double> seen, inside;
    for (const auto& [id, point] : scene.points3D) {
      const double depth = (master.cam_from_world * point.xyz).z();
      Eigen::Vector2d pixel;
      if (depth <= 0 || !scene.Project(master, point.xyz, &pixel) ||
          pixel.x() < 0 || pixel.y() < 0 || pixel.x() > camera.width ||
          pixel.y() > camera.height) {
        continue;
      }
      inside.push_back(depth);
      inside_xy.push_back(pixel);
      for (const TrackElement& element : point.track) {
        if (element.image_id != master.image_id) continue;
        seen.push_back(depth);
        seen_xy.push_back(pixel);
        break;
      }
    }
    const bool use_seen = seen.size() >= 10;
    depths_ = use_seen ? seen : inside;
    xy_ = use_seen ? seen_xy : inside_xy;
    if (options.max_depth > 0) {
      min_depth_ = options.min_depth;
      max_depth_ = options.max_depth;
    } else if (depths_.size() < 10) {
      ThrowInputError("master image ",
                      master.name,
                      ": fewer than 10 sparse points of the model lie in it, "
                      "so its depth range is unknown (give min_depth and "
                      "max_depth)");
    } else {
      const double low = Quantile(depths_, 0.02);
      const double high = Quantile(depths_, 0.98);
      // A scene as deep as a tenth of its distance at least: sparse points
      // on one plane facing the master all have the same depth.
      const double margin =
          options.depth_margin * std::max(high - low, 0.1 * high);
      min_depth_ = std::max(low - margin, 0.5 * low);
      max_depth_ = high + margin;
    }
    radius_ = options.sparse_radius_px;
    tolerance_ = options.sparse_tolerance;
    cols_ = static_cast<int>(camera.width / radius_) + 1;
    rows_ = static_cast<int>(camera.height / radius_) + 1;
    buckets_.resize(static_cast<size_t>(cols_) * rows_);
    for (size_t k = 0; k < xy_.size(); ++k) {
      if (depths_[k] < min_depth_ || depths_[k] > max_depth_) continue;
      buckets_[Bucket(xy_[k])].push_back(static_cast<int>(k));
    }
  }

  double min_depth() const { return min_depth_; }
  double max_depth() const { return max_depth_; }

  // The depths of the sparse points within the radius of `xy`, widened by
  // the tolerance (a share of the depth) and clipped to the master's range;
  // the whole range where fewer than three points are near.
  std::pair<double, double> Near(const Eigen::Vector2d& xy) const {
    double low = std::numeric_limits<double>::infinity(), high = 0;
    int count = 0;
    const int bx = static_cast<int>(xy.x() / radius_);
    const int by = static_cast<int>(xy.y() / radius_);
    for (int y = std::max(0, by - 1); y <= std::min(rows_ - 1, by + 1); ++y) {
      for (int x = std::max(0, bx - 1); x <= std::min(cols_ - 1, bx + 1); ++x) {
        for (int k : buckets_[static_cast<size_t>(y) * cols_ + x]) {
          if ((xy_[k] - xy).norm() > radius_) continue;
          low = std::min(low, depths_[k]);
          high = std::max(high, depths_[k]);
          ++count;
        }
      }
    }
    if (count < 3) return {min_depth_, max_depth_};
    return {std::max(min_depth_, low / (1 + tolerance_)),
            std::min(max_depth_, high * (1 + tolerance_))};
  }

 private:
  size_t Bucket(const Eigen::Vector2d& xy) const {
    const int x = std::clamp(static_cast<int>(xy.x() / radius_), 0, cols_ - 1);
    const int y = std::clamp(static_cast<int>(xy.y() / radius_), 0, rows_ - 1);
    return static_cast<size_t>(y) * cols_ + x;
  }

  std::vector<Eigen::Vector2d> xy_;
  std::vector<double> depths_;
  double min_depth_ = 0, max_depth_ = 0;
  double radius_ = 1, tolerance_ = 0;
  int cols_ = 1, rows_ = 1;
  std::vector<std::vector<int>> buckets_;
};

}  // namespace

std::pair<double, double> MasterDepthRange(const Scene& scene,
                                           const Image& master,
                                           const DenseOptions& options) {
  const SparseDepths depths(scene, master, options);
  return {depths.min_depth(), depths.max_depth()};
}

namespace {

// The cells of a master's dense pattern: whole cells inside the border.
void PatternSize(const cv::Mat& gray,
                 const DenseOptions& options,
                 int border,
                 int* cols,
                 int* rows) {
  *cols = std::max(0, (gray.cols - 2 * border) / options.cell_size);
  *rows = std::max(0, (gray.rows - 2 * border) / options.cell_size);
}

// The master's dense pattern: per cell the strongest Moravec point.
std::vector<Cell> DensePattern(const cv::Mat& gray,
                               const DenseOptions& options,
                               int border,
                               int* cols,
                               int* rows) {
  const cv::Mat interest = MoravecInterest(gray, options.moravec_window);
  const int size = options.cell_size;
  PatternSize(gray, options, border, cols, rows);
  std::vector<Cell> cells(static_cast<size_t>(*cols) * *rows);
  for (int cy = 0; cy < *rows; ++cy) {
    for (int cx = 0; cx < *cols; ++cx) {
      Cell& cell = cells[static_cast<size_t>(cy) * *cols + cx];
      float best = -1;
      for (int y = border + cy * size; y < border + (cy + 1) * size; ++y) {
        const float* row = interest.ptr<float>(y);
        for (int x = border + cx * size; x < border + (cx + 1) * size; ++x) {
          if (row[x] > best) {
            best = row[x];
            cell.xy = Eigen::Vector2d(x + 0.5, y + 0.5);
          }
        }
      }
      cell.reason = best >= options.min_interest ? DenseReject::kAccepted
                                                 : DenseReject::kNoTexture;
    }
  }
  return cells;
}

// MPGC for one cell from an approximation of its object point (and of the
// surface normal there, where known): the search views that correlate with
// the master at the approximation, the joint solution, and the precision
// test along the ray.
void SolveCell(const MpgcView& master,
               const std::vector<MpgcView>& search,
               const Ray& ray,
               const Eigen::Vector3d& approximation,
               const std::optional<Eigen::Vector3d>& normal,
               const DenseOptions& options,
               Cell* cell) {
  // Views where the approximation does not correlate at all (the point is
  // hidden there, or lit beyond recognition) are left out of MPGC from the
  // start instead of being found and dropped one re-solution at a time.
  const std::vector<double> view_ncc =
      ViewCorrelations(master,
                       cell->xy,
                       search,
                       approximation,
                       options.search.window_radius,
                       normal);
  std::vector<MpgcView> shown;
  std::vector<int> index;
  for (size_t j = 0; j < search.size(); ++j) {
    if (view_ncc[j] >= options.min_view_ncc) {
      shown.push_back(search[j]);
      index.push_back(static_cast<int>(j));
    }
  }
  cell->mpgc =
      MatchMpgc(master, cell->xy, shown, approximation, options.mpgc, normal);
  for (int& view : cell->mpgc.views) view = index[view];
  for (int& view : cell->mpgc.dropped) view = index[view];
  cell->reason = DenseRejectOf(cell->mpgc.status);
  if (!cell->mpgc.ok()) return;
  const double depth = (master.cam_from_world * cell->mpgc.xyz).z();
  const double gsd = depth / master.camera->MeanFocalLengthPx();
  const double along = std::sqrt(
      std::max(0.0, ray.direction.dot(cell->mpgc.covariance * ray.direction)));
  cell->sigma_gsd = along / gsd;
  if (cell->sigma_gsd > options.max_sigma_gsd) {
    cell->reason = DenseReject::kImprecise;
    return;
  }
  cell->depth = depth;
}

// The master ray of a cell and the cosine of its angle with the optical
// axis (depth = distance * cosine); nullopt with the reason set where there
// is none.
std::optional<std::pair<Ray, double>> CellRay(const MpgcView& master,
                                              Cell* cell) {
  const std::optional<Ray> ray = RayThroughPixel(
      *master.camera, master.cam_from_world, cell->xy, master.frame);
  if (!ray) {
    cell->reason = DenseReject::kMpgcOutside;
    return std::nullopt;
  }
  const double cosine = (master.cam_from_world.rotation * ray->direction).z();
  if (cosine <= 0) {
    cell->reason = DenseReject::kMpgcBehind;
    return std::nullopt;
  }
  return std::make_pair(*ray, cosine);
}

// Approximation by correlation along the ray between two depths, then MPGC.
void MatchCell(const MpgcView& master,
               const std::vector<MpgcView>& search,
               double min_depth,
               double max_depth,
               const DenseOptions& options,
               Cell* cell) {
  const auto ray = CellRay(master, cell);
  if (!ray) return;
  const double cosine = ray->second;
  // The search along the ray in the nearest views only (they are sorted
  // by viewing direction); which of all the views show the point is asked
  // at the approximation.
  const std::vector<MpgcView> nearest(
      search.begin(),
      search.begin() + std::min<size_t>(search.size(), options.num_ray_views));
  const EpipolarSearchResult found = SearchMasterRay(master,
                                                     cell->xy,
                                                     nearest,
                                                     min_depth / cosine,
                                                     max_depth / cosine,
                                                     options.search);
  if (!found.found) {
    cell->reason = DenseReject::kNoApproximation;
    return;
  }
  if (found.ncc - found.second_ncc < options.min_peak_margin) {
    cell->reason = DenseReject::kAmbiguous;
    return;
  }
  SolveCell(master, search, ray->first, found.xyz, std::nullopt, options, cell);
}

// Calls fn(cell) for the accepted cells within `radius` cells of `index`
// (the square around it, the cell itself included).
template <typename Fn>
void ForEachAcceptedAround(const std::vector<Cell>& cells,
                           int cols,
                           int rows,
                           int index,
                           int radius,
                           Fn fn) {
  const int cx = index % cols, cy = index / cols;
  for (int y = std::max(0, cy - radius); y <= std::min(rows - 1, cy + radius);
       ++y) {
    for (int x = std::max(0, cx - radius); x <= std::min(cols - 1, cx + radius);
         ++x) {
      const Cell& cell = cells[static_cast<size_t>(y) * cols + x];
      if (cell.reason == DenseReject::kAccepted) fn(cell);
    }
  }
}

// The accepted cells within `radius` cells of `index`, the cell itself
// left out: per neighbour its row (du, dv, 1/depth) relative to the cell's
// pixel (for PlaneDepth), its depth and its object point.
struct Neighbours {
  std::vector<Eigen::Vector3d> rows_uvw;
  std::vector<double> depths;
  std::vector<Eigen::Vector3d> points;
};

Neighbours AcceptedNeighbours(
    const std::vector<Cell>& cells, int cols, int rows, int index, int radius) {
  const Cell& own = cells[index];
  Neighbours found;
  ForEachAcceptedAround(
      cells, cols, rows, index, radius, [&](const Cell& cell) {
        if (&cell == &own) return;
        const Eigen::Vector2d d = cell.xy - own.xy;
        found.rows_uvw.emplace_back(d.x(), d.y(), 1 / cell.depth);
        found.depths.push_back(cell.depth);
        found.points.push_back(cell.mpgc.xyz);
      });
  return found;
}

// The depth at a cell that the plane of inverse depth, linear in the
// master's pixel coordinates, fitted to the chosen neighbours' rows
// (du, dv, 1/depth) relative to the cell (with five or more, once more
// without those off by more than three robust sigmas) predicts; nullopt
// where the plane is undetermined.
std::optional<double> PlaneDepth(const std::vector<Eigen::Vector3d>& rows_uvw,
                                 std::vector<bool> use) {
  double predicted = 0;
  const int passes = std::count(use.begin(), use.end(), true) >= 5 ? 2 : 1;
  for (int pass = 0; pass < passes; ++pass) {
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < rows_uvw.size(); ++k) {
      if (!use[k]) continue;
      const Eigen::Vector3d a(1, rows_uvw[k].x(), rows_uvw[k].y());
      N += a * a.transpose();
      b += a * rows_uvw[k].z();
    }
    const Eigen::Vector3d plane = N.ldlt().solve(b);
    if (!plane.allFinite()) return std::nullopt;
    predicted = plane(0);
    if (pass + 1 == passes) break;
    std::vector<double> residuals(rows_uvw.size(), 0.0), used;
    for (size_t k = 0; k < rows_uvw.size(); ++k) {
      const Eigen::Vector3d& r = rows_uvw[k];
      residuals[k] =
          std::abs(plane(0) + plane(1) * r.x() + plane(2) * r.y() - r.z());
      if (use[k]) used.push_back(residuals[k]);
    }
    const double limit = 3 * 1.4826 * Median(used);
    std::vector<bool> kept_use(use.size(), false);
    int kept = 0;
    for (size_t k = 0; k < rows_uvw.size(); ++k) {
      kept_use[k] = use[k] && residuals[k] <= limit;
      kept += kept_use[k];
    }
    if (kept < 3) break;
    use = std::move(kept_use);
  }
  if (!(predicted > 0)) return std::nullopt;
  return 1 / predicted;
}

// How far (in depth) a cell misses the plane of the chosen neighbours
// (PlaneDepth); 0 where the plane is undetermined.
double SurfaceMiss(const std::vector<Eigen::Vector3d>& rows_uvw,
                   const std::vector<bool>& use,
                   const Cell& own) {
  const std::optional<double> depth = PlaneDepth(rows_uvw, use);
  return depth ? std::abs(*depth - own.depth) : 0;
}

// A crease or step is judged by the neighbours on the cell's own side
// where there are this many (with 3, on the rendered tower, blunders came
// through with them: RMS 1.10 GSD against 0.88 with 5).
constexpr int kMinSideNeighbors = 5;

// Whether an accepted cell's depth agrees with the surface of its accepted
// neighbours (within `radius` cells): it is on the surface when it lies
// within off_surface_gsd ground sampling distances of their plane
// (SurfaceMiss) or, at a crease or a step, of the plane of the
// kMinSideNeighbors or more of them on its own side. A cell with fewer than
// min_neighbors accepted neighbours is isolated: nothing confirms it, and
// the blunders that MPGC lets through are mostly such (on the rendered
// tower, most of those beyond 20 GSD).
DenseReject SurfaceVerdict(const std::vector<Cell>& cells,
                           int cols,
                           int rows,
                           int index,
                           const DenseOptions& options,
                           double gsd_per_depth) {
  const Cell& own = cells[index];
  const double tolerance = options.off_surface_gsd * own.depth * gsd_per_depth;
  const Neighbours neighbours = AcceptedNeighbours(
      cells, cols, rows, index, options.surface_radius_cells);
  const std::vector<Eigen::Vector3d>& rows_uvw = neighbours.rows_uvw;
  std::vector<double> miss;  // |depth - own depth| / (1 + cells)
  for (size_t k = 0; k < rows_uvw.size(); ++k) {
    const double cells_away =
        Eigen::Vector2d(rows_uvw[k].x(), rows_uvw[k].y()).norm() /
        options.cell_size;
    miss.push_back(std::abs(neighbours.depths[k] - own.depth) /
                   (1 + cells_away));
  }
  if (static_cast<int>(rows_uvw.size()) < options.min_neighbors) {
    return DenseReject::kIsolated;
  }
  // The plane of all neighbours, robustly; where the cell lies at a crease
  // or a step (two surfaces among its neighbours, neither of them a clear
  // majority), the plane of those neighbours on its own side: near its
  // depth, allowing for the slope of an oblique surface.
  if (SurfaceMiss(rows_uvw, std::vector<bool>(rows_uvw.size(), true), own) <=
      tolerance) {
    return DenseReject::kAccepted;
  }
  std::vector<bool> near(rows_uvw.size());
  int num_near = 0;
  for (size_t k = 0; k < miss.size(); ++k) {
    near[k] = miss[k] <= tolerance;
    num_near += near[k];
  }
  if (num_near >= std::max(kMinSideNeighbors, options.min_neighbors) &&
      SurfaceMiss(rows_uvw, near, own) <= tolerance) {
    return DenseReject::kAccepted;
  }
  return DenseReject::kOffSurface;
}

// The unit normal of the plane through `points` (least squares), facing
// `towards`; nullopt for fewer than four points or points near a line.
std::optional<Eigen::Vector3d> PlaneNormal(
    const std::vector<Eigen::Vector3d>& points,
    const Eigen::Vector3d& towards) {
  if (points.size() < 4) return std::nullopt;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= points.size();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    scatter += (p - mean) * (p - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  // Points along a line (a row of cells) leave the plane turning about it.
  if (!(eigen.eigenvalues()(1) > 0.05 * eigen.eigenvalues()(2))) {
    return std::nullopt;
  }
  Eigen::Vector3d normal = eigen.eigenvectors().col(0);
  if (normal.dot(towards) < 0) normal = -normal;
  return normal;
}

// The accepted object points of the cells within `radius` of `index`.
std::vector<Eigen::Vector3d> AcceptedPointsAround(
    const std::vector<Cell>& cells, int cols, int rows, int index, int radius) {
  std::vector<Eigen::Vector3d> points;
  ForEachAcceptedAround(
      cells, cols, rows, index, radius, [&](const Cell& cell) {
        points.push_back(cell.mpgc.xyz);
      });
  return points;
}

// The unit normal of the plane through the accepted points of the cells
// around `index` (the nearest ring that determines one), facing the
// master's projection centre.
Eigen::Vector3f CellNormal(const std::vector<Cell>& cells,
                           int cols,
                           int rows,
                           int index,
                           const Eigen::Vector3d& centre) {
  const Eigen::Vector3d towards = (centre - cells[index].mpgc.xyz).normalized();
  for (int radius = 1; radius <= 2; ++radius) {
    const std::optional<Eigen::Vector3d> normal = PlaneNormal(
        AcceptedPointsAround(cells, cols, rows, index, radius), towards);
    if (normal) return normal->cast<float>();
  }
  return towards.cast<float>();
}

Eigen::Matrix<uint8_t, 3, 1> ColorAt(const cv::Mat& bgr,
                                     const Eigen::Vector2d& xy) {
  const int x = std::clamp(static_cast<int>(xy.x()), 0, bgr.cols - 1);
  const int y = std::clamp(static_cast<int>(xy.y()), 0, bgr.rows - 1);
  const cv::Vec3b& pixel = bgr.at<cv::Vec3b>(y, x);
  return Eigen::Matrix<uint8_t, 3, 1>(pixel[2], pixel[1], pixel[0]);
}

// Blunders that MPGC's own tests let through: off the surface of their
// neighbours, or isolated (SurfaceVerdict; judged all at once, so that one
// blunder does not change the verdict on another).
void RejectOffSurface(int cols,
                      int rows,
                      const DenseOptions& options,
                      double gsd_per_depth,
                      std::vector<Cell>* cells) {
  std::vector<std::pair<int, DenseReject>> verdicts;
  for (int i = 0; i < static_cast<int>(cells->size()); ++i) {
    if ((*cells)[i].reason != DenseReject::kAccepted) continue;
    const DenseReject verdict =
        SurfaceVerdict(*cells, cols, rows, i, options, gsd_per_depth);
    if (verdict != DenseReject::kAccepted) verdicts.push_back({i, verdict});
  }
  for (const auto& [i, verdict] : verdicts) (*cells)[i].reason = verdict;
}

// Whether a cell without a point may get one from the surface around it:
// it has texture and lies in the master, but the search along its ray, MPGC
// or a test after it failed.
bool Growable(DenseReject reason) {
  switch (reason) {
    case DenseReject::kNoApproximation:
    case DenseReject::kAmbiguous:
    case DenseReject::kMpgcTooFewViews:
    case DenseReject::kMpgcNotConverged:
    case DenseReject::kMpgcSingular:
    case DenseReject::kImprecise:
    case DenseReject::kOffSurface:
    case DenseReject::kIsolated:
      return true;
    default:
      return false;
  }
}

// Region growing (as Otto and Chau 1989 grow stereo matches from seeds): a
// cell without a point whose accepted neighbours (min_neighbors or more
// within surface_radius_cells) determine the surface there gets its
// approximation from them, the depth from the plane of their inverse depths
// (PlaneDepth) and the search patches' shapes from the plane through their
// object points, and MPGC starts from it without a search along the ray.
// Where the correlation along the ray found nothing (a face seen obliquely,
// where the window shaped for a plane facing the master does not fit),
// MPGC's larger patches, shaped by the surface, often still do. Passes
// repeat while they add points; a cell is tried again only when more
// neighbours support it than at its last try; after each pass the
// off-surface test runs again over all points, so that a grown blunder
// seeds nothing.
void GrowSurface(const MpgcView& master,
                 const std::vector<MpgcView>& search,
                 int cols,
                 int rows,
                 const DenseOptions& options,
                 const Eigen::Vector3d& master_centre,
                 double gsd_per_depth,
                 std::vector<Cell>* cells_ptr) {
  std::vector<Cell>& cells = *cells_ptr;
  DenseOptions grow_options = options;
  grow_options.mpgc.min_search_views = options.growth_min_search_views;
  std::vector<int> tried_support(cells.size(), 0);
  for (int pass = 0; pass < options.max_growth_passes; ++pass) {
    std::vector<int> todo;
    std::vector<int> support;
    for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
      if (!Growable(cells[i].reason)) continue;
      int count = 0;
      ForEachAcceptedAround(
          cells, cols, rows, i, options.surface_radius_cells, [&](const Cell&) {
            ++count;
          });
      if (count < std::max(kMinSideNeighbors, options.min_neighbors) ||
          count <= tried_support[i]) {
        continue;
      }
      todo.push_back(i);
      support.push_back(count);
    }
    if (todo.empty()) break;
    // Each pass reads the cells as they were before it and writes its
    // results afterwards: threads never read a cell another one writes.
    std::vector<Cell> grown(todo.size());
    ParallelFor(static_cast<int>(todo.size()), options.num_threads, [&](int k) {
      const int index = todo[k];
      Cell& cell = grown[k];
      cell = cells[index];
      cell.mpgc = MpgcResult();
      cell.depth = std::numeric_limits<double>::quiet_NaN();
      const Neighbours neighbours = AcceptedNeighbours(
          cells, cols, rows, index, options.surface_radius_cells);
      const std::optional<double> depth =
          PlaneDepth(neighbours.rows_uvw,
                     std::vector<bool>(neighbours.rows_uvw.size(), true));
      const auto ray = CellRay(master, &cell);
      if (!depth || !ray) return;
      const Eigen::Vector3d approximation =
          ray->first.origin + ray->first.direction * (*depth / ray->second);
      const std::optional<Eigen::Vector3d> normal = PlaneNormal(
          neighbours.points, (master_centre - approximation).normalized());
      SolveCell(master,
                search,
                ray->first,
                approximation,
                normal,
                grow_options,
                &cell);
      // MPGC's pull-in range is wider than the off-surface test's tolerance:
      // a grown point that left the surface it was predicted from is not
      // confirmed by it.
      if (cell.reason == DenseReject::kAccepted &&
          std::abs(cell.depth - *depth) >
              options.off_surface_gsd * *depth * gsd_per_depth) {
        cell.reason = DenseReject::kOffSurface;
      }
    });
    size_t added = 0;
    for (size_t k = 0; k < todo.size(); ++k) {
      tried_support[todo[k]] = support[k];
      // A cell keeps the reason of its first failure unless it now has a
      // point: what stopped it first is what its picture should show.
      if (grown[k].reason != DenseReject::kAccepted) continue;
      cells[todo[k]] = grown[k];
      ++added;
    }
    RejectOffSurface(cols, rows, options, gsd_per_depth, &cells);
    if (added == 0) break;
  }
}

// A master's accepted depths on its cell grid (NaN where none).
struct DepthGrid {
  MpgcView view;
  int cols = 0, rows = 0, border = 0, cell_size = 1;
  std::vector<float> depth;
};

// The visibility test against the surface the masters found (MPGC's
// occlusion detection across masters): each point is projected into the
// other masters; where one has accepted points in the cells around the
// projection, the point either lies on that surface (support), in front of
// it (it would hide what that master saw: a conflict), or behind it while
// matched in that master's image (it cannot have been seen there: a
// conflict). A point with more conflicts than support is rejected.
// Tolerance: off_surface_gsd ground sampling distances of that master.
std::vector<bool> ConsistentWithOtherMasters(
    const std::vector<Eigen::Vector3d>& points,
    const std::vector<int>& master_of,
    const std::vector<std::vector<image_t>>& seen,
    const std::vector<DepthGrid>& grids,
    const std::vector<MasterSelection>& masters,
    const DenseOptions& options) {
  // One byte per point: threads write their own points (a vector<bool>
  // packs neighbours into one word).
  std::vector<char> verdict(points.size(), 1);
  ParallelFor(static_cast<int>(points.size()), options.num_threads, [&](int i) {
    int support = 0, conflicts = 0;
    for (size_t g = 0; g < grids.size(); ++g) {
      if (static_cast<int>(g) == master_of[i]) continue;
      const DepthGrid& grid = grids[g];
      if (grid.view.camera == nullptr) continue;  // a skipped master
      const Eigen::Vector3d in_cam = grid.view.cam_from_world * points[i];
      Eigen::Vector2d pixel;
      if (!(in_cam.z() > 0) ||
          !grid.view.camera->ImgFromCam(in_cam, &pixel, grid.view.frame)) {
        continue;
      }
      const int cx = static_cast<int>(
          std::floor((pixel.x() - grid.border) / grid.cell_size));
      const int cy = static_cast<int>(
          std::floor((pixel.y() - grid.border) / grid.cell_size));
      float nearest = std::numeric_limits<float>::quiet_NaN();
      float front = std::numeric_limits<float>::infinity(), back = 0;
      for (int y = cy - 1; y <= cy + 1; ++y) {
        for (int x = cx - 1; x <= cx + 1; ++x) {
          if (x < 0 || y < 0 || x >= grid.cols || y >= grid.rows) continue;
          const float d = grid.depth[static_cast<size_t>(y) * grid.cols + x];
          if (!std::isfinite(d)) continue;
          if (!std::isfinite(nearest) ||
              std::abs(d - in_cam.z()) < std::abs(nearest - in_cam.z())) {
            nearest = d;
          }
          front = std::min(front, d);
          back = std::max(back, d);
        }
      }
      if (!std::isfinite(nearest)) continue;
      const double tolerance = options.off_surface_gsd * in_cam.z() /
                               grid.view.camera->MeanFocalLengthPx();
      if (std::abs(nearest - in_cam.z()) <= tolerance) {
        ++support;
      } else if (in_cam.z() < front - tolerance) {
        ++conflicts;
      } else if (in_cam.z() > back + tolerance &&
                 std::find(seen[i].begin(), seen[i].end(), masters[g].master) !=
                     seen[i].end()) {
        ++conflicts;
      }
    }
    verdict[i] = conflicts <= support;
  });
  return std::vector<bool>(verdict.begin(), verdict.end());
}

}  // namespace

PointCloud DenseReconstruct(const Scene& scene,
                            const std::map<image_t, DenseImage>& images,
                            const std::vector<MasterSelection>& masters,
                            const DenseOptions& options,
                            DenseReport* report,
                            std::vector<std::vector<image_t>>* visibility) {
  options.Check();
  const Timer total_timer;
  DenseReport local_report;
  if (report == nullptr) report = &local_report;
  *report = DenseReport();
  const auto view_of = [&](image_t id) {
    const Image& image = scene.images.at(id);
    MpgcView view;
    view.image = &images.at(id).gray;
    view.camera = &CameraOf(scene, image);
    view.cam_from_world = image.cam_from_world;
    view.frame = image.frame ? &*image.frame : nullptr;
    return view;
  };
  const int border = options.mpgc.lsm.patch_radius + 2;

  // What each master has to work with: its search images that could be
  // read, and its depth range; a master without them is skipped with the
  // reason, and the others are matched. One progress display over the
  // masters matched: the cells each pattern will have follow from the
  // image size.
  std::vector<std::vector<image_t>> search_ids(masters.size());
  std::vector<std::optional<SparseDepths>> depths(masters.size());
  std::vector<std::string> skipped(masters.size());
  size_t total_cells = 0;
  for (size_t m = 0; m < masters.size(); ++m) {
    const MasterSelection& selection = masters[m];
    for (image_t id : selection.search) {
      if (images.count(id) > 0) search_ids[m].push_back(id);
    }
    if (selection.search.empty()) {
      skipped[m] = StrCat("no other image within --max_search_angle_deg ",
                          options.max_search_angle_deg,
                          " of its viewing direction");
    } else if (images.count(selection.master) == 0) {
      skipped[m] = "its image could not be read";
    } else if (search_ids[m].empty()) {
      skipped[m] = "none of its search images could be read";
    } else {
      try {
        depths[m].emplace(scene, scene.images.at(selection.master), options);
      } catch (const InputError& error) {
        skipped[m] = error.what();
      }
    }
    if (!skipped[m].empty()) continue;
    int cols = 0, rows = 0;
    PatternSize(
        images.at(selection.master).gray, options, border, &cols, &rows);
    total_cells += static_cast<size_t>(cols) * rows;
  }
  if (std::all_of(skipped.begin(), skipped.end(), [](const std::string& why) {
        return !why.empty();
      })) {
    std::string reasons;
    for (size_t m = 0; m < masters.size(); ++m) {
      reasons += StrCat(m == 0 ? "" : "; ",
                        scene.images.at(masters[m].master).name,
                        ": ",
                        skipped[m]);
    }
    ThrowInputError("no master image can be matched (", reasons, ")");
  }
  Progress progress("dense", total_cells, "cells");

  // Each master's accepted depths on its cell grid, for the test of every
  // point against the other masters' surfaces at the end.
  std::vector<DepthGrid> grids(masters.size());
  std::vector<std::vector<image_t>> seen;  // per point: its images
  std::vector<int> master_of;              // per point: index into masters
  std::vector<int> cell_of;                // per point: its master's cell
  PointCloud cloud;
  DensePointAttributes attributes;
  for (size_t m = 0; m < masters.size(); ++m) {
    const Timer timer;
    const MasterSelection& selection = masters[m];
    const Image& master_image = scene.images.at(selection.master);
    DenseMasterReport master_report;
    master_report.master = selection.master;
    master_report.name = master_image.name;
    if (!skipped[m].empty()) {
      master_report.search = selection.search;  // those it would have had
      master_report.skipped = skipped[m];
      report->masters.push_back(std::move(master_report));
      continue;
    }
    const MpgcView master = view_of(selection.master);
    std::vector<MpgcView> search;
    for (image_t id : search_ids[m]) search.push_back(view_of(id));
    const SparseDepths& sparse = *depths[m];
    const double min_depth = sparse.min_depth(), max_depth = sparse.max_depth();

    int cols = 0, rows = 0;
    std::vector<Cell> cells = DensePattern(
        images.at(selection.master).gray, options, border, &cols, &rows);
    const int step = options.coarse_step;
    const auto is_coarse = [&](int index) {
      return (index % cols) % step == 0 && (index / cols) % step == 0;
    };
    std::vector<int> coarse, fine;
    for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
      if (cells[i].reason != DenseReject::kAccepted) {
        progress.Add();
        continue;
      }
      (is_coarse(i) ? coarse : fine).push_back(i);
    }
    // Coarse cells within the depths of the sparse points near them.
    ParallelFor(
        static_cast<int>(coarse.size()), options.num_threads, [&](int k) {
          Cell& cell = cells[coarse[k]];
          const auto [low, high] = sparse.Near(cell.xy);
          MatchCell(master, search, low, high, options, &cell);
          progress.Add();
        });
    // Every other cell inside the band of the coarse points around it.
    const int reach = options.band_radius_cells * step;
    ParallelFor(static_cast<int>(fine.size()), options.num_threads, [&](int k) {
      Cell& cell = cells[fine[k]];
      const int cx = fine[k] % cols, cy = fine[k] / cols;
      double low = std::numeric_limits<double>::infinity(), high = 0;
      for (int y = (std::max(0, cy - reach) + step - 1) / step * step;
           y <= std::min(rows - 1, cy + reach);
           y += step) {
        for (int x = (std::max(0, cx - reach) + step - 1) / step * step;
             x <= std::min(cols - 1, cx + reach);
             x += step) {
          const double depth = cells[static_cast<size_t>(y) * cols + x].depth;
          if (std::isfinite(depth)) {
            low = std::min(low, depth);
            high = std::max(high, depth);
          }
        }
      }
      if (high > 0) {
        MatchCell(master,
                  search,
                  low / (1 + options.band_tolerance),
                  high * (1 + options.band_tolerance),
                  options,
                  &cell);
      } else {
        cell.reason = DenseReject::kNoApproximation;
      }
      progress.Add();
    });

    const double gsd_per_depth = 1 / master.camera->MeanFocalLengthPx();
    RejectOffSurface(cols, rows, options, gsd_per_depth, &cells);
    GrowSurface(master,
                search,
                cols,
                rows,
                options,
                master_image.cam_from_world.Center(),
                gsd_per_depth,
                &cells);
    DepthGrid& grid = grids[m];
    grid.view = master;
    grid.cols = cols;
    grid.rows = rows;
    grid.border = border;
    grid.cell_size = options.cell_size;
    grid.depth.assign(cells.size(), std::numeric_limits<float>::quiet_NaN());
    for (size_t i = 0; i < cells.size(); ++i) {
      if (cells[i].reason == DenseReject::kAccepted) {
        grid.depth[i] = static_cast<float>(cells[i].depth);
      }
    }

    master_report.search = search_ids[m];
    master_report.min_depth = min_depth;
    master_report.max_depth = max_depth;
    master_report.num_cells = cells.size();
    master_report.reasons = cv::Mat(rows, cols, CV_8U);
    for (size_t i = 0; i < cells.size(); ++i) {
      master_report.reasons.at<uint8_t>(static_cast<int>(i)) =
          static_cast<uint8_t>(cells[i].reason);
    }
    master_report.border = border;
    master_report.cell_size = options.cell_size;
    const cv::Mat& color = images.at(selection.master).color;
    const Eigen::Vector3d centre = master_image.cam_from_world.Center();
    std::vector<double> sigmas;
    for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
      const Cell& cell = cells[i];
      ++master_report.rejects[static_cast<int>(cell.reason)];
      if (cell.reason != DenseReject::kAccepted) continue;
      const MpgcResult& result = cell.mpgc;
      cloud.positions.push_back(result.xyz);
      cloud.normals.push_back(CellNormal(cells, cols, rows, i, centre));
      cloud.colors.push_back(color.empty()
                                 ? Eigen::Matrix<uint8_t, 3, 1>(128, 128, 128)
                                 : ColorAt(color, cell.xy));
      const Eigen::Vector3d sigma = result.StdDev();
      attributes.sx.push_back(sigma.x());
      // Across the surface, from the full covariance: the figure that
      // judges a point against its neighbours' surface (and the truth).
      const Eigen::Vector3d normal = cloud.normals.back().cast<double>();
      attributes.s_normal.push_back(
          std::sqrt(std::max(0.0, normal.dot(result.covariance * normal))));
      attributes.sy.push_back(sigma.y());
      attributes.sz.push_back(sigma.z());
      attributes.num_images.push_back(1 + result.views.size());
      attributes.master_ids.push_back(selection.master);
      attributes.sigma0.push_back(result.sigma0);
      attributes.correlation.push_back(
          std::accumulate(
              result.correlation.begin(), result.correlation.end(), 0.0) /
          std::max<size_t>(1, result.correlation.size()));
      sigmas.push_back(cell.sigma_gsd);
      std::vector<image_t>& images_of_point = seen.emplace_back();
      images_of_point.push_back(selection.master);
      for (int view : result.views) {
        images_of_point.push_back(search_ids[m][view]);
      }
      master_of.push_back(static_cast<int>(m));
      cell_of.push_back(i);
    }
    master_report.num_points =
        master_report.rejects[static_cast<int>(DenseReject::kAccepted)];
    master_report.median_sigma_gsd = Median(sigmas);
    master_report.seconds = timer.Seconds();
    report->num_points += master_report.num_points;
    report->num_cells += master_report.num_cells;
    report->masters.push_back(std::move(master_report));
  }
  progress.Finish();
  const std::vector<bool> keep = ConsistentWithOtherMasters(
      cloud.positions, master_of, seen, grids, masters, options);
  attributes.MoveInto(&cloud);

  for (size_t i = 0; i < keep.size(); ++i) {
    if (keep[i]) continue;
    DenseMasterReport& master = report->masters[master_of[i]];
    --master.rejects[static_cast<int>(DenseReject::kAccepted)];
    ++master.rejects[static_cast<int>(DenseReject::kInconsistent)];
    master.reasons.at<uint8_t>(cell_of[i]) =
        static_cast<uint8_t>(DenseReject::kInconsistent);
    --master.num_points;
    --report->num_points;
  }
  cloud.Filter(keep);
  if (visibility != nullptr) {
    for (size_t i = 0; i < seen.size(); ++i) {
      if (keep[i]) visibility->push_back(std::move(seen[i]));
    }
  }
  report->seconds = total_timer.Seconds();
  return cloud;
}

void DensePointAttributes::MoveInto(PointCloud* cloud) {
  cloud->AddAttribute("sx", PlyScalarType::kFloat).values = std::move(sx);
  cloud->AddAttribute("sy", PlyScalarType::kFloat).values = std::move(sy);
  cloud->AddAttribute("sz", PlyScalarType::kFloat).values = std::move(sz);
  cloud->AddAttribute("s_normal", PlyScalarType::kFloat).values =
      std::move(s_normal);
  cloud->AddAttribute("num_images", PlyScalarType::kUChar).values =
      std::move(num_images);
  cloud->AddAttribute("master_id", PlyScalarType::kInt).values =
      std::move(master_ids);
  cloud->AddAttribute("sigma0", PlyScalarType::kFloat).values =
      std::move(sigma0);
  cloud->AddAttribute("correlation", PlyScalarType::kFloat).values =
      std::move(correlation);
}

void AddUnmodelledSigma(const DenseOptions& options,
                        PointCloud* cloud,
                        DenseReport* report) {
  // Without MPGC (refine off) the points state no precision (zeros). The
  // paper mode's points lie a cell apart: their nearest neighbours span
  // relief that no quadric follows, and the estimate takes it for error
  // (rendered tower, paper mode: 4.5 mm added, the true errors then 0.59
  // times the stated sigmas, against 1.48 without).
  if (!options.add_unmodelled_sigma || !options.refine ||
      options.mode != DenseMode::kMultiView) {
    return;
  }
  const double added =
      EstimateUnmodelledSigma(*cloud,
                              SurfaceFitEditOptions().num_neighbors,
                              options.num_threads,
                              "dense cloud");
  report->added_sigma = added;
  if (added == 0) return;
  for (const char* name : {"sx", "sy", "sz", "s_normal"}) {
    if (PointAttribute* attribute = cloud->FindAttribute(name)) {
      for (double& s : attribute->values) s = std::hypot(s, added);
    }
  }
}

std::string DenseReport::Summary() const {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  const bool pixels = mode == DenseMode::kMultiView;
  const char* cells = pixels ? " pixels" : " cells";
  std::array<size_t, static_cast<int>(DenseReject::kNumReasons)> rejects{};
  for (const DenseMasterReport& master : masters) {
    if (!master.skipped.empty()) {
      out << "  master " << master.name << ": skipped, " << master.skipped
          << "\n";
      continue;
    }
    out.precision(2);
    out << "  master " << master.name << " (" << master.search.size()
        << (pixels ? " source views" : " search images") << ", depth "
        << master.min_depth << " to " << master.max_depth
        << "): " << master.num_points << " points of " << master.num_cells
        << cells << ", median sigma along the ray ";
    out.precision(2);
    out << master.median_sigma_gsd << " GSD, ";
    out.precision(1);
    out << master.seconds << " s\n";
    for (size_t r = 0; r < rejects.size(); ++r) rejects[r] += master.rejects[r];
  }
  out << "  rejected:";
  for (size_t r = 1; r < rejects.size(); ++r) {
    if (rejects[r] > 0) {
      out << " " << DenseRejectName(static_cast<DenseReject>(r)) << " "
          << rejects[r];
    }
  }
  out.precision(0);
  out << "\n"
      << num_points << " points from " << masters.size() << " masters, "
      << num_cells << cells << " in ";
  out.precision(1);
  out << seconds << " s (";
  if (pixels) {
    out << "depth maps " << propagation_seconds << " s, fusion "
        << fusion_seconds << " s, MPGC " << mpgc_seconds << " s; ";
  }
  out.precision(0);
  out << CellsPerSecond() << cells << "/s, " << PointsPerSecond()
      << " points/s)";
  if (added_sigma > 0) {
    out.precision(5);
    out << "\n  stated sigmas include " << added_sigma << " object units"
        << " in quadrature: the errors MPGC's model leaves out, from the "
           "cloud's scatter about its local surface";
  }
  return out.str();
}

namespace {

// BGR colours of the reasons in RejectMap: green where a point was found,
// none where there is no texture, cold colours where there was no
// approximation, warm ones where MPGC or a later test rejected it.
std::optional<cv::Scalar> ReasonColor(DenseReject reason) {
  switch (reason) {
    case DenseReject::kAccepted:
      return cv::Scalar(60, 200, 60);
    case DenseReject::kNoApproximation:
      return cv::Scalar(200, 90, 30);
    case DenseReject::kAmbiguous:
      return cv::Scalar(200, 200, 40);
    case DenseReject::kImprecise:
      return cv::Scalar(40, 220, 240);
    case DenseReject::kOffSurface:
      return cv::Scalar(220, 60, 220);
    case DenseReject::kIsolated:
      return cv::Scalar(160, 90, 140);
    case DenseReject::kInconsistent:
      return cv::Scalar(255, 255, 255);
    case DenseReject::kMerged:
      return cv::Scalar(150, 230, 150);
    case DenseReject::kDepthEdge:
      return cv::Scalar(120, 120, 120);
    case DenseReject::kNoTexture:
    case DenseReject::kNumReasons:
      return std::nullopt;
    default:  // the MPGC statuses
      return cv::Scalar(40, 40, 230);
  }
}

}  // namespace

cv::Mat RejectMap(const DenseMasterReport& master, const cv::Mat& color) {
  cv::Mat picture;
  color.convertTo(picture, CV_8UC3, 0.5);  // dimmed: the cells stand out
  // The cells' colours painted over a copy, blended back once (where
  // nothing was painted the blend leaves the picture as it was).
  cv::Mat painted = picture.clone();
  const int size = master.cell_size;
  for (int cy = 0; cy < master.reasons.rows; ++cy) {
    for (int cx = 0; cx < master.reasons.cols; ++cx) {
      const std::optional<cv::Scalar> c = ReasonColor(
          static_cast<DenseReject>(master.reasons.at<uint8_t>(cy, cx)));
      if (!c) continue;
      cv::rectangle(
          painted,
          cv::Rect(
              master.border + cx * size, master.border + cy * size, size, size),
          *c,
          cv::FILLED);
    }
  }
  cv::addWeighted(picture, 0.35, painted, 0.65, 0, picture);
  // Legend: the reasons that occur, with their counts.
  const double scale = std::max(0.5, picture.cols / 2400.0);
  const int line = static_cast<int>(std::lround(24 * scale));
  int y = line;
  for (int r = 0; r < static_cast<int>(DenseReject::kNumReasons); ++r) {
    const DenseReject reason = static_cast<DenseReject>(r);
    if (master.rejects[r] == 0) continue;
    cv::rectangle(picture,
                  cv::Rect(line / 2, y - line + 6, line - 6, line - 6),
                  ReasonColor(reason).value_or(cv::Scalar(128, 128, 128)),
                  cv::FILLED);
    cv::putText(picture,
                StrCat(DenseRejectName(reason), " ", master.rejects[r]),
                cv::Point(line * 3 / 2, y),
                cv::FONT_HERSHEY_SIMPLEX,
                0.6 * scale,
                cv::Scalar(255, 255, 255),
                std::max(1, static_cast<int>(scale)),
                cv::LINE_AA);
    y += line;
  }
  return picture;
}

nlohmann::ordered_json DenseReportJson(const DenseReport& report,
                                       const DenseOptions& options) {
  nlohmann::ordered_json json;
  json["num_points"] = report.num_points;
  json["num_cells"] = report.num_cells;
  json["seconds"] = report.seconds;
  json["cells_per_second"] = report.CellsPerSecond();
  json["points_per_second"] = report.PointsPerSecond();
  json["mode"] = options.mode == DenseMode::kPaper ? "paper" : "multiview";
  json["added_sigma"] = report.added_sigma;
  if (options.mode == DenseMode::kPaper) {
    json["cell_size"] = options.cell_size;
  } else {
    json["propagation_seconds"] = report.propagation_seconds;
    json["fusion_seconds"] = report.fusion_seconds;
    json["mpgc_seconds"] = report.mpgc_seconds;
  }
  json["masters"] = nlohmann::ordered_json::array();
  for (const DenseMasterReport& master : report.masters) {
    nlohmann::ordered_json entry;
    entry["image_id"] = master.master;
    entry["name"] = master.name;
    entry["search_image_ids"] = master.search;
    if (!master.skipped.empty()) entry["skipped"] = master.skipped;
    entry["min_depth"] = master.min_depth;
    entry["max_depth"] = master.max_depth;
    entry["num_cells"] = master.num_cells;
    entry["num_points"] = master.num_points;
    entry["median_sigma_gsd"] = master.median_sigma_gsd;
    entry["seconds"] = master.seconds;
    nlohmann::ordered_json rejects = nlohmann::ordered_json::object();
    for (size_t r = 1; r < master.rejects.size(); ++r) {
      rejects[DenseRejectName(static_cast<DenseReject>(r))] = master.rejects[r];
    }
    entry["rejected"] = rejects;
    json["masters"].push_back(entry);
  }
  return json;
}

}  // namespace bayon
