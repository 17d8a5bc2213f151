// SPDX-License-Identifier: BSD-3-Clause
//
// Bad input to the bayon commands: one clear line naming what is wrong, exit
// code 2, and every input file unchanged.
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// Runs bayon, expects exit code 2 with a one-line message that contains
// `expected`, and checks that `inputs` are unchanged.
void ExpectRefused(const std::vector<std::string>& args,
                   const std::string& expected,
                   const std::vector<std::string>& inputs) {
  std::vector<std::map<std::string, uint64_t>> before;
  for (const std::string& input : inputs)
    before.push_back(testing::HashTree(input));
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  const std::string line = result.LastLine();
  EXPECT_NE(line.find("error: "), std::string::npos) << result.output;
  EXPECT_NE(line.find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.output;
  for (size_t i = 0; i < inputs.size(); ++i) {
    EXPECT_EQ(testing::HashTree(inputs[i]), before[i])
        << inputs[i] << " changed";
  }
}

std::string MakeImages(const std::string& dir) {
  fs::create_directories(dir);
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar(10, 120, 200));
  std::vector<uchar> png, jpg;
  cv::imencode(".png", image, png);
  cv::imencode(".jpg", image, jpg);
  WriteFileAtomically(dir + "/a.png", std::string(png.begin(), png.end()));
  WriteFileAtomically(dir + "/b.jpg", std::string(jpg.begin(), jpg.end()));
  return dir;
}

TEST(BadInput, MissingOrEmptyImageFolder) {
  const std::string dir = testing::TempDir("bad_folder");
  ExpectRefused({"import",
                 "--image_path",
                 dir + "/nope",
                 "--database_path",
                 dir + "/db.db"},
                "nope",
                {});
  fs::create_directories(dir + "/empty");
  ExpectRefused({"import",
                 "--image_path",
                 dir + "/empty",
                 "--database_path",
                 dir + "/db.db"},
                "no images found",
                {dir + "/empty"});
  EXPECT_FALSE(fs::exists(dir + "/db.db"));
}

TEST(BadInput, TruncatedJpegAndTextNamedPng) {
  const std::string dir = testing::TempDir("bad_images");
  const std::string images = MakeImages(dir + "/images");
  const std::string jpg = ReadFileToString(images + "/b.jpg");
  WriteFileAtomically(images + "/c.jpg", jpg.substr(0, jpg.size() - 200));
  ExpectRefused(
      {"import", "--image_path", images, "--database_path", dir + "/db.db"},
      "c.jpg: truncated JPEG",
      {images});
  fs::remove(images + "/c.jpg");
  WriteFileAtomically(images + "/d.png", "just some text\n");
  ExpectRefused(
      {"import", "--image_path", images, "--database_path", dir + "/db.db"},
      "d.png",
      {images});
  EXPECT_FALSE(fs::exists(dir + "/db.db"));
  EXPECT_TRUE(ListFilesRecursive(dir).size() == 3u);
}

TEST(BadInput, DatabaseThatIsNotSqlite) {
  const std::string dir = testing::TempDir("bad_database");
  const std::string images = MakeImages(dir + "/images");
  WriteFileAtomically(dir + "/db.db", "name,value\nthis,is a csv file\n");
  ExpectRefused(
      {"import", "--image_path", images, "--database_path", dir + "/db.db"},
      "not an SQLite database",
      {images, dir + "/db.db"});
}

TEST(BadInput, NewerSchemaDatabases) {
  const std::string dir = testing::TempDir("bad_schema");
  const std::string images = MakeImages(dir + "/images");
  {
    Database db(dir + "/newer_bayon.db", Database::Mode::kCreate);
    WriteBayonMeta(&db, "schema_version", "42");
  }
  ExpectRefused({"import",
                 "--image_path",
                 images,
                 "--database_path",
                 dir + "/newer_bayon.db"},
                "newer than this bayon",
                {dir + "/newer_bayon.db"});
  {
    SqliteConnection c(dir + "/colmap4.db", SqliteConnection::Mode::kCreate);
    c.Execute(
        "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY, model INTEGER, "
        "width INTEGER, height INTEGER, params BLOB, prior_focal_length "
        "INTEGER);"
        "CREATE TABLE images (image_id INTEGER PRIMARY KEY, name TEXT, "
        "camera_id "
        "INTEGER);"
        "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY, rows INTEGER, "
        "cols INTEGER, data BLOB);"
        "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY, rows INTEGER, "
        "cols INTEGER, data BLOB, type INTEGER);"
        "CREATE TABLE matches (pair_id INTEGER PRIMARY KEY, rows INTEGER, cols "
        "INTEGER, data BLOB);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY, rows "
        "INTEGER, cols INTEGER, data BLOB, config INTEGER, F BLOB, E BLOB, H "
        "BLOB, qvec BLOB, tvec BLOB);"
        "CREATE TABLE frames (frame_id INTEGER PRIMARY KEY, rig_id INTEGER);"
        "PRAGMA user_version = 4010100;");
  }
  ExpectRefused({"import",
                 "--image_path",
                 images,
                 "--database_path",
                 dir + "/colmap4.db"},
                "COLMAP 4.x",
                {dir + "/colmap4.db"});
}

class BadModel : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::TempDir(
        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    ASSERT_EQ(
        testing::RunBayon(
            {"synth", "--output_path", dir_ + "/ws", "--num_points", "100"})
            .exit_code,
        0);
    model_ = dir_ + "/ws/gt/sparse";
  }
  std::string dir_;
  std::string model_;
};

TEST_F(BadModel, TruncatedImagesBin) {
  ASSERT_EQ(testing::RunBayon({"model_converter",
                               "--input_path",
                               model_,
                               "--output_path",
                               dir_ + "/bin",
                               "--output_type",
                               "BIN"})
                .exit_code,
            0);
  const std::string data = ReadFileToString(dir_ + "/bin/images.bin");
  WriteFileAtomically(dir_ + "/bin/images.bin",
                      data.substr(0, data.size() / 3));
  ExpectRefused({"model_converter",
                 "--input_path",
                 dir_ + "/bin",
                 "--output_path",
                 dir_ + "/out",
                 "--output_type",
                 "TXT"},
                "images.bin: ",
                {dir_ + "/bin"});
  EXPECT_FALSE(fs::exists(dir_ + "/out/cameras.txt"));
}

TEST_F(BadModel, CamerasTxtWithWrongParameterCount) {
  std::string cameras = ReadFileToString(model_ + "/cameras.txt");
  cameras =
      cameras.substr(0, cameras.rfind(' ')) + "\n";  // one parameter short
  WriteFileAtomically(model_ + "/cameras.txt", cameras);
  ExpectRefused({"model_converter",
                 "--input_path",
                 model_,
                 "--output_path",
                 dir_ + "/out",
                 "--output_type",
                 "BIN"},
                "takes 12 parameters",
                {model_});
}

TEST_F(BadModel, OutputThatExistsWithoutOverwrite) {
  ExpectRefused({"synth", "--output_path", dir_ + "/ws"},
                "exists already",
                {dir_ + "/ws"});
  WriteFileAtomically(dir_ + "/points.ply", "keep me");
  ExpectRefused({"model_converter",
                 "--input_path",
                 model_,
                 "--output_path",
                 dir_ + "/points.ply",
                 "--output_type",
                 "PLY"},
                "exists already",
                {dir_ + "/points.ply", model_});
  const testing::CommandResult overwrite =
      testing::RunBayon({"model_converter",
                         "--input_path",
                         model_,
                         "--output_path",
                         dir_ + "/points.ply",
                         "--output_type",
                         "PLY",
                         "--overwrite",
                         "1"});
  EXPECT_EQ(overwrite.exit_code, 0) << overwrite.output;
}

TEST(BadInput, ConfigFileWithUnknownKey) {
  const std::string dir = testing::TempDir("bad_config");
  const std::string images = MakeImages(dir + "/images");
  WriteFileAtomically(dir + "/bad.ini",
                      "single_camera = 1\nsingel_camera = 1\n");
  ExpectRefused({"import",
                 "--config",
                 dir + "/bad.ini",
                 "--image_path",
                 images,
                 "--database_path",
                 dir + "/db.db"},
                "singel_camera",
                {images, dir + "/bad.ini"});
  EXPECT_FALSE(fs::exists(dir + "/db.db"));
  // The example config of the repository is accepted.
  const testing::CommandResult ok =
      testing::RunBayon({"import",
                         "--config",
                         testing::ConfigPath("import.ini"),
                         "--image_path",
                         images,
                         "--database_path",
                         dir + "/db.db"});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  Database db(dir + "/db.db", Database::Mode::kReadOnly);
  EXPECT_EQ(db.NumCameras(), 1);  // single_camera = 1 from the file
  EXPECT_EQ(db.NumImages(), 2);
}

// import --camera_params: a calibrated camera in COLMAP's parameter order;
// the wrong number of values, or a model bayon calibrates itself, is refused
// before anything is written.
TEST(BadInput, CameraParamsOfTheWrongCount) {
  const std::string dir = testing::TempDir("bad_camera_params");
  const std::string images = MakeImages(dir + "/images");
  const std::vector<std::string> import = {"import",
                                           "--image_path",
                                           images,
                                           "--database_path",
                                           dir + "/db.db",
                                           "--single_camera",
                                           "1",
                                           "--camera_model"};
  std::vector<std::string> args = import;
  args.insert(args.end(), {"PINHOLE", "--camera_params", "70,70,32"});
  ExpectRefused(args, "3 values, but PINHOLE has 4 parameters", {images});
  args = import;
  args.insert(args.end(), {"BROWN_BEYER", "--camera_params", "35,0,0"});
  ExpectRefused(args, "BROWN_BEYER", {images});
  EXPECT_FALSE(fs::exists(dir + "/db.db"));
  args = import;
  args.insert(args.end(), {"PINHOLE", "--camera_params", "70.5,71.25,31,23"});
  const testing::CommandResult ok = testing::RunBayon(args);
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  Database db(dir + "/db.db", Database::Mode::kReadOnly);
  const Camera camera = db.ReadCamera(1);
  EXPECT_EQ(camera.params, std::vector<double>({70.5, 71.25, 31, 23}));
  EXPECT_TRUE(camera.has_prior_focal_length);
}

TEST(BadInput, UnknownFlagAndUnknownCommand) {
  const testing::CommandResult flag = testing::RunBayon({"import",
                                                         "--image_path",
                                                         ".",
                                                         "--database_path",
                                                         "x.db",
                                                         "--no_such_flag",
                                                         "1"});
  EXPECT_EQ(flag.exit_code, 2);
  EXPECT_NE(flag.LastLine().find("no_such_flag"), std::string::npos)
      << flag.output;
  EXPECT_EQ(testing::RunBayon({"no_such_command"}).exit_code, 2);
}

// bayon features / match / relative / disparity (issue 4): a database
// without images, images missing on disk.
TEST(BadInput, OrientationChainWithoutImages) {
  const std::string dir = testing::TempDir("bad_orientation");
  const std::string images = MakeImages(dir + "/images");
  { Database db(dir + "/empty.db", Database::Mode::kCreate); }
  ExpectRefused({"features",
                 "--database_path",
                 dir + "/empty.db",
                 "--image_path",
                 images},
                "has no images",
                {dir + "/empty.db", images});
  ASSERT_EQ(
      testing::RunBayon(
          {"import", "--image_path", images, "--database_path", dir + "/db.db"})
          .exit_code,
      0);
  ExpectRefused({"relative", "--database_path", dir + "/db.db"},
                "no matched image pairs",
                {dir + "/db.db"});
  ExpectRefused(
      {"match", "--database_path", dir + "/db.db", "--image_path", images},
      "no image has keypoints",
      {dir + "/db.db"});
  fs::rename(images + "/b.jpg", dir + "/b.jpg");
  ExpectRefused(
      {"features", "--database_path", dir + "/db.db", "--image_path", images},
      "b.jpg: listed in",
      {dir + "/db.db", images});
}

}  // namespace
}  // namespace bayon
