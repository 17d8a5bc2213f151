// SPDX-License-Identifier: BSD-3-Clause
#include "ext/georef/crs.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <proj.h>
#include <regex>

namespace bayon {
namespace {

// A CRS object for a question about it; nullptr where PROJ does not know
// the text.
PJ* CreateCrs(PJ_CONTEXT* context, const std::string& crs) {
  PJ* object = proj_create(context, crs.c_str());
  if (object != nullptr && !proj_is_crs(object)) {
    proj_destroy(object);
    return nullptr;
  }
  return object;
}

// A context of our own that keeps quiet: PROJ's messages go to stderr,
// where the command's one line about bad input is to be the only one; the
// error is read from the context instead.
PJ_CONTEXT* QuietContext() {
  PJ_CONTEXT* context = proj_context_create();
  proj_log_level(context, PJ_LOG_NONE);
  return context;
}

std::string ProjError(PJ_CONTEXT* context) {
  const int error = proj_context_errno(context);
  return error == 0 ? "not a coordinate reference system"
                    : proj_context_errno_string(context, error);
}

}  // namespace

std::string NormalizeCrs(const std::string& text) {
  static const std::regex kOdmUtm(
      R"(\s*WGS84\s+UTM\s+(\d{1,2})\s*([NnSs])\s*)");
  std::smatch match;
  if (std::regex_match(text, match, kOdmUtm)) {
    const int zone = std::stoi(match[1]);
    if (zone < 1 || zone > 60) {
      ThrowInputError("CRS '", text, "': UTM zones are 1 to 60");
    }
    const bool north = match[2] == "N" || match[2] == "n";
    return StrCat("EPSG:", (north ? 32600 : 32700) + zone);
  }
  if (!text.empty() && text[0] == '+' &&
      text.find("+type=crs") == std::string::npos) {
    return text + " +type=crs";
  }
  return text;
}

namespace {

// What a CRS's horizontal part is (a compound CRS's first component, a
// bound CRS's source): projected in metres, geographic, or another kind.
enum class Horizontal { kMetricProjected, kGeographic, kOther };

Horizontal HorizontalKind(const std::string& crs) {
  PJ_CONTEXT* context = QuietContext();
  PJ* object = CreateCrs(context, crs);
  if (object == nullptr) {
    const std::string why = ProjError(context);
    proj_context_destroy(context);
    ThrowInputError("unknown CRS '", crs, "' (PROJ: ", why, ")");
  }
  for (int unwrap = 0; unwrap < 2 && object != nullptr; ++unwrap) {
    PJ* inner = nullptr;
    if (proj_get_type(object) == PJ_TYPE_COMPOUND_CRS) {
      inner = proj_crs_get_sub_crs(context, object, 0);
    } else if (proj_get_type(object) == PJ_TYPE_BOUND_CRS) {
      inner = proj_get_source_crs(context, object);
    } else {
      break;
    }
    proj_destroy(object);
    object = inner;
  }
  Horizontal kind = Horizontal::kOther;
  const PJ_TYPE type =
      object == nullptr ? PJ_TYPE_UNKNOWN : proj_get_type(object);
  if (type == PJ_TYPE_GEOGRAPHIC_2D_CRS || type == PJ_TYPE_GEOGRAPHIC_3D_CRS) {
    kind = Horizontal::kGeographic;
  } else if (type == PJ_TYPE_PROJECTED_CRS) {
    PJ* cs = proj_crs_get_coordinate_system(context, object);
    double factor = 0;
    if (cs != nullptr &&
        proj_cs_get_axis_info(context,
                              cs,
                              0,
                              nullptr,
                              nullptr,
                              nullptr,
                              &factor,
                              nullptr,
                              nullptr,
                              nullptr) &&
        factor == 1.0) {
      kind = Horizontal::kMetricProjected;
    }
    proj_destroy(cs);
  }
  proj_destroy(object);
  proj_context_destroy(context);
  return kind;
}

}  // namespace

bool IsMetricProjectedCrs(const std::string& crs) {
  return HorizontalKind(crs) == Horizontal::kMetricProjected;
}

std::string UtmCrsFor(double longitude_deg, double latitude_deg) {
  const int zone = std::clamp(
      static_cast<int>(std::floor((longitude_deg + 180) / 6)) + 1, 1, 60);
  return StrCat("EPSG:", (latitude_deg >= 0 ? 32600 : 32700) + zone);
}

std::string LocalFrameCrs(const std::string& crs,
                          const Eigen::Vector3d& point) {
  switch (HorizontalKind(crs)) {
    case Horizontal::kMetricProjected:
      return crs;
    case Horizontal::kGeographic: {
      const Eigen::Vector3d lonlat =
          CrsTransform(crs, "EPSG:4326").Forward(point);
      return UtmCrsFor(lonlat.x(), lonlat.y());
    }
    case Horizontal::kOther:
      break;
  }
  ThrowInputError("CRS '",
                  crs,
                  "' is neither geographic nor projected in metres (a grid "
                  "in feet would keep its heights in feet); give the "
                  "coordinates in a metric CRS");
}

CrsTransform::CrsTransform(const std::string& from, const std::string& to)
    : context_(QuietContext()), what_(StrCat("from ", from, " to ", to)) {
  for (const std::string* crs : {&from, &to}) {
    PJ* object = CreateCrs(context_, *crs);
    if (object == nullptr) {
      const std::string why = ProjError(context_);
      proj_context_destroy(context_);
      ThrowInputError("unknown CRS '", *crs, "' (PROJ: ", why, ")");
    }
    proj_destroy(object);
  }
  PJ* transform =
      proj_create_crs_to_crs(context_, from.c_str(), to.c_str(), nullptr);
  if (transform == nullptr) {
    const std::string why = ProjError(context_);
    proj_context_destroy(context_);
    ThrowInputError("no transformation ", what_, " (PROJ: ", why, ")");
  }
  // East / north and longitude / latitude, whatever the CRSs' axis order
  // (EPSG:4326 is latitude first).
  transform_ = proj_normalize_for_visualization(context_, transform);
  proj_destroy(transform);
  if (transform_ == nullptr) {
    proj_context_destroy(context_);
    ThrowInputError("no transformation ", what_);
  }
}

CrsTransform::~CrsTransform() {
  proj_destroy(transform_);
  proj_context_destroy(context_);
}

Eigen::Vector3d CrsTransform::Forward(const Eigen::Vector3d& point) const {
  return Transform(point, true);
}

Eigen::Vector3d CrsTransform::Inverse(const Eigen::Vector3d& point) const {
  return Transform(point, false);
}

Eigen::Vector3d CrsTransform::Transform(const Eigen::Vector3d& point,
                                        bool forward) const {
  const PJ_COORD in = proj_coord(point.x(), point.y(), point.z(), 0);
  const PJ_COORD out = proj_trans(transform_, forward ? PJ_FWD : PJ_INV, in);
  const Eigen::Vector3d result(out.xyz.x, out.xyz.y, out.xyz.z);
  if (!result.allFinite() || std::abs(result.x()) == HUGE_VAL) {
    ThrowInputError("(",
                    point.x(),
                    ", ",
                    point.y(),
                    ", ",
                    point.z(),
                    ") cannot be transformed ",
                    what_,
                    forward ? "" : " (inverse)");
  }
  return result;
}

std::string GeoFrameJson(const GeoFrame& frame) {
  nlohmann::ordered_json json;
  json["source_crs"] = frame.source_crs;
  json["crs"] = frame.crs;
  json["origin"] = {frame.origin.x(), frame.origin.y(), frame.origin.z()};
  json["note"] =
      "model coordinates = crs coordinates - origin (metres); heights as the "
      "survey gave them";
  return json.dump(2) + "\n";
}

void WriteGeoFrame(const std::string& path, const GeoFrame& frame) {
  WriteFileAtomically(path, GeoFrameJson(frame));
}

GeoFrame ReadGeoFrame(const std::string& path) {
  CheckFileExists(path, "crs.json");
  GeoFrame frame;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadFileToString(path));
    frame.source_crs = json.at("source_crs").get<std::string>();
    frame.crs = json.at("crs").get<std::string>();
    const auto& origin = json.at("origin");
    frame.origin = Eigen::Vector3d(origin.at(0).get<double>(),
                                   origin.at(1).get<double>(),
                                   origin.at(2).get<double>());
  } catch (const nlohmann::json::exception& error) {
    ThrowInputError(path, ": not a bayon crs.json (", error.what(), ")");
  }
  return frame;
}

std::optional<GeoFrame> ReadModelGeoFrame(const std::string& folder) {
  const std::string path = folder + "/crs.json";
  if (!std::filesystem::exists(path)) return std::nullopt;
  return ReadGeoFrame(path);
}

void PlaceGeoFrame(const std::optional<GeoFrame>& frame,
                   const std::string& output_folder) {
  const std::string path = output_folder + "/crs.json";
  if (frame) {
    WriteGeoFrame(path, *frame);
  } else {
    // An earlier model's frame is not this one's.
    std::filesystem::remove(path);
  }
}

bool CopyGeoFrame(const std::string& model_folder,
                  const std::string& output_folder) {
  // Read and written again: a malformed file is refused, not spread.
  const std::optional<GeoFrame> frame = ReadModelGeoFrame(model_folder);
  PlaceGeoFrame(frame, output_folder);
  return frame.has_value();
}

}  // namespace bayon
