// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_tie_points.h"

#include "ext/colmap/database.h"
#include "ext/core/errors.h"

#include <sqlite3.h>

#include <algorithm>
#include <map>
#include <optional>
#include <set>

namespace bayon {

const BayonTable kTiePointsTable = {
    "bayon_tie_points",
    "CREATE TABLE IF NOT EXISTS bayon_tie_points ("
    "point_id INTEGER PRIMARY KEY NOT NULL, name TEXT NOT NULL, "
    "source TEXT NOT NULL, num_observations INTEGER NOT NULL)"};

const BayonTable kTieObservationsTable = {
    "bayon_tie_observations",
    "CREATE TABLE IF NOT EXISTS bayon_tie_observations ("
    "point_id INTEGER NOT NULL, image_id INTEGER NOT NULL, "
    "x REAL NOT NULL, y REAL NOT NULL, "
    "var_x REAL NOT NULL, cov_xy REAL NOT NULL, var_y REAL NOT NULL, "
    "sigma0 REAL NOT NULL, correlation REAL NOT NULL, "
    "reference INTEGER NOT NULL, "
    "PRIMARY KEY(point_id, image_id), "
    "FOREIGN KEY(point_id) REFERENCES bayon_tie_points(point_id) "
    "ON DELETE CASCADE, "
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE)"};

void WriteTiePoints(Database* database,
                    const std::vector<TiePointRecord>& points) {
  database->CheckWritable("bayon_tie_points");
  std::set<image_t> images;
  for (const DatabaseImage& image : database->ReadAllImages()) {
    images.insert(image.image_id);
  }
  for (size_t p = 0; p < points.size(); ++p) {
    std::set<image_t> seen;
    for (const TieObservation& observation : points[p].observations) {
      if (!images.count(observation.image_id)) {
        ThrowInputError("tie point ",
                        p + 1,
                        ": observation in image ",
                        observation.image_id,
                        ", which is not in the database");
      }
      if (!seen.insert(observation.image_id).second) {
        ThrowInputError("tie point ",
                        p + 1,
                        ": two observations in image ",
                        observation.image_id);
      }
      if (!observation.xy.allFinite() || !observation.covariance.allFinite()) {
        ThrowInputError("tie point ",
                        p + 1,
                        ": non-finite position or covariance in image ",
                        observation.image_id);
      }
    }
  }
  std::optional<SqliteTransaction> transaction;
  if (sqlite3_get_autocommit(database->connection()->handle()) != 0) {
    transaction.emplace(database->connection());
  }
  EnsureBayonTable(database, kTiePointsTable);
  EnsureBayonTable(database, kTieObservationsTable);
  database->connection()->Execute("DELETE FROM bayon_tie_observations");
  database->connection()->Execute("DELETE FROM bayon_tie_points");
  SqliteStatement insert_point(
      database->connection(),
      "INSERT INTO bayon_tie_points(point_id, name, source, "
      "num_observations) VALUES(?, ?, ?, ?)");
  SqliteStatement insert_observation(
      database->connection(),
      "INSERT INTO bayon_tie_observations(point_id, image_id, x, y, var_x, "
      "cov_xy, var_y, sigma0, correlation, reference) "
      "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (size_t p = 0; p < points.size(); ++p) {
    const TiePointRecord& point = points[p];
    const int64_t point_id = static_cast<int64_t>(p + 1);
    insert_point.Reset();
    insert_point.Bind(1, point_id)
        .Bind(2, point.name)
        .Bind(3, point.source)
        .Bind(4, static_cast<int64_t>(point.observations.size()));
    insert_point.Execute();
    for (const TieObservation& observation : point.observations) {
      insert_observation.Reset();
      insert_observation.Bind(1, point_id)
          .Bind(2, static_cast<int64_t>(observation.image_id))
          .Bind(3, observation.xy.x())
          .Bind(4, observation.xy.y())
          .Bind(5, observation.covariance(0, 0))
          .Bind(6, observation.covariance(0, 1))
          .Bind(7, observation.covariance(1, 1))
          .Bind(8, observation.sigma0)
          .Bind(9, observation.correlation)
          .Bind(10, static_cast<int64_t>(observation.reference));
      insert_observation.Execute();
    }
  }
  if (transaction) transaction->Commit();
}

std::vector<TiePointRecord> ReadTiePoints(Database* database) {
  std::vector<TiePointRecord> points;
  if (!BayonTableExists(database, kTiePointsTable.name) ||
      !BayonTableExists(database, kTieObservationsTable.name)) {
    return points;
  }
  std::map<int64_t, size_t> index;
  SqliteStatement select_points(database->connection(),
                                "SELECT point_id, name, source FROM "
                                "bayon_tie_points ORDER BY point_id");
  while (select_points.Step()) {
    TiePointRecord point;
    point.point_id = select_points.ColumnInt64(0);
    point.name = select_points.ColumnText(1);
    point.source = select_points.ColumnText(2);
    index[point.point_id] = points.size();
    points.push_back(std::move(point));
  }
  SqliteStatement select_observations(
      database->connection(),
      "SELECT point_id, image_id, x, y, var_x, cov_xy, var_y, sigma0, "
      "correlation, reference FROM bayon_tie_observations "
      "ORDER BY point_id, image_id");
  while (select_observations.Step()) {
    const auto it = index.find(select_observations.ColumnInt64(0));
    if (it == index.end()) {
      ThrowInputError(database->path(),
                      ": bayon_tie_observations row of point ",
                      select_observations.ColumnInt64(0),
                      ", which is not in bayon_tie_points");
    }
    TieObservation observation;
    observation.image_id =
        static_cast<image_t>(select_observations.ColumnInt64(1));
    observation.xy = Eigen::Vector2d(select_observations.ColumnDouble(2),
                                     select_observations.ColumnDouble(3));
    observation.covariance << select_observations.ColumnDouble(4),
        select_observations.ColumnDouble(5),
        select_observations.ColumnDouble(5),
        select_observations.ColumnDouble(6);
    observation.sigma0 = select_observations.ColumnDouble(7);
    observation.correlation = select_observations.ColumnDouble(8);
    observation.reference = select_observations.ColumnInt64(9) != 0;
    points[it->second].observations.push_back(observation);
  }
  return points;
}

}  // namespace bayon
