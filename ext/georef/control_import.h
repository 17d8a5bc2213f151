// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon import_control`: ground control from the tools surveyors use, into
// bayon's control files (control_io.h) in a local projected frame (crs.h).
//
//   odm        OpenDroneMap's gcp_list.txt: a first line naming the CRS (a
//              PROJ string, EPSG:xxxx or "WGS84 UTM 32N"), then one image
//              measurement per line: geo_x geo_y geo_z im_x im_y image_name
//              [gcp_name [extras...]]. Pixel coordinates from the image's
//              upper-left corner, as COLMAP's. Lines without a name: one
//              point per distinct coordinate triple (GCP1, GCP2, ...).
//   metashape  Metashape's reference CSV: label,x,y,z[,accuracy_m[,...]]
//              (x, y longitude / latitude in a geographic CRS); no image
//              measurements (coded targets or control/observations.txt
//              give them).
//   csv        name,x,y,z[,sx,sy,sz[,control|check]].
// '#' starts a comment; csv and metashape take their CRS from --crs.
#pragma once

#include "ext/colmap/control_io.h"
#include "ext/core/option_registry.h"
#include "ext/georef/crs.h"

#include <string>
#include <vector>

namespace bayon {

struct ControlImportOptions {
  std::string format = "odm";  // odm | metashape | csv
  // The coordinates' CRS: required for csv and metashape; for odm it
  // replaces the file's first line.
  std::string crs;
  // Standard deviation of coordinates that state none, metres.
  double sigma_m = 0.01;
  // Points that are check points, not control (comma-separated names).
  std::string check_names;
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

struct ImportedControl {
  std::vector<ControlPoint> points;
  std::vector<ImageMeasurement> measurements;
  GeoFrame frame;
};

// Reads `path` and transforms its coordinates into the local frame.
// `image_names` (may be empty: unchecked): the photographs a measurement
// may name. Throws InputError naming the file and line for a malformed
// line, an unknown CRS, a photograph not in `image_names`, one name with
// two positions, or a check name that is no point.
ImportedControl ImportControl(const std::string& path,
                              const ControlImportOptions& options,
                              const std::vector<std::string>& image_names);

// points.txt, observations.txt (where there are measurements) and crs.json
// in `folder`, each written atomically.
void WriteImportedControl(const std::string& folder,
                          const ImportedControl& control);

}  // namespace bayon
