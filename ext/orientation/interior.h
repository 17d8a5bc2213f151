// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon interior`: the interior orientation in the narrow sense (each
// image's ImageFrame, ext/core/image_frame.h) of every image of a COLMAP
// database, written to bayon_interior (ext/colmap/bayon_tables.h), through
// which every later stage maps pixels to image millimetres.
//
// - Digital images (film_scan off): the frame follows from the camera's
//   pixel pitch and the image centre (Camera::DefaultFrame(); pitch 1, i.e.
//   image coordinates in pixels, for COLMAP cameras, which have none);
//   method "digital". The row records that frame for the report; later
//   stages give a digital image the default frame of the camera they work
//   with (InteriorRecord::MeasuredFrame()), e.g. adjust's BROWN_BEYER
//   conversion of a COLMAP camera, whose pitch is not 1.
// - Scanned film (film_scan on): the frame of each scan is measured by
//   virtual fiducials (virtual_fiducials.h); method "virtual_fiducials",
//   with the edges' residual RMS and the frame's rotation in the scan. The
//   frame's millimetres only mean something to a BROWN_BEYER camera (its
//   camera constant and principal point are in mm), so every image's camera
//   must have one in bayon_calibration. A scan whose frame cannot be
//   measured gets no row and is reported with the reason.
//
// Images that have a row already keep it unless `overwrite`; a failed
// measurement never removes an existing row. Everything is checked before
// anything is written (InputError, database unchanged); the rows are
// written in one transaction at the end.
#pragma once

#include "ext/colmap/bayon_tables.h"
#include "ext/core/types.h"
#include "ext/orientation/virtual_fiducials.h"

#include <string>
#include <vector>

namespace bayon {

struct InteriorOptions {
  // Scanned film frames, measured by virtual fiducials; off: digital images.
  bool film_scan = false;
  VirtualFiducialOptions fiducials;
  // Replace existing bayon_interior rows; without it such images are kept.
  bool overwrite = false;
  int num_threads = -1;  // images in parallel; -1 = all cores
  // Every field, the fiducials' without a prefix.
  void Register(OptionRegistry* registry);
  void Check() const;
};

enum class InteriorStatus {
  kDone,    // a row was written
  kKept,    // the image had a row; left as it was
  kFailed,  // the frame could not be measured; no row written
};

struct ImageInteriorReport {
  image_t image_id = kInvalidImageId;
  std::string name;
  InteriorStatus status = InteriorStatus::kFailed;
  std::string reason;     // kKept, kFailed: why
  InteriorRecord record;  // kDone: as written; kKept: the existing row
  VirtualFiducialResult fiducials;  // film scans
  double seconds = 0;
};

struct InteriorSummary {
  std::vector<ImageInteriorReport> images;  // in image_id order
  int num_done = 0;
  int num_kept = 0;
  int num_failed = 0;
  double seconds = 0;
};

// The frame of one scanned film image file (any depth and channel count
// OpenCV reads). Throws InputError for an unreadable file.
VirtualFiducialResult MeasureFilmFrame(const std::string& image_file,
                                       const VirtualFiducialOptions& options);

// The record a measurement gives (method "virtual_fiducials").
InteriorRecord InteriorFromFiducials(const VirtualFiducialResult& result);

// One log line for an image: edges, points, residuals, rotation, corner
// angles, or the reason it failed or was kept.
std::string DescribeInterior(const ImageInteriorReport& report);

// What was measured, in one line (the film frames' mean edge RMS and
// largest rotation).
std::string InteriorSummaryLine(const InteriorSummary& summary,
                                const InteriorOptions& options);

// Runs over every image of the database (see the header comment).
InteriorSummary OrientInteriors(const std::string& database_path,
                                const std::string& image_path,
                                const InteriorOptions& options);

}  // namespace bayon
