// SPDX-License-Identifier: BSD-3-Clause
//
// bayon against the real `colmap` 3.8 binary: reading what stock COLMAP
// writes (databases and models), writing what COLMAP reads, and COLMAP's own
// maintenance tools on a database bayon has touched.
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/core/file_util.h"
#include "ext/eval/sparse_eval.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <set>

#include "tests/temple_fixture.h"
#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// Stock COLMAP's database and mapper model of the temple ring (the tests'
// one COLMAP run of it, temple_fixture.h), and the model as COLMAP's
// model_converter writes it in text: <dir>/txt.
struct StockTemple {
  std::string database;
  std::string model;
  std::string txt;
};

StockTemple StockTempleFixture() {
  StockTemple temple;
  const testing::TempleColmap colmap = testing::TempleColmapFixture();
  temple.database = colmap.database;
  temple.model = colmap.model;
  temple.txt =
      testing::SharedFixture("interop_temple_txt",
                             [&](const std::string& dir) {
                               fs::create_directories(dir + "/txt");
                               const testing::CommandResult result =
                                   testing::RunColmap({"model_converter",
                                                       "--input_path",
                                                       colmap.model,
                                                       "--output_path",
                                                       dir + "/txt",
                                                       "--output_type",
                                                       "TXT"});
                               ASSERT_EQ(result.exit_code, 0) << result.output;
                             }) +
      "/txt";
  return temple;
}

int64_t Count(SqliteConnection* db, const std::string& sql) {
  return db->QueryInt64(sql);
}

TEST(ColmapInterop, ReadsEveryTableOfAStockDatabase) {
  BAYON_REQUIRE_DATA("temple-ring");
  const StockTemple fixture = StockTempleFixture();
  const std::string db_path = fixture.database;
  const auto before = testing::HashTree(db_path);
  Database db(db_path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.schema(), DatabaseSchema::kColmap38);
  SqliteConnection sql(db_path, SqliteConnection::Mode::kReadOnly);

  EXPECT_EQ(db.NumCameras(), Count(&sql, "SELECT count(*) FROM cameras"));
  // One camera for the ring (compare_colmap runs COLMAP with
  // --ImageReader.single_camera 1).
  EXPECT_EQ(db.ReadAllCameras().size(), 1u);
  const std::vector<DatabaseImage> images = db.ReadAllImages();
  ASSERT_EQ(images.size(), 16u);
  int64_t num_keypoints = 0, num_descriptors = 0;
  for (const DatabaseImage& image : images) {
    const FeatureKeypoints keypoints = db.ReadKeypoints(image.image_id);
    EXPECT_EQ(keypoints.cols(), 6);
    num_keypoints += keypoints.rows();
    num_descriptors += db.ReadDescriptors(image.image_id).rows();
  }
  EXPECT_EQ(num_keypoints, Count(&sql, "SELECT sum(rows) FROM keypoints"));
  EXPECT_EQ(num_descriptors, Count(&sql, "SELECT sum(rows) FROM descriptors"));
  int64_t num_matches = 0;
  for (const auto& [pair_id, matches] : db.ReadAllMatches()) {
    num_matches += matches.rows();
  }
  EXPECT_EQ(num_matches, Count(&sql, "SELECT sum(rows) FROM matches"));
  int64_t num_inliers = 0, num_with_f = 0;
  for (const auto& [pair_id, geometry] : db.ReadAllTwoViewGeometries()) {
    num_inliers += geometry.inlier_matches.rows();
    num_with_f += geometry.F.has_value();
  }
  EXPECT_EQ(num_inliers,
            Count(&sql, "SELECT sum(rows) FROM two_view_geometries"));
  EXPECT_EQ(num_with_f,
            Count(&sql,
                  "SELECT count(*) FROM two_view_geometries "
                  "WHERE F IS NOT NULL"));
  EXPECT_GT(num_with_f, 10);
  EXPECT_EQ(testing::HashTree(db_path), before);
}

TEST(ColmapInterop, RewritesAStockDatabaseRowByRowAndBlobByBlob) {
  BAYON_REQUIRE_DATA("temple-ring");
  const StockTemple fixture = StockTempleFixture();
  const std::string dir = testing::TempDir("interop_rewrite");
  const std::string copy = dir + "/copy.db";
  {
    Database src(fixture.database, Database::Mode::kReadOnly);
    Database dst(copy, Database::Mode::kCreate);
    auto transaction = dst.BeginTransaction();
    for (const Camera& camera : src.ReadAllCameras())
      dst.WriteCamera(camera, true);
    for (const DatabaseImage& image : src.ReadAllImages()) {
      dst.WriteImage(image, true);
      dst.WriteKeypoints(image.image_id, src.ReadKeypoints(image.image_id));
      dst.WriteDescriptors(image.image_id, src.ReadDescriptors(image.image_id));
    }
    // Canonical order in, canonical order out: no swapping on either side.
    for (const auto& [pair_id, matches] : src.ReadAllMatches()) {
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      dst.WriteMatches(id1, id2, matches);
    }
    for (const auto& [pair_id, geometry] : src.ReadAllTwoViewGeometries()) {
      const auto [id1, id2] = ImageIdsFromPairId(pair_id);
      dst.WriteTwoViewGeometry(id1, id2, geometry);
    }
    transaction.Commit();
  }
  SqliteConnection sql(copy, SqliteConnection::Mode::kReadWrite);
  sql.Execute("ATTACH DATABASE '" + fixture.database + "' AS stock");
  for (const char* table : {"cameras",
                            "images",
                            "keypoints",
                            "descriptors",
                            "matches",
                            "two_view_geometries"}) {
    const std::string t = table;
    const int64_t rows = Count(&sql, "SELECT count(*) FROM " + t);
    EXPECT_EQ(rows, Count(&sql, "SELECT count(*) FROM stock." + t)) << t;
    // Rows in one and not the other, compared with every column (blobs by
    // bytes, NULL equal to NULL).
    EXPECT_EQ(Count(&sql,
                    "SELECT count(*) FROM (SELECT * FROM " + t +
                        " EXCEPT SELECT * FROM stock." + t + ")"),
              0)
        << t;
    EXPECT_EQ(Count(&sql,
                    "SELECT count(*) FROM (SELECT * FROM stock." + t +
                        " EXCEPT SELECT * FROM " + t + ")"),
              0)
        << t;
    EXPECT_GT(rows, 0) << t;
  }
  EXPECT_EQ(
      Count(&sql, "SELECT seq FROM sqlite_sequence WHERE name='images'"),
      Count(&sql, "SELECT seq FROM stock.sqlite_sequence WHERE name='images'"));
}

TEST(ColmapInterop, MapperModelsRoundTripByteForByte) {
  BAYON_REQUIRE_DATA("temple-ring");
  const StockTemple fixture = StockTempleFixture();
  const std::string dir = testing::TempDir("interop_models");
  // Binary: COLMAP's mapper output through bayon and back.
  const Scene from_bin = ReadModel(fixture.model);
  fs::create_directories(dir + "/bin");
  WriteModel(from_bin, dir + "/bin", ModelFormat::kBinary);
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(ReadFileToString(dir + "/bin/" + file),
              ReadFileToString(fixture.model + "/" + file))
        << file;
  }
  // Text: COLMAP's model_converter output through bayon and back.
  const Scene from_txt = ReadModel(fixture.txt);
  fs::create_directories(dir + "/txt");
  WriteModel(from_txt, dir + "/txt", ModelFormat::kText);
  for (const char* file : {"cameras.txt", "images.txt", "points3D.txt"}) {
    EXPECT_EQ(ReadFileToString(dir + "/txt/" + file),
              ReadFileToString(fixture.txt + "/" + file))
        << file;
  }
  // The bayon command does the same.
  const testing::CommandResult converted = testing::RunBayon({"model_converter",
                                                              "--input_path",
                                                              fixture.model,
                                                              "--output_path",
                                                              dir + "/cmd_txt",
                                                              "--output_type",
                                                              "TXT"});
  ASSERT_EQ(converted.exit_code, 0) << converted.output;
  fs::create_directories(dir + "/lib_txt");
  WriteModel(from_bin, dir + "/lib_txt", ModelFormat::kText);
  EXPECT_EQ(testing::HashTree(dir + "/cmd_txt"),
            testing::HashTree(dir + "/lib_txt"));
  // COLMAP reads bayon's files, in both formats.
  for (const char* format : {"bin", "txt"}) {
    const testing::CommandResult analyzer =
        testing::RunColmap({"model_analyzer", "--path", dir + "/" + format});
    ASSERT_EQ(analyzer.exit_code, 0) << analyzer.output;
    EXPECT_NE(analyzer.output.find("Registered images: " +
                                   std::to_string(from_bin.images.size())),
              std::string::npos)
        << analyzer.output;
    EXPECT_NE(analyzer.output.find("Points: " +
                                   std::to_string(from_bin.points3D.size())),
              std::string::npos);
  }
  fs::create_directories(dir + "/colmap_bin");
  const testing::CommandResult back = testing::RunColmap({"model_converter",
                                                          "--input_path",
                                                          dir + "/txt",
                                                          "--output_path",
                                                          dir + "/colmap_bin",
                                                          "--output_type",
                                                          "BIN"});
  EXPECT_EQ(back.exit_code, 0) << back.output;
  EXPECT_TRUE(fs::exists(dir + "/colmap_bin/points3D.bin"));
}

// A workspace made only by bayon (synth --scene points) reconstructed by
// stock `colmap mapper`; the result compared with the truth.
TEST(ColmapInterop, StockMapperReconstructsABayonDatabase) {
  const std::string dir = testing::TempDir("interop_mapper");
  const std::string ws = dir + "/ws";
  const testing::CommandResult synth = testing::RunBayon({"synth",
                                                          "--scene",
                                                          "points",
                                                          "--output_path",
                                                          ws,
                                                          "--num_views",
                                                          "16",
                                                          "--keypoint_noise_px",
                                                          "0.3",
                                                          "--seed",
                                                          "7"});
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const auto bayon_db_before = testing::HashTree(ws + "/database.db");
  // COLMAP rewrites user_version and the journal mode: give it a copy.
  testing::CopyTree(ws + "/database.db", dir + "/colmap.db");
  fs::create_directories(dir + "/sparse");
  const testing::CommandResult mapper = testing::RunColmap(
      {"mapper",
       "--database_path",
       dir + "/colmap.db",
       "--image_path",
       ws + "/images",
       "--output_path",
       dir + "/sparse",
       "--Mapper.num_threads",
       "2",
       // bayon hands COLMAP the calibrated camera (the FULL_OPENCV fit of the
       // true one): refining eight distortion terms from the first image
       // pair alone makes COLMAP's initial model drift.
       "--Mapper.ba_refine_extra_params",
       "0"});
  ASSERT_EQ(mapper.exit_code, 0) << mapper.output;
  ASSERT_TRUE(fs::exists(dir + "/sparse/0/images.bin")) << mapper.output;
  EXPECT_FALSE(fs::exists(dir + "/sparse/1")) << "the block split in two";
  const Scene model = ReadModel(dir + "/sparse/0");
  const Scene truth = ReadModel(ws + "/gt/sparse");
  const SparseEvaluation evaluation = EvaluateSparse(model, truth);
  EXPECT_EQ(evaluation.num_registered, 16);
  // Better than 0.1 % of the ring radius (the mean camera distance).
  EXPECT_LT(evaluation.center_max_relative, 1e-3)
      << "centre RMS " << evaluation.center_rms << " of "
      << evaluation.mean_camera_distance;
  // 0.3 px noise on tracks of 4.7 images: about 0.03 deg (noise-free: 3e-4).
  EXPECT_LT(evaluation.rotation_max_deg, 0.1);
  EXPECT_EQ(testing::HashTree(ws + "/database.db"), bayon_db_before);

  // The same through `bayon evaluate`, with its JSON report.
  const testing::CommandResult evaluate =
      testing::RunBayon({"evaluate",
                         "--input_path",
                         dir + "/sparse/0",
                         "--ground_truth_path",
                         ws + "/gt/sparse",
                         "--output_path",
                         dir + "/evaluation.json"});
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  EXPECT_TRUE(fs::exists(dir + "/evaluation.json"));

  // COLMAP's image_deleter works on the model made from bayon's database.
  WriteFileAtomically(dir + "/delete.txt", "view_003.png\n");
  fs::create_directories(dir + "/deleted");
  const testing::CommandResult deleter =
      testing::RunColmap({"image_deleter",
                          "--input_path",
                          dir + "/sparse/0",
                          "--output_path",
                          dir + "/deleted",
                          "--image_names_path",
                          dir + "/delete.txt"});
  ASSERT_EQ(deleter.exit_code, 0) << deleter.output;
  EXPECT_EQ(ReadModel(dir + "/deleted").images.size(), 15u);
}

TEST(ColmapInterop, DatabaseCleanerKeepsBayonTablesConsistent) {
  const std::string dir = testing::TempDir("interop_cleaner");
  const std::string ws = dir + "/ws";
  ASSERT_EQ(
      testing::RunBayon({"synth", "--output_path", ws, "--num_points", "300"})
          .exit_code,
      0);
  for (const char* type : {"matches", "features", "images", "all"}) {
    const std::string copy = dir + "/" + type + ".db";
    testing::CopyTree(ws + "/database.db", copy);
    const testing::CommandResult cleaner = testing::RunColmap(
        {"database_cleaner", "--database_path", copy, "--type", type});
    ASSERT_EQ(cleaner.exit_code, 0) << type << ": " << cleaner.output;
    Database db(copy, Database::Mode::kReadOnly);
    SqliteConnection* sql = db.connection();
    // No bayon row without its COLMAP row, and none lost while it exists.
    EXPECT_EQ(sql->QueryInt64("SELECT count(*) FROM bayon_interior WHERE "
                              "image_id NOT IN (SELECT image_id FROM images)"),
              0)
        << type;
    EXPECT_EQ(sql->QueryInt64("SELECT count(*) FROM bayon_interior"),
              sql->QueryInt64("SELECT count(*) FROM images"))
        << type;
    EXPECT_EQ(
        sql->QueryInt64("SELECT count(*) FROM bayon_calibration WHERE "
                        "camera_id NOT IN (SELECT camera_id FROM cameras)"),
        0)
        << type;
    SqliteStatement integrity(sql, "PRAGMA integrity_check");
    ASSERT_TRUE(integrity.Step());
    EXPECT_EQ(integrity.ColumnText(0), "ok") << type;
  }
}

}  // namespace
}  // namespace bayon

namespace bayon {
namespace {

// `bayon features --detector sift` writes keypoints and descriptors that
// stock COLMAP's matcher reads as its own, and `bayon match` matches them
// as COLMAP does (ratio test 0.8, angle 0.7, mutual best in both
// directions): the same matches, pair by pair, up to rounding.
TEST(ColmapInterop, StockMatcherAndBayonMatchBayonSiftAlike) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = testing::TempDir("interop_sift");
  const std::string images = testing::DataPath("temple-ring");
  const std::string db = dir + "/bayon.db";
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{
           {"import", "--image_path", images, "--database_path", db},
           {"features",
            "--database_path",
            db,
            "--image_path",
            images,
            "--detector",
            "sift"}}) {
    const testing::CommandResult result = testing::RunBayon(args);
    ASSERT_EQ(result.exit_code, 0) << result.output;
  }
  testing::CopyTree(db, dir + "/colmap.db");
  const testing::CommandResult colmap =
      testing::RunColmap({"exhaustive_matcher",
                          "--database_path",
                          dir + "/colmap.db",
                          "--SiftMatching.use_gpu",
                          "0",
                          "--SiftMatching.num_threads",
                          "2"});
  ASSERT_EQ(colmap.exit_code, 0) << colmap.output;
  const testing::CommandResult bayon = testing::RunBayon({"match",
                                                          "--database_path",
                                                          db,
                                                          "--image_path",
                                                          images,
                                                          "--pairing",
                                                          "exhaustive",
                                                          "--min_num_matches",
                                                          "8"});
  ASSERT_EQ(bayon.exit_code, 0) << bayon.output;

  Database theirs(dir + "/colmap.db", Database::Mode::kReadOnly);
  Database ours(db, Database::Mode::kReadOnly);
  const std::vector<DatabaseImage> all = ours.ReadAllImages();
  int64_t num_theirs = 0, num_ours = 0, num_common = 0;
  for (size_t a = 0; a < all.size(); ++a) {
    for (size_t b = a + 1; b < all.size(); ++b) {
      const image_t id1 = all[a].image_id, id2 = all[b].image_id;
      std::set<std::pair<uint32_t, uint32_t>> their_matches;
      if (theirs.ExistsMatches(id1, id2)) {
        const FeatureMatches m = theirs.ReadMatches(id1, id2);
        for (int r = 0; r < m.rows(); ++r)
          their_matches.insert({m(r, 0), m(r, 1)});
      }
      // bayon writes pairs with 8 matches or more; COLMAP writes all.
      if (their_matches.size() < 8) continue;
      num_theirs += their_matches.size();
      if (!ours.ExistsMatches(id1, id2)) continue;
      const FeatureMatches m = ours.ReadMatches(id1, id2);
      num_ours += m.rows();
      for (int r = 0; r < m.rows(); ++r) {
        num_common += their_matches.count({m(r, 0), m(r, 1)});
      }
    }
  }
  std::printf(
      "temple-ring SIFT: COLMAP %lld matches, bayon %lld, %lld common\n",
      static_cast<long long>(num_theirs),
      static_cast<long long>(num_ours),
      static_cast<long long>(num_common));
  ASSERT_GT(num_theirs, 3000);
  EXPECT_GT(num_common, 0.99 * num_theirs);
  EXPECT_GT(num_common, 0.99 * num_ours);
  // COLMAP's geometric verification finds the ring's neighbours.
  EXPECT_GE(theirs.ReadAllTwoViewGeometries().size(), 16u);
}

}  // namespace
}  // namespace bayon
