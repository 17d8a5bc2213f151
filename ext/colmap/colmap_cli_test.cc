// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/colmap_cli.h"

#include "ext/colmap/database.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace bayon {
namespace {

TEST(ColmapCli, ReportsVersionAndChecksExpectedOutputs) {
  EXPECT_NE(ColmapVersion().find("COLMAP 3."), std::string::npos);
  const std::string dir = testing::TempDir("colmap_cli");
  Database(dir + "/db.db", Database::Mode::kCreate);
  // The mapper on a database without images exits 0 but writes nothing: the
  // wrapper must call that a failure.
  std::filesystem::create_directories(dir + "/sparse");
  std::filesystem::create_directories(dir + "/images");
  ColmapCall call;
  call.command = "mapper";
  call.options = {{"--database_path", dir + "/db.db"},
                  {"--image_path", dir + "/images"},
                  {"--output_path", dir + "/sparse"}};
  call.expected_outputs = {dir + "/sparse/0/cameras.bin"};
  ColmapRunOptions options;
  options.log_path = dir + "/colmap.log";
  const ColmapResult result = RunColmap(call, options);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("mapper"), std::string::npos) << result.message;
  EXPECT_NE(result.command_line.find("--database_path"), std::string::npos);
  EXPECT_NE(ReadFileToString(dir + "/colmap.log").find("$ colmap mapper"),
            std::string::npos);
}

TEST(ColmapCli, MissingBinaryIsAnInputError) {
  ColmapRunOptions options;
  options.executable = "/nonexistent/colmap";
  ColmapCall call;
  call.command = "help";
  EXPECT_THROW(RunColmap(call, options), InputError);
}

TEST(ColmapCli, CopyKeepsTheOriginalUntouched) {
  const std::string dir = testing::TempDir("colmap_cli_copy");
  {
    Database db(dir + "/db.db", Database::Mode::kCreate);
    db.WriteCamera(Camera::Create(CameraModelId::kPinhole, 100, 64, 48));
  }
  const auto before = testing::HashTree(dir + "/db.db");
  CopyDatabaseForColmap(dir + "/db.db", dir + "/copy.db");
  ColmapCall call;
  call.command = "database_cleaner";
  call.options = {{"--database_path", dir + "/copy.db"}, {"--type", "all"}};
  ASSERT_TRUE(RunColmap(call).success);
  EXPECT_EQ(testing::HashTree(dir + "/db.db"), before);
  EXPECT_EQ(Database(dir + "/copy.db", Database::Mode::kReadOnly).NumCameras(),
            0);
  EXPECT_EQ(Database(dir + "/db.db", Database::Mode::kReadOnly).NumCameras(),
            1);
}

// The mapper's model with the most registered images, read from the count
// at the head of images.bin; folders without a whole binary model ignored.
TEST(ColmapCli, LargestModelCountsRegisteredImages) {
  const std::string dir = testing::TempDir("colmap_largest_model");
  auto write_model =
      [&](const std::string& name, uint64_t num_images, bool complete) {
        const std::string folder = dir + "/" + name;
        std::filesystem::create_directories(folder);
        std::ofstream images(folder + "/images.bin", std::ios::binary);
        images.write(reinterpret_cast<const char*>(&num_images),
                     sizeof(num_images));
        std::ofstream(folder + "/cameras.bin");
        if (complete) std::ofstream(folder + "/points3D.bin");
      };
  EXPECT_EQ(LargestModel(dir), "");
  write_model("0", 3, true);
  write_model("1", 5, true);
  write_model("2", 9, false);
  write_model("3", 5, true);
  EXPECT_EQ(LargestModel(dir), dir + "/1");
}

}  // namespace
}  // namespace bayon
