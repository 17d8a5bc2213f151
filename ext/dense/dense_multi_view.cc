// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon dense` in its default mode: depth maps for every photograph, fused,
// then MPGC for every point (dense.h).
#include "ext/adjustment/triangulation.h"
#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/statistics.h"
#include "ext/dense/dense.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>
#include <set>

namespace bayon {
namespace {

// The smallest whole factor that brings the longer side to max_image_size.
int Downscale(const Camera& camera, int max_image_size) {
  const int longer = static_cast<int>(std::max(camera.width, camera.height));
  return std::max(1, (longer + max_image_size - 1) / max_image_size);
}

struct MasterState {
  std::vector<image_t> sources;  // those that could be read
  std::string skipped;
  double min_depth = 0, max_depth = 0;
  DepthMap map;
  double seconds = 0;
};

// The steps of DenseReconstructMultiView, over the state they share: the
// working views, each master's depth map, the fused points and what MPGC
// made of them.
class MultiViewReconstruction {
 public:
  MultiViewReconstruction(const Scene& scene,
                          const std::string& image_path,
                          const std::vector<MasterSelection>& masters,
                          const DenseOptions& options)
      : scene_(scene),
        image_path_(image_path),
        masters_(masters),
        options_(options),
        states_(masters.size()) {}

  // Every photograph once, kept at the depth maps' size (a source that is
  // not itself a master as well). Photographs that cannot be read go into
  // `unreadable`, or without it stop the run.
  void LoadViews(std::map<image_t, std::string>* unreadable);
  // Which masters can be matched, from which sources, over which depths;
  // refuses a run in which none can.
  void PlanMasters();
  // The depth maps, one master after the other (each in parallel).
  void EstimateDepthMaps();
  // Fusion over the masters that were matched; the depth maps are freed.
  void Fuse();
  // MPGC's search images per fused point: the masters that confirmed it,
  // the master's sources first; num_source_views at most.
  void ChooseSearchImages();
  // MPGC at full size, master by master (the fused points are in master
  // order), over the masters that confirmed each point.
  void RefineByMpgc();
  // The cloud, and per master what became of its pixels.
  PointCloud MakeCloud(DenseReport* report,
                       std::vector<std::vector<image_t>>* visibility);

 private:
  // MPGC on the fused points [begin, end), all of one master, with the
  // full-size photographs they need.
  void RefineMaster(size_t begin,
                    size_t end,
                    const MpgcOptions& mpgc,
                    std::map<image_t, cv::Mat>* resident);
  // Per matched master, the reasons map from the fusion's verdicts.
  void ReportFusionVerdicts(DenseReport* report) const;

  const Scene& scene_;
  const std::string& image_path_;
  const std::vector<MasterSelection>& masters_;
  const DenseOptions& options_;
  std::map<image_t, PinholeView> views_;
  std::vector<MasterState> states_;
  // The matched masters (indices into masters_) and their views.
  std::vector<int> matched_;
  std::vector<const PinholeView*> matched_views_;
  std::vector<std::vector<FusionVerdict>> verdicts_;
  std::vector<FusedPoint> fused_;
  std::vector<DenseReject> verdict_of_;
  std::vector<MpgcResult> results_;
  std::vector<std::vector<image_t>> search_of_;
};

void MultiViewReconstruction::LoadViews(
    std::map<image_t, std::string>* unreadable) {
  std::set<image_t> needed;
  for (const MasterSelection& selection : masters_) {
    needed.insert(selection.master);
    needed.insert(selection.search.begin(), selection.search.end());
  }
  const std::vector<image_t> ids(needed.begin(), needed.end());
  std::map<image_t, std::string> errors;
  std::mutex mutex;
  ParallelFor(static_cast<int>(ids.size()), options_.num_threads, [&](int k) {
    const image_t id = ids[k];
    const Image& image = scene_.images.at(id);
    const Camera& camera = scene_.cameras.at(image.camera_id);
    try {
      const DenseImage full = LoadDenseImage(
          scene_, id, image_path_, options_.highpass_sigma_px, true);
      PinholeView view =
          MakePinholeView(camera,
                          image.frame ? &*image.frame : nullptr,
                          image.cam_from_world,
                          full.gray,
                          full.color,
                          Downscale(camera, options_.max_image_size));
      const std::lock_guard<std::mutex> lock(mutex);
      views_.emplace(id, std::move(view));
    } catch (const InputError& error) {
      const std::lock_guard<std::mutex> lock(mutex);
      errors.emplace(id, error.what());
    }
  });
  if (!errors.empty() && unreadable == nullptr) {
    ThrowInputError(errors.begin()->second);
  }
  if (unreadable != nullptr) unreadable->insert(errors.begin(), errors.end());
}

void MultiViewReconstruction::PlanMasters() {
  for (size_t m = 0; m < masters_.size(); ++m) {
    MasterState& state = states_[m];
    const MasterSelection& selection = masters_[m];
    if (selection.search.empty()) {
      state.skipped = StrCat(
          "no other image sees what it looks at from between "
          "min_triangulation_angle_deg and max_search_angle_deg (",
          options_.min_triangulation_angle_deg,
          " to ",
          options_.max_search_angle_deg,
          " deg) away");
    } else if (views_.count(selection.master) == 0) {
      state.skipped = "its image could not be read";
    } else {
      for (image_t id : selection.search) {
        if (views_.count(id) > 0) state.sources.push_back(id);
      }
      if (state.sources.empty()) {
        state.skipped = "none of its source images could be read";
      }
    }
    if (state.skipped.empty()) {
      try {
        std::tie(state.min_depth, state.max_depth) = MasterDepthRange(
            scene_, scene_.images.at(selection.master), options_);
      } catch (const InputError& error) {
        state.skipped = error.what();
      }
    }
  }
  if (std::all_of(states_.begin(), states_.end(), [](const MasterState& s) {
        return !s.skipped.empty();
      })) {
    std::string reasons;
    for (size_t m = 0; m < masters_.size(); ++m) {
      reasons += StrCat(m == 0 ? "" : "; ",
                        scene_.images.at(masters_[m].master).name,
                        ": ",
                        states_[m].skipped);
    }
    ThrowInputError("no master image can be matched (", reasons, ")");
  }
}

void MultiViewReconstruction::EstimateDepthMaps() {
  size_t total_pixels = 0;
  for (size_t m = 0; m < masters_.size(); ++m) {
    if (states_[m].skipped.empty()) {
      total_pixels += views_.at(masters_[m].master).gray.total();
    }
  }
  Progress progress("depth maps", total_pixels, "pixels");
  for (size_t m = 0; m < masters_.size(); ++m) {
    MasterState& state = states_[m];
    if (!state.skipped.empty()) continue;
    const Image& master = scene_.images.at(masters_[m].master);
    const PinholeView& view = views_.at(master.image_id);
    std::vector<const PinholeView*> sources;
    for (image_t id : state.sources) sources.push_back(&views_.at(id));
    // The sparse points the master sees start their pixels.
    std::vector<DepthSeed> seeds;
    for (const Point2D& point2D : master.points2D) {
      if (!point2D.HasPoint3D()) continue;
      const Eigen::Vector3d in_cam =
          master.cam_from_world * scene_.points3D.at(point2D.point3D_id).xyz;
      const Eigen::Vector3d h = view.K * in_cam;
      if (in_cam.z() <= 0) continue;
      seeds.push_back({h.head<2>() / h.z(), in_cam.z()});
    }
    const Timer timer;
    state.map = EstimateDepthMap(view,
                                 sources,
                                 state.min_depth,
                                 state.max_depth,
                                 seeds,
                                 options_.patch_match,
                                 options_.num_threads);
    state.seconds = timer.Seconds();
    progress.Add(view.gray.total());
  }
  progress.Finish();
}

void MultiViewReconstruction::Fuse() {
  std::vector<const DepthMap*> matched_maps;
  for (size_t m = 0; m < masters_.size(); ++m) {
    if (!states_[m].skipped.empty()) continue;
    matched_.push_back(static_cast<int>(m));
    matched_views_.push_back(&views_.at(masters_[m].master));
    matched_maps.push_back(&states_[m].map);
  }
  fused_ =
      FuseDepthMaps(matched_views_, matched_maps, options_.fusion, &verdicts_);
  // The depth maps are done with; the fused points and verdicts remain.
  for (MasterState& state : states_) state.map = DepthMap();
}

void MultiViewReconstruction::ChooseSearchImages() {
  verdict_of_.assign(fused_.size(), DenseReject::kAccepted);
  results_.assign(fused_.size(), MpgcResult());
  search_of_.assign(fused_.size(), {});
  for (size_t k = 0; k < fused_.size(); ++k) {
    // (All the master's sources instead: on the tower completeness 67.3 ->
    // 70.9 %, but MPGC twice as long.)
    const std::vector<image_t>& sources =
        states_[matched_[fused_[k].master]].sources;
    std::vector<image_t>& search = search_of_[k];
    for (int v : fused_[k].views) {
      search.push_back(masters_[matched_[v]].master);
    }
    std::stable_partition(search.begin(), search.end(), [&](image_t id) {
      return std::find(sources.begin(), sources.end(), id) != sources.end();
    });
    if (static_cast<int>(search.size()) > options_.num_source_views) {
      search.resize(options_.num_source_views);
    }
  }
}

void MultiViewReconstruction::RefineByMpgc() {
  // A fused point was confirmed by min_consistent_views other masters; MPGC
  // keeps it with as many search images. (One search image instead: on the
  // rendered tower completeness 74.1 -> 76.7 %, but the cloud's RMS 1.03 ->
  // 1.12 GSD and its graph-cut mesh's 1.44 -> 1.51.)
  MpgcOptions mpgc = options_.mpgc;
  mpgc.min_search_views = std::max(1, options_.fusion.min_consistent_views);
  mpgc.lsm.min_template_stddev = options_.refine_min_template_stddev;
  // The full-size photographs of one master's points at a time; those the
  // next master needs as well stay.
  std::map<image_t, cv::Mat> resident;
  Progress progress("MPGC", fused_.size(), "points");
  size_t begin = 0;
  while (begin < fused_.size()) {
    size_t end = begin;
    while (end < fused_.size() && fused_[end].master == fused_[begin].master) {
      ++end;
    }
    RefineMaster(begin, end, mpgc, &resident);
    progress.Add(end - begin);
    begin = end;
  }
  progress.Finish();
}

void MultiViewReconstruction::RefineMaster(
    size_t begin,
    size_t end,
    const MpgcOptions& mpgc,
    std::map<image_t, cv::Mat>* resident) {
  const Image& master =
      scene_.images.at(masters_[matched_[fused_[begin].master]].master);
  std::set<image_t> group = {master.image_id};
  for (size_t k = begin; k < end; ++k) {
    group.insert(search_of_[k].begin(), search_of_[k].end());
  }
  std::map<image_t, cv::Mat> next;
  for (image_t id : group) {
    const auto it = resident->find(id);
    next[id] =
        it != resident->end()
            ? it->second
            : LoadDenseImage(
                  scene_, id, image_path_, options_.highpass_sigma_px, false)
                  .gray;
  }
  *resident = std::move(next);
  std::map<image_t, MpgcView> mpgc_views;
  for (image_t id : group) {
    const Image& image = scene_.images.at(id);
    MpgcView view;
    view.image = &resident->at(id);
    view.camera = &scene_.cameras.at(image.camera_id);
    view.cam_from_world = image.cam_from_world;
    view.frame = image.frame ? &*image.frame : nullptr;
    mpgc_views.emplace(id, view);
  }
  const MpgcView& master_view = mpgc_views.at(master.image_id);
  const Eigen::Vector3d centre = master.cam_from_world.Center();
  const double focal = master_view.camera->MeanFocalLengthPx();
  const double working_focal = views_.at(master.image_id).K(0, 0);
  ParallelFor(static_cast<int>(end - begin), options_.num_threads, [&](int i) {
    const size_t k = begin + i;
    const FusedPoint& point = fused_[k];
    Eigen::Vector2d xy;
    if (!scene_.Project(master, point.xyz, &xy)) {
      verdict_of_[k] = DenseReject::kMpgcBehind;
      return;
    }
    std::vector<MpgcView> search;
    for (image_t id : search_of_[k]) search.push_back(mpgc_views.at(id));
    MpgcResult& result = results_[k];
    result = MatchMpgc(
        master_view, xy, search, point.xyz, mpgc, point.normal.cast<double>());
    if (!result.ok()) {
      verdict_of_[k] = DenseRejectOf(result.status);
      return;
    }
    const Eigen::Vector3d ray = (result.xyz - centre).normalized();
    const double depth = (result.xyz - centre).norm();
    const double sigma_ray =
        std::sqrt(std::max(0.0, ray.dot(result.covariance * ray)));
    if (sigma_ray > options_.max_sigma_gsd * depth / focal) {
      verdict_of_[k] = DenseReject::kImprecise;
    } else if ((result.xyz - point.xyz).norm() >
               options_.max_refine_shift_gsd * depth / working_focal) {
      verdict_of_[k] = DenseReject::kOffSurface;
    }
  });
}

DenseReject RejectOfFusion(FusionVerdict verdict) {
  switch (verdict) {
    case FusionVerdict::kNone:
      return DenseReject::kNoTexture;
    case FusionVerdict::kPoorMatch:
      return DenseReject::kNoApproximation;
    case FusionVerdict::kInconsistent:
      return DenseReject::kInconsistent;
    case FusionVerdict::kPoint:
      return DenseReject::kAccepted;  // MPGC's verdict comes later
    case FusionVerdict::kMerged:
      return DenseReject::kMerged;
    case FusionVerdict::kDepthEdge:
      return DenseReject::kDepthEdge;
  }
  return DenseReject::kNoTexture;
}

void MultiViewReconstruction::ReportFusionVerdicts(DenseReport* report) const {
  for (size_t j = 0; j < matched_.size(); ++j) {
    DenseMasterReport& entry = report->masters[matched_[j]];
    const PinholeView& view = *matched_views_[j];
    entry.cell_size =
        Downscale(scene_.cameras.at(scene_.images.at(entry.master).camera_id),
                  options_.max_image_size);
    entry.border = 0;
    entry.reasons = cv::Mat(view.height(), view.width(), CV_8U);
    entry.num_cells = view.gray.total();
    for (size_t p = 0; p < verdicts_[j].size(); ++p) {
      entry.reasons.at<uint8_t>(static_cast<int>(p)) =
          static_cast<uint8_t>(RejectOfFusion(verdicts_[j][p]));
    }
  }
}

PointCloud MultiViewReconstruction::MakeCloud(
    DenseReport* report, std::vector<std::vector<image_t>>* visibility) {
  for (size_t m = 0; m < masters_.size(); ++m) {
    DenseMasterReport& entry = report->masters.emplace_back();
    entry.master = masters_[m].master;
    entry.name = scene_.images.at(entry.master).name;
    entry.skipped = states_[m].skipped;
    entry.min_depth = states_[m].min_depth;
    entry.max_depth = states_[m].max_depth;
    entry.seconds = states_[m].seconds;
    entry.search = states_[m].sources;
  }
  ReportFusionVerdicts(report);
  PointCloud cloud;
  DensePointAttributes attributes;
  const bool refined = options_.refine;
  std::vector<std::vector<double>> sigmas(masters_.size());
  for (size_t k = 0; k < fused_.size(); ++k) {
    const FusedPoint& point = fused_[k];
    const int m = matched_[point.master];
    DenseMasterReport& entry = report->masters[m];
    const PinholeView& view = *matched_views_[point.master];
    const int px = static_cast<int>(point.master_xy.x());
    const int py = static_cast<int>(point.master_xy.y());
    entry.reasons.at<uint8_t>(py, px) = static_cast<uint8_t>(verdict_of_[k]);
    if (verdict_of_[k] != DenseReject::kAccepted) continue;
    const MpgcResult& result = results_[k];
    cloud.positions.push_back(refined ? result.xyz : point.xyz);
    cloud.normals.push_back(point.normal);
    const cv::Vec3b& bgr = view.color.empty()
                               ? cv::Vec3b(128, 128, 128)
                               : view.color.at<cv::Vec3b>(py, px);
    cloud.colors.emplace_back(bgr[2], bgr[1], bgr[0]);
    const Eigen::Vector3d sigma =
        refined ? result.StdDev() : Eigen::Vector3d::Zero();
    attributes.sx.push_back(sigma.x());
    attributes.sy.push_back(sigma.y());
    attributes.sz.push_back(sigma.z());
    const Eigen::Vector3d normal = point.normal.cast<double>();
    attributes.s_normal.push_back(
        refined
            ? std::sqrt(std::max(0.0, normal.dot(result.covariance * normal)))
            : 0.0);
    std::vector<image_t> seen = {masters_[m].master};
    if (refined) {
      for (int v : result.views) seen.push_back(search_of_[k][v]);
    } else {
      for (int v : point.views) seen.push_back(masters_[matched_[v]].master);
    }
    attributes.num_images.push_back(static_cast<double>(seen.size()));
    attributes.master_ids.push_back(masters_[m].master);
    attributes.sigma0.push_back(refined ? result.sigma0 : 0.0);
    attributes.correlation.push_back(
        refined
            ? std::accumulate(
                  result.correlation.begin(), result.correlation.end(), 0.0) /
                  std::max<size_t>(1, result.correlation.size())
            : 1.0 - point.cost);
    if (refined) {
      const Eigen::Vector3d centre =
          scene_.images.at(masters_[m].master).cam_from_world.Center();
      const Eigen::Vector3d ray = (result.xyz - centre).normalized();
      const double gsd =
          (result.xyz - centre).norm() /
          scene_.cameras.at(scene_.images.at(masters_[m].master).camera_id)
              .MeanFocalLengthPx();
      sigmas[m].push_back(
          std::sqrt(std::max(0.0, ray.dot(result.covariance * ray))) / gsd);
    }
    if (visibility != nullptr) visibility->push_back(std::move(seen));
  }
  attributes.MoveInto(&cloud);
  for (size_t j = 0; j < matched_.size(); ++j) {
    DenseMasterReport& entry = report->masters[matched_[j]];
    for (int r = 0; r < entry.reasons.rows * entry.reasons.cols; ++r) {
      ++entry.rejects[entry.reasons.at<uint8_t>(r)];
    }
    entry.num_points = entry.rejects[static_cast<int>(DenseReject::kAccepted)];
    entry.median_sigma_gsd = Median(sigmas[matched_[j]]);
    report->num_points += entry.num_points;
    report->num_cells += entry.num_cells;
  }
  return cloud;
}

}  // namespace

std::vector<MasterSelection> SelectMultiViewMasters(
    const Scene& scene, const DenseOptions& options) {
  options.Check();
  if (scene.images.size() < 2) {
    ThrowInputError(
        "dense matching needs two or more oriented images; the model has ",
        scene.images.size());
  }
  std::vector<image_t> masters;
  if (options.master_names.empty() && options.num_masters == 0) {
    for (const auto& [id, image] : scene.images) masters.push_back(id);
  } else if (options.master_names.empty()) {
    // A few masters spread over the viewing directions, as the paper's.
    for (const MasterSelection& selection : SelectMasters(scene, options)) {
      masters.push_back(selection.master);
    }
  } else {
    for (const std::string& name : options.master_names) {
      const Image* image = scene.FindImageByName(name);
      if (image == nullptr) {
        ThrowInputError(
            "master_names: the model has no image named '", name, "'");
      }
      masters.push_back(image->image_id);
    }
  }
  // The images nearest in viewing direction (the paper's mode's choice):
  // the fallback where a master's depth range is unknown.
  DenseOptions by_direction = options;
  by_direction.master_names.clear();
  for (image_t id : masters) {
    by_direction.master_names.push_back(scene.images.at(id).name);
  }
  by_direction.num_search_images = options.num_source_views;
  std::vector<MasterSelection> selections = SelectMasters(scene, by_direction);
  for (MasterSelection& selection : selections) {
    const Image& master = scene.images.at(selection.master);
    const Camera& camera = scene.cameras.at(master.camera_id);
    // The point the master looks at: on its principal ray, in the middle
    // of its depth range.
    std::optional<Ray> axis =
        RayThroughPixel(camera,
                        master.cam_from_world,
                        camera.PrincipalPointPx(),
                        master.frame ? &*master.frame : nullptr);
    std::pair<double, double> range;
    try {
      range = MasterDepthRange(scene, master, options);
    } catch (const InputError&) {
      continue;  // refused later, with the reason, if it is matched
    }
    if (!axis) continue;
    const Eigen::Vector3d target =
        axis->origin +
        axis->direction * 0.5 * (range.first + range.second) /
            axis->direction.dot(master.cam_from_world.rotation.inverse() *
                                Eigen::Vector3d::UnitZ());
    // Sources: the images that see that point, at the smallest angle
    // between the rays to it that still gives depth (baseline and angle);
    // the point inside the source photograph is the overlap.
    std::vector<std::pair<double, image_t>> by_angle;
    for (const auto& [id, image] : scene.images) {
      if (id == master.image_id) continue;
      const Camera& other = scene.cameras.at(image.camera_id);
      Eigen::Vector2d xy;
      if ((image.cam_from_world * target).z() <= 0 ||
          !scene.Project(image, target, &xy) || xy.x() < 0 || xy.y() < 0 ||
          xy.x() > other.width || xy.y() > other.height) {
        continue;
      }
      const double angle =
          AngleBetweenDeg(target - master.cam_from_world.Center(),
                          target - image.cam_from_world.Center());
      if (angle >= options.min_triangulation_angle_deg &&
          angle <= options.max_search_angle_deg) {
        by_angle.push_back({angle, id});
      }
    }
    std::sort(by_angle.begin(), by_angle.end());
    selection.search.clear();
    for (const auto& [angle, id] : by_angle) {
      if (static_cast<int>(selection.search.size()) >=
          options.num_source_views) {
        break;
      }
      selection.search.push_back(id);
    }
  }
  return selections;
}

PointCloud DenseReconstructMultiView(
    const Scene& scene,
    const std::string& image_path,
    const std::vector<MasterSelection>& masters,
    const DenseOptions& options,
    DenseReport* report,
    std::vector<std::vector<image_t>>* visibility,
    std::map<image_t, std::string>* unreadable) {
  options.Check();
  const Timer total_timer;
  DenseReport local_report;
  if (report == nullptr) report = &local_report;
  *report = DenseReport();
  report->mode = DenseMode::kMultiView;

  MultiViewReconstruction reconstruction(scene, image_path, masters, options);
  reconstruction.LoadViews(unreadable);
  reconstruction.PlanMasters();
  Timer stage_timer;
  reconstruction.EstimateDepthMaps();
  report->propagation_seconds = stage_timer.Seconds();
  stage_timer = Timer();
  reconstruction.Fuse();
  report->fusion_seconds = stage_timer.Seconds();
  stage_timer = Timer();
  reconstruction.ChooseSearchImages();
  if (options.refine) reconstruction.RefineByMpgc();
  report->mpgc_seconds = stage_timer.Seconds();
  PointCloud cloud = reconstruction.MakeCloud(report, visibility);
  report->seconds = total_timer.Seconds();
  return cloud;
}

}  // namespace bayon
