// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/table_relative.h"

#include "ext/core/errors.h"

#include <cstring>

namespace bayon {

const BayonTable kRelativeOrientationTable = {
    "bayon_relative_orientation",
    "CREATE TABLE IF NOT EXISTS bayon_relative_orientation ("
    "pair_id INTEGER PRIMARY KEY NOT NULL, "
    "image_id1 INTEGER NOT NULL, image_id2 INTEGER NOT NULL, "
    "success INTEGER NOT NULL, reason TEXT NOT NULL, "
    "calibrated INTEGER NOT NULL, assume_zero_distortion INTEGER NOT NULL, "
    "num_matches INTEGER NOT NULL, num_inliers INTEGER NOT NULL, "
    "num_blunders INTEGER NOT NULL, "
    "omega_deg REAL, phi_deg REAL, kappa_deg REAL, "
    "std_omega_deg REAL, std_phi_deg REAL, std_kappa_deg REAL, "
    "bx REAL, by REAL, bz REAL, std_base1_deg REAL, std_base2_deg REAL, "
    "sigma0_px REAL, robust_sigma_px REAL, convergence_angle_deg REAL, "
    "median_intersection_angle_deg REAL, num_iterations INTEGER, "
    "L BLOB, covariance BLOB, qvec BLOB, tvec BLOB, inliers BLOB, "
    "seconds REAL NOT NULL, "
    "FOREIGN KEY(image_id1) REFERENCES images(image_id) ON DELETE CASCADE, "
    "FOREIGN KEY(image_id2) REFERENCES images(image_id) ON DELETE CASCADE)"};

namespace {

constexpr const char* kSelect =
    "SELECT image_id1, image_id2, success, reason, calibrated, "
    "assume_zero_distortion, num_matches, num_inliers, num_blunders, "
    "omega_deg, phi_deg, kappa_deg, std_omega_deg, std_phi_deg, "
    "std_kappa_deg, bx, by, bz, std_base1_deg, std_base2_deg, sigma0_px, "
    "robust_sigma_px, convergence_angle_deg, median_intersection_angle_deg, "
    "num_iterations, L, covariance, qvec, tvec, inliers, seconds FROM "
    "bayon_relative_orientation";

template <typename T>
bool ReadBlob(const SqliteStatement& statement, int col, size_t count, T* out) {
  if (statement.IsNull(col) ||
      statement.ColumnBytes(col) != static_cast<int>(count * sizeof(T))) {
    return false;
  }
  std::memcpy(out, statement.ColumnBlobData(col), count * sizeof(T));
  return true;
}

RelativeOrientationRecord FromRow(const SqliteStatement& s,
                                  const std::string& db) {
  RelativeOrientationRecord r;
  r.success = s.ColumnInt64(2) != 0;
  r.reason = s.ColumnText(3);
  r.calibrated = s.ColumnInt64(4) != 0;
  r.assume_zero_distortion = s.ColumnInt64(5) != 0;
  r.num_matches = static_cast<int>(s.ColumnInt64(6));
  r.num_inliers = static_cast<int>(s.ColumnInt64(7));
  r.num_blunders = static_cast<int>(s.ColumnInt64(8));
  r.omega_phi_kappa_deg << s.ColumnDouble(9), s.ColumnDouble(10),
      s.ColumnDouble(11);
  r.std_omega_phi_kappa_deg << s.ColumnDouble(12), s.ColumnDouble(13),
      s.ColumnDouble(14);
  r.base << s.ColumnDouble(15), s.ColumnDouble(16), s.ColumnDouble(17);
  r.std_base_deg << s.ColumnDouble(18), s.ColumnDouble(19);
  r.sigma0_px = s.ColumnDouble(20);
  r.robust_sigma_px = s.ColumnDouble(21);
  r.convergence_angle_deg = s.ColumnDouble(22);
  r.median_intersection_angle_deg = s.ColumnDouble(23);
  r.num_iterations = static_cast<int>(s.ColumnInt64(24));
  Eigen::Matrix<double, 8, 1> L;
  if (ReadBlob(s, 25, 8, L.data())) r.L = L;
  ReadBlob(s, 26, 25, r.covariance.data());
  double q[4] = {1, 0, 0, 0};
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  if (r.success && (!ReadBlob(s, 27, 4, q) || !ReadBlob(s, 28, 3, t.data()))) {
    ThrowInputError(db,
                    ": bayon_relative_orientation row of pair (",
                    s.ColumnInt64(0),
                    ", ",
                    s.ColumnInt64(1),
                    "): qvec/tvec missing or malformed");
  }
  r.cam2_from_cam1 =
      Rigid3d(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(), t);
  r.inliers.resize(s.ColumnBytes(29));
  if (!r.inliers.empty()) {
    std::memcpy(r.inliers.data(), s.ColumnBlobData(29), r.inliers.size());
  }
  r.seconds = s.ColumnDouble(30);
  return r;
}

}  // namespace

void WriteRelativeOrientation(Database* database,
                              image_t image_id1,
                              image_t image_id2,
                              const RelativeOrientationRecord& r) {
  if (image_id1 >= image_id2) {
    ThrowInputError("bayon_relative_orientation: pair (",
                    image_id1,
                    ", ",
                    image_id2,
                    ") is not in canonical order");
  }
  EnsureBayonTable(database, kRelativeOrientationTable);
  SqliteStatement s(
      database->connection(),
      "INSERT OR REPLACE INTO bayon_relative_orientation(pair_id, image_id1, "
      "image_id2, success, reason, calibrated, assume_zero_distortion, "
      "num_matches, num_inliers, num_blunders, omega_deg, phi_deg, "
      "kappa_deg, std_omega_deg, std_phi_deg, std_kappa_deg, bx, by, bz, "
      "std_base1_deg, std_base2_deg, sigma0_px, robust_sigma_px, "
      "convergence_angle_deg, median_intersection_angle_deg, num_iterations, "
      "L, covariance, qvec, tvec, inliers, seconds) VALUES(?, ?, ?, ?, ?, ?, "
      "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
      "?, ?, ?)");
  const Eigen::Quaterniond& rotation = r.cam2_from_cam1.rotation;
  const double q[4] = {rotation.w(), rotation.x(), rotation.y(), rotation.z()};
  s.Bind(1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)))
      .Bind(2, static_cast<int64_t>(image_id1))
      .Bind(3, static_cast<int64_t>(image_id2))
      .Bind(4, static_cast<int64_t>(r.success))
      .Bind(5, r.reason)
      .Bind(6, static_cast<int64_t>(r.calibrated))
      .Bind(7, static_cast<int64_t>(r.assume_zero_distortion))
      .Bind(8, static_cast<int64_t>(r.num_matches))
      .Bind(9, static_cast<int64_t>(r.num_inliers))
      .Bind(10, static_cast<int64_t>(r.num_blunders));
  for (int k = 0; k < 3; ++k) {
    s.Bind(11 + k, r.omega_phi_kappa_deg(k));
    s.Bind(14 + k, r.std_omega_phi_kappa_deg(k));
    s.Bind(17 + k, r.base(k));
  }
  s.Bind(20, r.std_base_deg(0))
      .Bind(21, r.std_base_deg(1))
      .Bind(22, r.sigma0_px)
      .Bind(23, r.robust_sigma_px)
      .Bind(24, r.convergence_angle_deg)
      .Bind(25, r.median_intersection_angle_deg)
      .Bind(26, static_cast<int64_t>(r.num_iterations));
  if (r.L) {
    s.BindBlob(27, r.L->data(), 8 * sizeof(double));
  } else {
    s.BindNull(27);
  }
  s.BindBlob(28, r.covariance.data(), 25 * sizeof(double));
  if (r.success) {
    s.BindBlob(29, q, sizeof(q));
    s.BindBlob(30, r.cam2_from_cam1.translation.data(), 3 * sizeof(double));
  } else {
    s.BindNull(29).BindNull(30);
  }
  s.BindBlob(31, r.inliers.data(), r.inliers.size()).Bind(32, r.seconds);
  s.Execute();
}

std::optional<RelativeOrientationRecord> ReadRelativeOrientation(
    Database* database, image_t image_id1, image_t image_id2) {
  if (!BayonTableExists(database, kRelativeOrientationTable.name)) {
    return std::nullopt;
  }
  SqliteStatement s(database->connection(),
                    std::string(kSelect) + " WHERE pair_id = ?");
  s.Bind(1, static_cast<int64_t>(PairIdFromImageIds(image_id1, image_id2)));
  if (!s.Step()) return std::nullopt;
  if (static_cast<image_t>(s.ColumnInt64(0)) !=
      std::min(image_id1, image_id2)) {
    return std::nullopt;
  }
  return FromRow(s, database->path());
}

std::map<pair_t, RelativeOrientationRecord> ReadAllRelativeOrientations(
    Database* database) {
  std::map<pair_t, RelativeOrientationRecord> records;
  if (!BayonTableExists(database, kRelativeOrientationTable.name)) {
    return records;
  }
  SqliteStatement s(database->connection(), kSelect);
  while (s.Step()) {
    const image_t id1 = static_cast<image_t>(s.ColumnInt64(0));
    const image_t id2 = static_cast<image_t>(s.ColumnInt64(1));
    records.emplace(PairIdFromImageIds(id1, id2), FromRow(s, database->path()));
  }
  return records;
}

}  // namespace bayon
