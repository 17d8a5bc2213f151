// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/bayon_tables.h"

#include "ext/core/camera_conversion.h"
#include "ext/core/errors.h"

#include <cstring>

namespace bayon {
namespace {

constexpr BayonTable kMetaTable = {
    "bayon_meta",
    "CREATE TABLE IF NOT EXISTS bayon_meta (key TEXT PRIMARY KEY NOT NULL, "
    "value TEXT NOT NULL)"};

template <typename T>
std::vector<T> BlobToVector(const SqliteStatement& statement, int col) {
  const int num_bytes = statement.ColumnBytes(col);
  std::vector<T> values(num_bytes / sizeof(T));
  if (!values.empty()) {
    std::memcpy(values.data(),
                statement.ColumnBlobData(col),
                values.size() * sizeof(T));
  }
  return values;
}

}  // namespace

const BayonTable kCalibrationTable = {
    "bayon_calibration",
    "CREATE TABLE IF NOT EXISTS bayon_calibration ("
    "camera_id INTEGER PRIMARY KEY NOT NULL, "
    "model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, "
    "params BLOB NOT NULL, pixel_pitch_mm REAL NOT NULL, "
    "colmap_fit_rms_px REAL NOT NULL, colmap_fit_max_px REAL NOT NULL, "
    "covariance BLOB, "
    "FOREIGN KEY(camera_id) REFERENCES cameras(camera_id) ON DELETE CASCADE)"};

const BayonTable kInteriorTable = {
    "bayon_interior",
    "CREATE TABLE IF NOT EXISTS bayon_interior ("
    "image_id INTEGER PRIMARY KEY NOT NULL, "
    "a11 REAL NOT NULL, a12 REAL NOT NULL, a13 REAL NOT NULL, "
    "a21 REAL NOT NULL, a22 REAL NOT NULL, a23 REAL NOT NULL, "
    "method TEXT NOT NULL, rms_residual_px REAL NOT NULL, "
    "frame_rotation_deg REAL NOT NULL, "
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)"};

bool BayonTableExists(Database* database, const char* name) {
  return database->connection()->TableExists(name);
}

void CheckBayonSchema(Database* database) {
  if (!BayonTableExists(database, kMetaTable.name)) return;
  const auto version = ReadBayonMeta(database, "schema_version");
  if (!version) return;
  int stored = 0;
  try {
    stored = std::stoi(*version);
  } catch (const std::exception&) {
    ThrowInputError(database->path(),
                    ": bayon_meta schema_version '",
                    *version,
                    "' is not a number");
  }
  if (stored > kBayonSchemaVersion) {
    ThrowInputError(database->path(),
                    ": bayon tables have schema version ",
                    stored,
                    ", newer than this bayon understands (",
                    kBayonSchemaVersion,
                    "); update bayon");
  }
}

void EnsureBayonTable(Database* database, const BayonTable& table) {
  SqliteConnection* connection = database->connection();
  if (connection->read_only()) {
    ThrowInputError(
        database->path(), ": opened read-only, cannot create ", table.name);
  }
  if (!connection->TableExists(kMetaTable.name)) {
    connection->Execute(kMetaTable.ddl);
  }
  CheckBayonSchema(database);
  if (!ReadBayonMeta(database, "schema_version")) {
    WriteBayonMeta(
        database, "schema_version", std::to_string(kBayonSchemaVersion));
  }
  if (!connection->TableExists(table.name)) connection->Execute(table.ddl);
}

std::optional<std::string> ReadBayonMeta(Database* database,
                                         const std::string& key) {
  if (!BayonTableExists(database, kMetaTable.name)) return std::nullopt;
  SqliteStatement statement(database->connection(),
                            "SELECT value FROM bayon_meta WHERE key = ?");
  statement.Bind(1, key);
  if (!statement.Step()) return std::nullopt;
  return statement.ColumnText(0);
}

void WriteBayonMeta(Database* database,
                    const std::string& key,
                    const std::string& value) {
  SqliteConnection* connection = database->connection();
  if (!connection->TableExists(kMetaTable.name)) {
    connection->Execute(kMetaTable.ddl);
  }
  SqliteStatement statement(
      connection, "INSERT OR REPLACE INTO bayon_meta(key, value) VALUES(?, ?)");
  statement.Bind(1, key).Bind(2, value);
  statement.Execute();
}

// ------------------------------------------------------------ calibration

camera_t WriteCameraWithCalibration(Database* database,
                                    const Camera& camera,
                                    bool use_camera_id) {
  if (camera.model_id != CameraModelId::kBrownBeyer) {
    return database->WriteCamera(camera, use_camera_id);
  }
  // COLMAP gets the closest COLMAP model; bayon keeps the full one.
  CalibrationRecord calibration;
  calibration.camera = camera;
  const CameraConversion conversion =
      ConvertCamera(camera, kColmapModelForBrownBeyer);
  calibration.colmap_fit_rms_px = conversion.rms_residual_px;
  calibration.colmap_fit_max_px = conversion.max_residual_px;
  const camera_t camera_id =
      database->WriteCamera(conversion.camera, use_camera_id);
  calibration.camera.camera_id = camera_id;
  WriteCalibration(database, calibration);
  return camera_id;
}

void WriteCalibration(Database* database, const CalibrationRecord& record) {
  EnsureBayonTable(database, kCalibrationTable);
  record.camera.Check();
  SqliteStatement statement(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_calibration(camera_id, model, width, "
      "height, params, pixel_pitch_mm, colmap_fit_rms_px, colmap_fit_max_px, "
      "covariance) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?)");
  const Camera& camera = record.camera;
  statement.Bind(1, static_cast<int64_t>(camera.camera_id))
      .Bind(2, static_cast<int64_t>(camera.model_id))
      .Bind(3, static_cast<int64_t>(camera.width))
      .Bind(4, static_cast<int64_t>(camera.height))
      .BindBlob(5, camera.params.data(), camera.params.size() * sizeof(double))
      .Bind(6, camera.pixel_pitch_mm)
      .Bind(7, record.colmap_fit_rms_px)
      .Bind(8, record.colmap_fit_max_px)
      .BindBlob(9,
                record.covariance.data(),
                record.covariance.size() * sizeof(double));
  statement.Execute();
}

namespace {

CalibrationRecord CalibrationFromRow(const SqliteStatement& statement,
                                     const std::string& db) {
  CalibrationRecord record;
  Camera& camera = record.camera;
  camera.camera_id = static_cast<camera_t>(statement.ColumnInt64(0));
  const int model = static_cast<int>(statement.ColumnInt64(1));
  if (!IsKnownCameraModelId(model)) {
    ThrowInputError(db,
                    ": bayon_calibration row ",
                    camera.camera_id,
                    ": unknown model id ",
                    model);
  }
  camera.model_id = static_cast<CameraModelId>(model);
  camera.width = statement.ColumnInt64(2);
  camera.height = statement.ColumnInt64(3);
  camera.params = BlobToVector<double>(statement, 4);
  camera.pixel_pitch_mm = statement.ColumnDouble(5);
  record.colmap_fit_rms_px = statement.ColumnDouble(6);
  record.colmap_fit_max_px = statement.ColumnDouble(7);
  record.covariance = BlobToVector<double>(statement, 8);
  try {
    camera.Check();
  } catch (const InputError& error) {
    ThrowInputError(db, ": bayon_calibration: ", error.what());
  }
  return record;
}

constexpr const char* kSelectCalibration =
    "SELECT camera_id, model, width, height, params, pixel_pitch_mm, "
    "colmap_fit_rms_px, colmap_fit_max_px, covariance FROM bayon_calibration";

}  // namespace

std::optional<CalibrationRecord> ReadCalibration(Database* database,
                                                 camera_t camera_id) {
  if (!BayonTableExists(database, kCalibrationTable.name)) return std::nullopt;
  SqliteStatement statement(
      database->connection(),
      std::string(kSelectCalibration) + " WHERE camera_id = ?");
  statement.Bind(1, static_cast<int64_t>(camera_id));
  if (!statement.Step()) return std::nullopt;
  return CalibrationFromRow(statement, database->path());
}

std::map<camera_t, CalibrationRecord> ReadAllCalibrations(Database* database) {
  std::map<camera_t, CalibrationRecord> records;
  if (!BayonTableExists(database, kCalibrationTable.name)) return records;
  SqliteStatement statement(database->connection(), kSelectCalibration);
  while (statement.Step()) {
    CalibrationRecord record = CalibrationFromRow(statement, database->path());
    records.emplace(record.camera.camera_id, std::move(record));
  }
  return records;
}

// ------------------------------------------------------------ interior

void WriteInterior(Database* database,
                   image_t image_id,
                   const InteriorRecord& record) {
  EnsureBayonTable(database, kInteriorTable);
  SqliteStatement statement(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_interior(image_id, a11, a12, a13, a21, "
      "a22, a23, method, rms_residual_px, frame_rotation_deg) "
      "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  const auto& a = record.frame.pixel_from_frame;
  statement.Bind(1, static_cast<int64_t>(image_id))
      .Bind(2, a(0, 0))
      .Bind(3, a(0, 1))
      .Bind(4, a(0, 2))
      .Bind(5, a(1, 0))
      .Bind(6, a(1, 1))
      .Bind(7, a(1, 2))
      .Bind(8, record.method)
      .Bind(9, record.rms_residual_px)
      .Bind(10, record.frame_rotation_deg);
  statement.Execute();
}

namespace {

constexpr const char* kSelectInterior =
    "SELECT image_id, a11, a12, a13, a21, a22, a23, method, rms_residual_px, "
    "frame_rotation_deg FROM bayon_interior";

InteriorRecord InteriorFromRow(const SqliteStatement& statement) {
  InteriorRecord record;
  auto& a = record.frame.pixel_from_frame;
  a << statement.ColumnDouble(1), statement.ColumnDouble(2),
      statement.ColumnDouble(3), statement.ColumnDouble(4),
      statement.ColumnDouble(5), statement.ColumnDouble(6);
  record.method = statement.ColumnText(7);
  record.rms_residual_px = statement.ColumnDouble(8);
  record.frame_rotation_deg = statement.ColumnDouble(9);
  return record;
}

}  // namespace

std::optional<InteriorRecord> ReadInterior(Database* database,
                                           image_t image_id) {
  if (!BayonTableExists(database, kInteriorTable.name)) return std::nullopt;
  SqliteStatement statement(
      database->connection(),
      std::string(kSelectInterior) + " WHERE image_id = ?");
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step()) return std::nullopt;
  return InteriorFromRow(statement);
}

std::map<image_t, InteriorRecord> ReadAllInteriors(Database* database) {
  std::map<image_t, InteriorRecord> records;
  if (!BayonTableExists(database, kInteriorTable.name)) return records;
  SqliteStatement statement(database->connection(), kSelectInterior);
  while (statement.Step()) {
    records.emplace(static_cast<image_t>(statement.ColumnInt64(0)),
                    InteriorFromRow(statement));
  }
  return records;
}

std::optional<ImageFrame> InteriorRecord::MeasuredFrame() const {
  // A digital row's frame is the default frame of the camera `bayon
  // interior` read, not necessarily of the camera a later stage works with:
  // for a COLMAP camera it has a pitch of 1 mm, while `bayon adjust`
  // converts that camera to BROWN_BEYER with a pitch of 36 mm / width.
  // Taken as the image's own frame, it scaled every projection by that
  // ratio and the adjustment of digital images collapsed (the temple ring:
  // 81 % centre error instead of 0.2 %). The camera's DefaultFrame() is by
  // definition right, whatever its pitch.
  if (method == kDigitalInteriorMethod) return std::nullopt;
  return frame;
}

void SetInteriorFrames(Database* database, Scene* scene) {
  const std::map<image_t, InteriorRecord> interiors =
      ReadAllInteriors(database);
  if (interiors.empty()) return;
  for (auto& [image_id, image] : scene->images) {
    const std::optional<DatabaseImage> row =
        database->ReadImageWithName(image.name);
    if (!row) continue;
    const auto interior = interiors.find(row->image_id);
    if (interior == interiors.end()) continue;
    const std::optional<ImageFrame> frame = interior->second.MeasuredFrame();
    if (frame) image.frame = *frame;
  }
}

}  // namespace bayon
