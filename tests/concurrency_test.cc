// SPDX-License-Identifier: BSD-3-Clause
//
// Two programs on one COLMAP database: two bayon processes, bayon beside stock
// COLMAP, and bayon against a lock held longer than it will wait. The later
// writer waits for the earlier one's transaction (busy timeout) or stops with
// one line naming the database; the database is never damaged.
#include "ext/colmap/database.h"
#include "ext/colmap/sqlite.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "tests/testing.h"

namespace bayon {
namespace {

namespace fs = std::filesystem;

// The first `num_images` photographs of temple-ring, imported into a fresh
// database; returns the test folder (images/ and database.db inside).
std::string TempleSubset(const std::string& name, int num_images) {
  const std::string dir = testing::TempDir(name);
  fs::create_directories(dir + "/images");
  std::vector<fs::path> images;
  for (const auto& entry :
       fs::directory_iterator(testing::DataPath("temple-ring"))) {
    if (entry.path().extension() == ".png") images.push_back(entry.path());
  }
  std::sort(images.begin(), images.end());
  for (int i = 0; i < num_images && i < static_cast<int>(images.size()); ++i) {
    fs::copy_file(images[i], dir + "/images/" + images[i].filename().string());
  }
  const testing::CommandResult import = testing::RunBayon({"import",
                                                           "--image_path",
                                                           dir + "/images",
                                                           "--database_path",
                                                           dir + "/database.db",
                                                           "--single_camera",
                                                           "1"});
  EXPECT_EQ(import.exit_code, 0) << import.output;
  return dir;
}

std::string IntegrityCheck(const std::string& database_path) {
  SqliteConnection connection(database_path, SqliteConnection::Mode::kReadOnly);
  SqliteStatement check(&connection, "PRAGMA integrity_check");
  return check.Step() ? check.ColumnText(0) : "no answer";
}

// Number of keypoints per image name.
std::map<std::string, int> KeypointCounts(const std::string& database_path) {
  Database database(database_path, Database::Mode::kReadOnly);
  std::map<std::string, int> counts;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    counts[image.name] =
        static_cast<int>(database.ReadKeypoints(image.image_id).rows());
  }
  return counts;
}

// Every stored match names keypoints that exist: a reader never saw a
// half-written image.
void ExpectMatchesReferToKeypoints(const std::string& database_path) {
  Database database(database_path, Database::Mode::kReadOnly);
  std::map<image_t, uint32_t> num_keypoints;
  for (const DatabaseImage& image : database.ReadAllImages()) {
    num_keypoints[image.image_id] =
        static_cast<uint32_t>(database.ReadKeypoints(image.image_id).rows());
  }
  const auto all_matches = database.ReadAllMatches();
  EXPECT_FALSE(all_matches.empty());
  for (const auto& [pair_id, matches] : all_matches) {
    const auto [image_id1, image_id2] = ImageIdsFromPairId(pair_id);
    if (matches.rows() == 0) continue;
    EXPECT_LT(matches.col(0).maxCoeff(), num_keypoints[image_id1]);
    EXPECT_LT(matches.col(1).maxCoeff(), num_keypoints[image_id2]);
  }
}

std::vector<std::string> FeaturesCommand(const std::string& dir) {
  return {"features",
          "--database_path",
          dir + "/database.db",
          "--image_path",
          dir + "/images",
          "--overwrite",
          "1",
          "--num_threads",
          "1"};
}

TEST(Concurrency, TwoBayonWritersOnOneDatabaseBothFinish) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleSubset("concurrency_two_bayon", 6);
  const std::string reference = dir + "/reference.db";
  fs::copy_file(dir + "/database.db", reference);
  std::vector<std::string> alone = FeaturesCommand(dir);
  alone[2] = reference;
  ASSERT_EQ(testing::RunBayon(alone).exit_code, 0);

  // Both replace every image's keypoints, one image per transaction, at the
  // same time: each waits for the other's commits.
  auto first = std::async(std::launch::async, [&] {
    return testing::RunBayon(FeaturesCommand(dir));
  });
  const testing::CommandResult second = testing::RunBayon(FeaturesCommand(dir));
  const testing::CommandResult first_result = first.get();
  EXPECT_EQ(first_result.exit_code, 0) << first_result.output;
  EXPECT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(IntegrityCheck(dir + "/database.db"), "ok");
  EXPECT_EQ(KeypointCounts(dir + "/database.db"), KeypointCounts(reference));
}

TEST(Concurrency, BayonMatchBesideColmapFeatureExtractor) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleSubset("concurrency_colmap", 6);
  ASSERT_EQ(testing::RunBayon(FeaturesCommand(dir)).exit_code, 0);
  // COLMAP adds images of its own (a second folder) and their SIFT features
  // while bayon matches the first six; COLMAP's connection does not wait, so
  // bayon keeps its write transactions short enough for it.
  const std::string more = dir + "/more";
  fs::create_directories(more);
  for (const auto& entry : fs::directory_iterator(dir + "/images")) {
    fs::copy_file(entry.path(),
                  more + "/copy_" + entry.path().filename().string());
  }
  auto colmap = std::async(std::launch::async, [&] {
    return testing::RunColmap({"feature_extractor",
                               "--database_path",
                               dir + "/database.db",
                               "--image_path",
                               more,
                               "--SiftExtraction.use_gpu",
                               "0",
                               "--SiftExtraction.num_threads",
                               "1"});
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const testing::CommandResult match = testing::RunBayon({"match",
                                                          "--database_path",
                                                          dir + "/database.db",
                                                          "--image_path",
                                                          dir + "/images",
                                                          "--pairing",
                                                          "exhaustive",
                                                          "--num_threads",
                                                          "1"});
  const testing::CommandResult colmap_result = colmap.get();
  if (colmap_result.exit_code != 0) {
    // COLMAP's connection has no busy timeout: a write of its that meets
    // one of bayon's short transactions fails at once (about 1 run in 8
    // here). That is COLMAP's answer to a lock, and the file stays whole.
    EXPECT_NE(colmap_result.output.find("locked"), std::string::npos)
        << colmap_result.output;
  }
  if (match.exit_code != 0) {
    // COLMAP registered one of its images (from a folder bayon was not
    // given) before bayon read the image list: bayon stops with one line,
    // which is also a right answer. Which comes first is the schedulers'
    // choice (the sanitizer build starts more slowly).
    EXPECT_EQ(match.exit_code, 2) << match.output;
    EXPECT_NE(match.LastLine().find("missing on disk"), std::string::npos)
        << match.output;
  } else {
    ExpectMatchesReferToKeypoints(dir + "/database.db");
  }
  EXPECT_EQ(IntegrityCheck(dir + "/database.db"), "ok");
  if (colmap_result.exit_code == 0) {
    EXPECT_EQ(KeypointCounts(dir + "/database.db").size(), 12u);
  }
}

TEST(Concurrency, LockHeldLongerThanTheTimeoutGivesOneLineAndChangesNothing) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleSubset("concurrency_locked", 3);
  const auto before = testing::HashTree(dir + "/database.db");
  SqliteConnection holder(dir + "/database.db",
                          SqliteConnection::Mode::kReadWrite);
  holder.Execute("BEGIN EXCLUSIVE");
  setenv("BAYON_DATABASE_TIMEOUT", "1", 1);
  const testing::CommandResult locked = testing::RunBayon(FeaturesCommand(dir));
  unsetenv("BAYON_DATABASE_TIMEOUT");
  holder.Execute("COMMIT");
  EXPECT_EQ(locked.exit_code, 2) << locked.output;
  EXPECT_NE(locked.LastLine().find(dir + "/database.db"), std::string::npos)
      << locked.LastLine();
  EXPECT_NE(locked.LastLine().find("held the database for longer than 1 s"),
            std::string::npos)
      << locked.LastLine();
  EXPECT_EQ(testing::HashTree(dir + "/database.db"), before);
  EXPECT_EQ(IntegrityCheck(dir + "/database.db"), "ok");
  // Once the other program is done, the same command works.
  EXPECT_EQ(testing::RunBayon(FeaturesCommand(dir)).exit_code, 0);
}

TEST(Concurrency, BadTimeoutValueIsRefused) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = TempleSubset("concurrency_bad_timeout", 1);
  setenv("BAYON_DATABASE_TIMEOUT", "soon", 1);
  const testing::CommandResult result = testing::RunBayon(FeaturesCommand(dir));
  unsetenv("BAYON_DATABASE_TIMEOUT");
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("BAYON_DATABASE_TIMEOUT='soon'"),
            std::string::npos)
      << result.LastLine();
}

}  // namespace
}  // namespace bayon
