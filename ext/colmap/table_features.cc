// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_features.h"

#include "ext/colmap/table_matches.h"
#include "ext/core/errors.h"

#include <cstring>

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
