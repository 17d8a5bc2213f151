// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/tie_points.h"

#include "ext/colmap/control_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/parallel.h"
#include "ext/core/progress.h"
#include "ext/core/string_printf.h"
#include "ext/image/image_io.h"
#include "ext/image/interpolation.h"
#include "ext/orientation/disparity_surface.h"

#include <Eigen/SVD>
#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <map>
#include <numeric>
#include <set>

namespace bayon {

namespace fs = std::filesystem;

KeypointRefinementOptions DefaultTieMatchingOptions() {
  KeypointRefinementOptions options;
  // 21 x 21: on the rendered tower the larger patch converges from more
  // correlation peaks and is as exact (tests/tiepoints_test.cc).
  options.lsm.patch_radius = 10;
  options.max_sigma_px = 0.1;
  options.max_shift_px = 1.5;
  options.min_correlation = 0.8;
  return options;
}

void TiePointOptions::Register(OptionRegistry* r) {
  r->Add("manual_path",
         &manual_path,
         "Manual image measurements: NAME IMAGE_NAME X Y [SIGMA]");
  r->Add("manual_sigma_px",
         &manual_sigma_px,
         "Sigma of manual measurements without one, pixels");
  r->Add("targets_path",
         &targets_path,
         "Coded targets' measurements (bayon targets --output_path): named "
         "tie points beside the manual ones");
  r->Add("grid_cols", &grid_cols, "Candidate grid columns");
  r->Add("grid_rows", &grid_rows, "Candidate grid rows");
  r->Add("candidates_per_cell",
         &candidates_per_cell,
         "Best-textured keypoints per grid cell");
  r->Add("min_texture_score",
         &min_texture_score,
         "Weakest patch texture followed (grey^2 / px^2)");
  r->Add("correlation_radius",
         &correlation_radius,
         "Half side of the correlation window, pixels");
  r->Add("min_ncc", &min_ncc, "Smallest correlation peak accepted");
  r->Add("min_ncc_margin",
         &min_ncc_margin,
         "Margin of the best peak over any other");
  r->Add("max_peaks",
         &max_peaks,
         "Correlation peaks tried by least-squares matching");
  r->Add("across_px",
         &across_px,
         "Search +- this many pixels across the epipolar line");
  r->Add("max_band_px", &max_band_px, "Longer bands are not searched");
  r->Add("max_epipolar_px",
         &max_epipolar_px,
         "Largest distance from another observation's epipolar line");
  r->Add("max_chain_px",
         &max_chain_px,
         "Largest disagreement of the previous link's patch, pixels");
  r->Add("min_images", &min_images, "Fewest images a point");
  r->Add("max_images", &max_images, "Most images a point");
  r->Add("min_distance_px",
         &min_distance_px,
         "Points closer than this in an image are one");
  r->AddNested("matching", &matching);
  r->Add("num_threads", &num_threads, "Threads (-1 = all cores)");
}

void TiePointOptions::Check() const {
  CheckNested("matching", matching);
  CheckOption(grid_cols >= 1, "TiePointOptions.grid_cols", ">= 1", grid_cols);
  CheckOption(grid_rows >= 1, "TiePointOptions.grid_rows", ">= 1", grid_rows);
  CheckOption(candidates_per_cell >= 1,
              "TiePointOptions.candidates_per_cell",
              ">= 1",
              candidates_per_cell);
  CheckOption(min_texture_score >= 0,
              "TiePointOptions.min_texture_score",
              ">= 0",
              min_texture_score);
  CheckOption(correlation_radius >= 2 && correlation_radius <= 15,
              "TiePointOptions.correlation_radius",
              "in [2, 15]",
              correlation_radius);
  CheckOption(min_ncc > 0 && min_ncc < 1,
              "TiePointOptions.min_ncc",
              "in (0, 1)",
              min_ncc);
  CheckOption(min_ncc_margin >= 0,
              "TiePointOptions.min_ncc_margin",
              ">= 0",
              min_ncc_margin);
  CheckOption(max_peaks >= 1, "TiePointOptions.max_peaks", ">= 1", max_peaks);
  CheckOption(peak_separation_px > 0,
              "TiePointOptions.peak_separation_px",
              "> 0",
              peak_separation_px);
  CheckOption(across_px >= 0 && across_px <= 10,
              "TiePointOptions.across_px",
              "in [0, 10]",
              across_px);
  CheckOption(
      max_band_px > 0, "TiePointOptions.max_band_px", "> 0", max_band_px);
  CheckOption(max_epipolar_px > 0,
              "TiePointOptions.max_epipolar_px",
              "> 0",
              max_epipolar_px);
  CheckOption(
      min_images >= 2, "TiePointOptions.min_images", ">= 2", min_images);
  CheckOption(max_images >= min_images,
              "TiePointOptions.max_images",
              ">= min_images",
              max_images);
  CheckOption(
      max_chain_px > 0, "TiePointOptions.max_chain_px", "> 0", max_chain_px);
  CheckOption(min_distance_px > 0,
              "TiePointOptions.min_distance_px",
              "> 0",
              min_distance_px);
  CheckOption(manual_sigma_px > 0,
              "TiePointOptions.manual_sigma_px",
              "> 0",
              manual_sigma_px);
}

const char* TieLinkOutcomeName(TieLinkOutcome outcome) {
  switch (outcome) {
    case TieLinkOutcome::kAccepted:
      return "accepted";
    case TieLinkOutcome::kNoBand:
      return "no band";
    case TieLinkOutcome::kLongBand:
      return "band too long";
    case TieLinkOutcome::kNoPeak:
      return "no correlation peak";
    case TieLinkOutcome::kAmbiguous:
      return "ambiguous peak";
    case TieLinkOutcome::kLsmRejected:
      return "least-squares rejected";
    case TieLinkOutcome::kEpipolar:
      return "off an epipolar line";
    case TieLinkOutcome::kChain:
      return "inconsistent along the chain";
    case TieLinkOutcome::kTaken:
      return "another point's";
  }
  return "unknown";
}

namespace {

struct TieImage {
  DatabaseImage image;
  cv::Mat gray;  // CV_32F, 0..255
  FeatureKeypoints keypoints;
  // Rows that are coded targets (bayon_keypoint_targets): no candidates,
  // for the targets come in as named points.
  std::set<uint32_t> target_rows;
};

// The surfaces of the database, by (searched from, searched in).
using SurfaceMap = std::map<std::pair<image_t, image_t>, DisparitySurface>;

struct Input {
  std::map<image_t, TieImage> images;
  SurfaceMap surfaces;
  // The images each image has a surface into.
  std::map<image_t, std::vector<image_t>> neighbors;
  std::vector<TiePointRecord> manual;  // manual_path's, then targets_path's
};

// One observation being built.
struct Link {
  image_t image_id = kInvalidImageId;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  Eigen::Matrix2d shape = Eigen::Matrix2d::Identity();  // from the reference
  ObservationRefinement lsm;
};

struct Chain {
  std::vector<Link> links;  // links[0]: the reference
  std::array<int64_t, kNumTieLinkOutcomes> num_by_link{};
  std::array<int64_t, kNumObservationOutcomes> num_by_lsm{};
};

// The reference window, zero mean and unit norm (empty where flat).
std::vector<float> NormalizedWindow(const cv::Mat& gray,
                                    const Eigen::Vector2d& center,
                                    int radius) {
  const int side = 2 * radius + 1;
  std::vector<float> values(side * side);
  for (int v = -radius; v <= radius; ++v) {
    for (int u = -radius; u <= radius; ++u) {
      float value;
      if (!SampleBilinear(gray, center.x() + u, center.y() + v, &value)) {
        return {};
      }
      values[(v + radius) * side + u + radius] = value;
    }
  }
  const double mean =
      std::accumulate(values.begin(), values.end(), 0.0) / values.size();
  double norm = 0;
  for (float& value : values) {
    value = static_cast<float>(value - mean);
    norm += double(value) * value;
  }
  if (!(std::sqrt(norm / values.size()) > 1.0)) return {};
  const float scale = static_cast<float>(1 / std::sqrt(norm));
  for (float& value : values) value *= scale;
  return values;
}

// NCC of the normalized window with the search image sampled at
// xy + shape (u, v); -2 where the window leaves the image or is flat.
double CorrelationAt(const std::vector<float>& window,
                     int radius,
                     const cv::Mat& search,
                     const Eigen::Vector2d& xy,
                     const Eigen::Matrix2d& shape) {
  const int side = 2 * radius + 1;
  double sum = 0, sum_sq = 0, dot = 0;
  for (int v = -radius; v <= radius; ++v) {
    for (int u = -radius; u <= radius; ++u) {
      const Eigen::Vector2d p = xy + shape * Eigen::Vector2d(u, v);
      float value;
      if (!SampleBilinear(search, p.x(), p.y(), &value)) return -2;
      sum += value;
      sum_sq += double(value) * value;
      dot += window[(v + radius) * side + u + radius] * value;
    }
  }
  const double n = side * side;
  const double variance = sum_sq - sum * sum / n;
  if (!(variance > n)) return -2;  // standard deviation below 1 grey value
  // The window has zero mean, so dot = sum w (g - mean g).
  return dot / std::sqrt(variance);
}

// The correlation peaks of the window along the band that reach min_ncc,
// best first: local maxima at least peak_separation_px apart, at most
// `max_peaks`, and none more than min_ncc_margin below the best (weaker
// ones are not worth a least-squares attempt).
std::vector<Eigen::Vector2d> SearchBand(const std::vector<float>& window,
                                        const cv::Mat& search,
                                        const SearchInterval& band,
                                        const Eigen::Matrix2d& shape,
                                        const TiePointOptions& options) {
  const Eigen::Vector2d chord = band.end - band.begin;
  const double length = chord.norm();
  const Eigen::Vector2d along =
      length > 1e-9 ? Eigen::Vector2d(chord / length) : band.direction;
  const Eigen::Vector2d across(-along.y(), along.x());
  const int num_along = static_cast<int>(std::ceil(length)) + 1;
  const int num_across = 2 * options.across_px + 1;
  std::vector<double> scores(static_cast<size_t>(num_along) * num_across);
  auto position = [&](int index) {
    const int i = index / num_across, k = index % num_across;
    return Eigen::Vector2d(band.begin + i * along +
                           (k - options.across_px) * across);
  };
  for (int index = 0; index < num_along * num_across; ++index) {
    scores[index] = CorrelationAt(
        window, options.correlation_radius, search, position(index), shape);
  }
  // Local maxima (8 neighbours) above the threshold.
  std::vector<int> maxima;
  for (int i = 0; i < num_along; ++i) {
    for (int k = 0; k < num_across; ++k) {
      const double score = scores[i * num_across + k];
      if (score < options.min_ncc) continue;
      bool is_max = true;
      for (int di = -1; di <= 1 && is_max; ++di) {
        for (int dk = -1; dk <= 1; ++dk) {
          const int ni = i + di, nk = k + dk;
          if ((di == 0 && dk == 0) || ni < 0 || nk < 0 || ni >= num_along ||
              nk >= num_across) {
            continue;
          }
          if (scores[ni * num_across + nk] > score) {
            is_max = false;
            break;
          }
        }
      }
      if (is_max) maxima.push_back(i * num_across + k);
    }
  }
  std::sort(maxima.begin(), maxima.end(), [&](int a, int b) {
    return scores[a] > scores[b];
  });
  std::vector<Eigen::Vector2d> peaks;
  for (int m : maxima) {
    if (scores[m] < scores[maxima[0]] - options.min_ncc_margin) break;
    const Eigen::Vector2d xy = position(m);
    bool separate = true;
    for (const Eigen::Vector2d& peak : peaks) {
      separate &= (peak - xy).norm() > options.peak_separation_px;
    }
    if (!separate) continue;
    peaks.push_back(xy);
    if (static_cast<int>(peaks.size()) >= options.max_peaks) break;
  }
  return peaks;
}

// The local affinity of the surface's prediction at `xy` (image-2 pixels
// per image-1 pixel): for a smooth object the shape a patch takes from one
// image to the other. Identity where the surface gives none or an
// implausible one.
Eigen::Matrix2d SurfaceShape(const DisparitySurface& surface,
                             const Eigen::Vector2d& xy) {
  constexpr double kStep = 4.0;
  const SearchInterval center = surface.Search(xy);
  const SearchInterval right = surface.Search(xy + Eigen::Vector2d(kStep, 0));
  const SearchInterval down = surface.Search(xy + Eigen::Vector2d(0, kStep));
  if (!center.valid || !right.valid || !down.valid) {
    return Eigen::Matrix2d::Identity();
  }
  Eigen::Matrix2d shape;
  shape.col(0) = (right.predicted - center.predicted) / kStep;
  shape.col(1) = (down.predicted - center.predicted) / kStep;
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(shape);
  const Eigen::Vector2d sv = svd.singularValues();
  if (!shape.allFinite() || shape.determinant() <= 0 || sv(1) < 0.4 ||
      sv(0) > 2.5) {
    return Eigen::Matrix2d::Identity();
  }
  return shape;
}

// Tries to add image `to` to the chain from link `from`.
TieLinkOutcome TryLink(const Input& input,
                       const Link& reference,
                       const std::vector<float>& window,
                       const Link& from,
                       image_t to,
                       const std::vector<Link>& links,
                       const TiePointOptions& options,
                       Link* result,
                       ObservationOutcome* lsm_outcome) {
  const DisparitySurface& surface = input.surfaces.at({from.image_id, to});
  const SearchInterval band = surface.Search(from.xy);
  if (!band.valid || !std::isfinite(band.length_px)) {
    return TieLinkOutcome::kNoBand;
  }
  if (band.length_px > options.max_band_px) return TieLinkOutcome::kLongBand;
  const cv::Mat& search = input.images.at(to).gray;
  // The reference window is centred on the pixel centre nearest to the
  // reference point; the peak is that centre's conjugate.
  const Eigen::Vector2d center(std::floor(reference.xy.x()) + 0.5,
                               std::floor(reference.xy.y()) + 0.5);
  // The approximate shape: the chain's so far, carried on by the local
  // affinity of this surface.
  const Eigen::Matrix2d shape = SurfaceShape(surface, from.xy) * from.shape;
  const std::vector<Eigen::Vector2d> peaks =
      SearchBand(window, search, band, shape, options);
  if (peaks.empty()) return TieLinkOutcome::kNoPeak;
  // Least-squares matching from each peak; the blunder checks decide.
  // More than one distinct survivor: ambiguous (repetitive texture).
  const cv::Mat& reference_gray = input.images.at(reference.image_id).gray;
  int num_good = 0;
  TieLinkOutcome outcome = TieLinkOutcome::kLsmRejected;
  for (const Eigen::Vector2d& peak : peaks) {
    const Eigen::Vector2d start = peak + shape * (reference.xy - center);
    Link candidate;
    candidate.lsm = RefineObservation(
        reference_gray, reference.xy, search, start, shape, options.matching);
    if (candidate.lsm.outcome != ObservationOutcome::kRefined) {
      if (num_good == 0) *lsm_outcome = candidate.lsm.outcome;
      continue;
    }
    candidate.image_id = to;
    candidate.xy = candidate.lsm.refined_xy;
    candidate.shape = candidate.lsm.shape;
    // Every image the point is in that has a surface into this one: the
    // observation must lie near its epipolar line.
    bool on_lines = true;
    for (const Link& other : links) {
      const auto it = input.surfaces.find({other.image_id, to});
      if (it == input.surfaces.end()) continue;
      const EpipolarPosition position =
          it->second.Locate(other.xy, candidate.xy);
      if (position.valid && position.across_px > options.max_epipolar_px) {
        on_lines = false;
      }
    }
    if (!on_lines) {
      if (num_good == 0) outcome = TieLinkOutcome::kEpipolar;
      continue;
    }
    // Further along a chain, the observation it came from must find it
    // too: its own patch, matched into this image, lands on the same point.
    // A neighbour's patch looks much more like this one than the
    // reference's does, so a wrong conjugate that fooled the reference
    // seldom fools it as well.
    if (from.image_id != reference.image_id) {
      const ObservationRefinement check =
          RefineObservation(input.images.at(from.image_id).gray,
                            from.xy,
                            search,
                            candidate.xy,
                            candidate.shape * from.shape.inverse(),
                            options.matching);
      if (check.outcome != ObservationOutcome::kRefined ||
          (check.refined_xy - candidate.xy).norm() > options.max_chain_px) {
        if (num_good == 0) outcome = TieLinkOutcome::kChain;
        continue;
      }
    }
    if (num_good > 0 && (candidate.xy - result->xy).norm() < 1.0) continue;
    *result = candidate;
    ++num_good;
  }
  if (num_good > 1) return TieLinkOutcome::kAmbiguous;
  if (num_good == 0) return outcome;
  return TieLinkOutcome::kAccepted;
}

// Follows one candidate through the surfaces, breadth first.
Chain FollowCandidate(const Input& input,
                      image_t image_id,
                      const Eigen::Vector2d& xy,
                      const TiePointOptions& options) {
  Chain chain;
  Link reference;
  reference.image_id = image_id;
  reference.xy = xy;
  const Eigen::Vector2d center(std::floor(xy.x()) + 0.5,
                               std::floor(xy.y()) + 0.5);
  const std::vector<float> window = NormalizedWindow(
      input.images.at(image_id).gray, center, options.correlation_radius);
  chain.links.push_back(reference);
  if (window.empty()) return chain;
  std::set<image_t> tried = {image_id};
  std::deque<size_t> queue = {0};
  while (!queue.empty() &&
         static_cast<int>(chain.links.size()) < options.max_images) {
    const Link from = chain.links[queue.front()];
    queue.pop_front();
    const auto neighbors = input.neighbors.find(from.image_id);
    if (neighbors == input.neighbors.end()) continue;
    for (image_t to : neighbors->second) {
      if (!tried.insert(to).second) continue;
      Link link;
      ObservationOutcome lsm_outcome = ObservationOutcome::kRefined;
      const TieLinkOutcome outcome = TryLink(input,
                                             chain.links[0],
                                             window,
                                             from,
                                             to,
                                             chain.links,
                                             options,
                                             &link,
                                             &lsm_outcome);
      ++chain.num_by_link[static_cast<int>(outcome)];
      if (outcome == TieLinkOutcome::kLsmRejected) {
        ++chain.num_by_lsm[static_cast<int>(lsm_outcome)];
      }
      if (outcome != TieLinkOutcome::kAccepted) continue;
      chain.links.push_back(link);
      queue.push_back(chain.links.size() - 1);
      if (static_cast<int>(chain.links.size()) >= options.max_images) break;
    }
  }
  return chain;
}

// The candidates of one image: its keypoints, the best textured in each
// grid cell, best first overall.
std::vector<Eigen::Vector2d> SelectCandidates(const TieImage& image,
                                              const TiePointOptions& options) {
  const int radius = options.matching.lsm.patch_radius;
  const cv::Mat& gray = image.gray;
  std::vector<std::vector<std::pair<double, Eigen::Vector2d>>> cells(
      options.grid_cols * options.grid_rows);
  for (int i = 0; i < static_cast<int>(image.keypoints.rows()); ++i) {
    if (image.target_rows.count(static_cast<uint32_t>(i))) continue;
    const Eigen::Vector2d xy = KeypointXY(image.keypoints, i);
    const double score = PatchTextureScore(gray, xy, radius);
    if (!(score >= options.min_texture_score) || score <= 0) continue;
    const int cx =
        std::clamp(static_cast<int>(xy.x() / gray.cols * options.grid_cols),
                   0,
                   options.grid_cols - 1);
    const int cy =
        std::clamp(static_cast<int>(xy.y() / gray.rows * options.grid_rows),
                   0,
                   options.grid_rows - 1);
    cells[cy * options.grid_cols + cx].emplace_back(score, xy);
  }
  std::vector<std::pair<double, Eigen::Vector2d>> chosen;
  for (auto& cell : cells) {
    std::sort(cell.begin(), cell.end(), [](const auto& a, const auto& b) {
      return a.first > b.first;
    });
    const size_t n =
        std::min(cell.size(), static_cast<size_t>(options.candidates_per_cell));
    chosen.insert(chosen.end(), cell.begin(), cell.begin() + n);
  }
  std::stable_sort(
      chosen.begin(), chosen.end(), [](const auto& a, const auto& b) {
        return a.first > b.first;
      });
  std::vector<Eigen::Vector2d> candidates;
  for (const auto& [score, xy] : chosen) candidates.push_back(xy);
  return candidates;
}

bool NearAny(const std::vector<Eigen::Vector2d>& points,
             const Eigen::Vector2d& xy,
             double distance) {
  for (const Eigen::Vector2d& point : points) {
    if ((point - xy).squaredNorm() < distance * distance) return true;
  }
  return false;
}

// Measurements in a file (control_io.h format) as tie points of `source`,
// one per name.
std::vector<TiePointRecord> ReadNamedPoints(
    const std::string& path,
    const std::string& source,
    const std::map<std::string, image_t>& image_ids,
    double default_sigma_px) {
  std::map<std::string, TiePointRecord> by_name;
  for (const ImageMeasurement& m : ReadImageMeasurements(path)) {
    const auto image = image_ids.find(m.image_name);
    if (image == image_ids.end()) {
      ThrowInputError(path,
                      ": point ",
                      m.point_name,
                      " is measured in image ",
                      m.image_name,
                      ", which is not in the database");
    }
    TiePointRecord& point = by_name[m.point_name];
    point.name = m.point_name;
    point.source = source;
    TieObservation observation;
    observation.image_id = image->second;
    observation.xy = m.xy;
    const double sigma = m.sigma_px > 0 ? m.sigma_px : default_sigma_px;
    observation.covariance = sigma * sigma * Eigen::Matrix2d::Identity();
    point.observations.push_back(observation);
  }
  std::vector<TiePointRecord> points;
  for (auto& [name, point] : by_name) {
    std::sort(point.observations.begin(),
              point.observations.end(),
              [](const TieObservation& a, const TieObservation& b) {
                return a.image_id < b.image_id;
              });
    points.push_back(std::move(point));
  }
  return points;
}

Input ReadInput(const std::string& database_path,
                const std::string& image_path,
                const TiePointOptions& options,
                TiePointSummary* summary) {
  Input input;
  Database database(database_path, Database::Mode::kReadOnly);
  std::map<camera_t, Camera> cameras;
  for (const Camera& camera : database.ReadAllCameras()) {
    cameras.emplace(camera.camera_id, camera);
  }
  std::map<std::string, image_t> image_ids;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    image_ids[image.name] = image.image_id;
    TieImage entry;
    entry.image = image;
    if (database.ExistsKeypoints(image.image_id)) {
      entry.keypoints = database.ReadKeypoints(image.image_id);
      entry.target_rows = KeypointTargetRows(
          &database, image.image_id, static_cast<int>(entry.keypoints.rows()));
    }
    input.images.emplace(image.image_id, std::move(entry));
  }
  if (input.images.empty()) {
    ThrowInputError(database_path, ": no images (run `bayon import`)");
  }
  int64_t num_keypoints = 0;
  for (const auto& [id, image] : input.images) {
    num_keypoints += image.keypoints.rows();
  }
  if (options.manual_path.empty() && options.targets_path.empty() &&
      num_keypoints == 0) {
    ThrowInputError(database_path,
                    ": no keypoints (run `bayon features` first)");
  }
  // Surfaces in both directions, where current.
  for (const auto& [id1, image1] : input.images) {
    for (const auto& [id2, image2] : input.images) {
      if (id1 == id2) continue;
      std::optional<DisparitySurface> surface =
          LoadDisparitySurface(&database, id1, id2);
      if (!surface) continue;
      input.surfaces.emplace(std::make_pair(id1, id2), std::move(*surface));
      input.neighbors[id1].push_back(id2);
    }
  }
  summary->num_surfaces = static_cast<int>(input.surfaces.size());
  if (options.manual_path.empty() && options.targets_path.empty() &&
      input.surfaces.empty()) {
    ThrowInputError(database_path,
                    ": no current disparity surfaces (run `bayon relative` "
                    "and `bayon disparity` first)");
  }
  if (!options.manual_path.empty()) {
    CheckFileExists(options.manual_path, "manual_path");
    input.manual = ReadNamedPoints(
        options.manual_path, "manual", image_ids, options.manual_sigma_px);
  }
  if (!options.targets_path.empty()) {
    CheckFileExists(options.targets_path, "targets_path");
    std::set<std::string> manual_names;
    for (const TiePointRecord& point : input.manual) {
      manual_names.insert(point.name);
    }
    for (TiePointRecord& point : ReadNamedPoints(options.targets_path,
                                                 "target",
                                                 image_ids,
                                                 options.manual_sigma_px)) {
      if (manual_names.count(point.name) > 0) {
        ThrowInputError(options.targets_path,
                        ": target ",
                        point.name,
                        " is also a manual point in ",
                        options.manual_path,
                        "; one name, one point");
      }
      input.manual.push_back(std::move(point));
    }
  }
  // Images: every one with keypoints and a surface is read.
  std::vector<ExpectedImage> expected;
  std::vector<image_t> to_read;
  for (const auto& [id, image] : input.images) {
    if (image.keypoints.rows() == 0 || !input.neighbors.count(id)) continue;
    const auto camera = cameras.find(image.image.camera_id);
    expected.push_back(
        {image.image.name,
         camera == cameras.end() ? 0 : static_cast<int>(camera->second.width),
         camera == cameras.end() ? 0
                                 : static_cast<int>(camera->second.height)});
    to_read.push_back(id);
  }
  CheckImagesOnDisk(image_path, expected, database_path);
  ParallelFor(
      static_cast<int>(to_read.size()), options.num_threads, [&](int i) {
        TieImage& image = input.images.at(to_read[i]);
        image.gray = SmoothForMatching(
            ReadImageGrayFloat(
                (fs::path(image_path) / image.image.name).string()),
            options.matching);
      });
  return input;
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

// A kept chain as a record: the reference gets the mean covariance of the
// matched observations (the same patch and noise: the precision of that
// point in a single image).
TiePointRecord ToRecord(const std::vector<Link>& links) {
  TiePointRecord record;
  record.source = "alsm";
  Eigen::Matrix2d mean = Eigen::Matrix2d::Zero();
  for (size_t i = 1; i < links.size(); ++i) {
    mean += links[i].lsm.covariance_xy;
  }
  mean /= std::max<size_t>(1, links.size() - 1);
  for (size_t i = 0; i < links.size(); ++i) {
    TieObservation observation;
    observation.image_id = links[i].image_id;
    observation.xy = links[i].xy;
    if (i == 0) {
      observation.covariance = mean;
      observation.reference = true;
    } else {
      observation.covariance = links[i].lsm.covariance_xy;
      observation.sigma0 = links[i].lsm.sigma0;
      observation.correlation = links[i].lsm.correlation;
    }
    record.observations.push_back(observation);
  }
  std::sort(record.observations.begin(),
            record.observations.end(),
            [](const TieObservation& a, const TieObservation& b) {
              return a.image_id < b.image_id;
            });
  return record;
}

}  // namespace

TiePointSummary FindTiePoints(const std::string& database_path,
                              const std::string& image_path,
                              const std::string& colmap_output_path,
                              bool overwrite,
                              const TiePointOptions& options) {
  options.Check();
  const Timer timer;
  CheckFileExists(database_path, "database_path");
  CheckDirectoryExists(image_path, "image_path");
  if (!colmap_output_path.empty()) {
    CheckDerivedDatabasePath(
        database_path, colmap_output_path, overwrite, "tiepoints");
  }
  {
    Database check(database_path, Database::Mode::kReadWrite);
    check.CheckWritable("bayon tiepoints");
  }
  TiePointSummary summary;
  const Input input = ReadInput(database_path, image_path, options, &summary);

  // Observations taken so far, per image.
  std::map<image_t, std::vector<Eigen::Vector2d>> taken;
  std::vector<TiePointRecord> points;
  std::vector<double> sigmas;
  std::map<image_t, TieImageReport> reports;
  for (const auto& [id, image] : input.images) {
    TieImageReport& report = reports[id];
    report.image_id = id;
    report.name = image.image.name;
    report.num_keypoints = static_cast<int>(image.keypoints.rows());
  }
  int num_work_images = 0;
  for (const auto& [id, image] : input.images) {
    num_work_images += !image.gray.empty();
  }
  Progress progress("Following tie points", num_work_images, "images");
  for (const auto& [image_id, image] : input.images) {
    if (image.gray.empty()) continue;
    std::vector<Eigen::Vector2d> candidates = SelectCandidates(image, options);
    reports[image_id].num_candidates = static_cast<int>(candidates.size());
    summary.num_candidates += static_cast<int>(candidates.size());
    // Candidates on an earlier point's observation are that point.
    const std::vector<Eigen::Vector2d>& here = taken[image_id];
    candidates.erase(std::remove_if(candidates.begin(),
                                    candidates.end(),
                                    [&](const Eigen::Vector2d& xy) {
                                      return NearAny(
                                          here, xy, options.min_distance_px);
                                    }),
                     candidates.end());
    summary.num_followed += static_cast<int>(candidates.size());
    std::vector<Chain> chains(candidates.size());
    // A copy: C++17 lambdas cannot capture a structured binding (clang).
    const image_t start_id = image_id;
    ParallelFor(
        static_cast<int>(candidates.size()), options.num_threads, [&](int c) {
          chains[c] = FollowCandidate(input, start_id, candidates[c], options);
        });
    // Sequentially, best candidates first: one point per place.
    for (Chain& chain : chains) {
      for (int k = 0; k < kNumTieLinkOutcomes; ++k) {
        summary.num_by_link[k] += chain.num_by_link[k];
      }
      for (int k = 0; k < kNumObservationOutcomes; ++k) {
        summary.num_by_lsm[k] += chain.num_by_lsm[k];
      }
      if (NearAny(
              taken[image_id], chain.links[0].xy, options.min_distance_px)) {
        continue;
      }
      std::vector<Link> kept = {chain.links[0]};
      for (size_t i = 1; i < chain.links.size(); ++i) {
        const Link& link = chain.links[i];
        if (NearAny(taken[link.image_id], link.xy, options.min_distance_px)) {
          ++summary.num_by_link[static_cast<int>(TieLinkOutcome::kTaken)];
          --summary.num_by_link[static_cast<int>(TieLinkOutcome::kAccepted)];
          continue;
        }
        kept.push_back(link);
      }
      if (static_cast<int>(kept.size()) < options.min_images) continue;
      for (const Link& link : kept) {
        taken[link.image_id].push_back(link.xy);
        ++reports[link.image_id].num_observations;
      }
      for (size_t i = 1; i < kept.size(); ++i) {
        sigmas.push_back(kept[i].lsm.sigma_xy.maxCoeff());
      }
      ++reports[image_id].num_references;
      points.push_back(ToRecord(kept));
    }
    progress.Add();
  }
  progress.Finish();
  summary.num_points = static_cast<int>(points.size());
  for (const TiePointRecord& point : input.manual) {
    ++(point.source == "target" ? summary.num_target_points
                                : summary.num_manual_points);
    for (const TieObservation& observation : point.observations) {
      ++reports[observation.image_id].num_observations;
    }
    points.push_back(point);
  }
  summary.points_by_images.assign(options.max_images + 1, 0);
  for (const TiePointRecord& point : points) {
    summary.num_observations += point.observations.size();
    const size_t n = std::min(point.observations.size(),
                              static_cast<size_t>(options.max_images));
    ++summary.points_by_images[n];
  }
  summary.mean_images_per_point =
      points.empty()
          ? 0.0
          : static_cast<double>(summary.num_observations) / points.size();
  summary.median_sigma_px = Median(sigmas);
  for (auto& [id, report] : reports) summary.images.push_back(report);

  {
    Database database(database_path, Database::Mode::kReadWrite);
    WriteTiePoints(&database, points);
    points = ReadTiePoints(&database);  // with their ids
  }
  if (!colmap_output_path.empty()) {
    summary.colmap_pairs = ExportTiePointsToColmap(
        database_path, points, colmap_output_path, overwrite);
  }
  summary.points = std::move(points);
  summary.seconds = timer.Seconds();
  return summary;
}

int ExportTiePointsToColmap(const std::string& database_path,
                            const std::vector<TiePointRecord>& points,
                            const std::string& output_path,
                            bool overwrite) {
  CheckDerivedDatabasePath(database_path, output_path, overwrite, "tiepoints");
  // Keypoints per image: the observations in point order; and for every
  // pair of images the pairs of keypoint indices of shared points.
  std::map<image_t, std::vector<Eigen::Vector2d>> keypoints;
  std::map<std::pair<image_t, image_t>, std::vector<Eigen::Vector2i>> pairs;
  for (const TiePointRecord& point : points) {
    std::vector<std::pair<image_t, int>> indices;
    for (const TieObservation& observation : point.observations) {
      std::vector<Eigen::Vector2d>& list = keypoints[observation.image_id];
      indices.emplace_back(observation.image_id, static_cast<int>(list.size()));
      list.push_back(observation.xy);
    }
    for (size_t a = 0; a < indices.size(); ++a) {
      for (size_t b = a + 1; b < indices.size(); ++b) {
        auto first = indices[a], second = indices[b];
        if (first.first > second.first) std::swap(first, second);
        pairs[{first.first, second.first}].emplace_back(first.second,
                                                        second.second);
      }
    }
  }
  WriteDerivedDatabase(database_path, output_path, [&](Database* database) {
    std::map<camera_t, bool> prior;
    for (const Camera& camera : database->ReadAllCameras()) {
      prior[camera.camera_id] = camera.has_prior_focal_length;
    }
    std::map<image_t, camera_t> camera_of;
    for (const DatabaseImage& image : database->ReadAllImages()) {
      camera_of[image.image_id] = image.camera_id;
    }
    // Everything that refers to the old keypoints goes.
    for (const auto& [pair_id, unused] : database->ReadAllMatches()) {
      (void)unused;
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      DeletePairResults(database, id1, id2);
    }
    for (const auto& [pair_id, unused] : database->ReadAllTwoViewGeometries()) {
      (void)unused;
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      DeletePairResults(database, id1, id2);
    }
    database->connection()->Execute("DELETE FROM descriptors");
    database->connection()->Execute("DELETE FROM keypoints");
    for (const auto& [image_id, xy] : keypoints) {
      database->WriteKeypoints(image_id, KeypointsFromXY(xy));
    }
    for (const auto& [ids, list] : pairs) {
      FeatureMatches matches(list.size(), 2);
      for (size_t i = 0; i < list.size(); ++i) {
        matches(i, 0) = static_cast<uint32_t>(list[i].x());
        matches(i, 1) = static_cast<uint32_t>(list[i].y());
      }
      database->WriteMatches(ids.first, ids.second, matches);
      TwoViewGeometry geometry;
      geometry.config =
          prior[camera_of[ids.first]] && prior[camera_of[ids.second]]
              ? TwoViewConfig::kCalibrated
              : TwoViewConfig::kUncalibrated;
      geometry.inlier_matches = matches;
      database->WriteTwoViewGeometry(ids.first, ids.second, geometry);
    }
  });
  return static_cast<int>(pairs.size());
}

nlohmann::ordered_json TiePointSummaryJson(const TiePointSummary& summary) {
  nlohmann::ordered_json json;
  json["num_surfaces"] = summary.num_surfaces;
  json["num_candidates"] = summary.num_candidates;
  json["num_followed"] = summary.num_followed;
  json["num_points"] = summary.num_points;
  json["num_manual_points"] = summary.num_manual_points;
  json["num_target_points"] = summary.num_target_points;
  json["num_observations"] = summary.num_observations;
  json["mean_images_per_point"] = summary.mean_images_per_point;
  json["points_by_images"] = summary.points_by_images;
  json["median_sigma_px"] = summary.median_sigma_px;
  nlohmann::ordered_json links = nlohmann::ordered_json::object();
  for (int i = 0; i < kNumTieLinkOutcomes; ++i) {
    links[TieLinkOutcomeName(static_cast<TieLinkOutcome>(i))] =
        summary.num_by_link[i];
  }
  json["links"] = links;
  nlohmann::ordered_json lsm = nlohmann::ordered_json::object();
  for (int i = 0; i < kNumObservationOutcomes; ++i) {
    if (summary.num_by_lsm[i] == 0) continue;
    lsm[ObservationOutcomeName(static_cast<ObservationOutcome>(i))] =
        summary.num_by_lsm[i];
  }
  json["lsm_rejections"] = lsm;
  json["images"] = nlohmann::ordered_json::array();
  for (const TieImageReport& image : summary.images) {
    json["images"].push_back({{"image_id", image.image_id},
                              {"name", image.name},
                              {"num_keypoints", image.num_keypoints},
                              {"num_candidates", image.num_candidates},
                              {"num_references", image.num_references},
                              {"num_observations", image.num_observations}});
  }
  json["colmap_pairs"] = summary.colmap_pairs;
  json["seconds"] = summary.seconds;
  return json;
}

std::string TiePointSummaryLine(const TiePointSummary& summary) {
  int num_three = 0;
  for (size_t n = 3; n < summary.points_by_images.size(); ++n) {
    num_three += summary.points_by_images[n];
  }
  return StrCat(summary.num_points,
                " tie points (",
                num_three,
                " in 3 or more images, ",
                summary.mean_images_per_point,
                " images on average, median sigma ",
                summary.median_sigma_px,
                " px) from ",
                summary.num_followed,
                " candidates over ",
                summary.num_surfaces,
                " surfaces",
                summary.num_manual_points > 0
                    ? StrCat(", ", summary.num_manual_points, " manual points")
                    : std::string(),
                summary.num_target_points > 0
                    ? StrCat(", ", summary.num_target_points, " coded targets")
                    : std::string());
}

std::string TiePointTables(const TiePointSummary& summary) {
  std::string text;
  text += StringPrintf("%-28s %9s %10s %10s %12s\n",
                       "image",
                       "keypoints",
                       "candidates",
                       "references",
                       "observations");
  for (const TieImageReport& image : summary.images) {
    text += StringPrintf("%-28s %9d %10d %10d %12d\n",
                         image.name.c_str(),
                         image.num_keypoints,
                         image.num_candidates,
                         image.num_references,
                         image.num_observations);
  }
  std::string histogram;
  for (size_t n = 2; n < summary.points_by_images.size(); ++n) {
    if (summary.points_by_images[n] == 0) continue;
    histogram += StrCat(
        histogram.empty() ? "" : ", ", summary.points_by_images[n], " in ", n);
  }
  text += StringPrintf("points by images: %s\n",
                       histogram.empty() ? "none" : histogram.c_str());
  std::string links;
  for (int i = 0; i < kNumTieLinkOutcomes; ++i) {
    links += StrCat(links.empty() ? "" : ", ",
                    TieLinkOutcomeName(static_cast<TieLinkOutcome>(i)),
                    " ",
                    summary.num_by_link[i]);
  }
  text += StringPrintf("links: %s\n", links.c_str());
  std::string lsm;
  for (int i = 0; i < kNumObservationOutcomes; ++i) {
    if (summary.num_by_lsm[i] == 0) continue;
    lsm += StrCat(lsm.empty() ? "" : ", ",
                  ObservationOutcomeName(static_cast<ObservationOutcome>(i)),
                  " ",
                  summary.num_by_lsm[i]);
  }
  text += StringPrintf("least-squares rejections: %s\n",
                       lsm.empty() ? "none" : lsm.c_str());
  return text;
}

}  // namespace bayon
