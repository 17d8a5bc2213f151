// SPDX-License-Identifier: BSD-3-Clause
//
// The limits a user's project meets: a 100-megapixel photograph, a database of
// 1000 images, a disk that fills up, a workspace the user may not write, and
// paths with spaces and non-ASCII characters. Each gets a correct result or
// one clear line with exit code 2; never a crash, a damaged database or a
// half-written output under its final name; memory stays bounded (the peak
// resident memory of each command is measured and printed).
#include "ext/colmap/database.h"
#include "ext/colmap/sqlite.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <sys/mount.h>
#include <sys/statvfs.h>
#include <unistd.h>
#include <vector>

#include "tests/testing.h"

namespace bayon {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;

// A bayon command with its wall time and peak resident memory (from
// /usr/bin/time; -1 where that program is absent).
struct MeasuredRun {
  CommandResult result;
  double seconds = 0;
  double peak_mb = -1;
};

MeasuredRun RunBayonMeasured(const std::vector<std::string>& args) {
  static const bool have_time = fs::exists("/usr/bin/time");
  const std::string peak_file =
      (fs::temp_directory_path() / ("bayon-limits-peak" + TempSuffix()))
          .string();
  std::vector<std::string> argv;
  if (have_time) argv = {"/usr/bin/time", "-f", "%M", "-o", peak_file};
  argv.push_back(testing::BayonBin());
  argv.insert(argv.end(), args.begin(), args.end());
  MeasuredRun run;
  const auto start = std::chrono::steady_clock::now();
  run.result = testing::RunCommand(argv);
  run.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  // The last line is the peak in kB (a note on a nonzero exit precedes it).
  std::ifstream peak(peak_file);
  std::string line, last;
  while (std::getline(peak, line)) {
    if (!line.empty()) last = line;
  }
  if (!last.empty() && last.find_first_not_of("0123456789") == last.npos) {
    run.peak_mb = std::stod(last) / 1024.0;
  }
  std::error_code ec;
  fs::remove(peak_file, ec);
  std::cout << "bayon " << args[0] << ": exit " << run.result.exit_code << ", "
            << run.seconds << " s, peak " << run.peak_mb << " MB" << std::endl;
  return run;
}

std::string IntegrityCheck(const std::string& database_path) {
  SqliteConnection connection(database_path, SqliteConnection::Mode::kReadOnly);
  SqliteStatement check(&connection, "PRAGMA integrity_check");
  return check.Step() ? check.ColumnText(0) : "no answer";
}

// A refusal as the tools promise it: exit code 2 and a last line
// "bayon <command>: error: ..." that contains `expected`.
void ExpectClearError(const CommandResult& result,
                      const std::string& command,
                      const std::string& expected) {
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_EQ(result.LastLine().rfind("bayon " + command + ": error: ", 0), 0u)
      << result.output;
  EXPECT_NE(result.LastLine().find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.LastLine();
}

// Smooth random texture (Moravec finds corners, correlation finds matches):
// uniform noise of `width / cell` x `height / cell`, enlarged bicubically.
cv::Mat Texture(int width, int height, int cell, uint64_t seed) {
  cv::Mat coarse(height / cell + 1, width / cell + 1, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
  cv::Mat image;
  cv::resize(coarse,
             image,
             cv::Size(coarse.cols * cell, coarse.rows * cell),
             0,
             0,
             cv::INTER_CUBIC);
  return image(cv::Rect(0, 0, width, height)).clone();
}

// `count` photographs of one textured strip, each shifted by `step` px
// against the previous one: <folder>/<prefix>NNNN.png.
void WriteShiftedImages(const std::string& folder,
                        const std::string& prefix,
                        int count,
                        int width,
                        int height,
                        int step) {
  fs::create_directories(folder);
  const cv::Mat strip =
      Texture(width + step * (count - 1), height, 4, /*seed=*/7);
  for (int i = 0; i < count; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%04d.png", i);
    cv::imwrite(folder + "/" + prefix + name,
                strip(cv::Rect(i * step, 0, width, height)));
  }
}

// `bayon import` (one camera) and `bayon features` into `db`.
void ImportAndExtract(const std::string& images, const std::string& db) {
  const CommandResult import = testing::RunBayon({"import",
                                                  "--image_path",
                                                  images,
                                                  "--database_path",
                                                  db,
                                                  "--single_camera",
                                                  "1"});
  ASSERT_EQ(import.exit_code, 0) << import.output;
  const CommandResult features = testing::RunBayon(
      {"features", "--image_path", images, "--database_path", db});
  ASSERT_EQ(features.exit_code, 0) << features.output;
}

std::vector<std::string> FilesUnder(const std::string& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(folder, ec);
       it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    names.push_back(fs::relative(it->path(), folder).string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// No "<name>.tmp-..." file or folder left anywhere under `folder`.
void ExpectNoTemporaries(const std::string& folder) {
  for (const std::string& name : FilesUnder(folder)) {
    EXPECT_EQ(name.find(".tmp-"), std::string::npos)
        << "temporary left behind: " << folder << "/" << name;
  }
}

// ---------------------------------------------------------------------------
// A 100-megapixel photograph among normal ones: imported and its features
// extracted at full resolution, in memory proportional to one image.

TEST(LimitsTest, HundredMegapixelImage) {
  const std::string dir = testing::TempDir("limits_large_image");
  const std::string images = dir + "/images";
  WriteShiftedImages(images, "small", 2, 640, 480, 40);
  const int width = 12000, height = 8400;
  // Coarse texture compresses well: about 10 MB of JPEG.
  ASSERT_TRUE(cv::imwrite(images + "/large.jpg",
                          Texture(width, height, 16, 3),
                          {cv::IMWRITE_JPEG_QUALITY, 80}));
  const std::string db = dir + "/database.db";

  const MeasuredRun import = RunBayonMeasured(
      {"import", "--image_path", images, "--database_path", db});
  ASSERT_EQ(import.result.exit_code, 0) << import.result.output;
  // Each image is decoded once to check it (one 8-bit image in memory at a
  // time: 215 MB measured, about 105 MB of which any bayon command takes).
  if (import.peak_mb > 0) {
    EXPECT_LT(import.peak_mb, 400) << "import";
  }

  const MeasuredRun features = RunBayonMeasured({"features",
                                                 "--image_path",
                                                 images,
                                                 "--database_path",
                                                 db,
                                                 "--num_threads",
                                                 "1"});
  ASSERT_EQ(features.result.exit_code, 0) << features.result.output;
  // About 13 bytes per pixel of the largest image (its float grey values and
  // the operator's planes), per image in flight: 1.3 GB measured.
  if (features.peak_mb > 0) {
    EXPECT_LT(features.peak_mb, 2000) << "features";
  }

  Database database(db, Database::Mode::kReadOnly);
  const std::optional<DatabaseImage> large =
      database.ReadImageWithName("large.jpg");
  ASSERT_TRUE(large.has_value());
  const FeatureKeypoints keypoints = database.ReadKeypoints(large->image_id);
  EXPECT_GT(keypoints.rows(), 1000);
  for (int i = 0; i < keypoints.rows(); ++i) {
    ASSERT_TRUE(keypoints(i, 0) > 0 && keypoints(i, 0) < width &&
                keypoints(i, 1) > 0 && keypoints(i, 1) < height)
        << "keypoint " << i << " at " << keypoints(i, 0) << ", "
        << keypoints(i, 1);
  }
  // Points spread over the whole frame, not one corner of it.
  EXPECT_GT(keypoints.col(0).maxCoeff(), 0.9 * width);
  EXPECT_GT(keypoints.col(1).maxCoeff(), 0.9 * height);
}

// ---------------------------------------------------------------------------
// 1000 photographs: every stage that reads the whole database works in
// bounded time and memory.

TEST(LimitsTest, ThousandImages) {
  const std::string dir = testing::TempDir("limits_1000_images");
  const std::string images = dir + "/images";
  const int count = 1000;
  WriteShiftedImages(images, "", count, 160, 120, 2);
  const std::string db = dir + "/database.db";

  const MeasuredRun import = RunBayonMeasured({"import",
                                               "--image_path",
                                               images,
                                               "--database_path",
                                               db,
                                               "--single_camera",
                                               "1",
                                               "--camera_model",
                                               "PINHOLE",
                                               "--camera_params",
                                               "200,200,80,60"});
  ASSERT_EQ(import.result.exit_code, 0) << import.result.output;
  const MeasuredRun features = RunBayonMeasured(
      {"features", "--image_path", images, "--database_path", db});
  ASSERT_EQ(features.result.exit_code, 0) << features.result.output;
  // Pair selection over all 1000 images; every tenth neighbouring pair is
  // matched, so the test stays short.
  const std::string pairs = dir + "/pairs.txt";
  {
    std::ofstream list(pairs);
    for (int i = 0; i + 1 < count; i += 10) {
      char line[32];
      std::snprintf(line, sizeof(line), "%04d.png %04d.png\n", i, i + 1);
      list << line;
    }
  }
  const MeasuredRun match = RunBayonMeasured({"match",
                                              "--image_path",
                                              images,
                                              "--database_path",
                                              db,
                                              "--pairing",
                                              "list",
                                              "--pair_list_path",
                                              pairs});
  ASSERT_EQ(match.result.exit_code, 0) << match.result.output;
  // The shifted crops of one plane leave the relative orientations
  // undetermined; what matters here is that every stage reads the whole
  // database and answers (oriented or not) in bounded time and memory.
  // With no pair oriented, relative says so in one line (exit code 2).
  const MeasuredRun relative =
      RunBayonMeasured({"relative", "--database_path", db});
  if (relative.result.exit_code != 0) {
    EXPECT_EQ(relative.result.exit_code, 2) << relative.result.output;
    EXPECT_NE(relative.result.LastLine().find("could be oriented"),
              std::string::npos)
        << relative.result.output;
  }
  const MeasuredRun strip = RunBayonMeasured(
      {"strip", "--database_path", db, "--output_path", dir + "/sparse"});
  EXPECT_GE(strip.result.exit_code, 0);
  EXPECT_LE(strip.result.exit_code, 2) << strip.result.output;
  if (strip.result.exit_code != 0) {
    EXPECT_EQ(strip.result.LastLine().rfind("bayon strip: "), 0u)
        << strip.result.output;
  }

  for (const MeasuredRun* run :
       {&import, &features, &match, &relative, &strip}) {
    EXPECT_LT(run->seconds, 60) << run->result.output;
    if (run->peak_mb > 0) {
      EXPECT_LT(run->peak_mb, 600) << run->result.output;
    }
  }
  EXPECT_EQ(IntegrityCheck(db), "ok");
  Database database(db, Database::Mode::kReadOnly);
  EXPECT_EQ(database.NumImages(), count);
  EXPECT_EQ(database.NumKeypointRows(), count);
}

// ---------------------------------------------------------------------------
// A full disk: a small tmpfs as the workspace. Writers stop with one line
// naming the disk; the database keeps its earlier contents and passes the
// integrity check; no output appears under its final name; no temporaries.

class LimitsFullDiskTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = testing::TempDir("limits_full_disk");
    disk_ = root_ + "/disk";
    fs::create_directories(disk_);
    if (::mount("tmpfs", disk_.c_str(), "tmpfs", 0, "size=4m") != 0) {
      BAYON_SKIP("cannot mount a tmpfs on "
                 << disk_ << ": " << std::strerror(errno) << " (needs root)");
    }
    mounted_ = true;
  }
  void TearDown() override {
    if (mounted_) ::umount2(disk_.c_str(), MNT_DETACH);
  }

  // Fills the disk with a file until `leave_bytes` remain free.
  void FillDisk(uint64_t leave_bytes) {
    struct statvfs stats;
    ASSERT_EQ(::statvfs(disk_.c_str(), &stats), 0);
    const uint64_t free = uint64_t(stats.f_bavail) * stats.f_frsize;
    ASSERT_GT(free, leave_bytes);
    std::ofstream filler(disk_ + "/filler", std::ios::binary);
    const std::string block(4096, 'x');
    for (uint64_t n = 0; n + block.size() <= free - leave_bytes;
         n += block.size()) {
      filler.write(block.data(), block.size());
    }
  }

  std::string root_, disk_;
  bool mounted_ = false;
};

TEST_F(LimitsFullDiskTest, WritersStopCleanly) {
  const std::string images = root_ + "/images";
  WriteShiftedImages(images, "", 8, 640, 480, 40);
  const std::string db = disk_ + "/database.db";
  ASSERT_NO_FATAL_FAILURE(ImportAndExtract(images, db));
  // Outputs too large for what is left: a sparse model, a dense cloud.
  const std::string synth = root_ + "/synth";
  ASSERT_EQ(testing::RunBayon({"synth",
                               "--scene",
                               "points",
                               "--output_path",
                               synth,
                               "--num_views",
                               "30",
                               "--num_points",
                               "3000"})
                .exit_code,
            0);
  // An earlier model that a failed conversion must leave as it was.
  const std::string small = root_ + "/small";
  ASSERT_EQ(testing::RunBayon({"synth",
                               "--scene",
                               "points",
                               "--output_path",
                               small,
                               "--num_views",
                               "4",
                               "--num_points",
                               "50",
                               "--seed",
                               "2"})
                .exit_code,
            0);
  const std::string old_model = disk_ + "/sparse/old";
  ASSERT_EQ(testing::RunBayon({"model_converter",
                               "--input_path",
                               small + "/gt/sparse",
                               "--output_path",
                               old_model,
                               "--output_type",
                               "TXT"})
                .exit_code,
            0);
  // (Its camera differs from the new model's in a comment only.)
  std::ofstream(old_model + "/cameras.txt", std::ios::app)
      << "# the earlier model\n";
  const auto old_hashes = testing::HashTree(old_model);
  FillDisk(32 * 1024);
  const uint64_t db_hash = FileHash(db);
  const std::vector<std::string> before = FilesUnder(disk_);

  // The database: more keypoints than fit.
  const CommandResult features = testing::RunBayon({"features",
                                                    "--image_path",
                                                    images,
                                                    "--database_path",
                                                    db,
                                                    "--overwrite",
                                                    "1",
                                                    "--patch_size",
                                                    "3"});
  ExpectClearError(features, "features", "full");
  EXPECT_EQ(FileHash(db), db_hash) << "the database changed";
  EXPECT_EQ(IntegrityCheck(db), "ok");

  // A new database.
  const CommandResult import = testing::RunBayon(
      {"import", "--image_path", images, "--database_path", disk_ + "/new.db"});
  ExpectClearError(import, "import", disk_ + "/new.db: ");
  EXPECT_NE(import.LastLine().find("full"), std::string::npos) << import.output;

  // A sparse model, binary and text.
  for (const char* type : {"BIN", "TXT"}) {
    const CommandResult model = testing::RunBayon({"model_converter",
                                                   "--input_path",
                                                   synth + "/gt/sparse",
                                                   "--output_path",
                                                   disk_ + "/sparse/" + type,
                                                   "--output_type",
                                                   type});
    ExpectClearError(model, "model_converter", "No space left on device");
  }

  // Replacing the earlier model: it stays whole.
  const CommandResult replace = testing::RunBayon({"model_converter",
                                                   "--input_path",
                                                   synth + "/gt/sparse",
                                                   "--output_path",
                                                   old_model,
                                                   "--output_type",
                                                   "TXT",
                                                   "--overwrite",
                                                   "1"});
  ExpectClearError(replace, "model_converter", "No space left on device");
  EXPECT_EQ(testing::HashTree(old_model), old_hashes)
      << "a failed conversion changed the earlier model";

  // A dense cloud (PLY).
  const CommandResult cloud = testing::RunBayon({"synth_cloud",
                                                 "--output_path",
                                                 disk_ + "/points.ply",
                                                 "--num_points",
                                                 "50000"});
  ExpectClearError(cloud, "synth_cloud", "No space left on device");

  // Nothing new on the disk but the logs: no half-written output, no
  // temporaries, no journal.
  const auto without_logs = [](const std::vector<std::string>& names) {
    std::vector<std::string> kept;
    for (const std::string& name : names) {
      if (name.rfind("logs", 0) != 0) kept.push_back(name);
    }
    return kept;
  };
  EXPECT_EQ(without_logs(FilesUnder(disk_)), without_logs(before));
  ExpectNoTemporaries(disk_);
  EXPECT_EQ(IntegrityCheck(db), "ok");
  EXPECT_EQ(FileHash(db), db_hash);
}

// ---------------------------------------------------------------------------
// A workspace the user may not write (run as another user: root writes
// anywhere). One clear line before any work; nothing changed.

TEST(LimitsTest, ReadOnlyWorkspace) {
  std::vector<std::string> as_other_user;
  if (::geteuid() == 0) {
    if (!fs::exists("/usr/bin/setpriv")) {
      BAYON_SKIP(
          "running as root without setpriv: cannot drop the "
          "rights to write");
    }
    as_other_user = {
        "/usr/bin/setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"};
  }
  const std::string dir = testing::TempDir("limits_read_only");
  const std::string images = dir + "/images";
  const std::string ws = dir + "/ws";
  WriteShiftedImages(images, "", 4, 640, 480, 40);
  fs::create_directories(ws);
  const std::string db = ws + "/database.db";
  ASSERT_NO_FATAL_FAILURE(ImportAndExtract(images, db));
  const std::string synth = dir + "/synth";
  ASSERT_EQ(testing::RunBayon({"synth",
                               "--scene",
                               "points",
                               "--output_path",
                               synth,
                               "--num_views",
                               "6",
                               "--num_points",
                               "200"})
                .exit_code,
            0);
  fs::remove_all(ws + "/logs");
  // Readable by everyone, writable by the owner only.
  for (const std::string& path : {dir, images, ws, synth}) {
    fs::permissions(path,
                    fs::perms::owner_all | fs::perms::group_read |
                        fs::perms::group_exec | fs::perms::others_read |
                        fs::perms::others_exec);
  }
  if (::geteuid() != 0) {
    fs::permissions(ws, fs::perms::owner_write, fs::perm_options::remove);
    fs::permissions(db, fs::perms::owner_write, fs::perm_options::remove);
  }
  const auto run = [&](const std::vector<std::string>& args) {
    std::vector<std::string> argv = as_other_user;
    argv.push_back(testing::BayonBin());
    argv.insert(argv.end(), args.begin(), args.end());
    return testing::RunCommand(argv);
  };
  const auto before = testing::HashTree(ws);

  // A stage that logs into the workspace: its log folder cannot be made.
  ExpectClearError(run({"features",
                        "--image_path",
                        images,
                        "--database_path",
                        db,
                        "--overwrite",
                        "1"}),
                   "features",
                   "cannot create the log folder");

  // Logging elsewhere, the database itself is refused before any work.
  const std::string log = dir + "/logs";
  fs::create_directories(log);
  fs::permissions(log, fs::perms::all);
  for (const std::string command : {"features", "match"}) {
    std::vector<std::string> args = {command,
                                     "--database_path",
                                     db,
                                     "--overwrite",
                                     "1",
                                     "--log_path",
                                     log + "/" + command + ".log"};
    args.insert(args.end(), {"--image_path", images});
    const CommandResult result = run(args);
    ExpectClearError(result, command, db + ": cannot write");
    EXPECT_EQ(result.output.find("Extracting"), std::string::npos)
        << "work was done before the refusal: " << result.output;
    EXPECT_EQ(result.output.find("Matching image pairs"), std::string::npos)
        << "work was done before the refusal: " << result.output;
  }

  // A new database in the workspace: refused before the images are read.
  const CommandResult import = run({"import",
                                    "--image_path",
                                    images,
                                    "--database_path",
                                    ws + "/new.db",
                                    "--log_path",
                                    log + "/import.log"});
  ExpectClearError(import, "import", ws + "/new.db: cannot write");

  // A model written into the workspace.
  ExpectClearError(run({"model_converter",
                        "--input_path",
                        synth + "/gt/sparse",
                        "--output_path",
                        ws + "/sparse",
                        "--output_type",
                        "TXT"}),
                   "model_converter",
                   ws + "/sparse");

  EXPECT_EQ(testing::HashTree(ws), before);
  EXPECT_FALSE(fs::exists(ws + "/new.db"));
  EXPECT_FALSE(fs::exists(ws + "/sparse"));
  ExpectNoTemporaries(ws);
  EXPECT_EQ(IntegrityCheck(db), "ok");
}

// ---------------------------------------------------------------------------
// Paths with spaces and non-ASCII characters: the same photographs give the
// same keypoints, matches, orientations and model as under a plain path.

TEST(LimitsTest, SpacesAndNonAsciiInPaths) {
  const std::string root = testing::TempDir("limits_paths");
  const std::string plain = root + "/plain";
  const std::string odd = root + "/Bayon tower/Prasat Bayon \u2014 \u6771";
  const std::string odd_name = "face \u00e9 \u6771 ";
  std::map<std::string, std::string> summaries;
  for (const std::string& ws : {plain, odd}) {
    const std::string images = ws + "/images \u00fc";
    WriteShiftedImages(images, odd_name, 4, 480, 360, 50);
    const std::string db = ws + "/data base \u00e9.db";
    const std::vector<std::vector<std::string>> stages = {
        {"import",
         "--image_path",
         images,
         "--database_path",
         db,
         "--single_camera",
         "1",
         "--camera_model",
         "PINHOLE",
         "--camera_params",
         "600,600,240,180"},
        {"features", "--image_path", images, "--database_path", db},
        {"match",
         "--image_path",
         images,
         "--database_path",
         db,
         "--pairing",
         "sequential"},
        {"model_converter",
         "--input_path",
         ws + "/missing model \u6771",
         "--output_path",
         ws + "/out",
         "--output_type",
         "TXT"},
    };
    for (const auto& args : stages) {
      const CommandResult result = testing::RunBayon(args);
      if (args[0] == "model_converter") {
        // A missing input is named as given, characters intact.
        ExpectClearError(result, args[0], ws + "/missing model \u6771");
        continue;
      }
      ASSERT_EQ(result.exit_code, 0) << result.output;
      // The summary names the database as given, with its characters.
      EXPECT_NE(result.output.find(db), std::string::npos) << result.output;
    }
    EXPECT_TRUE(fs::exists(ws + "/logs/match.log"));
    Database database(db, Database::Mode::kReadOnly);
    std::string summary;
    for (const DatabaseImage& image : database.ReadAllImages()) {
      const FeatureKeypoints keypoints = database.ReadKeypoints(image.image_id);
      summary += image.name + ": " + std::to_string(keypoints.rows()) + " " +
                 std::to_string(keypoints.sum()) + "\n";
    }
    for (const auto& [pair_id, matches] : database.ReadAllMatches()) {
      summary += std::to_string(pair_id) + ": " +
                 std::to_string(matches.rows()) + "\n";
    }
    EXPECT_GT(database.NumMatches(), 100) << summary;
    summaries[ws] = summary;
  }
  EXPECT_EQ(summaries[plain], summaries[odd]);
}

}  // namespace
}  // namespace bayon
