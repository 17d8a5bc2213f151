// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/keypoint_refinement.h"

#include "ext/colmap/sqlite.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/string_printf.h"
#include "ext/image/image_io.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <glog/logging.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <set>

namespace bayon {

namespace fs = std::filesystem;

LsmOptions DefaultRefinementLsmOptions() {
  LsmOptions options;
  options.step_control = true;
  return options;
}

void KeypointRefinementOptions::Check() const {
  CheckNested("lsm", lsm);
  CheckOption(smoothing_sigma_px >= 0 && smoothing_sigma_px <= 5,
              "smoothing_sigma_px",
              "in [0, 5]",
              smoothing_sigma_px);
  CheckOption(max_sigma0 > 0, "max_sigma0", "> 0", max_sigma0);
  CheckOption(min_correlation >= -1 && min_correlation < 1,
              "min_correlation",
              "in [-1, 1)",
              min_correlation);
  CheckOption(max_sigma_px > 0, "max_sigma_px", "> 0", max_sigma_px);
  CheckOption(max_shift_px > 0, "max_shift_px", "> 0", max_shift_px);
  CheckOption(
      max_backmatch_px > 0, "max_backmatch_px", "> 0", max_backmatch_px);
  CheckOption(num_reference_candidates >= 1,
              "num_reference_candidates",
              ">= 1",
              num_reference_candidates);
  CheckOption(
      max_track_length >= 2, "max_track_length", ">= 2", max_track_length);
}

void KeypointRefinementOptions::RegisterMatchChecks(OptionRegistry* r) {
  r->AddNested("lsm", &lsm);
  r->Add("max_sigma0", &max_sigma0, "Largest sigma0, grey values");
  r->Add("min_correlation",
         &min_correlation,
         "Smallest correlation of the matched patches");
  r->Add("max_sigma_px",
         &max_sigma_px,
         "Largest standard deviation of a shift, pixels");
  r->Add("max_shift_px",
         &max_shift_px,
         "Largest move from the start (keypoint or correlation peak), px");
  r->Add("back_matching",
         &back_matching,
         "1: match back into the reference image");
  r->Add("max_backmatch_px",
         &max_backmatch_px,
         "Largest back-matching miss, pixels");
}

void KeypointRefinementOptions::Register(OptionRegistry* r) {
  RegisterMatchChecks(r);
  r->Add("smoothing_sigma_px",
         &smoothing_sigma_px,
         "Gaussian smoothing of the images before matching, px (0: none)");
  r->Add("use_keypoint_shape",
         &use_keypoint_shape,
         "1: start from the keypoints' affine frames");
  r->Add("num_reference_candidates",
         &num_reference_candidates,
         "Best-textured observations tried as the track's reference");
  r->Add("max_track_length", &max_track_length, "Longer tracks are left alone");
  r->Add("num_threads", &num_threads, "Threads (-1 = all cores)");
}

const char* ObservationOutcomeName(ObservationOutcome outcome) {
  switch (outcome) {
    case ObservationOutcome::kReference:
      return "reference";
    case ObservationOutcome::kRefined:
      return "refined";
    case ObservationOutcome::kOutsideImage:
      return "outside_image";
    case ObservationOutcome::kFlatPatch:
      return "flat_patch";
    case ObservationOutcome::kNotConverged:
      return "not_converged";
    case ObservationOutcome::kDiverged:
      return "diverged";
    case ObservationOutcome::kShiftUndetermined:
      return "shift_undetermined";
    case ObservationOutcome::kSingular:
      return "singular";
    case ObservationOutcome::kLargeSigma0:
      return "large_sigma0";
    case ObservationOutcome::kLowCorrelation:
      return "low_correlation";
    case ObservationOutcome::kImprecise:
      return "imprecise";
    case ObservationOutcome::kLargeShift:
      return "large_shift";
    case ObservationOutcome::kBackMatching:
      return "back_matching";
    case ObservationOutcome::kLongTrack:
      return "long_track";
  }
  return "?";
}

// ------------------------------------------------------------------ tracks

namespace {

// Union-find over observation indices, with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  size_t Find(size_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  void Union(size_t a, size_t b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<size_t> parent_;
};

}  // namespace

std::vector<KeypointTrack> BuildKeypointTracks(
    const std::vector<std::pair<pair_t, FeatureMatches>>& matches) {
  // Number the observations that occur in any match, in sorted order.
  std::vector<TrackObservation> observations;
  for (const auto& [pair_id, pair_matches] : matches) {
    const auto [image_id1, image_id2] = ImageIdsFromPairId(pair_id);
    for (int i = 0; i < pair_matches.rows(); ++i) {
      observations.push_back({image_id1, pair_matches(i, 0)});
      observations.push_back({image_id2, pair_matches(i, 1)});
    }
  }
  std::sort(observations.begin(), observations.end());
  observations.erase(std::unique(observations.begin(), observations.end()),
                     observations.end());
  const auto index_of = [&](const TrackObservation& observation) {
    return static_cast<size_t>(std::lower_bound(observations.begin(),
                                                observations.end(),
                                                observation) -
                               observations.begin());
  };
  DisjointSets sets(observations.size());
  for (const auto& [pair_id, pair_matches] : matches) {
    const auto [image_id1, image_id2] = ImageIdsFromPairId(pair_id);
    for (int i = 0; i < pair_matches.rows(); ++i) {
      sets.Union(index_of({image_id1, pair_matches(i, 0)}),
                 index_of({image_id2, pair_matches(i, 1)}));
    }
  }
  // Roots are the smallest members, so tracks come out in the order of
  // their smallest observation, each sorted.
  std::vector<int> track_of_root(observations.size(), -1);
  std::vector<KeypointTrack> tracks;
  for (size_t i = 0; i < observations.size(); ++i) {
    const size_t root = sets.Find(i);
    if (track_of_root[root] < 0) {
      track_of_root[root] = static_cast<int>(tracks.size());
      tracks.emplace_back();
    }
    tracks[track_of_root[root]].push_back(observations[i]);
  }
  tracks.erase(std::remove_if(
                   tracks.begin(),
                   tracks.end(),
                   [](const KeypointTrack& track) { return track.size() < 2; }),
               tracks.end());
  return tracks;
}

// ------------------------------------------------------- one observation

namespace {

// The affine frame of a stored keypoint (colmap-interop.md 1.3).
Eigen::Matrix2d KeypointFrame(const FeatureKeypoints& keypoints, int idx) {
  if (keypoints.cols() >= 6) {
    Eigen::Matrix2d frame;
    frame << keypoints(idx, 2), keypoints(idx, 3), keypoints(idx, 4),
        keypoints(idx, 5);
    return frame;
  }
  if (keypoints.cols() == 4) {
    const double scale = keypoints(idx, 2);
    const double angle = keypoints(idx, 3);
    Eigen::Matrix2d frame;
    frame << std::cos(angle), -std::sin(angle), std::sin(angle),
        std::cos(angle);
    return scale * frame;
  }
  return Eigen::Matrix2d::Identity();
}

// The pixel centre nearest to a point (COLMAP coordinates).
Eigen::Vector2d NearestPixelCenter(const Eigen::Vector2d& xy) {
  return Eigen::Vector2d(std::floor(xy.x()) + 0.5, std::floor(xy.y()) + 0.5);
}

ObservationOutcome OutcomeOfLsm(LsmStatus status) {
  switch (status) {
    case LsmStatus::kConverged:
      return ObservationOutcome::kRefined;
    case LsmStatus::kOutsideImage:
      return ObservationOutcome::kOutsideImage;
    case LsmStatus::kFlatPatch:
      return ObservationOutcome::kFlatPatch;
    case LsmStatus::kShiftUndetermined:
      return ObservationOutcome::kShiftUndetermined;
    case LsmStatus::kNotConverged:
      return ObservationOutcome::kNotConverged;
    case LsmStatus::kDiverged:
      return ObservationOutcome::kDiverged;
    case LsmStatus::kSingular:
      return ObservationOutcome::kSingular;
  }
  return ObservationOutcome::kSingular;
}

// Matches the patch around the pixel centre nearest to `xy` in `from` into
// `to`, where `xy` is approximately at `to_xy` and the patch has the shape
// `shape` (and radiometry r0, r1). Returns the LSM result and, in
// `conjugate_xy`, the conjugate of `xy` itself.
LsmMatch MatchPoint(const cv::Mat& from,
                    const Eigen::Vector2d& xy,
                    const cv::Mat& to,
                    const Eigen::Vector2d& to_xy,
                    const Eigen::Matrix2d& shape,
                    double r0,
                    double r1,
                    const LsmOptions& options,
                    Eigen::Vector2d* conjugate_xy) {
  const Eigen::Vector2d center = NearestPixelCenter(xy);
  const Eigen::Vector2d offset = xy - center;
  LsmTemplate patch;
  LsmMatch match;
  if (!ExtractLsmTemplate(
          from, center, options.patch_radius, options.interpolation, &patch)) {
    match.status = LsmStatus::kOutsideImage;
    *conjugate_xy = to_xy;
    return match;
  }
  LsmParameters approximation =
      LsmParameters::At(to_xy - shape * offset, shape);
  approximation.r0 = r0;
  approximation.r1 = r1;
  match = MatchLsm(patch, to, approximation, options);
  *conjugate_xy = match.xy + match.params.Shape() * offset;
  return match;
}

}  // namespace

Eigen::Matrix2d KeypointShapeRatio(const FeatureKeypoints& from_keypoints,
                                   int from_idx,
                                   const FeatureKeypoints& to_keypoints,
                                   int to_idx) {
  const Eigen::Matrix2d from = KeypointFrame(from_keypoints, from_idx);
  const Eigen::Matrix2d to = KeypointFrame(to_keypoints, to_idx);
  if (!from.allFinite() || !to.allFinite() ||
      !(std::abs(from.determinant()) > 1e-12) ||
      !(std::abs(to.determinant()) > 1e-12)) {
    return Eigen::Matrix2d::Identity();
  }
  const Eigen::Matrix2d ratio = to * from.inverse();
  return ratio.allFinite() ? ratio : Eigen::Matrix2d::Identity();
}

cv::Mat SmoothForMatching(const cv::Mat& gray,
                          const KeypointRefinementOptions& options) {
  CHECK_EQ(gray.type(), CV_32F);
  if (options.smoothing_sigma_px <= 0) return gray.clone();
  cv::Mat smoothed;
  cv::GaussianBlur(gray,
                   smoothed,
                   cv::Size(0, 0),
                   options.smoothing_sigma_px,
                   options.smoothing_sigma_px,
                   cv::BORDER_REPLICATE);
  return smoothed;
}

double PatchTextureScore(const cv::Mat& gray,
                         const Eigen::Vector2d& xy,
                         int radius) {
  LsmTemplate patch;
  if (!ExtractLsmTemplate(gray,
                          NearestPixelCenter(xy),
                          radius,
                          Interpolation::kBilinear,
                          &patch)) {
    return 0;
  }
  Eigen::Matrix2d tensor = Eigen::Matrix2d::Zero();
  for (int k = 0; k < patch.size(); ++k) {
    const Eigen::Vector2d g(patch.dx[k], patch.dy[k]);
    tensor += g * g.transpose();
  }
  tensor /= patch.size();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(tensor,
                                                        Eigen::EigenvaluesOnly)
      .eigenvalues()[0];
}

ObservationRefinement RefineObservation(
    const cv::Mat& reference,
    const Eigen::Vector2d& reference_xy,
    const cv::Mat& search,
    const Eigen::Vector2d& start_xy,
    const Eigen::Matrix2d& shape,
    const KeypointRefinementOptions& options) {
  ObservationRefinement result;
  result.original_xy = start_xy;
  result.refined_xy = start_xy;
  result.matched_xy = start_xy;
  Eigen::Vector2d conjugate;
  const LsmMatch forward = MatchPoint(reference,
                                      reference_xy,
                                      search,
                                      start_xy,
                                      shape,
                                      0.0,
                                      1.0,
                                      options.lsm,
                                      &conjugate);
  result.sigma0 = forward.sigma0;
  result.correlation = forward.correlation;
  result.sigma_xy = forward.sigma_xy;
  result.covariance_xy = forward.covariance_xy;
  result.shape = forward.params.Shape();
  result.outcome = OutcomeOfLsm(forward.status);
  if (forward.status != LsmStatus::kOutsideImage &&
      forward.status != LsmStatus::kFlatPatch &&
      forward.status != LsmStatus::kSingular) {
    result.matched_xy = conjugate;
  }
  if (!forward.ok()) return result;
  if (forward.sigma0 > options.max_sigma0) {
    result.outcome = ObservationOutcome::kLargeSigma0;
    return result;
  }
  if (forward.correlation < options.min_correlation) {
    result.outcome = ObservationOutcome::kLowCorrelation;
    return result;
  }
  if (!(forward.sigma_xy.maxCoeff() <= options.max_sigma_px)) {
    result.outcome = ObservationOutcome::kImprecise;
    return result;
  }
  if ((conjugate - start_xy).norm() > options.max_shift_px) {
    result.outcome = ObservationOutcome::kLargeShift;
    return result;
  }
  if (options.back_matching) {
    // The refined patch of the search image, matched back into the
    // reference image from where the forward solution puts it.
    const Eigen::Matrix2d inverse_shape = forward.params.Shape().inverse();
    Eigen::Vector2d back;
    const LsmMatch backward = MatchPoint(search,
                                         conjugate,
                                         reference,
                                         reference_xy,
                                         inverse_shape,
                                         -forward.params.r0 / forward.params.r1,
                                         1.0 / forward.params.r1,
                                         options.lsm,
                                         &back);
    result.backmatch_px = (back - reference_xy).norm();
    if (!backward.ok() || !(result.backmatch_px <= options.max_backmatch_px)) {
      result.outcome = ObservationOutcome::kBackMatching;
      return result;
    }
  }
  result.refined_xy = conjugate;
  result.outcome = ObservationOutcome::kRefined;
  return result;
}

namespace {

// Every observation but `reference` matched to the reference; `initial`
// holds the original positions.
std::vector<ObservationRefinement> RefineAgainst(
    const KeypointTrack& track,
    const std::map<image_t, RefinementImage>& images,
    size_t reference,
    const std::vector<ObservationRefinement>& initial,
    const KeypointRefinementOptions& options,
    int* num_refined) {
  std::vector<ObservationRefinement> results = initial;
  const RefinementImage& reference_image = images.at(track[reference].image_id);
  const int reference_idx = static_cast<int>(track[reference].point2D_idx);
  results[reference].outcome = ObservationOutcome::kReference;
  *num_refined = 0;
  for (size_t i = 0; i < track.size(); ++i) {
    if (i == reference) continue;
    const RefinementImage& image = images.at(track[i].image_id);
    const Eigen::Matrix2d shape =
        options.use_keypoint_shape
            ? KeypointShapeRatio(reference_image.keypoints,
                                 reference_idx,
                                 image.keypoints,
                                 static_cast<int>(track[i].point2D_idx))
            : Eigen::Matrix2d::Identity();
    results[i] = RefineObservation(reference_image.gray,
                                   initial[reference].original_xy,
                                   image.gray,
                                   initial[i].original_xy,
                                   shape,
                                   options);
    results[i].observation = track[i];
    *num_refined += results[i].outcome == ObservationOutcome::kRefined;
  }
  return results;
}

}  // namespace

std::vector<ObservationRefinement> RefineTrack(
    const KeypointTrack& track,
    const std::map<image_t, RefinementImage>& images,
    const KeypointRefinementOptions& options) {
  std::vector<ObservationRefinement> results(track.size());
  for (size_t i = 0; i < track.size(); ++i) {
    const RefinementImage& image = images.at(track[i].image_id);
    results[i].observation = track[i];
    results[i].original_xy = results[i].refined_xy = results[i].matched_xy =
        KeypointXY(image.keypoints, static_cast<int>(track[i].point2D_idx));
  }
  if (static_cast<int>(track.size()) > options.max_track_length) {
    for (ObservationRefinement& result : results) {
      result.outcome = ObservationOutcome::kLongTrack;
    }
    return results;
  }
  // References in the order of their texture; the next one is tried where
  // fewer than half of the others match the current one.
  std::vector<std::pair<double, size_t>> candidates;
  for (size_t i = 0; i < track.size(); ++i) {
    candidates.emplace_back(
        -PatchTextureScore(images.at(track[i].image_id).gray,
                           results[i].original_xy,
                           options.lsm.patch_radius),
        i);
  }
  std::sort(candidates.begin(), candidates.end());
  const int num_attempts = std::min<int>(options.num_reference_candidates,
                                         static_cast<int>(track.size()));
  std::vector<ObservationRefinement> best;
  int best_num_refined = -1;
  for (int attempt = 0; attempt < num_attempts; ++attempt) {
    int num_refined = 0;
    std::vector<ObservationRefinement> attempt_results =
        RefineAgainst(track,
                      images,
                      candidates[attempt].second,
                      results,
                      options,
                      &num_refined);
    if (num_refined > best_num_refined) {
      best = std::move(attempt_results);
      best_num_refined = num_refined;
    }
    if (2 * best_num_refined >= static_cast<int>(track.size()) - 1) break;
  }
  return best;
}

// ------------------------------------------------------------- database

namespace {

struct RefinementInput {
  std::vector<DatabaseImage> images;  // image_id order
  std::map<image_t, RefinementImage> data;
  std::vector<std::pair<pair_t, FeatureMatches>> matches;
  std::string match_source;
};

// Matches, keypoints and images; every match index is checked against its
// image's keypoints.
RefinementInput ReadInput(const std::string& database_path) {
  RefinementInput input;
  Database database(database_path, Database::Mode::kReadOnly);
  input.images = database.ReadAllImages();
  for (auto& [pair_id, geometry] : database.ReadAllTwoViewGeometries()) {
    if (geometry.inlier_matches.rows() > 0) {
      input.matches.emplace_back(pair_id, std::move(geometry.inlier_matches));
    }
  }
  input.match_source = "two_view_geometries";
  if (input.matches.empty()) {
    for (auto& [pair_id, matches] : database.ReadAllMatches()) {
      if (matches.rows() > 0) input.matches.emplace_back(pair_id, matches);
    }
    input.match_source = "matches";
  }
  if (input.matches.empty()) {
    ThrowInputError(database_path,
                    ": no matches to refine (neither two_view_geometries nor "
                    "matches has a row; run a matcher first)");
  }
  std::set<image_t> known;
  for (const DatabaseImage& image : input.images) known.insert(image.image_id);
  for (const auto& [pair_id, matches] : input.matches) {
    const auto [image_id1, image_id2] = ImageIdsFromPairId(pair_id);
    for (image_t image_id : {image_id1, image_id2}) {
      if (input.data.count(image_id)) continue;
      if (!known.count(image_id)) {
        ThrowInputError(database_path,
                        ": ",
                        input.match_source,
                        " row ",
                        pair_id,
                        " names image ",
                        image_id,
                        ", which is not in the images table");
      }
      if (!database.ExistsKeypoints(image_id)) {
        ThrowInputError(database_path,
                        ": image ",
                        image_id,
                        " has matches but no keypoints row");
      }
      input.data[image_id].keypoints = database.ReadKeypoints(image_id);
    }
    const int64_t rows1 = input.data[image_id1].keypoints.rows();
    const int64_t rows2 = input.data[image_id2].keypoints.rows();
    if (matches.size() > 0 && (matches.col(0).maxCoeff() >= rows1 ||
                               matches.col(1).maxCoeff() >= rows2)) {
      ThrowInputError(database_path,
                      ": ",
                      input.match_source,
                      " row ",
                      pair_id,
                      " (images ",
                      image_id1,
                      ", ",
                      image_id2,
                      "): a keypoint index beyond the images' ",
                      rows1,
                      " and ",
                      rows2,
                      " keypoints");
    }
  }
  return input;
}

// Every image that will be read must be on disk with its camera's size.
void CheckAndLoadImages(const std::string& database_path,
                        const std::string& image_path,
                        const KeypointRefinementOptions& options,
                        RefinementInput* input) {
  Database database(database_path, Database::Mode::kReadOnly);
  std::map<camera_t, Camera> cameras;
  for (const Camera& camera : database.ReadAllCameras()) {
    cameras.emplace(camera.camera_id, camera);
  }
  std::vector<ExpectedImage> expected;
  std::vector<std::pair<image_t, std::string>> to_read;
  for (const DatabaseImage& image : input->images) {
    if (!input->data.count(image.image_id)) continue;
    const auto camera = cameras.find(image.camera_id);
    expected.push_back(
        {image.name,
         camera == cameras.end() ? 0 : static_cast<int>(camera->second.width),
         camera == cameras.end() ? 0
                                 : static_cast<int>(camera->second.height)});
    to_read.emplace_back(image.image_id,
                         (fs::path(image_path) / image.name).string());
  }
  CheckImagesOnDisk(image_path, expected, database_path);
  ParallelFor(
      static_cast<int>(to_read.size()), options.num_threads, [&](int i) {
        input->data.at(to_read[i].first).gray =
            SmoothForMatching(ReadImageGrayFloat(to_read[i].second), options);
      });
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

// Refines every track, in blocks of tracks spread over the threads.
std::vector<std::vector<ObservationRefinement>> RefineTracks(
    const std::vector<KeypointTrack>& tracks,
    const std::map<image_t, RefinementImage>& images,
    const KeypointRefinementOptions& options) {
  constexpr int kBlockSize = 64;
  std::vector<std::vector<ObservationRefinement>> results(tracks.size());
  const int num_blocks =
      static_cast<int>((tracks.size() + kBlockSize - 1) / kBlockSize);
  Progress progress("refine_keypoints", tracks.size(), "tracks");
  ParallelFor(num_blocks, options.num_threads, [&](int block) {
    const size_t begin = static_cast<size_t>(block) * kBlockSize;
    const size_t end = std::min(tracks.size(), begin + kBlockSize);
    for (size_t t = begin; t < end; ++t) {
      results[t] = RefineTrack(tracks[t], images, options);
    }
    progress.Add(end - begin);
  });
  progress.Finish();
  return results;
}

// Applies the refined positions to the keypoints and counts per image.
void Summarise(const RefinementInput& input,
               const std::vector<std::vector<ObservationRefinement>>& results,
               std::map<image_t, FeatureKeypoints>* refined,
               KeypointRefinementSummary* summary) {
  std::map<image_t, ImageRefinementReport> reports;
  std::map<image_t, std::vector<double>> shifts;
  std::vector<double> all_shifts;
  for (const DatabaseImage& image : input.images) {
    ImageRefinementReport& report = reports[image.image_id];
    report.image_id = image.image_id;
    report.name = image.name;
    const auto data = input.data.find(image.image_id);
    if (data != input.data.end()) {
      report.num_keypoints = static_cast<int>(data->second.keypoints.rows());
    }
  }
  for (const auto& track : results) {
    for (const ObservationRefinement& result : track) {
      const image_t image_id = result.observation.image_id;
      ImageRefinementReport& report = reports[image_id];
      ++report.num_observations;
      ++summary->num_observations;
      ++summary->num_by_outcome[static_cast<int>(result.outcome)];
      if (result.outcome == ObservationOutcome::kReference) {
        ++report.num_reference;
        ++summary->num_reference;
      } else if (result.outcome == ObservationOutcome::kRefined) {
        ++report.num_refined;
        ++summary->num_refined;
        const double shift = (result.refined_xy - result.original_xy).norm();
        shifts[image_id].push_back(shift);
        all_shifts.push_back(shift);
        FeatureKeypoints& keypoints = (*refined)[image_id];
        if (keypoints.size() == 0) {
          keypoints = input.data.at(image_id).keypoints;
        }
        keypoints(result.observation.point2D_idx, 0) =
            static_cast<float>(result.refined_xy.x());
        keypoints(result.observation.point2D_idx, 1) =
            static_cast<float>(result.refined_xy.y());
      } else {
        ++report.num_rejected;
        ++summary->num_rejected;
      }
    }
  }
  for (auto& [image_id, report] : reports) {
    report.median_shift_px = Median(shifts[image_id]);
    summary->images.push_back(report);
  }
  summary->median_shift_px = Median(all_shifts);
  summary->mean_shift_px =
      all_shifts.empty()
          ? 0.0
          : std::accumulate(all_shifts.begin(), all_shifts.end(), 0.0) /
                all_shifts.size();
}

}  // namespace

KeypointRefinementSummary RefineDatabaseKeypoints(
    const std::string& database_path,
    const std::string& image_path,
    const std::string& output_path,
    bool overwrite,
    const KeypointRefinementOptions& options) {
  options.Check();
  const Timer total;
  CheckFileExists(database_path, "database_path");
  CheckDerivedDatabasePath(
      database_path, output_path, overwrite, "refine_keypoints");
  CheckDirectoryExists(image_path, "image_path");
  KeypointRefinementSummary summary;

  Timer timer;
  RefinementInput input = ReadInput(database_path);
  CheckAndLoadImages(database_path, image_path, options, &input);
  summary.match_source = input.match_source;
  summary.num_pairs = static_cast<int>(input.matches.size());
  const std::vector<KeypointTrack> tracks = BuildKeypointTracks(input.matches);
  summary.num_tracks = static_cast<int>(tracks.size());
  summary.read_seconds = timer.Seconds();
  LOG(INFO) << "refine_keypoints: " << summary.num_tracks << " tracks from "
            << summary.num_pairs << " pairs of " << input.match_source;

  timer = Timer();
  const auto results = RefineTracks(tracks, input.data, options);
  std::map<image_t, FeatureKeypoints> refined;
  Summarise(input, results, &refined, &summary);
  summary.refine_seconds = timer.Seconds();

  timer = Timer();
  // A copy of the input with the refined keypoints rows.
  WriteDerivedDatabase(database_path, output_path, [&](Database* database) {
    for (const auto& [image_id, keypoints] : refined) {
      database->WriteKeypoints(image_id, keypoints);
    }
  });
  summary.write_seconds = timer.Seconds();
  summary.seconds = total.Seconds();
  return summary;
}

nlohmann::ordered_json KeypointRefinementSummaryJson(
    const KeypointRefinementSummary& summary,
    const std::string& database_path,
    const std::string& output_path) {
  nlohmann::ordered_json json;
  json["database_path"] = database_path;
  json["output_path"] = output_path;
  json["match_source"] = summary.match_source;
  json["num_pairs"] = summary.num_pairs;
  json["num_tracks"] = summary.num_tracks;
  json["num_observations"] = summary.num_observations;
  json["num_reference"] = summary.num_reference;
  json["num_refined"] = summary.num_refined;
  json["num_rejected"] = summary.num_rejected;
  json["median_shift_px"] = summary.median_shift_px;
  json["mean_shift_px"] = summary.mean_shift_px;
  nlohmann::ordered_json outcomes = nlohmann::ordered_json::object();
  for (int i = 0; i < kNumObservationOutcomes; ++i) {
    outcomes[ObservationOutcomeName(static_cast<ObservationOutcome>(i))] =
        summary.num_by_outcome[i];
  }
  json["outcomes"] = outcomes;
  json["images"] = nlohmann::ordered_json::array();
  for (const ImageRefinementReport& image : summary.images) {
    json["images"].push_back({{"image_id", image.image_id},
                              {"name", image.name},
                              {"num_keypoints", image.num_keypoints},
                              {"num_observations", image.num_observations},
                              {"num_reference", image.num_reference},
                              {"num_refined", image.num_refined},
                              {"num_rejected", image.num_rejected},
                              {"median_shift_px", image.median_shift_px}});
  }
  json["seconds"] = {{"read", summary.read_seconds},
                     {"refine", summary.refine_seconds},
                     {"write", summary.write_seconds},
                     {"total", summary.seconds}};
  return json;
}

std::string KeypointRefinementTable(const KeypointRefinementSummary& summary) {
  std::string text;
  text += StringPrintf("%-28s %9s %9s %9s %9s %9s %12s\n",
                       "image",
                       "keypoints",
                       "in tracks",
                       "reference",
                       "refined",
                       "rejected",
                       "median shift");
  for (const ImageRefinementReport& image : summary.images) {
    text += StringPrintf("%-28s %9d %9d %9d %9d %9d %9.3f px\n",
                         image.name.c_str(),
                         image.num_keypoints,
                         image.num_observations,
                         image.num_reference,
                         image.num_refined,
                         image.num_rejected,
                         image.median_shift_px);
  }
  std::string rejections;
  for (int i = 0; i < kNumObservationOutcomes; ++i) {
    const auto outcome = static_cast<ObservationOutcome>(i);
    if (!IsRejection(outcome) || summary.num_by_outcome[i] == 0) continue;
    rejections += StrCat(rejections.empty() ? "" : ", ",
                         ObservationOutcomeName(outcome),
                         " ",
                         summary.num_by_outcome[i]);
  }
  text += StringPrintf("rejected: %s\n",
                       rejections.empty() ? "none" : rejections.c_str());
  return text;
}

}  // namespace bayon
