// SPDX-License-Identifier: BSD-3-Clause
//
// bayon's extension tables in a COLMAP database (colmap-interop.md, 4):
// named bayon_*, created on demand, each with an explicit primary key, and
// referencing `images`/`cameras` only with ON DELETE CASCADE so that COLMAP's
// own deletes (database_cleaner, image_deleter) keep working and take bayon's
// rows with them. `bayon_meta` records the schema version; a database written
// by a newer bayon is refused instead of being misread.
//
// Tables of later stages are declared in their own table_*.{h,cc} files here,
// each with a BayonTable spec that EnsureBayonTable creates.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/camera.h"
#include "ext/core/image_frame.h"
#include "ext/core/scene.h"

#include <map>
#include <optional>
#include <string>

namespace bayon {

// Version of the bayon_* schema this build writes and understands.
constexpr int kBayonSchemaVersion = 1;

struct BayonTable {
  const char* name;  // bayon_...
  const char* ddl;   // CREATE TABLE IF NOT EXISTS ...
};

// Creates bayon_meta if needed and checks the recorded schema version.
// Read-only databases without bayon tables are accepted (nothing to check).
void CheckBayonSchema(Database* database);

// Creates the table (and bayon_meta) if missing, inside its own transaction
// unless one is open. Throws InputError for a read-only database.
void EnsureBayonTable(Database* database, const BayonTable& table);
bool BayonTableExists(Database* database, const char* name);

std::optional<std::string> ReadBayonMeta(Database* database,
                                         const std::string& key);
void WriteBayonMeta(Database* database,
                    const std::string& key,
                    const std::string& value);

// ---------------------------------------------------------------------------
// bayon_calibration: the full photogrammetric calibration of a camera, which
// COLMAP's cameras table cannot hold (BROWN_BEYER with its ten additional
// parameters), beside the COLMAP model fitted to it (and its fit residual).
struct CalibrationRecord {
  Camera camera;  // model BROWN_BEYER (or a COLMAP model), with pixel pitch
  // RMS and maximum difference between `camera` and the row in `cameras`.
  double colmap_fit_rms_px = 0;
  double colmap_fit_max_px = 0;
  // Optional covariance of camera.params (row-major n x n), from adjustment.
  std::vector<double> covariance;
};
extern const BayonTable kCalibrationTable;
void WriteCalibration(Database* database, const CalibrationRecord& record);
// Adds a camera as `bayon import` does: a COLMAP model goes to `cameras`
// as it is; a BROWN_BEYER camera goes to `cameras` as its FULL_OPENCV fit
// (kColmapModelForBrownBeyer) and to bayon_calibration in full, with the
// fit residual. Returns the new camera_id (the camera's own id when
// `use_camera_id`).
camera_t WriteCameraWithCalibration(Database* database,
                                    const Camera& camera,
                                    bool use_camera_id = false);
std::optional<CalibrationRecord> ReadCalibration(Database* database,
                                                 camera_t camera_id);
std::map<camera_t, CalibrationRecord> ReadAllCalibrations(Database* database);

// The bayon_interior method of a digital image's row. Its frame is no
// measurement: it is the DefaultFrame() of the camera `bayon interior` saw
// (for a COLMAP camera, which has no pixel pitch, a pitch of 1), recorded
// for the report. A reader gives such an image the default frame of the
// camera it works with (InteriorRecord::MeasuredFrame()), which may have
// another pitch.
inline constexpr const char kDigitalInteriorMethod[] = "digital";

// bayon_interior: each image's interior orientation (image frame), the
// affine map between image millimetres and pixels, with how it was found.
struct InteriorRecord {
  ImageFrame frame;
  std::string method;          // "digital" or "virtual_fiducials"
  double rms_residual_px = 0;  // line-fit residual for film scans
  double frame_rotation_deg = 0;

  // The frame that replaces the camera's default frame for this image
  // (Scene's Image::frame): the stored one, except for a digital image,
  // which has none of its own (nullopt: the camera's DefaultFrame()).
  std::optional<ImageFrame> MeasuredFrame() const;
};
extern const BayonTable kInteriorTable;
void WriteInterior(Database* database,
                   image_t image_id,
                   const InteriorRecord& record);
std::optional<InteriorRecord> ReadInterior(Database* database,
                                           image_t image_id);
std::map<image_t, InteriorRecord> ReadAllInteriors(Database* database);
// Gives each image of `scene` that has a measured interior orientation in
// the database (matched by name: a model's ids need not be the database's;
// InteriorRecord::MeasuredFrame()) its frame; the others keep theirs
// (digital images: the default frame of the scene's camera).
void SetInteriorFrames(Database* database, Scene* scene);

}  // namespace bayon
