// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/database.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/sqlite.h"
#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "tests/testing.h"

namespace bayon {
namespace {

Camera TestCamera() {
  Camera camera = Camera::Create(CameraModelId::kSimpleRadial, 500, 640, 480);
  camera.params[3] = -0.01;
  camera.has_prior_focal_length = true;
  return camera;
}

TEST(Database, PairIdsFollowColmap) {
  EXPECT_EQ(PairIdFromImageIds(1, 2), 2147483649ull);
  EXPECT_EQ(PairIdFromImageIds(2, 3), 4294967297ull);
  EXPECT_EQ(PairIdFromImageIds(3, 2), 4294967297ull);
  const auto [a, b] = ImageIdsFromPairId(4294967297ull);
  EXPECT_EQ(a, 2u);
  EXPECT_EQ(b, 3u);
}

TEST(Database, WritesAndReadsEveryTable) {
  const std::string dir = testing::TempDir("database_rw");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  EXPECT_EQ(db.UserVersion(), 3800);
  EXPECT_EQ(db.schema(), DatabaseSchema::kColmap38);
  const camera_t camera_id = db.WriteCamera(TestCamera());
  DatabaseImage image1{kInvalidImageId, "a.png", camera_id, {}, {}};
  DatabaseImage image2{kInvalidImageId, "b.png", camera_id, {}, {}};
  image2.prior_t = {47.1, 8.5, std::nullopt};
  const image_t id1 = db.WriteImage(image1);
  const image_t id2 = db.WriteImage(image2);
  EXPECT_EQ(id1, 1u);
  EXPECT_EQ(id2, 2u);
  EXPECT_EQ(db.ReadImage(id2).prior_t[0], 47.1);
  EXPECT_FALSE(db.ReadImage(id2).prior_t[2].has_value());
  db.WriteKeypoints(id1, KeypointsFromXY({{1.5, 2.5}, {10, 20}}));
  db.WriteKeypoints(id2, KeypointsFromXY({{3, 4}, {30, 40}, {5, 6}}));
  FeatureMatches matches(2, 2);
  matches << 0, 2, 1, 0;
  // Written as (2, 1): stored canonically with the columns swapped.
  db.WriteMatches(id2, id1, matches);
  const FeatureMatches forward = db.ReadMatches(id1, id2);
  EXPECT_EQ(forward(0, 0), 2u);
  EXPECT_EQ(forward(0, 1), 0u);
  EXPECT_EQ(db.ReadMatches(id2, id1), matches);

  TwoViewGeometry geometry;
  geometry.config = TwoViewConfig::kCalibrated;
  geometry.inlier_matches = matches;
  const Eigen::Quaterniond rotation(
      Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  geometry.qvec =
      Eigen::Vector4d(rotation.w(), rotation.x(), rotation.y(), rotation.z());
  geometry.tvec = Eigen::Vector3d(1, 0, 0);
  Eigen::Matrix3d F;
  F << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  geometry.F = F;
  db.WriteTwoViewGeometry(id2, id1, geometry);
  const TwoViewGeometry back = db.ReadTwoViewGeometry(id2, id1);
  EXPECT_EQ(back.inlier_matches, matches);
  EXPECT_LT((*back.F - F).norm(), 1e-12);
  EXPECT_LT((*back.qvec - *geometry.qvec).norm(), 1e-12);
  EXPECT_LT((*back.tvec - *geometry.tvec).norm(), 1e-12);
  EXPECT_FALSE(back.E.has_value());
  // Stored inverted: F transposed, pose inverted.
  const TwoViewGeometry stored = db.ReadTwoViewGeometry(id1, id2);
  EXPECT_LT((*stored.F - F.transpose()).norm(), 1e-12);
  EXPECT_EQ(db.NumInlierMatches(), 2);
  EXPECT_EQ(db.NumKeypoints(), 5);
}

// A single-row read must not keep its read lock: with it, this connection's
// next BEGIN IMMEDIATE failed at once ("database is locked") while another
// connection was writing, instead of waiting for it (`bayon match` beside
// `bayon features` on one database).
TEST(Database, ReadsReleaseTheirLockSoTransactionsWaitForOtherWriters) {
  const std::string dir = testing::TempDir("database_concurrent");
  const std::string path = dir + "/db.db";
  camera_t camera_id = kInvalidCameraId;
  {
    Database db(path, Database::Mode::kCreate);
    camera_id = db.WriteCamera(TestCamera());
    db.WriteImage(DatabaseImage{kInvalidImageId, "a.png", camera_id, {}, {}});
  }
  Database reader(path, Database::Mode::kReadWrite);
  Database writer(path, Database::Mode::kReadWrite);
  auto writing = writer.BeginTransaction();
  writer.WriteImage(DatabaseImage{kInvalidImageId, "b.png", camera_id, {}, {}});
  ASSERT_TRUE(reader.ReadImageWithName("a.png"));
  std::thread commit([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    writing.Commit();
  });
  std::string error;
  try {
    auto transaction = reader.BeginTransaction();  // waits for the commit
    reader.WriteImage(
        DatabaseImage{kInvalidImageId, "c.png", camera_id, {}, {}});
    transaction.Commit();
  } catch (const std::exception& e) {
    error = e.what();
  }
  commit.join();
  EXPECT_EQ(error, "");
  EXPECT_TRUE(reader.ReadImageWithName("b.png"));
  EXPECT_TRUE(reader.ReadImageWithName("c.png"));
}

TEST(Database, RefusesWhatIsNotAColmapDatabase) {
  const std::string dir = testing::TempDir("database_bad");
  WriteFileAtomically(dir + "/text.db", "SQLite format 3? no, just text\n");
  try {
    Database db(dir + "/text.db", Database::Mode::kReadOnly);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("not an SQLite database"),
              std::string::npos)
        << error.what();
  }
  EXPECT_THROW(Database(dir + "/missing.db", Database::Mode::kReadOnly),
               InputError);
  {
    SqliteConnection other(dir + "/other.db", SqliteConnection::Mode::kCreate);
    other.Execute("CREATE TABLE notes(id INTEGER PRIMARY KEY, text TEXT)");
  }
  EXPECT_THROW(Database(dir + "/other.db", Database::Mode::kReadWrite),
               InputError);
}

TEST(Database, DetectsNewerSchemasAndRefusesToWriteImagesThere) {
  const std::string dir = testing::TempDir("database_versions");
  {
    // A 4.x-like database: images without priors, rigs and frames, typed
    // descriptors.
    SqliteConnection c(dir + "/v4.db", SqliteConnection::Mode::kCreate);
    c.Execute(
        "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT "
        "NULL, model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER "
        "NOT NULL, params BLOB, prior_focal_length INTEGER NOT NULL);"
        "CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT "
        "NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL);"
        "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows "
        "INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);"
        "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows "
        "INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, type INTEGER NOT "
        "NULL);"
        "CREATE TABLE matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows "
        "INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT "
        "NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config "
        "INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);"
        "CREATE TABLE rigs (rig_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, "
        "ref_sensor_id INTEGER NOT NULL, ref_sensor_type INTEGER NOT NULL);"
        "CREATE TABLE frames (frame_id INTEGER PRIMARY KEY AUTOINCREMENT NOT "
        "NULL, rig_id INTEGER NOT NULL);"
        "INSERT INTO images(image_id, name, camera_id) VALUES(1, 'x.jpg', 1);"
        "PRAGMA user_version = 4010100;");
  }
  Database db(dir + "/v4.db", Database::Mode::kReadWrite);
  EXPECT_EQ(db.schema(), DatabaseSchema::kColmap40);
  ASSERT_EQ(db.ReadAllImages().size(), 1u);
  EXPECT_EQ(db.ReadAllImages()[0].name, "x.jpg");
  try {
    db.WriteImage(DatabaseImage{kInvalidImageId, "y.jpg", 1, {}, {}});
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("COLMAP 4.x"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(db.UserVersion(), 4010100);
}

TEST(BayonTables, CascadeWithImagesAndKeepUserVersion) {
  const std::string dir = testing::TempDir("bayon_tables");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  const camera_t camera_id = db.WriteCamera(TestCamera());
  const image_t image_id =
      db.WriteImage(DatabaseImage{kInvalidImageId, "a.png", camera_id, {}, {}});
  InteriorRecord interior;
  interior.frame = ImageFrame::Digital(640, 480, 0.01);
  interior.method = "digital";
  WriteInterior(&db, image_id, interior);
  CalibrationRecord calibration;
  calibration.camera =
      Camera::Create(CameraModelId::kBrownBeyer, 500, 640, 480, 0.01);
  calibration.camera.camera_id = camera_id;
  WriteCalibration(&db, calibration);
  ASSERT_TRUE(ReadInterior(&db, image_id));
  EXPECT_LT((ReadInterior(&db, image_id)->frame.pixel_from_frame -
             interior.frame.pixel_from_frame)
                .norm(),
            1e-15);
  EXPECT_NEAR(
      ReadCalibration(&db, camera_id)->camera.pixel_pitch_mm, 0.01, 1e-15);
  EXPECT_EQ(ReadBayonMeta(&db, "schema_version"),
            std::to_string(kBayonSchemaVersion));
  db.connection()->Execute("DELETE FROM images");
  EXPECT_FALSE(ReadInterior(&db, image_id));
  db.connection()->Execute("DELETE FROM cameras");
  EXPECT_FALSE(ReadCalibration(&db, camera_id));
  EXPECT_EQ(db.UserVersion(), 3800);
}

TEST(BayonTables, MatchRecordsKeepTheirStandardDeviations) {
  const std::string dir = testing::TempDir("bayon_tables_matches");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  const camera_t camera_id = db.WriteCamera(TestCamera());
  const image_t a =
      db.WriteImage(DatabaseImage{kInvalidImageId, "a.png", camera_id, {}, {}});
  const image_t b =
      db.WriteImage(DatabaseImage{kInvalidImageId, "b.png", camera_id, {}, {}});
  MatchRecord record;
  record.xy1 = {Eigen::Vector2f(1.5f, 2.5f), Eigen::Vector2f(3.5f, 4.5f)};
  record.xy2 = {Eigen::Vector2f(5.25f, 6.75f), Eigen::Vector2f(7.f, 8.f)};
  record.ncc = {0.9f, 0.8f};
  record.sigma_px = {0.1f, 0.3f};
  WriteMatchRecord(&db, a, b, record);
  const std::optional<MatchRecord> read = ReadMatchRecord(&db, a, b);
  ASSERT_TRUE(read);
  EXPECT_EQ(read->xy2[0], record.xy2[0]);
  EXPECT_EQ(read->ncc, record.ncc);
  EXPECT_EQ(read->sigma_px, record.sigma_px);
  // A row written before the standard deviations were kept (five floats
  // per match) still reads, without them.
  const std::vector<float> old_points = {
      1.5f, 2.5f, 5.25f, 6.75f, 0.9f, 3.5f, 4.5f, 7.f, 8.f, 0.8f};
  SqliteStatement update(db.connection(),
                         "UPDATE bayon_matches SET points = ?");
  update.BindBlob(1, old_points.data(), old_points.size() * sizeof(float));
  update.Execute();
  const std::optional<MatchRecord> old = ReadMatchRecord(&db, a, b);
  ASSERT_TRUE(old);
  EXPECT_EQ(old->xy2[1], record.xy2[1]);
  EXPECT_EQ(old->ncc, record.ncc);
  EXPECT_TRUE(old->sigma_px.empty());
}

TEST(BayonTables, BrownBeyerCameraGoesToCamerasAsItsFit) {
  const std::string dir = testing::TempDir("bayon_tables_fit");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  Camera camera =
      Camera::Create(CameraModelId::kBrownBeyer, 1750, 1800, 1200, 0.02);
  camera.params[brown::kK1] = -3e-5;
  camera.params[brown::kB2] = 1e-4;  // shear: FULL_OPENCV cannot hold it
  const camera_t camera_id = WriteCameraWithCalibration(&db, camera);
  EXPECT_EQ(db.ReadCamera(camera_id).model_id, CameraModelId::kFullOpenCV);
  const auto calibration = ReadCalibration(&db, camera_id);
  ASSERT_TRUE(calibration);
  EXPECT_EQ(calibration->camera.params, camera.params);
  EXPECT_GT(calibration->colmap_fit_max_px, 0.0);
  EXPECT_LT(calibration->colmap_fit_max_px, 1.0);
  // A COLMAP model is written as it is, without a calibration row.
  const camera_t colmap_id = WriteCameraWithCalibration(&db, TestCamera());
  EXPECT_EQ(db.ReadCamera(colmap_id).params, TestCamera().params);
  EXPECT_FALSE(ReadCalibration(&db, colmap_id));
}

TEST(BayonTables, RefusesNewerBayonSchema) {
  const std::string dir = testing::TempDir("bayon_tables_newer");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  WriteBayonMeta(&db, "schema_version", "999");
  EXPECT_THROW(CheckBayonSchema(&db), InputError);
}

TEST(Database, TransactionRollsBackOnError) {
  const std::string dir = testing::TempDir("database_tx");
  Database db(dir + "/db.db", Database::Mode::kCreate);
  try {
    auto transaction = db.BeginTransaction();
    db.WriteCamera(TestCamera());
    throw std::runtime_error("interrupted");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(db.NumCameras(), 0);
}

}  // namespace
}  // namespace bayon
