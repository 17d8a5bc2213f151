// SPDX-License-Identifier: BSD-3-Clause
//
// COLMAP's database.db, read and written by bayon's own code: the 3.8 schema
// (colmap-interop.md, section 1) with its blob layouts and pair ids, plus
// reading of databases written by later COLMAP versions where their layout
// allows it. bayon's own data lives in `bayon_*` tables (bayon_tables.h).
//
// Rules kept here:
// - writes happen in transactions (Database::Transaction);
// - `user_version` and the journal mode of an existing database are never
//   changed; a database bayon creates gets what `colmap database_creator`
//   writes (user_version 3800, rollback journal);
// - matches and geometries are stored in COLMAP's canonical pair order, with
//   columns swapped and geometries inverted as COLMAP does.
#pragma once

#include "ext/colmap/sqlite.h"
#include "ext/core/camera.h"
#include "ext/core/rigid3.h"
#include "ext/core/types.h"

#include <Eigen/Core>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

// A row of `images`. The prior columns exist only in 3.8/3.9 databases; NULL
// stays NULL (prior_t* hold EXIF GPS latitude, longitude, altitude).
struct DatabaseImage {
  image_t image_id = kInvalidImageId;
  std::string name;
  camera_t camera_id = kInvalidCameraId;
  std::array<std::optional<double>, 4> prior_q;
  std::array<std::optional<double>, 3> prior_t;
};

// Keypoints as stored: N rows of 2 (x, y), 4 (+ scale, orientation) or
// 6 (+ affine shape a11 a12 a21 a22) float32 columns, pixel coordinates.
using FeatureKeypoints =
    Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// SIFT-like descriptors, N x 128 uint8 (see colmap-interop.md 1.3 for scaling).
using FeatureDescriptors =
    Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// Matches as (keypoint index in image 1, keypoint index in image 2).
using FeatureMatches =
    Eigen::Matrix<uint32_t, Eigen::Dynamic, 2, Eigen::RowMajor>;

// Keypoint coordinates of row `idx`.
inline Eigen::Vector2d KeypointXY(const FeatureKeypoints& keypoints, int idx) {
  return Eigen::Vector2d(keypoints(idx, 0), keypoints(idx, 1));
}
// The scale of row `idx`: its third column in the 4-column form, sqrt |det|
// of the affine shape in the 6-column form; 1 for the 2-column form.
double KeypointScale(const FeatureKeypoints& keypoints, int idx);
// N x 6 keypoints (COLMAP's written form) with an identity affine shape.
FeatureKeypoints KeypointsFromXY(const std::vector<Eigen::Vector2d>& xy);

enum class TwoViewConfig : int {
  kUndefined = 0,
  kDegenerate = 1,
  kCalibrated = 2,
  kUncalibrated = 3,
  kPlanar = 4,
  kPanoramic = 5,
  kPlanarOrPanoramic = 6,
  kWatermark = 7,
  kMultiple = 8,
  kCalibratedRig = 9,  // COLMAP 3.13+
};

// A row of `two_view_geometries`, in the caller's image order. F, E, H and
// the relative pose cam2_from_cam1 are optional because COLMAP writes NULL
// for pairs it could not verify.
struct TwoViewGeometry {
  TwoViewConfig config = TwoViewConfig::kUndefined;
  FeatureMatches inlier_matches;
  std::optional<Eigen::Matrix3d> F;  // x2^T F x1 = 0, pixels
  std::optional<Eigen::Matrix3d> E;  // E = [t]x R for (R, t) = cam2_from_cam1
  std::optional<Eigen::Matrix3d> H;  // maps image 1 to image 2
  std::optional<Eigen::Vector4d> qvec;  // cam2_from_cam1 rotation (w, x, y, z)
  std::optional<Eigen::Vector3d> tvec;  // cam2_from_cam1 translation, |t| = 1

  // cam2_from_cam1 (|t| = 1) as qvec and tvec store it, or nullopt where
  // they are missing or zero (a geometry of E, F or H alone).
  std::optional<Rigid3d> StoredPose() const;
};

// What the schema of an opened database looks like.
enum class DatabaseSchema {
  kEmpty,      // no COLMAP tables yet
  kColmap38,   // 3.8/3.9: images with prior_* columns
  kColmap310,  // 3.10/3.11: pose_priors table, no prior_* columns
  kColmap312,  // 3.12/3.13: rigs and frames
  kColmap40,   // 4.x: descriptors.type, rebuilt pose_priors
};
const char* DatabaseSchemaName(DatabaseSchema schema);

class Database {
 public:
  enum class Mode {
    kReadOnly,   // never writes; the file may be read-only
    kReadWrite,  // an existing database, COLMAP tables must exist
    kCreate,     // a new file with the 3.8 schema; the path must not exist
    kOpenOrCreate,
  };

  // Opens or creates a database. Throws InputError for a missing file, a
  // file that is not SQLite, a database without COLMAP's tables (in modes
  // other than kCreate) or one whose layout bayon cannot read.
  Database(const std::string& path, Mode mode);

  const std::string& path() const { return connection_->path(); }
  DatabaseSchema schema() const { return schema_; }
  int64_t UserVersion();
  SqliteConnection* connection() { return connection_.get(); }

  // Refuses writes to COLMAP's tables where this schema cannot take them.
  void CheckWritable(const char* what) const;

  // --- counts
  int NumCameras();
  int NumImages();
  int NumKeypointRows();   // images with a keypoints row
  int64_t NumKeypoints();  // sum of rows
  int64_t NumDescriptors();
  int NumMatchedPairs();  // matches rows with rows > 0
  int64_t NumMatches();
  int NumVerifiedPairs();  // two_view_geometries rows with rows > 0
  int64_t NumInlierMatches();

  // --- cameras
  bool ExistsCamera(camera_t camera_id);
  Camera ReadCamera(camera_t camera_id);
  std::vector<Camera> ReadAllCameras();
  // Inserts a camera; with use_camera_id the camera's id is kept, otherwise
  // SQLite assigns one. Returns the id. BROWN_BEYER cameras are refused: they
  // go to COLMAP as their fitted COLMAP model (camera_conversion.h).
  camera_t WriteCamera(const Camera& camera, bool use_camera_id = false);
  void UpdateCamera(const Camera& camera);

  // --- images
  bool ExistsImage(image_t image_id);
  std::optional<DatabaseImage> ReadImageWithName(const std::string& name);
  DatabaseImage ReadImage(image_t image_id);
  std::vector<DatabaseImage> ReadAllImages();  // in image_id order
  image_t WriteImage(const DatabaseImage& image, bool use_image_id = false);
  void UpdateImage(const DatabaseImage& image);

  // --- keypoints and descriptors
  bool ExistsKeypoints(image_t image_id);
  bool ExistsDescriptors(image_t image_id);
  FeatureKeypoints ReadKeypoints(image_t image_id);
  FeatureDescriptors ReadDescriptors(image_t image_id);
  // Inserts or replaces the image's row.
  void WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints);
  void WriteDescriptors(image_t image_id,
                        const FeatureDescriptors& descriptors);

  // --- matches (in the caller's image order)
  bool ExistsMatches(image_t image_id1, image_t image_id2);
  FeatureMatches ReadMatches(image_t image_id1, image_t image_id2);
  // All rows, in pair_id order, as stored (canonical order).
  std::vector<std::pair<pair_t, FeatureMatches>> ReadAllMatches();
  std::vector<pair_t> ReadMatchedPairIds();
  void WriteMatches(image_t image_id1,
                    image_t image_id2,
                    const FeatureMatches& matches);
  void DeleteMatches(image_t image_id1, image_t image_id2);

  // --- two-view geometries (in the caller's image order)
  bool ExistsTwoViewGeometry(image_t image_id1, image_t image_id2);
  TwoViewGeometry ReadTwoViewGeometry(image_t image_id1, image_t image_id2);
  std::vector<std::pair<pair_t, TwoViewGeometry>> ReadAllTwoViewGeometries();
  void WriteTwoViewGeometry(image_t image_id1,
                            image_t image_id2,
                            const TwoViewGeometry& geometry);
  void DeleteTwoViewGeometry(image_t image_id1, image_t image_id2);

  // A write transaction (BEGIN IMMEDIATE ... COMMIT); rolled back when it
  // goes out of scope uncommitted.
  SqliteTransaction BeginTransaction() {
    return SqliteTransaction(connection_.get());
  }

 private:
  void CreateColmapTables();
  void DetectSchema();
  // One use of a cached statement: reset when the lease ends. A SELECT left
  // on a row keeps a read lock on the file; another process's COMMIT then
  // waits for it, and this connection's next BEGIN IMMEDIATE fails at once
  // with "database is locked" (SQLite does not wait where waiting could
  // deadlock): `bayon match` beside `bayon features` did so.
  class StatementLease {
   public:
    explicit StatementLease(SqliteStatement* statement)
        : statement_(statement) {}
    ~StatementLease() { statement_->Reset(); }
    StatementLease(const StatementLease&) = delete;
    StatementLease& operator=(const StatementLease&) = delete;
    SqliteStatement& operator*() const { return *statement_; }

   private:
    SqliteStatement* statement_;
  };
  StatementLease Statement(const std::string& sql);

  std::unique_ptr<SqliteConnection> connection_;
  DatabaseSchema schema_ = DatabaseSchema::kEmpty;
  bool images_have_priors_ = false;
  std::vector<std::pair<std::string, std::unique_ptr<SqliteStatement>>>
      statements_;
};

// Inverts a two-view geometry so that it describes (image 2, image 1).
TwoViewGeometry InvertTwoViewGeometry(const TwoViewGeometry& geometry);

// The cameras-table row of each image, by image id. Throws InputError
// naming the first image whose camera is not in the table.
std::map<image_t, Camera> ReadImageCameras(
    Database* database, const std::vector<DatabaseImage>& images);

// For stages that write a new database derived from the user's (which is
// never modified): the checks on the output path (not empty, not the input,
// its folder exists, an existing file only with `overwrite`; InputError
// naming `what` otherwise), then the copy. WriteDerivedDatabase copies
// `database_path` (SQLite's backup) to a temporary name beside
// `output_path`, calls `modify` on it inside one transaction, and renames
// it to `output_path` when complete; on any error the temporary file is
// removed and nothing else changes.
void CheckDerivedDatabasePath(const std::string& database_path,
                              const std::string& output_path,
                              bool overwrite,
                              const std::string& what);
void WriteDerivedDatabase(const std::string& database_path,
                          const std::string& output_path,
                          const std::function<void(Database*)>& modify);

}  // namespace bayon
