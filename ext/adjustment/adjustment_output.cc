// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment_output.h"

#include "ext/colmap/model_io.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/string_printf.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace bayon {
namespace {

using Json = nlohmann::ordered_json;

constexpr double kMm = 1000.0;
constexpr double kMilliDeg = 180.0 / M_PI * 1000.0;

Json Vec(const Eigen::Vector3d& v) { return Json::array({v(0), v(1), v(2)}); }

Eigen::Vector3d StdDevs(const Eigen::Matrix3d& covariance) {
  return covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
}

// Units of the camera parameters, for the printout.
std::string ParameterUnit(CameraModelId model, const std::string& name) {
  if (model != CameraModelId::kBrownBeyer) {
    return name == "f" || name == "fx" || name == "fy" || name == "cx" ||
                   name == "cy"
               ? "px"
               : "-";
  }
  if (name == "c" || name == "x0" || name == "y0" || name == "dc" ||
      name == "dx0" || name == "dy0") {
    return "mm";
  }
  if (name == "K1") return "mm^-2";
  if (name == "K2") return "mm^-4";
  if (name == "K3") return "mm^-6";
  if (name == "P1" || name == "P2") return "mm^-1";
  return "-";
}

struct Counts {
  std::vector<int> rays;  // per block point
  std::map<int, int> histogram;
  int num_tie = 0;
  int num_control = 0;
  int num_check = 0;
};

Counts CountPoints(const AdjustmentBlock& block) {
  Counts counts;
  counts.rays = block.CountPointObservations();
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (!point.active) continue;
    switch (point.kind) {
      case PointKind::kTie:
        ++counts.num_tie;
        ++counts.histogram[std::min(counts.rays[p], 10)];
        break;
      case PointKind::kControl:
        ++counts.num_control;
        break;
      case PointKind::kCheck:
        ++counts.num_check;
        break;
    }
  }
  return counts;
}

std::string PointLabel(const BlockPoint& point) {
  if (!point.name.empty()) return point.name;
  return std::to_string(point.point3D_id);
}

class ReportBuilder {
 public:
  ReportBuilder(const AdjustmentInput& input,
                const AdjustmentResult& result,
                const AdjustmentOptions& options,
                const AdjustmentRunInfo& info)
      : input_(input),
        block_(input.block),
        result_(result),
        precision_(result.precision),
        options_(options),
        info_(info),
        counts_(CountPoints(input.block)) {}

  Json Build() {
    Json root;
    root["format"] = "bayon-adjustment";
    root["version"] = 1;
    root["input"] = {{"database_path", info_.database_path},
                     {"input_path", info_.input_path},
                     {"control_path", info_.control_path}};
    root["datum"] = DatumJson();
    // The control's frame in the world (bayon import_control's crs.json):
    // the model's coordinates are the CRS's minus the origin. Only a block
    // fitted to the control lies in that frame: a free or minimum datum
    // (fewer than three control points) does not.
    if (!info_.georeference_json.empty()) {
      if (input_.datum.type == DatumType::kControl) {
        root["georeference"] = Json::parse(info_.georeference_json);
      } else {
        LOG(WARNING) << info_.control_path
                     << "/crs.json: not carried to the model, whose datum is "
                     << DatumTypeName(input_.datum.type)
                     << ", not the control's (it needs three control points)";
      }
    }
    root["cameras"] = CamerasJson();
    root["steps"] = StepsJson();
    root["statistics"] = StatisticsJson();
    root["self_calibration"] = SelfCalibrationJson();
    root["blunder_detection"] = BlundersJson();
    root["check_points"] = CheckPointsJson();
    root["control_points"] = ControlPointsJson();
    root["distances"] = DistancesJson();
    root["images"] = ImagesJson();
    root["points"] = PointsJson();
    root["notes"] = input_.notes;
    return root;
  }

  double check_rms_m() const { return check_rms_m_; }

 private:
  Json DatumJson() const {
    const DatumSetup& datum = input_.datum;
    Json json;
    json["type"] = DatumTypeName(datum.type);
    json["description"] = datum.description;
    json["precision"] = PrecisionMeaning();
    // What z is: up from the control or the bar, up from the photographs
    // (an upright free network), or "" (arbitrary).
    json["vertical"] = datum.vertical;
    if (datum.type == DatumType::kFree) {
      json["num_datum_points"] = precision_.num_datum_points;
      json["min_datum_intersection_angle_deg"] = kMinDatumIntersectionAngleDeg;
    }
    const Sim3d& sim = datum.object_from_model;
    json["object_from_model"] = {{"scale", sim.scale},
                                 {"qvec",
                                  {sim.rotation.w(),
                                   sim.rotation.x(),
                                   sim.rotation.y(),
                                   sim.rotation.z()}},
                                 {"tvec", Vec(sim.translation)}};
    if (!datum.similarity_residuals.empty()) {
      Json residuals = Json::array();
      for (const SimilarityResidual& r : datum.similarity_residuals) {
        residuals.push_back({{"name", r.name},
                             {"residual_m", Vec(r.residual)},
                             {"inlier", r.inlier}});
      }
      json["similarity_rms_m"] = datum.similarity_rms_m;
      json["similarity_residuals"] = residuals;
    }
    return json;
  }

  // What the standard deviations of this datum mean.
  std::string PrecisionMeaning() const {
    switch (input_.datum.type) {
      case DatumType::kFree:
        return StrCat(
            "relative to the centroid of the ",
            precision_.num_datum_points,
            " tie points whose rays intersect at ",
            kMinDatumIntersectionAngleDeg,
            " deg or more (inner constraints): the precision of the "
            "network's shape, without its position, orientation and scale; "
            "it is what remains after aligning the model to any reference by "
            "a similarity over those points");
      case DatumType::kMinimum:
        return "in the object frame of the minimum datum: relative to the "
               "levelling bar's lower end (held), with the bar's length as "
               "the scale and its direction as the vertical, and the held "
               "coordinate of the datum point; they grow with the distance "
               "from the bar";
      case DatumType::kControl:
      case DatumType::kAuto:
        break;
    }
    return "in the control points' frame: they include the given standard "
           "deviations of weighted control points and take held control "
           "coordinates as exact; check points are compared with their "
           "given coordinates";
  }

  Json CamerasJson() const {
    Json cameras = Json::array();
    for (size_t c = 0; c < block_.cameras.size(); ++c) {
      const Camera& camera = block_.cameras[c].camera;
      const CameraSource& source = input_.cameras[c];
      Json json = {{"camera_id", camera.camera_id},
                   {"model", camera.ModelName()},
                   {"source", source.source},
                   {"input_model", source.input_model}};
      if (source.conversion_rms_px > 0) {
        json["conversion_rms_px"] = source.conversion_rms_px;
      }
      if (camera.pixel_pitch_mm > 0) {
        json["pixel_pitch_mm"] = camera.pixel_pitch_mm;
      }
      cameras.push_back(json);
    }
    return cameras;
  }

  Json StepsJson() const {
    Json steps = Json::array();
    for (const AdjustmentStep& step : result_.steps) {
      steps.push_back({{"name", step.name},
                       {"iterations", step.num_iterations},
                       {"sigma0_px", step.sigma0},
                       {"time_s", step.time_s}});
    }
    return steps;
  }

  // Mean pixel size (mm) over the images with a photogrammetric camera; 0
  // when the block adjusts COLMAP cameras (pixels only).
  double MeanPitchMm() const {
    double sum = 0;
    int count = 0;
    for (const BlockImage& image : block_.images) {
      if (block_.cameras[image.camera_idx].camera.model_id !=
          CameraModelId::kBrownBeyer) {
        continue;
      }
      sum += image.frame.MeanPitchMm();
      ++count;
    }
    return count > 0 ? sum / count : 0.0;
  }

  Json StatisticsJson() {
    const AdjustmentPrecision& p = precision_;
    Json json;
    json["num_images"] = block_.images.size();
    json["num_tie_points"] = counts_.num_tie;
    json["num_control_points"] = counts_.num_control;
    json["num_check_points"] = counts_.num_check;
    Json histogram;
    for (const auto& [rays, count] : counts_.histogram) {
      histogram[rays == 10 ? "10+" : std::to_string(rays)] = count;
    }
    json["tie_points_by_rays"] = histogram;
    json["n"] = p.num_observations;
    json["n_image_coordinates"] = p.num_image_coordinates;
    json["u"] = p.num_unknowns;
    json["d"] = p.datum_defect;
    json["r"] = p.redundancy;
    json["r_over_n"] = static_cast<double>(p.redundancy) / p.num_observations;
    json["sigma0_apriori_px"] = block_.sigma0_px;
    json["sigma0_px"] = p.sigma0;
    const double pitch = MeanPitchMm();
    if (pitch > 0) json["sigma0_image_um"] = p.sigma0 * pitch * 1000.0;
    json["variance_factor"] = p.sigma0 / block_.sigma0_px;
    if (!result_.variance_components.empty()) {
      Json components = Json::array();
      for (const VarianceComponent& c : result_.variance_components) {
        components.push_back({{"group", c.name},
                              {"num_observations", c.num_observations},
                              {"redundancy", c.redundancy},
                              {"variance_scale", c.variance_scale},
                              {"median_sigma_px", c.median_sigma_px}});
      }
      json["variance_components"] = components;
    }
    // Image residuals.
    Eigen::Vector2d sum_sq = Eigen::Vector2d::Zero();
    double max_residual = 0, sum_redundancy = 0, min_redundancy = 1;
    double sum_norm = 0;
    int count = 0;
    for (const ObservationStatistics& s : p.observations) {
      if (!s.valid) continue;
      sum_sq += s.residual_px.cwiseAbs2();
      sum_norm += s.residual_px.norm();
      max_residual = std::max(max_residual, s.residual_px.norm());
      sum_redundancy += s.redundancy.sum();
      min_redundancy = std::min(min_redundancy, s.redundancy.minCoeff());
      ++count;
    }
    if (count > 0) {
      json["residual_rms_px"] = {std::sqrt(sum_sq.x() / count),
                                 std::sqrt(sum_sq.y() / count)};
      json["residual_max_px"] = max_residual;
      // COLMAP's figure (model_analyzer's "mean reprojection error").
      json["mean_reprojection_error_px"] = sum_norm / count;
      json["redundancy_number_mean"] = sum_redundancy / (2.0 * count);
      json["redundancy_number_min"] = min_redundancy;
    }
    // Theoretical precision of the tie points and of the exterior
    // orientations: RMS of the standard deviations. The tie points whose
    // rays meet at less than kMinDatumIntersectionAngleDeg are counted apart:
    // each is free to slide along its rays, and a handful of them would
    // make the RMS of all (each keeps its own figure in "points").
    Eigen::Vector3d point_sq = Eigen::Vector3d::Zero(),
                    point_max = Eigen::Vector3d::Zero();
    int num_points = 0, num_weak = 0;
    const std::vector<double> angles = block_.IntersectionAnglesDeg();
    for (size_t i = 0; i < block_.points.size(); ++i) {
      const BlockPoint& point = block_.points[i];
      if (!point.active || point.kind != PointKind::kTie) continue;
      if (angles[i] < kMinDatumIntersectionAngleDeg) {
        ++num_weak;
        continue;
      }
      const Eigen::Vector3d s = StdDevs(p.point_covariance[i]);
      point_sq += s.cwiseAbs2();
      point_max = point_max.cwiseMax(s);
      ++num_points;
    }
    if (num_points > 0) {
      json["point_precision_rms_mm"] =
          Vec(kMm * (point_sq / num_points).cwiseSqrt());
      json["point_precision_max_mm"] = Vec(kMm * point_max);
    }
    json["num_weak_tie_points"] = num_weak;
    json["min_intersection_angle_deg"] = kMinDatumIntersectionAngleDeg;
    Eigen::Vector3d center_sq = Eigen::Vector3d::Zero(),
                    rotation_sq = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < block_.images.size(); ++i) {
      const Eigen::Matrix<double, 6, 6>& C = p.image_covariance[i];
      center_sq += C.diagonal().tail<3>();
      rotation_sq += C.diagonal().head<3>();
    }
    const double num_images = static_cast<double>(block_.images.size());
    json["center_precision_rms_mm"] =
        Vec(kMm * (center_sq / num_images).cwiseMax(0.0).cwiseSqrt());
    json["rotation_precision_rms_mdeg"] =
        Vec(kMilliDeg * (rotation_sq / num_images).cwiseMax(0.0).cwiseSqrt());
    json["time_s"] = result_.total_time_s;
    return json;
  }

  Json SelfCalibrationJson() const {
    Json json;
    json["mode"] = info_.self_calibration;
    json["significance_t"] = options_.significance_t;
    json["candidates"] = result_.candidate_parameters;
    Json removed = Json::array();
    for (const RemovedParameter& r : result_.removed_parameters) {
      removed.push_back(
          {{"camera_id",
            block_.cameras[r.estimate.camera_idx].camera.camera_id},
           {"name", r.estimate.name},
           {"value", r.estimate.value},
           {"std_dev", r.estimate.std_dev},
           {"t", r.estimate.t_value},
           {"reason", r.reason}});
    }
    json["removed"] = removed;
    Json parameters = Json::array();
    for (const ParameterEstimate& e : result_.final_parameters) {
      const Camera& camera = block_.cameras[e.camera_idx].camera;
      parameters.push_back(
          {{"camera_id", camera.camera_id},
           {"name", e.name},
           {"unit", ParameterUnit(camera.model_id, e.name)},
           {"value", e.value},
           {"std_dev", e.std_dev},
           {"t", std::isfinite(e.t_value) ? Json(e.t_value) : Json(nullptr)},
           {"max_correlation_exterior", e.exterior_correlation}});
    }
    json["parameters"] = parameters;
    Json correlations = Json::array();
    for (size_t c = 0; c < block_.cameras.size(); ++c) {
      std::vector<std::string> names;
      for (const ParameterEstimate& e : result_.final_parameters) {
        if (e.camera_idx == static_cast<int>(c)) names.push_back(e.name);
      }
      const Eigen::MatrixXd& m = result_.parameter_correlations[c];
      Json matrix = Json::array();
      for (Eigen::Index i = 0; i < m.rows(); ++i) {
        std::vector<double> row(m.cols());
        for (Eigen::Index j = 0; j < m.cols(); ++j) row[j] = m(i, j);
        matrix.push_back(row);
      }
      correlations.push_back({{"camera_id", block_.cameras[c].camera.camera_id},
                              {"names", names},
                              {"matrix", matrix}});
    }
    json["correlations"] = correlations;
    Json flags = Json::array();
    for (const CorrelationFlag& flag : result_.correlation_flags) {
      flags.push_back(
          {{"camera_id", block_.cameras[flag.camera_idx].camera.camera_id},
           {"parameters", {flag.name1, flag.name2}},
           {"correlation", flag.correlation}});
    }
    json["max_correlation"] = options_.max_correlation;
    json["flagged_correlations"] = flags;
    return json;
  }

  Json BlundersJson() const {
    Json json;
    json["method"] = info_.blunder_detection;
    json["critical_value"] = options_.snooping_critical_value;
    json["iterations"] = result_.num_snooping_iterations;
    json["num_rejected"] = result_.rejected.size();
    json["num_points_removed"] = result_.num_points_removed;
    Json rejected = Json::array();
    for (const RejectedObservation& r : result_.rejected) {
      const BlockObservation& o = block_.observations[r.observation_idx];
      Json item = {{"image", block_.images[o.image_idx].name},
                   {"point", PointLabel(block_.points[o.point_idx])}};
      if (o.point2D_idx != kInvalidPoint2DIdx) {
        item["point2D_idx"] = o.point2D_idx;
      }
      item["xy"] = {o.xy.x(), o.xy.y()};
      item["residual_px"] = {r.residual_px.x(), r.residual_px.y()};
      item["w"] = r.w;
      item["redundancy"] = r.redundancy;
      item["iteration"] = r.iteration;
      rejected.push_back(item);
    }
    json["rejected"] = rejected;
    return json;
  }

  Json CheckPointsJson() {
    Json json;
    Json points = Json::array();
    Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
    int count = 0;
    double max_normalized = 0;
    for (size_t i = 0; i < block_.points.size(); ++i) {
      const BlockPoint& point = block_.points[i];
      if (point.kind != PointKind::kCheck || !point.active) continue;
      const Eigen::Vector3d difference = point.xyz - point.given_xyz;
      sum_sq += difference.cwiseAbs2();
      ++count;
      // The difference's standard deviation: the adjusted point's and the
      // given coordinates' (the survey's), independent of each other.
      const Eigen::Vector3d std_dev = StdDevs(precision_.point_covariance[i]);
      const Eigen::Vector3d difference_std_dev =
          (std_dev.cwiseAbs2() + point.given_sigma.cwiseAbs2()).cwiseSqrt();
      double normalized = 0;  // over the axes with a standard deviation
      for (int k = 0; k < 3; ++k) {
        if (difference_std_dev[k] > 0) {
          normalized = std::max(
              normalized, std::abs(difference[k]) / difference_std_dev[k]);
        }
      }
      max_normalized = std::max(max_normalized, normalized);
      points.push_back({{"name", point.name},
                        {"given", Vec(point.given_xyz)},
                        {"adjusted", Vec(point.xyz)},
                        {"difference_mm", Vec(kMm * difference)},
                        {"std_dev_mm", Vec(kMm * std_dev)},
                        {"given_std_dev_mm", Vec(kMm * point.given_sigma)},
                        {"max_normalized_difference", normalized},
                        {"rays", counts_.rays[i]}});
    }
    json["num"] = count;
    // The largest |difference| over its standard deviation (adjusted and
    // given together), over the axes and points: within 3 where the stated
    // precisions hold.
    json["max_normalized_difference"] = max_normalized;
    if (count > 0) {
      const Eigen::Vector3d rms = (sum_sq / count).cwiseSqrt();
      json["rms_mm"] = Vec(kMm * rms);
      check_rms_m_ = rms.norm();
      json["rms_3d_mm"] = kMm * check_rms_m_;
    }
    json["points"] = points;
    return json;
  }

  Json ControlPointsJson() const {
    Json points = Json::array();
    for (size_t i = 0; i < block_.points.size(); ++i) {
      const BlockPoint& point = block_.points[i];
      if (point.kind != PointKind::kControl) continue;
      Json fixed = Json::array();
      for (int k = 0; k < 3; ++k) fixed.push_back(point.fixed[k]);
      Json item = {
          {"name", point.name},
          {"given", Vec(point.given_xyz)},
          {"adjusted", Vec(point.xyz)},
          {"fixed", fixed},
          {"residual_mm", Vec(kMm * (point.xyz - point.given_xyz))},
          {"std_dev_mm", Vec(kMm * StdDevs(precision_.point_covariance[i]))},
          {"rays", counts_.rays[i]}};
      points.push_back(item);
    }
    return points;
  }

  Json DistancesJson() const {
    Json distances = Json::array();
    for (size_t d = 0; d < block_.distances.size(); ++d) {
      const BlockDistance& distance = block_.distances[d];
      const BlockPoint& a = block_.points[distance.point_a];
      const BlockPoint& b = block_.points[distance.point_b];
      Json item = {{"points", {a.name, b.name}},
                   {"given_m", distance.distance_m},
                   {"adjusted_m", (b.xyz - a.xyz).norm()}};
      if (d < precision_.distance_redundancy.size()) {
        item["redundancy"] = precision_.distance_redundancy[d];
      }
      distances.push_back(item);
    }
    return distances;
  }

  Json ImagesJson() const {
    Json images = Json::array();
    for (size_t i = 0; i < block_.images.size(); ++i) {
      const BlockImage& image = block_.images[i];
      const Eigen::Matrix<double, 6, 6>& C = precision_.image_covariance[i];
      const Eigen::Vector3d s_center =
          C.diagonal().tail<3>().cwiseMax(0.0).cwiseSqrt();
      const Eigen::Vector3d s_rotation =
          C.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt();
      images.push_back(
          {{"image_id", image.image_id},
           {"name", image.name},
           {"qvec",
            {image.rotation(0),
             image.rotation(1),
             image.rotation(2),
             image.rotation(3)}},
           {"center", Vec(image.center)},
           {"center_std_dev_mm", Vec(kMm * s_center)},
           {"rotation_std_dev_mdeg", Vec(kMilliDeg * s_rotation)}});
    }
    return images;
  }

  Json PointsJson() const {
    Json points = Json::array();
    for (size_t i = 0; i < block_.points.size(); ++i) {
      const BlockPoint& point = block_.points[i];
      if (!point.active) continue;
      Json item;
      if (point.point3D_id != kInvalidPoint3DId) {
        item["point3D_id"] = point.point3D_id;
      }
      if (!point.name.empty()) item["name"] = point.name;
      item["kind"] = PointKindName(point.kind);
      item["xyz"] = Vec(point.xyz);
      item["std_dev_mm"] = Vec(kMm * StdDevs(precision_.point_covariance[i]));
      item["rays"] = counts_.rays[i];
      points.push_back(item);
    }
    return points;
  }

  const AdjustmentInput& input_;
  const AdjustmentBlock& block_;
  const AdjustmentResult& result_;
  const AdjustmentPrecision& precision_;
  const AdjustmentOptions& options_;
  const AdjustmentRunInfo& info_;
  Counts counts_;
  double check_rms_m_ = 0;
};

// ---------------------------------------------------------------------------
// The printout.

std::string Rule(char c = '-') { return std::string(79, c) + "\n"; }

std::string Triple(const Json& v, const char* format) {
  return StringPrintf(
      format, v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

// The title, the inputs, the datum and the notes.
std::string PrintoutHeader(const Json& r) {
  std::string out;
  out += Rule('=');
  out +=
      " bayon adjust: self-calibrating bundle adjustment (SGAP after Gruen, "
      "Zhang,\n Visnovcova, Bayon tower, section 3.2.4)\n";
  out += Rule('=');
  out += StringPrintf(" %-18s %s\n",
                      "input model",
                      r["input"]["input_path"].get<std::string>().c_str());
  out += StringPrintf(" %-18s %s\n",
                      "database",
                      r["input"]["database_path"].get<std::string>().c_str());
  const std::string control = r["input"]["control_path"].get<std::string>();
  out += StringPrintf(
      " %-18s %s\n", "control", control.empty() ? "(none)" : control.c_str());
  out += StringPrintf(" %-18s %s: %s\n",
                      "datum",
                      r["datum"]["type"].get<std::string>().c_str(),
                      r["datum"]["description"].get<std::string>().c_str());
  for (const Json& camera : r["cameras"]) {
    out += StringPrintf(" %-18s %u %s from %s",
                        "camera",
                        camera["camera_id"].get<unsigned>(),
                        camera["model"].get<std::string>().c_str(),
                        camera["source"].get<std::string>().c_str());
    if (camera.contains("conversion_rms_px")) {
      out += StringPrintf(" (fit %.3f px RMS)",
                          camera["conversion_rms_px"].get<double>());
    }
    out += "\n";
  }
  if (r["datum"].contains("similarity_residuals")) {
    out += "\n 7-PARAMETER SIMILARITY MODEL -> OBJECT (approximations)\n";
    const Json& sim = r["datum"]["object_from_model"];
    out += StringPrintf("   scale %.6f   RMS residual %.1f mm\n",
                        sim["scale"].get<double>(),
                        kMm * r["datum"]["similarity_rms_m"].get<double>());
    for (const Json& res : r["datum"]["similarity_residuals"]) {
      out +=
          StringPrintf("   %-12s %s%s\n",
                       res["name"].get<std::string>().c_str(),
                       Triple(res["residual_m"], "%9.4f %9.4f %9.4f m").c_str(),
                       res["inlier"].get<bool>() ? "" : "   SUSPECT");
    }
  }
  if (r["datum"].contains("precision")) {
    out += StringPrintf(" %-18s %s\n",
                        "standard dev.",
                        r["datum"]["precision"].get<std::string>().c_str());
  }
  if (r["datum"]["type"] == "free") {
    out +=
        " note: a free network keeps the input model's units; figures in "
        "mm are 1/1000 of them\n";
  }
  for (const Json& note : r["notes"]) {
    out += " note: " + note.get<std::string>() + "\n";
  }
  return out;
}

// The steps of the adjustment: iterations, sigma0 and time.
std::string PrintoutIterations(const Json& r) {
  std::string out;
  out += "\n ITERATIONS\n";
  for (const Json& step : r["steps"]) {
    out += StringPrintf("   %-40s %4d it.",
                        step["name"].get<std::string>().c_str(),
                        step["iterations"].get<int>());
    if (step["sigma0_px"].get<double>() > 0) {
      out +=
          StringPrintf("   sigma0 %8.4f px", step["sigma0_px"].get<double>());
    }
    out += StringPrintf("   %6.2f s\n", step["time_s"].get<double>());
  }
  return out;
}

// Observations, unknowns, redundancy, sigma0 and the theoretical precision.
std::string PrintoutStatistics(const Json& r) {
  std::string out;
  const Json& s = r["statistics"];
  out += "\n" + Rule();
  out += " STATISTICS\n" + Rule();
  out += StringPrintf("   images                                   %8d\n",
                      s["num_images"].get<int>());
  out +=
      StringPrintf("   tie points                               %8d   by rays:",
                   s["num_tie_points"].get<int>());
  for (const auto& [rays, count] : s["tie_points_by_rays"].items()) {
    out += StringPrintf(" %s:%d", rays.c_str(), count.get<int>());
  }
  out += "\n";
  out += StringPrintf("   control points / check points            %8d / %d\n",
                      s["num_control_points"].get<int>(),
                      s["num_check_points"].get<int>());
  out += StringPrintf(
      "   observations                         n = %8d   (image "
      "coordinates %d)\n",
      s["n"].get<int>(),
      s["n_image_coordinates"].get<int>());
  out += StringPrintf("   unknowns                             u = %8d\n",
                      s["u"].get<int>());
  out += StringPrintf("   datum defect                         d = %8d\n",
                      s["d"].get<int>());
  out += StringPrintf("   redundancy                           r = %8d\n",
                      s["r"].get<int>());
  out += StringPrintf("   global internal reliability        r/n = %8.3f\n",
                      s["r_over_n"].get<double>());
  out += StringPrintf("   sigma0 a priori                          %8.4f px\n",
                      s["sigma0_apriori_px"].get<double>());
  out += StringPrintf("   sigma0 a posteriori                  s0 = %8.4f px",
                      s["sigma0_px"].get<double>());
  if (s.contains("sigma0_image_um")) {
    out += StringPrintf(" = %.2f micron", s["sigma0_image_um"].get<double>());
  }
  out += "\n";
  if (s.contains("variance_components")) {
    out += "   variance components (a priori variances scaled per group):\n";
    for (const Json& c : s["variance_components"]) {
      out += StringPrintf(
          "     %-26s %7d points  r = %9.1f  x %8.4f  -> %.4f px\n",
          c["group"].get<std::string>().c_str(),
          c["num_observations"].get<int>(),
          c["redundancy"].get<double>(),
          c["variance_scale"].get<double>(),
          c["median_sigma_px"].get<double>());
    }
  }
  if (s.contains("residual_rms_px")) {
    out += StringPrintf(
        "   RMS of image residuals x, y              %8.4f %8.4f "
        "px   (max %.3f px)\n",
        s["residual_rms_px"][0].get<double>(),
        s["residual_rms_px"][1].get<double>(),
        s["residual_max_px"].get<double>());
    out +=
        StringPrintf("   mean reprojection error (COLMAP's)       %8.4f px\n",
                     s["mean_reprojection_error_px"].get<double>());
    out += StringPrintf(
        "   redundancy numbers, mean / min           %8.3f / %.3f\n",
        s["redundancy_number_mean"].get<double>(),
        s["redundancy_number_min"].get<double>());
  }
  if (s.contains("point_precision_rms_mm")) {
    out += StringPrintf(
        "   theoretical precision of the tie points (RMS; without the %d "
        "whose rays meet at less than %.1f deg):\n",
        s["num_weak_tie_points"].get<int>(),
        s["min_intersection_angle_deg"].get<double>());
    out += "     " +
           Triple(s["point_precision_rms_mm"],
                  "sx = %.2f mm   sy = %.2f mm   sz = %.2f mm") +
           Triple(s["point_precision_max_mm"], "   (max %.2f %.2f %.2f)") +
           "\n";
  }
  out += "   theoretical precision of the exterior orientations (RMS):\n";
  out += "     " +
         Triple(s["center_precision_rms_mm"],
                "sX0 = %.2f mm  sY0 = %.2f mm  sZ0 = %.2f mm") +
         "\n     " +
         Triple(s["rotation_precision_rms_mdeg"],
                "rotations about the camera axes x, y, z: %.3f %.3f %.3f "
                "mdeg") +
         "\n";
  return out;
}

// The self-calibration: parameters kept and removed, their correlations.
std::string PrintoutCameraParameters(const Json& r) {
  std::string out;
  const Json& sc = r["self_calibration"];
  out += "\n" + Rule();
  out += StringPrintf(
      " CAMERA PARAMETERS (self-calibration: %s, t-test at %.2f)\n",
      sc["mode"].get<std::string>().c_str(),
      sc["significance_t"].get<double>());
  out += Rule();
  out +=
      "   camera  parameter          value        std dev        t   unit"
      "     max corr. with ext. or.\n";
  for (const Json& p : sc["parameters"]) {
    out += StringPrintf(
        "   %6u  %-9s %14.6e %14.6e %8s   %-6s %6.2f\n",
        p["camera_id"].get<unsigned>(),
        p["name"].get<std::string>().c_str(),
        p["value"].get<double>(),
        p["std_dev"].get<double>(),
        p["t"].is_null() ? "-"
                         : StringPrintf("%.1f", p["t"].get<double>()).c_str(),
        p["unit"].get<std::string>().c_str(),
        p["max_correlation_exterior"].get<double>());
  }
  for (const Json& p : sc["removed"]) {
    out += StringPrintf("   removed %-9s %14.6e %14.6e %8.2f   %s\n",
                        p["name"].get<std::string>().c_str(),
                        p["value"].get<double>(),
                        p["std_dev"].get<double>(),
                        p["t"].get<double>(),
                        p["reason"].get<std::string>().c_str());
  }
  for (const Json& c : sc["correlations"]) {
    const std::vector<std::string> names = c["names"];
    if (names.size() < 2) continue;
    out += StringPrintf("\n   correlation matrix, camera %u\n          ",
                        c["camera_id"].get<unsigned>());
    for (const std::string& name : names)
      out += StringPrintf("%7s", name.c_str());
    out += "\n";
    for (size_t i = 0; i < names.size(); ++i) {
      out += StringPrintf("   %-6s", names[i].c_str());
      for (size_t j = 0; j < names.size(); ++j) {
        out += StringPrintf("%7.2f", c["matrix"][i][j].get<double>());
      }
      out += "\n";
    }
  }
  if (!sc["flagged_correlations"].empty()) {
    out += StringPrintf("   correlations above %.2f:",
                        sc["max_correlation"].get<double>());
    for (const Json& f : sc["flagged_correlations"]) {
      out += StringPrintf(" %s-%s %.3f;",
                          f["parameters"][0].get<std::string>().c_str(),
                          f["parameters"][1].get<std::string>().c_str(),
                          f["correlation"].get<double>());
    }
    out += "\n";
  }
  return out;
}

// The observations data snooping rejected.
std::string PrintoutBlunders(const Json& r) {
  std::string out;
  const Json& b = r["blunder_detection"];
  out += "\n" + Rule();
  out += StringPrintf(
      " BLUNDER DETECTION (%s; data snooping, critical value %.2f)\n",
      b["method"].get<std::string>().c_str(),
      b["critical_value"].get<double>());
  out += Rule();
  out += StringPrintf(
      "   %zu observations rejected in %d iterations, %d tie points "
      "left with fewer than two rays\n",
      b["rejected"].size(),
      b["iterations"].get<int>(),
      b["num_points_removed"].get<int>());
  if (!b["rejected"].empty()) {
    out +=
        "   image                      point          vx [px]   vy [px]"
        "       w      r\n";
    for (const Json& o : b["rejected"]) {
      out += StringPrintf("   %-26s %-12s %9.2f %9.2f %7.1f %6.3f\n",
                          o["image"].get<std::string>().c_str(),
                          o["point"].get<std::string>().c_str(),
                          o["residual_px"][0].get<double>(),
                          o["residual_px"][1].get<double>(),
                          o["w"].get<double>(),
                          o["redundancy"].get<double>());
    }
  }
  return out;
}

// Check points, control points and distances.
std::string PrintoutControl(const Json& r) {
  std::string out;
  const Json& checks = r["check_points"];
  if (checks["num"].get<int>() > 0) {
    out += "\n" + Rule();
    out += " CHECK POINTS (adjusted - given)\n" + Rule();
    out +=
        "   name          dX [mm]   dY [mm]   dZ [mm]    sX [mm]   sY "
        "[mm]   sZ [mm]  rays  |d|/s\n";
    for (const Json& p : checks["points"]) {
      out +=
          StringPrintf("   %-10s %s  %s %5d %6.2f\n",
                       p["name"].get<std::string>().c_str(),
                       Triple(p["difference_mm"], "%9.2f %9.2f %9.2f").c_str(),
                       Triple(p["std_dev_mm"], "%9.2f %9.2f %9.2f").c_str(),
                       p["rays"].get<int>(),
                       p["max_normalized_difference"].get<double>());
    }
    out +=
        "   (s: the adjusted point's; |d|/s: the largest difference over "
        "its standard deviation, the given coordinates' included)\n";
    out += "   RMS        " + Triple(checks["rms_mm"], "%9.2f %9.2f %9.2f") +
           StringPrintf("    3D: %.2f mm\n", checks["rms_3d_mm"].get<double>());
  }
  if (!r["control_points"].empty()) {
    out += "\n" + Rule();
    out += " CONTROL POINTS\n" + Rule();
    out +=
        "   name            X [m]        Y [m]        Z [m]   held   "
        "residual [mm]             rays\n";
    for (const Json& p : r["control_points"]) {
      std::string held;
      for (int k = 0; k < 3; ++k) held += p["fixed"][k].get<bool>() ? "F" : "w";
      out += StringPrintf("   %-10s %s  %s   %s %5d\n",
                          p["name"].get<std::string>().c_str(),
                          Triple(p["adjusted"], "%12.4f %12.4f %12.4f").c_str(),
                          held.c_str(),
                          Triple(p["residual_mm"], "%7.2f %7.2f %7.2f").c_str(),
                          p["rays"].get<int>());
    }
  }
  if (!r["distances"].empty()) {
    out += "\n DISTANCES\n";
    for (const Json& d : r["distances"]) {
      out += StringPrintf("   %s-%s  given %.4f m  adjusted %.4f m\n",
                          d["points"][0].get<std::string>().c_str(),
                          d["points"][1].get<std::string>().c_str(),
                          d["given_m"].get<double>(),
                          d["adjusted_m"].get<double>());
    }
  }
  return out;
}

// Each image's projection centre and its precision.
std::string PrintoutExteriorOrientations(const Json& r) {
  std::string out;
  out += "\n" + Rule();
  out += " EXTERIOR ORIENTATIONS\n" + Rule();
  out +=
      "   image                         X0 [m]       Y0 [m]       Z0 [m]"
      "   sX0   sY0   sZ0 [mm]  srx  sry  srz [mdeg]\n";
  for (const Json& image : r["images"]) {
    out += StringPrintf(
        "   %-24s %s %s %s\n",
        image["name"].get<std::string>().c_str(),
        Triple(image["center"], "%12.4f %12.4f %12.4f").c_str(),
        Triple(image["center_std_dev_mm"], "%5.1f %5.1f %5.1f").c_str(),
        Triple(image["rotation_std_dev_mdeg"], "%5.1f %5.1f %5.1f").c_str());
  }
  return out;
}

// Each object point and its precision.
std::string PrintoutObjectPoints(const Json& r) {
  std::string out;
  out += "\n" + Rule();
  out += " OBJECT POINTS\n" + Rule();
  out +=
      "   point          kind          X [m]        Y [m]        Z [m]"
      "    sX    sY    sZ [mm]  rays\n";
  for (const Json& p : r["points"]) {
    const std::string label =
        p.contains("name") ? p["name"].get<std::string>()
                           : std::to_string(p["point3D_id"].get<uint64_t>());
    out += StringPrintf("   %-14s %-7s %s %s %4d\n",
                        label.c_str(),
                        p["kind"].get<std::string>().c_str(),
                        Triple(p["xyz"], "%12.4f %12.4f %12.4f").c_str(),
                        Triple(p["std_dev_mm"], "%5.1f %5.1f %5.1f").c_str(),
                        p["rays"].get<int>());
  }
  return out;
}

// The printout of `bayon adjust`, section by section, from its report.
std::string Printout(const Json& r) {
  return PrintoutHeader(r) + PrintoutIterations(r) + PrintoutStatistics(r) +
         PrintoutCameraParameters(r) + PrintoutBlunders(r) +
         PrintoutControl(r) + PrintoutExteriorOrientations(r) +
         PrintoutObjectPoints(r) + Rule('=');
}

}  // namespace

AdjustmentOutputs MakeAdjustmentOutputs(const AdjustmentInput& input,
                                        const AdjustmentResult& result,
                                        const AdjustmentOptions& options,
                                        const AdjustmentRunInfo& info) {
  AdjustmentOutputs outputs;
  const AdjustmentBlock& block = input.block;
  outputs.model = input.scene;
  UpdateSceneFromBlock(block, &outputs.model);
  const std::vector<SceneCameraConversion> conversions =
      ConvertSceneCamerasToColmap(&outputs.model);
  outputs.model.UpdateReprojectionErrors();
  std::map<camera_t, const SceneCameraConversion*> conversion_of;
  for (const SceneCameraConversion& conversion : conversions) {
    conversion_of[conversion.source.camera_id] = &conversion;
  }
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    CalibrationEntry entry;
    entry.camera = block.cameras[c].camera;
    const Eigen::MatrixXd& covariance = result.precision.camera_covariance[c];
    const Eigen::Index n = covariance.rows();
    for (Eigen::Index i = 0; i < n; ++i) {
      entry.std_devs.push_back(std::sqrt(std::max(covariance(i, i), 0.0)));
      for (Eigen::Index j = 0; j < n; ++j) {
        entry.covariance.push_back(covariance(i, j));
      }
    }
    auto it = conversion_of.find(entry.camera.camera_id);
    if (it != conversion_of.end()) {
      entry.colmap_camera = it->second->conversion.camera;
      entry.colmap_fit_rms_px = it->second->conversion.rms_residual_px;
      entry.colmap_fit_max_px = it->second->conversion.max_residual_px;
      outputs.max_colmap_fit_rms_px =
          std::max(outputs.max_colmap_fit_rms_px, entry.colmap_fit_rms_px);
    }
    outputs.calibration.push_back(std::move(entry));
  }
  ReportBuilder builder(input, result, options, info);
  Json report = builder.Build();
  Json colmap = Json::array();
  for (const CalibrationEntry& entry : outputs.calibration) {
    if (!entry.colmap_camera) continue;
    colmap.push_back({{"camera_id", entry.camera.camera_id},
                      {"model", entry.colmap_camera->ModelName()},
                      {"fit_rms_px", entry.colmap_fit_rms_px},
                      {"fit_max_px", entry.colmap_fit_max_px}});
  }
  report["colmap_cameras"] = colmap;
  outputs.json = report.dump(1) + "\n";
  if (report.contains("georeference")) {
    outputs.crs_json = report["georeference"].dump(2) + "\n";
  }
  outputs.text = Printout(report);
  for (const Json& c : colmap) {
    outputs.text += StringPrintf(
        " camera %u written to the COLMAP model as %s: fit RMS %.4f px, max "
        "%.4f px (what FULL_OPENCV cannot express, e.g. shear)\n",
        c["camera_id"].get<unsigned>(),
        c["model"].get<std::string>().c_str(),
        c["fit_rms_px"].get<double>(),
        c["fit_max_px"].get<double>());
  }
  outputs.sigma0_px = result.precision.sigma0;
  outputs.check_rms_m = builder.check_rms_m();
  return outputs;
}

void WriteAdjustmentOutputs(const AdjustmentOutputs& outputs,
                            const std::string& output_path,
                            bool overwrite) {
  OutputDirectory output(output_path, overwrite);
  WriteModel(outputs.model, output.temp_path(), ModelFormat::kBinary);
  WriteCalibrationJson(output.File("calibration.json"), outputs.calibration);
  WriteFileAtomically(output.File("adjustment.json"), outputs.json);
  WriteFileAtomically(output.File("adjustment.txt"), outputs.text);
  if (!outputs.crs_json.empty()) {
    WriteFileAtomically(output.File("crs.json"), outputs.crs_json);
  }
  output.Commit();
}

}  // namespace bayon
