// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_disparity.h"

#include "ext/core/errors.h"

#include <cstring>

namespace bayon {

const BayonTable kDisparitySurfacesTable = {
    "bayon_disparity_surfaces",
    "CREATE TABLE IF NOT EXISTS bayon_disparity_surfaces ("
    "image_id1 INTEGER NOT NULL, image_id2 INTEGER NOT NULL, "
    "pair_id INTEGER NOT NULL, "
    "success INTEGER NOT NULL, reason TEXT NOT NULL, "
    "assume_zero_distortion INTEGER NOT NULL, qvec BLOB, tvec BLOB, "
    "origin_x REAL, origin_y REAL, cell_size_px REAL, "
    "cols INTEGER NOT NULL, rows INTEGER NOT NULL, "
    "inverse_depth BLOB, sigma_px BLOB, support_points BLOB, "
    "support_inverse_depth BLOB, hull BLOB, "
    "spacing_px REAL, smoothness REAL, band_k REAL, support_radius_px REAL, "
    "growth_px_per_px REAL, gradient_factor REAL, depth_tolerance REAL, "
    "range_neighbors INTEGER, "
    "num_points INTEGER NOT NULL, num_used INTEGER NOT NULL, "
    "num_blunders INTEGER NOT NULL, "
    "robust_sigma_px REAL, cv_sigma_px REAL, cv_coverage REAL, "
    "median_band_px REAL, median_range_px REAL, seconds REAL NOT NULL, "
    "PRIMARY KEY(image_id1, image_id2), "
    "FOREIGN KEY(image_id1) REFERENCES images(image_id) ON DELETE CASCADE, "
    "FOREIGN KEY(image_id2) REFERENCES images(image_id) ON DELETE CASCADE)"};

namespace {

// Columns in the order of the SELECT below and of the INSERT.
constexpr const char* kColumns =
    "image_id1, image_id2, pair_id, success, reason, assume_zero_distortion, "
    "qvec, tvec, origin_x, origin_y, cell_size_px, cols, rows, "
    "inverse_depth, sigma_px, support_points, hull, spacing_px, smoothness, "
    "band_k, support_radius_px, growth_px_per_px, gradient_factor, "
    "depth_tolerance, num_points, num_used, num_blunders, robust_sigma_px, "
    "cv_sigma_px, cv_coverage, median_band_px, median_range_px, seconds, "
    "support_inverse_depth, range_neighbors";
constexpr int kNumColumns = 35;

[[noreturn]] void ThrowBadRow(const SqliteStatement& s,
                              const std::string& db,
                              const std::string& what) {
  ThrowInputError(db,
                  ": bayon_disparity_surfaces row (",
                  s.ColumnInt64(0),
                  ", ",
                  s.ColumnInt64(1),
                  "): ",
                  what);
}

// A blob of exactly `count` doubles.
std::vector<double> DoubleBlob(const SqliteStatement& s,
                               int col,
                               size_t count,
                               const std::string& db,
                               const char* name) {
  if (s.IsNull(col) ||
      s.ColumnBytes(col) != static_cast<int>(count * sizeof(double))) {
    ThrowBadRow(s,
                db,
                StrCat(name,
                       " has ",
                       s.ColumnBytes(col),
                       " bytes, expected ",
                       count * sizeof(double)));
  }
  std::vector<double> values(count);
  if (count > 0) {
    std::memcpy(values.data(), s.ColumnBlobData(col), count * sizeof(double));
  }
  return values;
}

// A blob of 2D points (x, y doubles); empty for NULL.
std::vector<Eigen::Vector2d> PointBlob(const SqliteStatement& s,
                                       int col,
                                       const std::string& db,
                                       const char* name) {
  const int bytes = s.IsNull(col) ? 0 : s.ColumnBytes(col);
  if (bytes % (2 * sizeof(double)) != 0) {
    ThrowBadRow(s, db, StrCat(name, " has ", bytes, " bytes"));
  }
  const std::vector<double> values =
      bytes == 0 ? std::vector<double>()
                 : DoubleBlob(s, col, bytes / sizeof(double), db, name);
  std::vector<Eigen::Vector2d> points;
  for (size_t k = 0; k + 1 < values.size(); k += 2) {
    points.emplace_back(values[k], values[k + 1]);
  }
  return points;
}

std::vector<double> Flatten(const std::vector<Eigen::Vector2d>& points) {
  std::vector<double> values;
  values.reserve(2 * points.size());
  for (const Eigen::Vector2d& p : points) {
    values.push_back(p.x());
    values.push_back(p.y());
  }
  return values;
}

DisparitySurfaceRecord FromRow(const SqliteStatement& s,
                               const std::string& db) {
  DisparitySurfaceRecord r;
  r.success = s.ColumnInt64(3) != 0;
  r.reason = s.ColumnText(4);
  r.assume_zero_distortion = s.ColumnInt64(5) != 0;
  r.num_points = static_cast<int>(s.ColumnInt64(24));
  r.num_used = static_cast<int>(s.ColumnInt64(25));
  r.num_blunders = static_cast<int>(s.ColumnInt64(26));
  r.seconds = s.ColumnDouble(32);
  // The orientation is recorded for failures too (to tell when they are
  // worth trying again), but only a surface needs it.
  if (r.success || !s.IsNull(6)) {
    const std::vector<double> q = DoubleBlob(s, 6, 4, db, "qvec");
    const std::vector<double> t = DoubleBlob(s, 7, 3, db, "tvec");
    r.cam2_from_cam1 =
        Rigid3d(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(),
                Eigen::Vector3d(t[0], t[1], t[2]));
  }
  if (!r.success) return r;

  r.origin = Eigen::Vector2d(s.ColumnDouble(8), s.ColumnDouble(9));
  r.cell_size_px = s.ColumnDouble(10);
  r.cols = static_cast<int>(s.ColumnInt64(11));
  r.rows = static_cast<int>(s.ColumnInt64(12));
  if (r.cols < 1 || r.rows < 1 || r.cols > 4096 || r.rows > 4096 ||
      !(r.cell_size_px > 0)) {
    ThrowBadRow(s,
                db,
                StrCat("grid of ",
                       r.cols,
                       " x ",
                       r.rows,
                       " cells of ",
                       r.cell_size_px,
                       " px is not valid"));
  }
  const size_t num_nodes = r.NumNodes();
  r.inverse_depth = DoubleBlob(s, 13, num_nodes, db, "inverse_depth");
  r.sigma_px = DoubleBlob(s, 14, num_nodes, db, "sigma_px");
  r.support_points = PointBlob(s, 15, db, "support_points");
  r.hull = PointBlob(s, 16, db, "hull");
  if (r.support_points.empty()) ThrowBadRow(s, db, "no support points");
  r.support_inverse_depth =
      DoubleBlob(s, 33, r.support_points.size(), db, "support_inverse_depth");
  r.range_neighbors = static_cast<int>(s.ColumnInt64(34));
  r.spacing_px = s.ColumnDouble(17);
  r.smoothness = s.ColumnDouble(18);
  r.band_k = s.ColumnDouble(19);
  r.support_radius_px = s.ColumnDouble(20);
  r.growth_px_per_px = s.ColumnDouble(21);
  r.gradient_factor = s.ColumnDouble(22);
  r.depth_tolerance = s.ColumnDouble(23);
  r.robust_sigma_px = s.ColumnDouble(27);
  r.cv_sigma_px = s.ColumnDouble(28);
  r.cv_coverage = s.ColumnDouble(29);
  r.median_band_px = s.ColumnDouble(30);
  r.median_range_px = s.ColumnDouble(31);
  if (!(r.spacing_px > 0)) {
    ThrowBadRow(s, db, StrCat("spacing_px ", r.spacing_px, " is not > 0"));
  }
  return r;
}

}  // namespace

void WriteDisparitySurface(Database* database,
                           image_t image_id1,
                           image_t image_id2,
                           const DisparitySurfaceRecord& r) {
  if (image_id1 == image_id2) {
    ThrowInputError(
        "bayon_disparity_surfaces: image ", image_id1, " paired with itself");
  }
  const size_t num_nodes = r.success ? r.NumNodes() : 0;
  if (r.success &&
      (r.inverse_depth.size() != num_nodes || r.sigma_px.size() != num_nodes ||
       r.support_points.empty() ||
       r.support_inverse_depth.size() != r.support_points.size() ||
       !(r.spacing_px > 0))) {
    ThrowInputError("bayon_disparity_surfaces: pair (",
                    image_id1,
                    ", ",
                    image_id2,
                    "): the surface does not match its ",
                    r.cols,
                    " x ",
                    r.rows,
                    " grid or has no support");
  }
  EnsureBayonTable(database, kDisparitySurfacesTable);
  std::string placeholders = "?";
  for (int k = 1; k < kNumColumns; ++k) placeholders += ", ?";
  SqliteStatement s(database->connection(),
                    StrCat("INSERT OR REPLACE INTO bayon_disparity_surfaces(",
                           kColumns,
                           ") VALUES(",
                           placeholders,
                           ")"));
  s.Bind(1, static_cast<int64_t>(image_id1))
      .Bind(2, static_cast<int64_t>(image_id2))
      .Bind(3, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)))
      .Bind(4, static_cast<int64_t>(r.success))
      .Bind(5, r.reason)
      .Bind(6, static_cast<int64_t>(r.assume_zero_distortion));
  const Eigen::Quaterniond& rotation = r.cam2_from_cam1.rotation;
  const double q[4] = {rotation.w(), rotation.x(), rotation.y(), rotation.z()};
  s.BindBlob(7, q, sizeof(q))
      .BindBlob(8, r.cam2_from_cam1.translation.data(), 3 * sizeof(double));
  const std::vector<double> support = Flatten(r.support_points);
  const std::vector<double> hull = Flatten(r.hull);
  if (r.success) {
    s.Bind(9, r.origin.x())
        .Bind(10, r.origin.y())
        .Bind(11, r.cell_size_px)
        .Bind(12, static_cast<int64_t>(r.cols))
        .Bind(13, static_cast<int64_t>(r.rows))
        .BindBlob(14, r.inverse_depth.data(), num_nodes * sizeof(double))
        .BindBlob(15, r.sigma_px.data(), num_nodes * sizeof(double))
        .BindBlob(16, support.data(), support.size() * sizeof(double))
        .BindBlob(17, hull.data(), hull.size() * sizeof(double));
  } else {
    for (int col = 9; col <= 17; ++col) s.BindNull(col);
    s.Bind(12, static_cast<int64_t>(0)).Bind(13, static_cast<int64_t>(0));
  }
  s.Bind(18, r.spacing_px)
      .Bind(19, r.smoothness)
      .Bind(20, r.band_k)
      .Bind(21, r.support_radius_px)
      .Bind(22, r.growth_px_per_px)
      .Bind(23, r.gradient_factor)
      .Bind(24, r.depth_tolerance)
      .Bind(25, static_cast<int64_t>(r.num_points))
      .Bind(26, static_cast<int64_t>(r.num_used))
      .Bind(27, static_cast<int64_t>(r.num_blunders))
      .Bind(28, r.robust_sigma_px)
      .Bind(29, r.cv_sigma_px)
      .Bind(30, r.cv_coverage)
      .Bind(31, r.median_band_px)
      .Bind(32, r.median_range_px)
      .Bind(33, r.seconds)
      .Bind(35, static_cast<int64_t>(r.range_neighbors));
  if (r.success) {
    s.BindBlob(34,
               r.support_inverse_depth.data(),
               r.support_inverse_depth.size() * sizeof(double));
  } else {
    s.BindNull(34);
  }
  s.Execute();
}

std::optional<DisparitySurfaceRecord> ReadDisparitySurface(Database* database,
                                                           image_t image_id1,
                                                           image_t image_id2) {
  if (!BayonTableExists(database, kDisparitySurfacesTable.name)) {
    return std::nullopt;
  }
  SqliteStatement s(database->connection(),
                    StrCat("SELECT ",
                           kColumns,
                           " FROM bayon_disparity_surfaces WHERE image_id1 = "
                           "? AND image_id2 = ?"));
  s.Bind(1, static_cast<int64_t>(image_id1))
      .Bind(2, static_cast<int64_t>(image_id2));
  if (!s.Step()) return std::nullopt;
  return FromRow(s, database->path());
}

std::map<std::pair<image_t, image_t>, DisparitySurfaceRecord>
ReadAllDisparitySurfaces(Database* database) {
  std::map<std::pair<image_t, image_t>, DisparitySurfaceRecord> records;
  if (!BayonTableExists(database, kDisparitySurfacesTable.name)) {
    return records;
  }
  SqliteStatement s(
      database->connection(),
      StrCat("SELECT ", kColumns, " FROM bayon_disparity_surfaces"));
  while (s.Step()) {
    const image_t id1 = static_cast<image_t>(s.ColumnInt64(0));
    const image_t id2 = static_cast<image_t>(s.ColumnInt64(1));
    records.emplace(std::make_pair(id1, id2), FromRow(s, database->path()));
  }
  return records;
}

}  // namespace bayon
