// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_matches.h"

#include "ext/core/errors.h"

#include <glog/logging.h>

#include <algorithm>
#include <cstring>

namespace bayon {

const BayonTable kMatchesTable = {
    "bayon_matches",
    "CREATE TABLE IF NOT EXISTS bayon_matches ("
    "pair_id INTEGER PRIMARY KEY NOT NULL, "
    "image_id1 INTEGER NOT NULL, image_id2 INTEGER NOT NULL, "
    "rotation_deg INTEGER NOT NULL, mapping_found INTEGER NOT NULL, "
    "affine BLOB NOT NULL, num_candidates INTEGER NOT NULL, "
    "seconds REAL NOT NULL, rows INTEGER NOT NULL, points BLOB, "
    "FOREIGN KEY(image_id1) REFERENCES images(image_id) ON DELETE CASCADE, "
    "FOREIGN KEY(image_id2) REFERENCES images(image_id) ON DELETE CASCADE)"};

namespace {

// Per row: x1, y1, x2, y2, ncc, sigma_px as float32; rows written before
// sigma_px was kept have the first five (the blob's size tells them apart).
constexpr int kFloatsPerRow = 6;
constexpr int kFloatsPerOldRow = 5;

}  // namespace

void WriteMatchRecord(Database* database,
                      image_t image_id1,
                      image_t image_id2,
                      const MatchRecord& record) {
  if (image_id1 >= image_id2) {
    ThrowInputError("bayon_matches: pair (",
                    image_id1,
                    ", ",
                    image_id2,
                    ") is not in canonical order");
  }
  EnsureBayonTable(database, kMatchesTable);
  const size_t rows = record.xy1.size();
  CHECK_EQ(record.xy2.size(), rows);
  CHECK_EQ(record.ncc.size(), rows);
  CHECK(record.sigma_px.empty() || record.sigma_px.size() == rows);
  std::vector<float> points(rows * kFloatsPerRow);
  for (size_t i = 0; i < rows; ++i) {
    float* row = &points[i * kFloatsPerRow];
    row[0] = record.xy1[i].x();
    row[1] = record.xy1[i].y();
    row[2] = record.xy2[i].x();
    row[3] = record.xy2[i].y();
    row[4] = record.ncc[i];
    row[5] = record.sigma_px.empty() ? 0.f : record.sigma_px[i];
  }
  double affine[6];
  Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> affine_map(affine);
  affine_map = record.affine;
  SqliteStatement statement(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_matches(pair_id, image_id1, image_id2, "
      "rotation_deg, mapping_found, affine, num_candidates, seconds, rows, "
      "points) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  statement
      .Bind(1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)))
      .Bind(2, static_cast<int64_t>(image_id1))
      .Bind(3, static_cast<int64_t>(image_id2))
      .Bind(4, static_cast<int64_t>(record.rotation_deg))
      .Bind(5, static_cast<int64_t>(record.mapping_found))
      .BindBlob(6, affine, sizeof(affine))
      .Bind(7, static_cast<int64_t>(record.num_candidates))
      .Bind(8, record.seconds)
      .Bind(9, static_cast<int64_t>(rows))
      .BindBlob(10, points.data(), points.size() * sizeof(float));
  statement.Execute();
}

std::optional<MatchRecord> ReadMatchRecord(Database* database,
                                           image_t image_id1,
                                           image_t image_id2) {
  if (!BayonTableExists(database, kMatchesTable.name)) return std::nullopt;
  if (image_id1 >= image_id2) return std::nullopt;
  SqliteStatement statement(
      database->connection(),
      "SELECT rotation_deg, mapping_found, affine, num_candidates, seconds, "
      "rows, points FROM bayon_matches WHERE pair_id = ?");
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  if (!statement.Step()) return std::nullopt;
  MatchRecord record;
  record.rotation_deg = static_cast<int>(statement.ColumnInt64(0));
  record.mapping_found = statement.ColumnInt64(1) != 0;
  if (statement.ColumnBytes(2) != 6 * sizeof(double)) {
    ThrowInputError(database->path(),
                    ": bayon_matches row of pair (",
                    image_id1,
                    ", ",
                    image_id2,
                    "): affine blob of ",
                    statement.ColumnBytes(2),
                    " bytes, expected 48");
  }
  double affine[6];
  std::memcpy(affine, statement.ColumnBlobData(2), sizeof(affine));
  record.affine =
      Eigen::Map<const Eigen::Matrix<double, 2, 3, Eigen::RowMajor>>(affine);
  record.num_candidates = static_cast<int>(statement.ColumnInt64(3));
  record.seconds = statement.ColumnDouble(4);
  const int64_t rows = statement.ColumnInt64(5);
  const int64_t bytes = statement.ColumnBytes(6);
  // A forged count would overflow the products below.
  const bool rows_ok = rows >= 0 && rows <= INT32_MAX;
  const int per_row =
      rows_ok && rows > 0 &&
              bytes ==
                  static_cast<int64_t>(rows * kFloatsPerOldRow * sizeof(float))
          ? kFloatsPerOldRow
          : kFloatsPerRow;
  if (!rows_ok ||
      bytes != static_cast<int64_t>(rows * per_row * sizeof(float))) {
    ThrowInputError(database->path(),
                    ": bayon_matches row of pair (",
                    image_id1,
                    ", ",
                    image_id2,
                    "): points blob does not hold ",
                    rows,
                    " rows");
  }
  std::vector<float> points(rows * per_row);
  if (rows > 0) {
    std::memcpy(points.data(),
                statement.ColumnBlobData(6),
                points.size() * sizeof(float));
  }
  for (int64_t i = 0; i < rows; ++i) {
    const float* row = &points[i * per_row];
    record.xy1.emplace_back(row[0], row[1]);
    record.xy2.emplace_back(row[2], row[3]);
    record.ncc.push_back(row[4]);
    if (per_row == kFloatsPerRow) record.sigma_px.push_back(row[5]);
  }
  return record;
}

void DeleteMatchRecord(Database* database,
                       image_t image_id1,
                       image_t image_id2) {
  if (!BayonTableExists(database, kMatchesTable.name)) return;
  SqliteStatement statement(database->connection(),
                            "DELETE FROM bayon_matches WHERE pair_id = ?");
  statement.Bind(
      1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  statement.Execute();
}

std::vector<std::string> BayonPairTables(Database* database) {
  SqliteConnection* connection = database->connection();
  std::vector<std::string> names, pair_tables;
  {
    SqliteStatement tables(connection,
                           "SELECT name FROM sqlite_master WHERE type='table' "
                           "AND name LIKE 'bayon\\_%' ESCAPE '\\' ORDER BY "
                           "name");
    while (tables.Step()) names.push_back(tables.ColumnText(0));
  }
  for (const std::string& name : names) {
    const std::vector<std::string> columns = connection->TableColumns(name);
    const auto has = [&](const char* column) {
      return std::find(columns.begin(), columns.end(), column) != columns.end();
    };
    if (has("image_id1") && has("image_id2")) pair_tables.push_back(name);
  }
  return pair_tables;
}

void DeletePairResults(Database* database,
                       image_t image_id1,
                       image_t image_id2) {
  database->DeleteMatches(image_id1, image_id2);
  database->DeleteTwoViewGeometry(image_id1, image_id2);
  for (const std::string& table : BayonPairTables(database)) {
    SqliteStatement statement(database->connection(),
                              "DELETE FROM " + table +
                                  " WHERE (image_id1 = ?1 AND image_id2 = ?2) "
                                  "OR (image_id1 = ?2 AND image_id2 = ?1)");
    statement.Bind(1, static_cast<int64_t>(image_id1))
        .Bind(2, static_cast<int64_t>(image_id2));
    statement.Execute();
  }
}

}  // namespace bayon
