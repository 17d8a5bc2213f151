// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/relative_eval.h"

#include "ext/colmap/table_relative.h"
#include "ext/core/errors.h"
#include "ext/core/rigid3.h"
#include "ext/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace bayon {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

// The pairs to judge, each in image id order: a ring's in ring order,
// otherwise by pair id.
std::vector<std::pair<image_t, image_t>> PairsToJudge(
    Database* database,
    const std::vector<DatabaseImage>& images,
    const std::map<pair_t, RelativeOrientationRecord>& records,
    bool adjacent_only) {
  std::vector<pair_t> pair_ids;
  if (adjacent_only) {
    const size_t n = images.size();
    for (size_t k = 0; n > 1 && k < (n == 2 ? 1 : n); ++k) {
      pair_ids.push_back(
          PairIdFromImageIds(images[k].image_id, images[(k + 1) % n].image_id));
    }
  } else {
    std::set<pair_t> all;
    for (const pair_t pair_id : database->ReadMatchedPairIds()) {
      all.insert(pair_id);
    }
    for (const auto& [pair_id, record] : records) all.insert(pair_id);
    pair_ids.assign(all.begin(), all.end());
  }
  std::vector<std::pair<image_t, image_t>> pairs;
  for (const pair_t pair_id : pair_ids) {
    pairs.push_back(ImageIdsFromPairId(pair_id));
  }
  return pairs;
}

void Summarise(RelativeEvaluation* evaluation) {
  std::vector<double> rotation_errors;
  for (const PairEvaluation& pair : evaluation->pairs) {
    ++evaluation->num_pairs;
    if (!pair.oriented) continue;
    ++evaluation->num_oriented;
    rotation_errors.push_back(pair.rotation_error_deg);
    evaluation->max_rotation_error_deg =
        std::max(evaluation->max_rotation_error_deg, pair.rotation_error_deg);
    evaluation->max_base_error_deg =
        std::max(evaluation->max_base_error_deg, pair.base_error_deg);
    if (pair.std_rotation_deg > 0) {
      evaluation->max_rotation_ratio =
          std::max(evaluation->max_rotation_ratio,
                   pair.rotation_error_deg / pair.std_rotation_deg);
    }
    if (pair.std_base_deg > 0) {
      evaluation->max_base_ratio = std::max(
          evaluation->max_base_ratio, pair.base_error_deg / pair.std_base_deg);
    }
  }
  if (!rotation_errors.empty()) {
    evaluation->median_rotation_error_deg = Median(std::move(rotation_errors));
  }
}

}  // namespace

RelativeEvaluation EvaluateRelativeOrientations(
    Database* database,
    const Scene& truth,
    const RelativeEvaluationOptions& options) {
  const std::vector<DatabaseImage> images = database->ReadAllImages();
  std::map<image_t, std::string> names;
  for (const DatabaseImage& image : images) names[image.image_id] = image.name;
  const std::map<pair_t, RelativeOrientationRecord> records =
      ReadAllRelativeOrientations(database);

  RelativeEvaluation evaluation;
  for (const auto& [id1, id2] :
       PairsToJudge(database, images, records, options.adjacent_only)) {
    PairEvaluation pair;
    pair.name1 = names.at(id1);
    pair.name2 = names.at(id2);
    const Image* truth1 = truth.FindImageByName(pair.name1);
    const Image* truth2 = truth.FindImageByName(pair.name2);
    if (truth1 == nullptr || truth2 == nullptr) {
      ThrowInputError("image '",
                      truth1 == nullptr ? pair.name1 : pair.name2,
                      "' of the database is not in the truth");
    }
    const auto record = records.find(PairIdFromImageIds(id1, id2));
    if (record == records.end() || !record->second.success) {
      pair.reason =
          record == records.end() ? "no orientation" : record->second.reason;
      evaluation.pairs.push_back(pair);
      continue;
    }
    const RelativeOrientationRecord& r = record->second;
    pair.oriented = true;
    pair.num_matches = r.num_matches;
    pair.num_inliers = r.num_inliers;
    pair.sigma0_px = r.sigma0_px;
    pair.std_rotation_deg = r.std_omega_phi_kappa_deg.norm();
    pair.std_base_deg = r.std_base_deg.norm();
    // The record is cam2_from_cam1 with image 1 the smaller id.
    const Rigid3d true_pose =
        truth2->cam_from_world * truth1->cam_from_world.Inverse();
    pair.rotation_error_deg =
        RotationAngleBetween(r.cam2_from_cam1.rotation, true_pose.rotation) *
        kDegPerRad;
    const Eigen::Vector3d a = r.cam2_from_cam1.Center().normalized();
    const Eigen::Vector3d b = true_pose.Center().normalized();
    pair.base_error_deg = std::atan2(a.cross(b).norm(), a.dot(b)) * kDegPerRad;
    evaluation.pairs.push_back(pair);
  }
  Summarise(&evaluation);
  return evaluation;
}

std::string RelativeEvaluationTable(const std::string& label,
                                    const RelativeEvaluation& evaluation) {
  std::string table = StrCat(label,
                             ": pair orientations against the truth (",
                             evaluation.num_oriented,
                             " of ",
                             evaluation.num_pairs,
                             " pairs oriented)\n");
  char line[320];
  for (const PairEvaluation& pair : evaluation.pairs) {
    if (!pair.oriented) {
      std::snprintf(line,
                    sizeof(line),
                    "  %s - %s: not oriented (%s)\n",
                    pair.name1.c_str(),
                    pair.name2.c_str(),
                    pair.reason.c_str());
    } else {
      std::snprintf(line,
                    sizeof(line),
                    "  %s - %s: %4d of %4d matches, sigma0 %.3f px, rotation "
                    "error %.4f deg (std %.4f), base error %.3f deg (std "
                    "%.3f)\n",
                    pair.name1.c_str(),
                    pair.name2.c_str(),
                    pair.num_inliers,
                    pair.num_matches,
                    pair.sigma0_px,
                    pair.rotation_error_deg,
                    pair.std_rotation_deg,
                    pair.base_error_deg,
                    pair.std_base_deg);
    }
    table += line;
  }
  std::snprintf(line,
                sizeof(line),
                "  largest errors %.4f deg rotation, %.3f deg base (%.1f and "
                "%.1f standard deviations); median rotation error %.4f deg\n",
                evaluation.max_rotation_error_deg,
                evaluation.max_base_error_deg,
                evaluation.max_rotation_ratio,
                evaluation.max_base_ratio,
                evaluation.median_rotation_error_deg);
  return table + line;
}

nlohmann::ordered_json RelativeEvaluationJson(const RelativeEvaluation& e) {
  nlohmann::ordered_json json = {
      {"num_pairs", e.num_pairs},
      {"num_oriented", e.num_oriented},
      {"median_rotation_error_deg", e.median_rotation_error_deg},
      {"max_rotation_error_deg", e.max_rotation_error_deg},
      {"max_base_error_deg", e.max_base_error_deg},
      {"max_rotation_ratio", e.max_rotation_ratio},
      {"max_base_ratio", e.max_base_ratio},
      {"pairs", nlohmann::ordered_json::array()}};
  for (const PairEvaluation& pair : e.pairs) {
    nlohmann::ordered_json p = {{"image1", pair.name1},
                                {"image2", pair.name2},
                                {"oriented", pair.oriented}};
    if (pair.oriented) {
      p["num_matches"] = pair.num_matches;
      p["num_inliers"] = pair.num_inliers;
      p["sigma0_px"] = pair.sigma0_px;
      p["rotation_error_deg"] = pair.rotation_error_deg;
      p["std_rotation_deg"] = pair.std_rotation_deg;
      p["base_error_deg"] = pair.base_error_deg;
      p["std_base_deg"] = pair.std_base_deg;
    } else {
      p["reason"] = pair.reason;
    }
    json["pairs"].push_back(p);
  }
  return json;
}

}  // namespace bayon
