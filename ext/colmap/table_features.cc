// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_features.h"

#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"

#include <glog/logging.h>

#include <cstring>
#include <sstream>

namespace bayon {

const BayonTable kKeypointInterestTable = {
    "bayon_keypoint_interest",
    "CREATE TABLE IF NOT EXISTS bayon_keypoint_interest ("
    "image_id INTEGER PRIMARY KEY NOT NULL, "
    "detector TEXT NOT NULL, window_size INTEGER NOT NULL, "
    "patch_size INTEGER NOT NULL, rows INTEGER NOT NULL, interest BLOB, "
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)"};

void WriteKeypointInterest(Database* database,
                           image_t image_id,
                           const KeypointInterestRecord& record) {
  EnsureBayonTable(database, kKeypointInterestTable);
  SqliteStatement statement(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_keypoint_interest(image_id, detector, "
      "window_size, patch_size, rows, interest) VALUES(?, ?, ?, ?, ?, ?)");
  statement.Bind(1, static_cast<int64_t>(image_id))
      .Bind(2, record.detector)
      .Bind(3, static_cast<int64_t>(record.window_size))
      .Bind(4, static_cast<int64_t>(record.patch_size))
      .Bind(5, static_cast<int64_t>(record.interest.size()))
      .BindBlob(
          6, record.interest.data(), record.interest.size() * sizeof(float));
  statement.Execute();
}

std::optional<KeypointInterestRecord> ReadKeypointInterest(Database* database,
                                                           image_t image_id) {
  if (!BayonTableExists(database, kKeypointInterestTable.name)) {
    return std::nullopt;
  }
  SqliteStatement statement(
      database->connection(),
      "SELECT detector, window_size, patch_size, rows, interest FROM "
      "bayon_keypoint_interest WHERE image_id = ?");
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step()) return std::nullopt;
  KeypointInterestRecord record;
  record.detector = statement.ColumnText(0);
  record.window_size = static_cast<int>(statement.ColumnInt64(1));
  record.patch_size = static_cast<int>(statement.ColumnInt64(2));
  const int64_t rows = statement.ColumnInt64(3);
  // In 64 bits: a forged count must not wrap around to the blob's size.
  if (rows < 0 || rows > INT32_MAX ||
      statement.ColumnBytes(4) != rows * static_cast<int64_t>(sizeof(float))) {
    ThrowInputError(database->path(),
                    ": bayon_keypoint_interest row of image ",
                    image_id,
                    ": blob size does not match ",
                    rows,
                    " rows");
  }
  record.interest.resize(rows);
  if (rows > 0) {
    std::memcpy(record.interest.data(),
                statement.ColumnBlobData(4),
                rows * sizeof(float));
  }
  return record;
}

void DeleteKeypointInterest(Database* database, image_t image_id) {
  if (!BayonTableExists(database, kKeypointInterestTable.name)) return;
  SqliteStatement statement(
      database->connection(),
      "DELETE FROM bayon_keypoint_interest WHERE image_id = ?");
  statement.Bind(1, static_cast<int64_t>(image_id));
  statement.Execute();
}

const BayonTable kKeypointTargetsTable = {
    "bayon_keypoint_targets",
    "CREATE TABLE IF NOT EXISTS bayon_keypoint_targets ("
    "image_id INTEGER PRIMARY KEY NOT NULL, "
    "num_keypoints INTEGER NOT NULL, targets TEXT NOT NULL, "
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)"};

// One line per target: POINT2D_IDX NAME SIGMA_PX.
void WriteKeypointTargets(Database* database,
                          image_t image_id,
                          int num_keypoints,
                          const std::vector<KeypointTarget>& targets) {
  EnsureBayonTable(database, kKeypointTargetsTable);
  std::ostringstream text;
  text.precision(9);
  for (const KeypointTarget& target : targets) {
    CHECK_LT(target.point2D_idx, static_cast<uint32_t>(num_keypoints));
    text << target.point2D_idx << " " << target.name << " " << target.sigma_px
         << "\n";
  }
  SqliteStatement statement(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_keypoint_targets(image_id, "
      "num_keypoints, targets) VALUES(?, ?, ?)");
  statement.Bind(1, static_cast<int64_t>(image_id))
      .Bind(2, static_cast<int64_t>(num_keypoints))
      .Bind(3, text.str());
  statement.Execute();
}

std::vector<KeypointTarget> ReadKeypointTargets(Database* database,
                                                image_t image_id,
                                                int num_keypoints) {
  if (!BayonTableExists(database, kKeypointTargetsTable.name)) return {};
  SqliteStatement statement(database->connection(),
                            "SELECT num_keypoints, targets FROM "
                            "bayon_keypoint_targets WHERE image_id = ?");
  statement.Bind(1, static_cast<int64_t>(image_id));
  if (!statement.Step() || statement.ColumnInt64(0) != num_keypoints) {
    return {};
  }
  std::vector<KeypointTarget> targets;
  std::istringstream lines(statement.ColumnText(1));
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    KeypointTarget target;
    int64_t idx = -1;
    if (!(fields >> idx >> target.name >> target.sigma_px) || idx < 0 ||
        idx >= num_keypoints) {
      ThrowInputError(database->path(),
                      ": bayon_keypoint_targets row of image ",
                      image_id,
                      ": '",
                      line,
                      "' is not a keypoint row, a name and a sigma");
    }
    target.point2D_idx = static_cast<uint32_t>(idx);
    targets.push_back(std::move(target));
  }
  return targets;
}

std::set<uint32_t> KeypointTargetRows(Database* database,
                                      image_t image_id,
                                      int num_keypoints) {
  std::set<uint32_t> rows;
  for (const KeypointTarget& target :
       ReadKeypointTargets(database, image_id, num_keypoints)) {
    rows.insert(target.point2D_idx);
  }
  return rows;
}

void DeleteKeypointTargets(Database* database, image_t image_id) {
  if (!BayonTableExists(database, kKeypointTargetsTable.name)) return;
  SqliteStatement statement(
      database->connection(),
      "DELETE FROM bayon_keypoint_targets WHERE image_id = ?");
  statement.Bind(1, static_cast<int64_t>(image_id));
  statement.Execute();
}

}  // namespace bayon

namespace bayon {

int DeleteKeypointDependents(Database* database, image_t image_id) {
  SqliteConnection* connection = database->connection();
  const int64_t id = image_id;
  // pair_id = kMaxNumImages * min(id1, id2) + max(id1, id2) (types.h).
  const std::string pair_of_image =
      " WHERE pair_id % " + std::to_string(kMaxNumImages) +
      " = ?1 OR pair_id / " + std::to_string(kMaxNumImages) + " = ?1";
  int num_pairs = 0;
  {
    SqliteStatement statement(connection,
                              "DELETE FROM matches" + pair_of_image);
    statement.Bind(1, id);
    statement.Execute();
    num_pairs = connection->Changes();
  }
  {
    SqliteStatement statement(
        connection, "DELETE FROM two_view_geometries" + pair_of_image);
    statement.Bind(1, id);
    statement.Execute();
  }
  {
    SqliteStatement statement(connection,
                              "DELETE FROM descriptors WHERE image_id = ?");
    statement.Bind(1, id);
    statement.Execute();
  }
  for (const std::string& table : BayonPairTables(database)) {
    SqliteStatement statement(
        connection,
        "DELETE FROM " + table + " WHERE image_id1 = ?1 OR image_id2 = ?1");
    statement.Bind(1, id);
    statement.Execute();
  }
  return num_pairs;
}

}  // namespace bayon
