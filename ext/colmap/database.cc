// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/database.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>

namespace bayon {

std::optional<Rigid3d> TwoViewGeometry::StoredPose() const {
  if (!qvec || !tvec || tvec->norm() <= 1e-12 || qvec->norm() <= 0.5) {
    return std::nullopt;
  }
  const Eigen::Vector4d& q = *qvec;
  return Rigid3d(Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized(),
                 tvec->normalized());
}
namespace {

// The DDL of COLMAP 3.8 (src/base/database.cc), character for character, so
// that `.schema` of a bayon database reads like `colmap database_creator`'s.
constexpr const char* kCreateCameras =
    "CREATE TABLE IF NOT EXISTS cameras   (camera_id            INTEGER  "
    "PRIMARY KEY AUTOINCREMENT  NOT NULL,    model                INTEGER    "
    "                         NOT NULL,    width                INTEGER      "
    "                       NOT NULL,    height               INTEGER        "
    "                     NOT NULL,    params               BLOB,    "
    "prior_focal_length   INTEGER                             NOT NULL);";
constexpr const char* kCreateImages =
    "CREATE TABLE IF NOT EXISTS images   (image_id   INTEGER  PRIMARY KEY "
    "AUTOINCREMENT  NOT NULL,    name       TEXT                             "
    "   NOT NULL UNIQUE,    camera_id  INTEGER                             NOT "
    "NULL,    prior_qw   REAL,    prior_qx   REAL,    prior_qy   REAL,    "
    "prior_qz   REAL,    prior_tx   REAL,    prior_ty   REAL,    prior_tz   "
    "REAL,CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < "
    "2147483647),FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));"
    "CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);";
constexpr const char* kCreateKeypoints =
    "CREATE TABLE IF NOT EXISTS keypoints   (image_id  INTEGER  PRIMARY KEY  "
    "NOT NULL,    rows      INTEGER               NOT NULL,    cols      "
    "INTEGER               NOT NULL,    data      BLOB,FOREIGN KEY(image_id) "
    "REFERENCES images(image_id) ON DELETE CASCADE);";
constexpr const char* kCreateDescriptors =
    "CREATE TABLE IF NOT EXISTS descriptors   (image_id  INTEGER  PRIMARY KEY "
    " NOT NULL,    rows      INTEGER               NOT NULL,    cols      "
    "INTEGER               NOT NULL,    data      BLOB,FOREIGN KEY(image_id) "
    "REFERENCES images(image_id) ON DELETE CASCADE);";
constexpr const char* kCreateMatches =
    "CREATE TABLE IF NOT EXISTS matches   (pair_id  INTEGER  PRIMARY KEY  NOT "
    "NULL,    rows     INTEGER               NOT NULL,    cols     INTEGER    "
    "           NOT NULL,    data     BLOB);";
constexpr const char* kCreateTwoViewGeometries =
    "CREATE TABLE IF NOT EXISTS two_view_geometries   (pair_id  INTEGER  "
    "PRIMARY KEY  NOT NULL,    rows     INTEGER               NOT NULL,    "
    "cols     INTEGER               NOT NULL,    data     BLOB,    config   "
    "INTEGER               NOT NULL,    F        BLOB,    E        BLOB,    H "
    "       BLOB,    qvec     BLOB,    tvec     BLOB);";

constexpr const char* kColmapTables[] = {"cameras",
                                         "images",
                                         "keypoints",
                                         "descriptors",
                                         "matches",
                                         "two_view_geometries"};

template <typename MatrixType>
MatrixType ReadMatrixBlob(const SqliteStatement& statement,
                          int rows_col,
                          int cols_col,
                          int data_col,
                          const std::string& what) {
  using Scalar = typename MatrixType::Scalar;
  const int64_t rows = statement.ColumnInt64(rows_col);
  const int64_t cols = statement.ColumnInt64(cols_col);
  const int64_t num_bytes = statement.ColumnBytes(data_col);
  if (rows < 0 || cols < 0 || rows > INT32_MAX || cols > INT32_MAX ||
      (MatrixType::ColsAtCompileTime != Eigen::Dynamic && rows > 0 &&
       cols != MatrixType::ColsAtCompileTime)) {
    ThrowInputError(what, ": bad blob shape ", rows, " x ", cols);
  }
  // rows * cols fits in 64 bits, times sizeof(Scalar) it may not.
  const int64_t scalar_bytes = sizeof(Scalar);
  if (num_bytes % scalar_bytes != 0 ||
      rows * cols != num_bytes / scalar_bytes) {
    ThrowInputError(what,
                    ": blob holds ",
                    num_bytes,
                    " bytes, expected ",
                    rows,
                    " x ",
                    cols,
                    " x ",
                    sizeof(Scalar));
  }
  MatrixType matrix;
  if (MatrixType::ColsAtCompileTime == Eigen::Dynamic) {
    matrix.resize(rows, cols);
  } else {
    matrix.resize(rows, MatrixType::ColsAtCompileTime);
  }
  if (num_bytes > 0) {
    std::memcpy(matrix.data(), statement.ColumnBlobData(data_col), num_bytes);
  }
  return matrix;
}

template <typename MatrixType>
void BindMatrixBlob(SqliteStatement& statement,
                    int first_idx,
                    const MatrixType& matrix) {
  statement.Bind(first_idx, static_cast<int64_t>(matrix.rows()));
  statement.Bind(first_idx + 1, static_cast<int64_t>(matrix.cols()));
  statement.BindBlob(first_idx + 2,
                     matrix.data(),
                     matrix.size() * sizeof(typename MatrixType::Scalar));
}

// Fixed-size blobs: COLMAP stores 3x3 matrices row-major, quaternions as
// (w, x, y, z). NULL or empty reads as nullopt.
template <int kRows, int kCols>
std::optional<Eigen::Matrix<double, kRows, kCols>> ReadFixedBlob(
    const SqliteStatement& statement, int col, const std::string& what) {
  if (statement.IsNull(col) || statement.ColumnBytes(col) == 0) {
    return std::nullopt;
  }
  constexpr int kBytes = kRows * kCols * sizeof(double);
  if (statement.ColumnBytes(col) != kBytes) {
    ThrowInputError(what,
                    ": blob holds ",
                    statement.ColumnBytes(col),
                    " bytes, expected ",
                    kBytes);
  }
  Eigen::Matrix<double,
                kRows,
                kCols,
                kCols == 1 ? Eigen::ColMajor : Eigen::RowMajor>
      row_major;
  std::memcpy(row_major.data(), statement.ColumnBlobData(col), kBytes);
  return Eigen::Matrix<double, kRows, kCols>(row_major);
}

template <int kRows, int kCols>
void BindFixedBlob(
    SqliteStatement& statement,
    int idx,
    const std::optional<Eigen::Matrix<double, kRows, kCols>>& value) {
  if (!value) {
    statement.BindNull(idx);
    return;
  }
  const Eigen::Matrix<double,
                      kRows,
                      kCols,
                      kCols == 1 ? Eigen::ColMajor : Eigen::RowMajor>
      row_major = *value;
  statement.BindBlob(idx, row_major.data(), sizeof(double) * kRows * kCols);
}

}  // namespace

double KeypointScale(const FeatureKeypoints& keypoints, int idx) {
  if (keypoints.cols() == 4) return std::abs(keypoints(idx, 2));
  if (keypoints.cols() < 6) return 1.0;
  const double det =
      static_cast<double>(keypoints(idx, 2)) * keypoints(idx, 5) -
      static_cast<double>(keypoints(idx, 3)) * keypoints(idx, 4);
  return std::sqrt(std::abs(det));
}

FeatureKeypoints KeypointsFromXY(const std::vector<Eigen::Vector2d>& xy) {
  FeatureKeypoints keypoints(xy.size(), 6);
  for (size_t i = 0; i < xy.size(); ++i) {
    keypoints.row(i) << static_cast<float>(xy[i].x()),
        static_cast<float>(xy[i].y()), 1.f, 0.f, 0.f, 1.f;
  }
  return keypoints;
}

const char* DatabaseSchemaName(DatabaseSchema schema) {
  switch (schema) {
    case DatabaseSchema::kEmpty:
      return "empty";
    case DatabaseSchema::kColmap38:
      return "COLMAP 3.8/3.9";
    case DatabaseSchema::kColmap310:
      return "COLMAP 3.10/3.11 (pose_priors, no prior_* columns)";
    case DatabaseSchema::kColmap312:
      return "COLMAP 3.12/3.13 (rigs, frames)";
    case DatabaseSchema::kColmap40:
      return "COLMAP 4.x (rigs, frames, typed descriptors)";
  }
  return "unknown";
}

Database::Database(const std::string& path, Mode mode) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool exists = fs::exists(path, ec);
  SqliteConnection::Mode connection_mode = SqliteConnection::Mode::kReadWrite;
  if (mode == Mode::kReadOnly) {
    connection_mode = SqliteConnection::Mode::kReadOnly;
  } else if (mode == Mode::kCreate ||
             (mode == Mode::kOpenOrCreate && !exists)) {
    connection_mode = SqliteConnection::Mode::kCreate;
    if (!path.empty() && fs::path(path).has_parent_path() &&
        !fs::is_directory(fs::path(path).parent_path(), ec)) {
      ThrowInputError(path,
                      ": the folder ",
                      fs::path(path).parent_path(),
                      " does not exist");
    }
  }
  connection_ = std::make_unique<SqliteConnection>(path, connection_mode);
  if (connection_mode == SqliteConnection::Mode::kCreate) {
    CreateColmapTables();
    // What `colmap database_creator` leaves in a new file.
    connection_->Execute("PRAGMA user_version = 3800");
  }
  DetectSchema();
  if (schema_ == DatabaseSchema::kEmpty) {
    if (mode == Mode::kReadOnly) {
      ThrowInputError(path,
                      ": not a COLMAP database (no cameras/images tables)");
    }
    // An empty SQLite file given on purpose: give it COLMAP's tables.
    if (connection_->QueryInt64("SELECT count(*) FROM sqlite_master") > 0) {
      ThrowInputError(path,
                      ": an SQLite database without COLMAP's tables; refusing "
                      "to add them to someone else's database");
    }
    CreateColmapTables();
    DetectSchema();
  }
}

void Database::CreateColmapTables() {
  SqliteTransaction transaction(connection_.get());
  connection_->Execute(kCreateCameras);
  connection_->Execute(kCreateImages);
  connection_->Execute(kCreateKeypoints);
  connection_->Execute(kCreateDescriptors);
  connection_->Execute(kCreateMatches);
  connection_->Execute(kCreateTwoViewGeometries);
  transaction.Commit();
}

void Database::DetectSchema() {
  int num_present = 0;
  std::string missing;
  for (const char* table : kColmapTables) {
    if (connection_->TableExists(table)) {
      ++num_present;
    } else {
      missing += missing.empty() ? table : std::string(", ") + table;
    }
  }
  if (num_present == 0) {
    schema_ = DatabaseSchema::kEmpty;
    return;
  }
  if (num_present < 6) {
    ThrowInputError(path(),
                    ": not a complete COLMAP database (missing tables: ",
                    missing,
                    ")");
  }
  const std::vector<std::string> image_columns =
      connection_->TableColumns("images");
  images_have_priors_ =
      std::find(image_columns.begin(), image_columns.end(), "prior_qw") !=
      image_columns.end();
  const std::vector<std::string> descriptor_columns =
      connection_->TableColumns("descriptors");
  const bool typed_descriptors =
      std::find(descriptor_columns.begin(), descriptor_columns.end(), "type") !=
      descriptor_columns.end();
  const bool has_rigs =
      connection_->TableExists("rigs") || connection_->TableExists("frames");
  if (typed_descriptors) {
    schema_ = DatabaseSchema::kColmap40;
  } else if (has_rigs) {
    schema_ = DatabaseSchema::kColmap312;
  } else if (!images_have_priors_) {
    schema_ = DatabaseSchema::kColmap310;
  } else {
    schema_ = DatabaseSchema::kColmap38;
  }
  // The columns bayon reads by name must be there, whatever the version.
  const std::vector<std::string> geometry_columns =
      connection_->TableColumns("two_view_geometries");
  for (const char* column : {"pair_id", "rows", "cols", "data", "config"}) {
    if (std::find(geometry_columns.begin(), geometry_columns.end(), column) ==
        geometry_columns.end()) {
      ThrowInputError(path(),
                      ": two_view_geometries has no column ",
                      column,
                      "; the database looks like ",
                      DatabaseSchemaName(schema_),
                      " but its layout is not one bayon can read");
    }
  }
  if (typed_descriptors) {
    // 4.x stores ALIKED (float) descriptors under other types; bayon reads
    // only SIFT-type rows as uint8 x 128.
    const int64_t non_sift = connection_->QueryInt64(
        "SELECT count(*) FROM descriptors WHERE type != 0");
    if (non_sift > 0) {
      ThrowInputError(path(),
                      ": ",
                      non_sift,
                      " images have non-SIFT descriptors (COLMAP 4.x "
                      "descriptors.type != 0), which bayon cannot read");
    }
  }
}

void Database::CheckWritable(const char* what) const {
  if (connection_->read_only()) {
    ThrowInputError(path(), ": opened read-only, cannot write ", what);
  }
  // SQLite opens a file it may not write read-only without a word, and
  // fails only at the first write; its journal needs the folder as well.
  CheckCanWrite(path(), what);
  if (schema_ == DatabaseSchema::kColmap312 ||
      schema_ == DatabaseSchema::kColmap40) {
    ThrowInputError(path(),
                    ": looks like a ",
                    DatabaseSchemaName(schema_),
                    " database; bayon writes ",
                    what,
                    " only to the COLMAP 3.8 schema (4.x would need rig and "
                    "frame rows); import the images into a new database");
  }
}

int64_t Database::UserVersion() {
  return connection_->QueryInt64("PRAGMA user_version");
}

Database::StatementLease Database::Statement(const std::string& sql) {
  for (auto& [text, statement] : statements_) {
    if (text == sql) {
      statement->Reset();
      return StatementLease(statement.get());
    }
  }
  statements_.emplace_back(
      sql, std::make_unique<SqliteStatement>(connection_.get(), sql));
  return StatementLease(statements_.back().second.get());
}

// ---------------------------------------------------------------- counts

int Database::NumCameras() {
  return static_cast<int>(
      connection_->QueryInt64("SELECT count(*) FROM cameras"));
}
int Database::NumImages() {
  return static_cast<int>(
      connection_->QueryInt64("SELECT count(*) FROM images"));
}
int Database::NumKeypointRows() {
  return static_cast<int>(
      connection_->QueryInt64("SELECT count(*) FROM keypoints"));
}
int64_t Database::NumKeypoints() {
  return connection_->QueryInt64(
      "SELECT coalesce(sum(rows), 0) FROM keypoints");
}
int64_t Database::NumDescriptors() {
  return connection_->QueryInt64(
      "SELECT coalesce(sum(rows), 0) FROM descriptors");
}
int Database::NumMatchedPairs() {
  return static_cast<int>(
      connection_->QueryInt64("SELECT count(*) FROM matches WHERE rows > 0"));
}
int64_t Database::NumMatches() {
  return connection_->QueryInt64("SELECT coalesce(sum(rows), 0) FROM matches");
}
int Database::NumVerifiedPairs() {
  return static_cast<int>(connection_->QueryInt64(
      "SELECT count(*) FROM two_view_geometries WHERE rows > 0"));
}
int64_t Database::NumInlierMatches() {
  return connection_->QueryInt64(
      "SELECT coalesce(sum(rows), 0) FROM two_view_geometries");
}

// ---------------------------------------------------------------- cameras

namespace {

Camera CameraFromRow(const SqliteStatement& statement, const std::string& db) {
  Camera camera;
  camera.camera_id = static_cast<camera_t>(statement.ColumnInt64(0));
  const int64_t model = statement.ColumnInt64(1);
  const std::string what = StrCat(db, ": cameras row ", camera.camera_id);
  if (!IsKnownCameraModelId(static_cast<int>(model)) ||
      !IsColmapCameraModel(static_cast<CameraModelId>(model))) {
    ThrowInputError(what,
                    ": camera model id ",
                    model,
                    " is not one COLMAP 3.8 knows (0-10); a newer COLMAP "
                    "wrote it");
  }
  camera.model_id = static_cast<CameraModelId>(model);
  const int64_t width = statement.ColumnInt64(2);
  const int64_t height = statement.ColumnInt64(3);
  if (width <= 0 || height <= 0) {
    ThrowInputError(
        what, ": image size ", width, "x", height, " must be positive");
  }
  camera.width = static_cast<uint64_t>(width);
  camera.height = static_cast<uint64_t>(height);
  const int num_params = camera.ModelInfo().num_params;
  const int num_bytes = statement.ColumnBytes(4);
  if (num_bytes != num_params * static_cast<int>(sizeof(double))) {
    ThrowInputError(what,
                    ": ",
                    camera.ModelName(),
                    " takes ",
                    num_params,
                    " parameters, the params blob holds ",
                    num_bytes,
                    " bytes");
  }
  camera.params.resize(num_params);
  std::memcpy(camera.params.data(), statement.ColumnBlobData(4), num_bytes);
  camera.has_prior_focal_length = statement.ColumnInt64(5) != 0;
  return camera;
}

}  // namespace

bool Database::ExistsCamera(camera_t camera_id) {
  const StatementLease lease =
      Statement("SELECT 1 FROM cameras WHERE camera_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(camera_id));
  return statement.Step();
}

Camera Database::ReadCamera(camera_t camera_id) {
  const StatementLease lease = Statement(
      "SELECT camera_id, model, width, height, params, prior_focal_length "
      "FROM cameras WHERE camera_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(camera_id));
  if (!statement.Step()) {
    ThrowInputError(path(), ": no camera with id ", camera_id);
  }
  return CameraFromRow(statement, path());
}

std::vector<Camera> Database::ReadAllCameras() {
  std::vector<Camera> cameras;
  const StatementLease lease = Statement(
      "SELECT camera_id, model, width, height, params, prior_focal_length "
      "FROM cameras ORDER BY camera_id");
  SqliteStatement& statement = *lease;
  while (statement.Step()) cameras.push_back(CameraFromRow(statement, path()));
  return cameras;
}

camera_t Database::WriteCamera(const Camera& camera, bool use_camera_id) {
  CheckWritable("cameras");
  if (!IsColmapCameraModel(camera.model_id)) {
    ThrowInputError(path(),
                    ": camera model ",
                    camera.ModelName(),
                    " cannot be stored in COLMAP's cameras table");
  }
  camera.Check();
  const StatementLease lease = Statement(
      "INSERT INTO cameras(camera_id, model, width, height, params, "
      "prior_focal_length) VALUES(?, ?, ?, ?, ?, ?)");
  SqliteStatement& statement = *lease;
  if (use_camera_id) {
    statement.Bind(1, static_cast<int64_t>(camera.camera_id));
  } else {
    statement.BindNull(1);
  }
  statement.Bind(2, static_cast<int64_t>(camera.model_id));
  statement.Bind(3, static_cast<int64_t>(camera.width));
  statement.Bind(4, static_cast<int64_t>(camera.height));
  statement.BindBlob(
      5, camera.params.data(), camera.params.size() * sizeof(double));
  statement.Bind(6, static_cast<int64_t>(camera.has_prior_focal_length));
  statement.Execute();
  return static_cast<camera_t>(connection_->LastInsertRowId());
}

void Database::UpdateCamera(const Camera& camera) {
  CheckWritable("cameras");
  camera.Check();
  const StatementLease lease = Statement(
      "UPDATE cameras SET model = ?, width = ?, height = ?, params = ?, "
      "prior_focal_length = ? WHERE camera_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(camera.model_id));
  statement.Bind(2, static_cast<int64_t>(camera.width));
  statement.Bind(3, static_cast<int64_t>(camera.height));
  statement.BindBlob(
      4, camera.params.data(), camera.params.size() * sizeof(double));
  statement.Bind(5, static_cast<int64_t>(camera.has_prior_focal_length));
  statement.Bind(6, static_cast<int64_t>(camera.camera_id));
  statement.Execute();
}

// ---------------------------------------------------------------- images

namespace {

DatabaseImage ImageFromRow(const SqliteStatement& statement, bool priors) {
  DatabaseImage image;
  image.image_id = static_cast<image_t>(statement.ColumnInt64(0));
  image.name = statement.ColumnText(1);
  image.camera_id = static_cast<camera_t>(statement.ColumnInt64(2));
  if (priors) {
    for (int i = 0; i < 4; ++i)
      image.prior_q[i] = statement.ColumnOptionalDouble(3 + i);
    for (int i = 0; i < 3; ++i)
      image.prior_t[i] = statement.ColumnOptionalDouble(7 + i);
  }
  return image;
}

std::string ImageSelect(bool priors) {
  return priors ? "SELECT image_id, name, camera_id, prior_qw, prior_qx, "
                  "prior_qy, prior_qz, prior_tx, prior_ty, prior_tz FROM images"
                : "SELECT image_id, name, camera_id FROM images";
}

}  // namespace

bool Database::ExistsImage(image_t image_id) {
  const StatementLease lease =
      Statement("SELECT 1 FROM images WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  return statement.Step();
}

std::optional<DatabaseImage> Database::ReadImageWithName(
    const std::string& name) {
  const StatementLease lease =
      Statement(ImageSelect(images_have_priors_) + " WHERE name = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, name);
  if (!statement.Step()) return std::nullopt;
  return ImageFromRow(statement, images_have_priors_);
}

DatabaseImage Database::ReadImage(image_t image_id) {
  const StatementLease lease =
      Statement(ImageSelect(images_have_priors_) + " WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step()) {
    ThrowInputError(path(), ": no image with id ", image_id);
  }
  return ImageFromRow(statement, images_have_priors_);
}

std::vector<DatabaseImage> Database::ReadAllImages() {
  std::vector<DatabaseImage> images;
  const StatementLease lease =
      Statement(ImageSelect(images_have_priors_) + " ORDER BY image_id");
  SqliteStatement& statement = *lease;
  while (statement.Step()) {
    images.push_back(ImageFromRow(statement, images_have_priors_));
  }
  return images;
}

image_t Database::WriteImage(const DatabaseImage& image, bool use_image_id) {
  CheckWritable("images");
  if (image.name.empty()) ThrowInputError(path(), ": an image needs a name");
  const StatementLease lease = Statement(
      images_have_priors_
          ? "INSERT INTO images(image_id, name, camera_id, prior_qw, prior_qx, "
            "prior_qy, prior_qz, prior_tx, prior_ty, prior_tz) "
            "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)"
          : "INSERT INTO images(image_id, name, camera_id) VALUES(?, ?, ?)");
  SqliteStatement& statement = *lease;
  if (use_image_id) {
    statement.Bind(1, static_cast<int64_t>(image.image_id));
  } else {
    statement.BindNull(1);
  }
  statement.Bind(2, image.name);
  statement.Bind(3, static_cast<int64_t>(image.camera_id));
  if (images_have_priors_) {
    for (int i = 0; i < 4; ++i) statement.Bind(4 + i, image.prior_q[i]);
    for (int i = 0; i < 3; ++i) statement.Bind(8 + i, image.prior_t[i]);
  }
  statement.Execute();
  return static_cast<image_t>(connection_->LastInsertRowId());
}

void Database::UpdateImage(const DatabaseImage& image) {
  CheckWritable("images");
  const StatementLease lease = Statement(
      images_have_priors_
          ? "UPDATE images SET name = ?, camera_id = ?, prior_qw = ?, "
            "prior_qx = ?, prior_qy = ?, prior_qz = ?, prior_tx = ?, "
            "prior_ty = ?, prior_tz = ? WHERE image_id = ?"
          : "UPDATE images SET name = ?, camera_id = ? WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, image.name);
  statement.Bind(2, static_cast<int64_t>(image.camera_id));
  int idx = 3;
  if (images_have_priors_) {
    for (int i = 0; i < 4; ++i) statement.Bind(idx++, image.prior_q[i]);
    for (int i = 0; i < 3; ++i) statement.Bind(idx++, image.prior_t[i]);
  }
  statement.Bind(idx, static_cast<int64_t>(image.image_id));
  statement.Execute();
}

// ---------------------------------------------------- keypoints, descriptors

bool Database::ExistsKeypoints(image_t image_id) {
  const StatementLease lease =
      Statement("SELECT 1 FROM keypoints WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  return statement.Step();
}

bool Database::ExistsDescriptors(image_t image_id) {
  const StatementLease lease =
      Statement("SELECT 1 FROM descriptors WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  return statement.Step();
}

FeatureKeypoints Database::ReadKeypoints(image_t image_id) {
  const StatementLease lease =
      Statement("SELECT rows, cols, data FROM keypoints WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step()) return FeatureKeypoints(0, 2);
  const std::string what = StrCat(path(), ": keypoints of image ", image_id);
  FeatureKeypoints keypoints =
      ReadMatrixBlob<FeatureKeypoints>(statement, 0, 1, 2, what);
  if (keypoints.rows() > 0 && keypoints.cols() != 2 && keypoints.cols() != 4 &&
      keypoints.cols() != 6) {
    ThrowInputError(what,
                    ": ",
                    keypoints.cols(),
                    " columns; COLMAP keypoints have 2, 4 or 6");
  }
  return keypoints;
}

FeatureDescriptors Database::ReadDescriptors(image_t image_id) {
  const StatementLease lease =
      Statement("SELECT rows, cols, data FROM descriptors WHERE image_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step()) return FeatureDescriptors(0, 128);
  return ReadMatrixBlob<FeatureDescriptors>(
      statement, 0, 1, 2, StrCat(path(), ": descriptors of image ", image_id));
}

void Database::WriteKeypoints(image_t image_id,
                              const FeatureKeypoints& keypoints) {
  CheckWritable("keypoints");
  const StatementLease lease = Statement(
      "INSERT OR REPLACE INTO keypoints(image_id, rows, cols, data) "
      "VALUES(?, ?, ?, ?)");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  BindMatrixBlob(statement, 2, keypoints);
  statement.Execute();
}

void Database::WriteDescriptors(image_t image_id,
                                const FeatureDescriptors& descriptors) {
  CheckWritable("descriptors");
  const StatementLease lease = Statement(
      "INSERT OR REPLACE INTO descriptors(image_id, rows, cols, data) "
      "VALUES(?, ?, ?, ?)");
  SqliteStatement& statement = *lease;
  statement.Bind(1, static_cast<int64_t>(image_id));
  BindMatrixBlob(statement, 2, descriptors);
  statement.Execute();
}

// ---------------------------------------------------------------- matches

namespace {

FeatureMatches SwapColumns(const FeatureMatches& matches) {
  // Columns of an empty matrix (COLMAP's rows = 0) would offset a null
  // pointer.
  if (matches.rows() == 0) return FeatureMatches(0, 2);
  FeatureMatches swapped(matches.rows(), 2);
  swapped.col(0) = matches.col(1);
  swapped.col(1) = matches.col(0);
  return swapped;
}

}  // namespace

bool Database::ExistsMatches(image_t image_id1, image_t image_id2) {
  const StatementLease lease =
      Statement("SELECT 1 FROM matches WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  return statement.Step();
}

FeatureMatches Database::ReadMatches(image_t image_id1, image_t image_id2) {
  const StatementLease lease =
      Statement("SELECT rows, cols, data FROM matches WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  if (!statement.Step()) return FeatureMatches(0, 2);
  FeatureMatches matches = ReadMatrixBlob<FeatureMatches>(
      statement,
      0,
      1,
      2,
      StrCat(path(), ": matches of images ", image_id1, " and ", image_id2));
  return SwapImagePair(image_id1, image_id2) ? SwapColumns(matches) : matches;
}

std::vector<std::pair<pair_t, FeatureMatches>> Database::ReadAllMatches() {
  std::vector<std::pair<pair_t, FeatureMatches>> all;
  const StatementLease lease = Statement(
      "SELECT pair_id, rows, cols, data FROM matches ORDER BY pair_id");
  SqliteStatement& statement = *lease;
  while (statement.Step()) {
    const pair_t pair_id = static_cast<pair_t>(statement.ColumnInt64(0));
    all.emplace_back(
        pair_id,
        ReadMatrixBlob<FeatureMatches>(
            statement, 1, 2, 3, StrCat(path(), ": matches row ", pair_id)));
  }
  return all;
}

std::vector<pair_t> Database::ReadMatchedPairIds() {
  std::vector<pair_t> pair_ids;
  const StatementLease lease =
      Statement("SELECT pair_id FROM matches WHERE rows > 0 ORDER BY pair_id");
  SqliteStatement& statement = *lease;
  while (statement.Step()) pair_ids.push_back(statement.ColumnInt64(0));
  return pair_ids;
}

void Database::WriteMatches(image_t image_id1,
                            image_t image_id2,
                            const FeatureMatches& matches) {
  CheckWritable("matches");
  const StatementLease lease = Statement(
      "INSERT OR REPLACE INTO matches(pair_id, rows, cols, data) "
      "VALUES(?, ?, ?, ?)");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  if (SwapImagePair(image_id1, image_id2)) {
    BindMatrixBlob(statement, 2, SwapColumns(matches));
  } else {
    BindMatrixBlob(statement, 2, matches);
  }
  statement.Execute();
}

void Database::DeleteMatches(image_t image_id1, image_t image_id2) {
  CheckWritable("matches");
  const StatementLease lease =
      Statement("DELETE FROM matches WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  statement.Execute();
}

// ------------------------------------------------------- two-view geometries

TwoViewGeometry InvertTwoViewGeometry(const TwoViewGeometry& geometry) {
  TwoViewGeometry inverse = geometry;
  inverse.inlier_matches = SwapColumns(geometry.inlier_matches);
  if (geometry.F) inverse.F = geometry.F->transpose();
  if (geometry.E) inverse.E = geometry.E->transpose();
  if (geometry.H) inverse.H = geometry.H->inverse();
  if (geometry.qvec && geometry.tvec) {
    const Eigen::Vector4d& q = *geometry.qvec;
    // The inverse pose: R^T, -R^T t. A zero quaternion (not computed) stays
    // as it is, sign bits and all, as COLMAP leaves it.
    if (q.squaredNorm() > 0) {
      const Eigen::Quaterniond rotation(q(0), q(1), q(2), q(3));
      const Eigen::Quaterniond inverse_rotation = rotation.inverse();
      inverse.qvec = Eigen::Vector4d(inverse_rotation.w(),
                                     inverse_rotation.x(),
                                     inverse_rotation.y(),
                                     inverse_rotation.z());
      inverse.tvec = -(inverse_rotation * *geometry.tvec);
    }
  }
  return inverse;
}

bool Database::ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) {
  const StatementLease lease =
      Statement("SELECT 1 FROM two_view_geometries WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  return statement.Step();
}

namespace {

constexpr const char* kSelectGeometry =
    "SELECT pair_id, rows, cols, data, config, F, E, H, qvec, tvec FROM "
    "two_view_geometries";

TwoViewGeometry GeometryFromRow(const SqliteStatement& statement,
                                const std::string& what) {
  TwoViewGeometry geometry;
  geometry.inlier_matches =
      ReadMatrixBlob<FeatureMatches>(statement, 1, 2, 3, what);
  geometry.config = static_cast<TwoViewConfig>(statement.ColumnInt64(4));
  geometry.F = ReadFixedBlob<3, 3>(statement, 5, what + " F");
  geometry.E = ReadFixedBlob<3, 3>(statement, 6, what + " E");
  geometry.H = ReadFixedBlob<3, 3>(statement, 7, what + " H");
  geometry.qvec = ReadFixedBlob<4, 1>(statement, 8, what + " qvec");
  geometry.tvec = ReadFixedBlob<3, 1>(statement, 9, what + " tvec");
  return geometry;
}

}  // namespace

TwoViewGeometry Database::ReadTwoViewGeometry(image_t image_id1,
                                              image_t image_id2) {
  const StatementLease lease =
      Statement(std::string(kSelectGeometry) + " WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  if (!statement.Step()) return TwoViewGeometry();
  const TwoViewGeometry geometry =
      GeometryFromRow(statement,
                      StrCat(path(),
                             ": two_view_geometries of images ",
                             image_id1,
                             " and ",
                             image_id2));
  return SwapImagePair(image_id1, image_id2) ? InvertTwoViewGeometry(geometry)
                                             : geometry;
}

std::vector<std::pair<pair_t, TwoViewGeometry>>
Database::ReadAllTwoViewGeometries() {
  std::vector<std::pair<pair_t, TwoViewGeometry>> all;
  const StatementLease lease =
      Statement(std::string(kSelectGeometry) + " ORDER BY pair_id");
  SqliteStatement& statement = *lease;
  while (statement.Step()) {
    const pair_t pair_id = static_cast<pair_t>(statement.ColumnInt64(0));
    all.emplace_back(
        pair_id,
        GeometryFromRow(statement,
                        StrCat(path(), ": two_view_geometries row ", pair_id)));
  }
  return all;
}

void Database::WriteTwoViewGeometry(image_t image_id1,
                                    image_t image_id2,
                                    const TwoViewGeometry& geometry) {
  CheckWritable("two_view_geometries");
  const TwoViewGeometry stored = SwapImagePair(image_id1, image_id2)
                                     ? InvertTwoViewGeometry(geometry)
                                     : geometry;
  const StatementLease lease = Statement(
      "INSERT OR REPLACE INTO two_view_geometries(pair_id, rows, cols, data, "
      "config, F, E, H, qvec, tvec) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  BindMatrixBlob(statement, 2, stored.inlier_matches);
  statement.Bind(5, static_cast<int64_t>(stored.config));
  BindFixedBlob<3, 3>(statement, 6, stored.F);
  BindFixedBlob<3, 3>(statement, 7, stored.E);
  BindFixedBlob<3, 3>(statement, 8, stored.H);
  BindFixedBlob<4, 1>(statement, 9, stored.qvec);
  BindFixedBlob<3, 1>(statement, 10, stored.tvec);
  statement.Execute();
}

void Database::DeleteTwoViewGeometry(image_t image_id1, image_t image_id2) {
  CheckWritable("two_view_geometries");
  const StatementLease lease =
      Statement("DELETE FROM two_view_geometries WHERE pair_id = ?");
  SqliteStatement& statement = *lease;
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  statement.Execute();
}

std::map<image_t, Camera> ReadImageCameras(
    Database* database, const std::vector<DatabaseImage>& images) {
  std::map<camera_t, Camera> cameras;
  for (const Camera& camera : database->ReadAllCameras()) {
    cameras.emplace(camera.camera_id, camera);
  }
  std::map<image_t, Camera> of_image;
  for (const DatabaseImage& image : images) {
    const auto camera = cameras.find(image.camera_id);
    if (camera == cameras.end()) {
      ThrowInputError(database->path(),
                      ": image ",
                      image.name,
                      " refers to camera ",
                      image.camera_id,
                      ", which is not in the cameras table");
    }
    of_image.emplace(image.image_id, camera->second);
  }
  return of_image;
}

void CheckDerivedDatabasePath(const std::string& database_path,
                              const std::string& output_path,
                              bool overwrite,
                              const std::string& what) {
  namespace fs = std::filesystem;
  if (output_path.empty()) ThrowInputError(what, ": no output path");
  std::error_code ec;
  if (fs::exists(output_path, ec) &&
      fs::equivalent(database_path, output_path, ec)) {
    ThrowInputError(output_path,
                    ": the output is the input database; ",
                    what,
                    " writes a new database");
  }
  CheckOutputPath(output_path, overwrite);
  const fs::path parent = fs::absolute(output_path).parent_path();
  if (!fs::is_directory(parent, ec)) {
    ThrowInputError(
        output_path, ": the output folder ", parent, " does not exist");
  }
}

void WriteDerivedDatabase(const std::string& database_path,
                          const std::string& output_path,
                          const std::function<void(Database*)>& modify) {
  namespace fs = std::filesystem;
  const std::string temp_path = output_path + TempSuffix();
  TempFileGuard guard(temp_path);
  CopySqliteDatabase(database_path, temp_path);
  {
    Database database(temp_path, Database::Mode::kReadWrite);
    SqliteTransaction transaction = database.BeginTransaction();
    modify(&database);
    transaction.Commit();
  }
  // A journal left beside an older output would be replayed into the new
  // file: remove the companions before the rename.
  std::error_code ec;
  for (const char* suffix : {"-journal", "-wal", "-shm"}) {
    fs::remove(output_path + suffix, ec);
  }
  fs::rename(temp_path, output_path, ec);
  if (ec) {
    ThrowInputError(output_path, ": cannot write (", ec.message(), ")");
  }
  guard.Keep();
}

}  // namespace bayon
