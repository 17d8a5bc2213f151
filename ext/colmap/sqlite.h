// SPDX-License-Identifier: BSD-3-Clause
//
// A thin RAII layer over SQLite: a connection, prepared statements with typed
// binding and column access, and transactions. Every SQLite error becomes an
// InputError naming the database file, because in practice they come from
// the user's file (not a database, locked, read-only, corrupt).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace bayon {

class SqliteConnection;

class SqliteStatement {
 public:
  SqliteStatement(SqliteConnection* connection, const std::string& sql);
  ~SqliteStatement();
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  // Parameter indices start at 1, as in SQLite.
  SqliteStatement& Bind(int idx, int64_t value);
  SqliteStatement& Bind(int idx, double value);
  SqliteStatement& Bind(int idx, const std::string& value);
  // A NULL pointer or zero size binds NULL, as COLMAP's writes do.
  SqliteStatement& BindBlob(int idx, const void* data, size_t num_bytes);
  SqliteStatement& BindNull(int idx);
  SqliteStatement& Bind(int idx, const std::optional<double>& value);

  // Returns true while there is a row.
  bool Step();
  // Steps once and expects no row (INSERT/UPDATE/DELETE).
  void Execute();
  void Reset();

  bool IsNull(int col) const;
  int64_t ColumnInt64(int col) const;
  double ColumnDouble(int col) const;
  std::optional<double> ColumnOptionalDouble(int col) const;
  std::string ColumnText(int col) const;
  // Blob bytes; an empty vector for NULL (check IsNull to tell them apart).
  std::vector<uint8_t> ColumnBlob(int col) const;
  int ColumnBytes(int col) const;
  const void* ColumnBlobData(int col) const;

 private:
  SqliteConnection* connection_;
  sqlite3_stmt* statement_ = nullptr;
  std::string sql_;
};

class SqliteConnection {
 public:
  enum class Mode { kReadOnly, kReadWrite, kCreate };
  SqliteConnection(const std::string& path, Mode mode);
  ~SqliteConnection();
  SqliteConnection(const SqliteConnection&) = delete;
  SqliteConnection& operator=(const SqliteConnection&) = delete;

  void Execute(const std::string& sql);
  int64_t QueryInt64(const std::string& sql);
  bool TableExists(const std::string& table);
  std::vector<std::string> TableColumns(const std::string& table);
  int64_t LastInsertRowId() const;
  int Changes() const;

  const std::string& path() const { return path_; }
  bool read_only() const { return mode_ == Mode::kReadOnly; }
  sqlite3* handle() { return db_; }

  // Throws InputError "<path>: <what>: <sqlite message>" unless `rc` is ok.
  void Check(int rc, const std::string& what) const;

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
  Mode mode_;
};

// BEGIN IMMEDIATE on construction, ROLLBACK on destruction unless committed:
// a write that throws halfway leaves the database as it was.
class SqliteTransaction {
 public:
  explicit SqliteTransaction(SqliteConnection* connection);
  ~SqliteTransaction();
  SqliteTransaction(const SqliteTransaction&) = delete;
  SqliteTransaction& operator=(const SqliteTransaction&) = delete;
  void Commit();

 private:
  SqliteConnection* connection_;
  bool active_ = true;
};

// Copies a database file consistently (SQLite's online backup, so that a WAL
// database is copied with its log) to `dst_path`, which must not exist.
void CopySqliteDatabase(const std::string& src_path,
                        const std::string& dst_path);

}  // namespace bayon
