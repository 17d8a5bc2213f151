// SPDX-License-Identifier: BSD-3-Clause
//
// Coordinate reference systems through PROJ. A survey gives ground control
// in a national or UTM grid, or in longitude and latitude; the model works
// in a local projected frame: the survey's projected CRS where it is in
// metres (for geographic coordinates, the UTM zone of the points) with an
// origin near the object subtracted. Grid coordinates of
// a few million metres would leave single precision (PLY, glTF) centimetres;
// the origin, stated with the model (crs.json), is kept in double.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>

struct pj_ctx;
struct PJconsts;

namespace bayon {

// The model's frame in the world: model = crs coordinates - origin (metres;
// heights as the survey gave them).
struct GeoFrame {
  std::string source_crs;  // the survey's CRS, as given
  std::string crs;         // the projected CRS of the model's frame
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

// OpenDroneMap's "WGS84 UTM 32N" as "EPSG:32632", a PROJ string with
// "+type=crs" added (PROJ reads a bare "+proj=utm ..." as a conversion);
// other text (EPSG:xxxx, WKT) unchanged.
std::string NormalizeCrs(const std::string& text);

// True for a projected CRS in metres (the horizontal part of a compound
// one). Throws InputError for a CRS PROJ does not know.
bool IsMetricProjectedCrs(const std::string& crs);

// The WGS 84 UTM zone of a point, as "EPSG:326zz" (north) or "EPSG:327zz".
std::string UtmCrsFor(double longitude_deg, double latitude_deg);

// The projected CRS in metres a model made near `point` (in `crs`) works
// in: `crs` itself where it is one, else (geographic coordinates) the UTM
// zone of the point. A projected grid in other units (feet) is refused
// with InputError: PROJ would convert its eastings and northings but not
// its heights.
std::string LocalFrameCrs(const std::string& crs, const Eigen::Vector3d& point);

// A transformation between two CRSs, in east / north (longitude / latitude
// in degrees) order whatever the CRSs' own axis order.
class CrsTransform {
 public:
  // Throws InputError naming the CRS that PROJ does not know.
  CrsTransform(const std::string& from, const std::string& to);
  ~CrsTransform();
  CrsTransform(const CrsTransform&) = delete;
  CrsTransform& operator=(const CrsTransform&) = delete;

  // Throws InputError where the point cannot be transformed (outside the
  // CRS's area, a non-finite result).
  Eigen::Vector3d Forward(const Eigen::Vector3d& point) const;
  Eigen::Vector3d Inverse(const Eigen::Vector3d& point) const;

 private:
  Eigen::Vector3d Transform(const Eigen::Vector3d& point, bool forward) const;
  pj_ctx* context_ = nullptr;
  PJconsts* transform_ = nullptr;
  std::string what_;
};

// crs.json: {"source_crs", "crs", "origin": [x, y, z]}; GeoFrameJson is
// its text.
std::string GeoFrameJson(const GeoFrame& frame);
void WriteGeoFrame(const std::string& path, const GeoFrame& frame);
GeoFrame ReadGeoFrame(const std::string& path);

// A model folder's crs.json (adjust writes the control's beside the
// model); nullopt where it has none. Throws InputError for a malformed one.
std::optional<GeoFrame> ReadModelGeoFrame(const std::string& folder);

// The frame written into `output_folder` as crs.json, or where there is
// none, an earlier crs.json there removed.
void PlaceGeoFrame(const std::optional<GeoFrame>& frame,
                   const std::string& output_folder);

// ReadModelGeoFrame then PlaceGeoFrame: so that a cloud or a textured
// model made from a model says where it lies in the world. False where the
// model has none.
bool CopyGeoFrame(const std::string& model_folder,
                  const std::string& output_folder);

}  // namespace bayon
