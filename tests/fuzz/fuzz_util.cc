// SPDX-License-Identifier: BSD-3-Clause
#include "tests/fuzz/fuzz_util.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_disparity.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_matches.h"
#include "ext/colmap/table_relative.h"
#include "ext/colmap/table_tie_points.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>
#include <utility>

namespace fs = std::filesystem;

namespace bayon::fuzz {
namespace {

struct Scratch {
  Scratch() {
    const char* tmp = std::getenv("TMPDIR");
    path = (fs::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") /
            ("bayon-fuzz-" + std::to_string(getpid())))
               .string();
    fs::create_directories(path);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string path;
};

}  // namespace

const std::string& ScratchDir() {
  static const Scratch scratch;
  return scratch.path;
}

std::string FreshPath(const std::string& name) {
  const std::string path = (fs::path(ScratchDir()) / name).string();
  std::error_code ec;
  fs::remove_all(path, ec);
  return path;
}

void WriteFile(const std::string& path, const std::string& data) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(data.data(), static_cast<std::streamsize>(data.size()));
  if (!file) {
    // The harness's own failure, not the reader's: stop loudly.
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

std::vector<std::string> SplitInput(const uint8_t* data,
                                    size_t size,
                                    int num_parts) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t split_size = std::strlen(kSplit);
  std::vector<std::string> parts;
  size_t start = 0;
  while (static_cast<int>(parts.size()) + 1 < num_parts) {
    const size_t end = input.find(kSplit, start);
    if (end == std::string::npos) break;
    parts.push_back(input.substr(start, end - start));
    start = end + split_size;
  }
  parts.push_back(input.substr(std::min(start, input.size())));
  parts.resize(num_parts);
  return parts;
}

uint8_t InputCursor::Byte() { return pos_ < size_ ? data_[pos_++] : 0; }

uint16_t InputCursor::Uint16() {
  const uint16_t high = Byte();
  return static_cast<uint16_t>(high << 8 | Byte());
}

int64_t InputCursor::Int64() {
  uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value = value << 8 | Byte();
  return static_cast<int64_t>(value);
}

double InputCursor::Double() {
  const int64_t bits = Int64();
  double value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

std::string InputCursor::Bytes(size_t count) {
  count = std::min(count, remaining());
  std::string bytes(reinterpret_cast<const char*>(data_ + pos_), count);
  pos_ += count;
  return bytes;
}

void ReadWholeDatabase(Database* database) {
  Expect([&] {
    database->UserVersion();
    database->NumCameras();
    database->NumImages();
    database->NumKeypointRows();
    database->NumKeypoints();
    database->NumDescriptors();
    database->NumMatchedPairs();
    database->NumMatches();
    database->NumVerifiedPairs();
    database->NumInlierMatches();
  });
  Expect([&] { CheckBayonSchema(database); });
  Expect([&] {
    for (const Camera& camera : database->ReadAllCameras()) {
      if (database->ExistsCamera(camera.camera_id)) {
        database->ReadCamera(camera.camera_id);
      }
      ReadCalibration(database, camera.camera_id);
    }
  });
  std::vector<DatabaseImage> images;
  Expect([&] { images = database->ReadAllImages(); });
  for (const DatabaseImage& image : images) {
    Expect([&] {
      database->ReadImage(image.image_id);
      database->ReadImageWithName(image.name);
    });
    Expect([&] {
      if (database->ExistsKeypoints(image.image_id)) {
        database->ReadKeypoints(image.image_id);
      }
    });
    Expect([&] {
      if (database->ExistsDescriptors(image.image_id)) {
        database->ReadDescriptors(image.image_id);
      }
    });
    Expect([&] { ReadKeypointInterest(database, image.image_id); });
    Expect([&] { ReadInterior(database, image.image_id); });
  }
  Expect([&] { ReadImageCameras(database, images); });
  Expect([&] { database->ReadMatchedPairIds(); });
  // Every pair some table has a row of, read by every pair reader in both
  // image orders.
  std::set<std::pair<image_t, image_t>> pairs;
  Expect([&] {
    for (const auto& row : database->ReadAllMatches()) {
      pairs.insert(ImageIdsFromPairId(row.first));
    }
  });
  Expect([&] {
    for (const auto& row : database->ReadAllTwoViewGeometries()) {
      pairs.insert(ImageIdsFromPairId(row.first));
    }
  });
  Expect([&] {
    for (const std::string& table : BayonPairTables(database)) {
      SqliteStatement statement(
          database->connection(),
          "SELECT image_id1, image_id2 FROM " + table + " LIMIT 100");
      while (statement.Step()) {
        pairs.emplace(static_cast<image_t>(statement.ColumnInt64(0)),
                      static_cast<image_t>(statement.ColumnInt64(1)));
      }
    }
  });
  for (const auto& [first, second] : pairs) {
    // Named copies: a lambda may not capture a structured binding (C++17).
    const image_t image_id1 = first;
    const image_t image_id2 = second;
    for (int swap = 0; swap < 2; ++swap) {
      const image_t a = swap == 0 ? image_id1 : image_id2;
      const image_t b = swap == 0 ? image_id2 : image_id1;
      Expect([&] { database->ReadMatches(a, b); });
      Expect([&] { database->ReadTwoViewGeometry(a, b); });
    }
    if (image_id1 < image_id2) {
      Expect([&] { ReadMatchRecord(database, image_id1, image_id2); });
    }
    Expect([&] { ReadRelativeOrientation(database, image_id1, image_id2); });
    Expect([&] { ReadDisparitySurface(database, image_id1, image_id2); });
  }
  Expect([&] { ReadAllCalibrations(database); });
  Expect([&] { ReadAllInteriors(database); });
  Expect([&] { ReadAllRelativeOrientations(database); });
  Expect([&] { ReadAllDisparitySurfaces(database); });
  Expect([&] { ReadTiePoints(database); });
  Expect([&] { BayonPairTables(database); });
}

}  // namespace bayon::fuzz
