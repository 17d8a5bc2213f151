// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/sqlite.h"

#include "ext/core/errors.h"

#include <sqlite3.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace bayon {
namespace {

// How long a connection waits for another program's lock before it gives up
// with "database is locked": 60 s, or $BAYON_DATABASE_TIMEOUT seconds for
// a user whose other program holds it longer (or a test that cannot wait).
int BusyTimeoutMs() {
  const char* env = std::getenv("BAYON_DATABASE_TIMEOUT");
  if (!env || !*env) return 60000;
  char* end = nullptr;
  const double seconds = std::strtod(env, &end);
  if (*end != '\0' || !(seconds >= 0 && seconds <= 86400)) {
    ThrowInputError("BAYON_DATABASE_TIMEOUT='",
                    env,
                    "' is not a number of seconds from 0 to 86400");
  }
  return static_cast<int>(seconds * 1000);
}

}  // namespace

SqliteStatement::SqliteStatement(SqliteConnection* connection,
                                 const std::string& sql)
    : connection_(connection), sql_(sql) {
  connection_->Check(
      sqlite3_prepare_v2(
          connection_->handle(), sql.c_str(), -1, &statement_, nullptr),
      "cannot prepare \"" + sql.substr(0, 80) + "\"");
}

SqliteStatement::~SqliteStatement() { sqlite3_finalize(statement_); }

SqliteStatement& SqliteStatement::Bind(int idx, int64_t value) {
  connection_->Check(sqlite3_bind_int64(statement_, idx, value), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::Bind(int idx, double value) {
  connection_->Check(sqlite3_bind_double(statement_, idx, value), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::Bind(int idx, const std::string& value) {
  connection_->Check(sqlite3_bind_text(statement_,
                                       idx,
                                       value.c_str(),
                                       static_cast<int>(value.size()),
                                       SQLITE_TRANSIENT),
                     "bind");
  return *this;
}

SqliteStatement& SqliteStatement::BindBlob(int idx,
                                           const void* data,
                                           size_t num_bytes) {
  if (data == nullptr || num_bytes == 0) return BindNull(idx);
  connection_->Check(
      sqlite3_bind_blob64(statement_, idx, data, num_bytes, SQLITE_TRANSIENT),
      "bind");
  return *this;
}

SqliteStatement& SqliteStatement::BindNull(int idx) {
  connection_->Check(sqlite3_bind_null(statement_, idx), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::Bind(int idx,
                                       const std::optional<double>& value) {
  return value ? Bind(idx, *value) : BindNull(idx);
}

bool SqliteStatement::Step() {
  const int rc = sqlite3_step(statement_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  connection_->Check(rc, "cannot run \"" + sql_.substr(0, 80) + "\"");
  return false;
}

void SqliteStatement::Execute() {
  Step();
  Reset();
}

void SqliteStatement::Reset() {
  sqlite3_reset(statement_);
  sqlite3_clear_bindings(statement_);
}

bool SqliteStatement::IsNull(int col) const {
  return sqlite3_column_type(statement_, col) == SQLITE_NULL;
}

int64_t SqliteStatement::ColumnInt64(int col) const {
  return sqlite3_column_int64(statement_, col);
}

double SqliteStatement::ColumnDouble(int col) const {
  return sqlite3_column_double(statement_, col);
}

std::optional<double> SqliteStatement::ColumnOptionalDouble(int col) const {
  if (IsNull(col)) return std::nullopt;
  return ColumnDouble(col);
}

std::string SqliteStatement::ColumnText(int col) const {
  const unsigned char* text = sqlite3_column_text(statement_, col);
  if (text == nullptr) return std::string();
  return std::string(reinterpret_cast<const char*>(text),
                     sqlite3_column_bytes(statement_, col));
}

const void* SqliteStatement::ColumnBlobData(int col) const {
  return sqlite3_column_blob(statement_, col);
}

int SqliteStatement::ColumnBytes(int col) const {
  return sqlite3_column_bytes(statement_, col);
}

std::vector<uint8_t> SqliteStatement::ColumnBlob(int col) const {
  const auto* data = static_cast<const uint8_t*>(ColumnBlobData(col));
  const int num_bytes = ColumnBytes(col);
  if (data == nullptr || num_bytes <= 0) return {};
  return std::vector<uint8_t>(data, data + num_bytes);
}

SqliteConnection::SqliteConnection(const std::string& path, Mode mode)
    : path_(path), mode_(mode) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (mode != Mode::kCreate && !fs::is_regular_file(path, ec)) {
    ThrowInputError(path, ": database not found");
  }
  if (mode == Mode::kCreate && fs::exists(path, ec)) {
    ThrowInputError(path,
                    ": exists already (bayon creates a new database here)");
  }
  int flags = SQLITE_OPEN_NOMUTEX;
  if (mode == Mode::kReadOnly) {
    flags |= SQLITE_OPEN_READONLY;
  } else {
    flags |= SQLITE_OPEN_READWRITE;
    if (mode == Mode::kCreate) flags |= SQLITE_OPEN_CREATE;
  }
  // Read before opening: a bad value throws, and a constructor that throws
  // runs no destructor to close the connection.
  const int busy_timeout_ms = BusyTimeoutMs();
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    ThrowInputError(path, ": cannot open database: ", message);
  }
  // Wait for a concurrent writer (another bayon or colmap) instead of failing
  // at once; COLMAP's own connections do not wait, so be patient here.
  sqlite3_busy_timeout(db_, busy_timeout_ms);
  sqlite3_extended_result_codes(db_, 1);
  // Reading the schema is the first real access: a file that is not SQLite
  // fails here with "file is not a database".
  try {
    QueryInt64("SELECT count(*) FROM sqlite_master");
    // Connection settings only; nothing is stored in the file. COLMAP runs
    // with foreign keys on, which is what makes ON DELETE CASCADE work.
    Execute("PRAGMA foreign_keys=ON");
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

SqliteConnection::~SqliteConnection() {
  if (db_) sqlite3_close_v2(db_);
}

void SqliteConnection::Check(int rc, const std::string& what) const {
  if (rc == SQLITE_OK || rc == SQLITE_ROW || rc == SQLITE_DONE) return;
  const int primary = rc & 0xff;
  std::string hint;
  if (primary == SQLITE_NOTADB) hint = " (the file is not an SQLite database)";
  if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED) {
    char waited[32];
    std::snprintf(waited, sizeof(waited), "%g", BusyTimeoutMs() / 1000.0);
    hint = std::string(" (another program held the database for longer than ") +
           waited + " s; try again when it is done, or set " +
           "BAYON_DATABASE_TIMEOUT)";
  }
  if (primary == SQLITE_READONLY) hint = " (the database is read-only)";
  if (primary == SQLITE_FULL) hint = " (the disk is full)";
  if (primary == SQLITE_CORRUPT) hint = " (the database file is damaged)";
  ThrowInputError(path_, ": ", what, ": ", sqlite3_errstr(rc), hint);
}

void SqliteConnection::Execute(const std::string& sql) {
  char* error = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error);
  if (rc != SQLITE_OK) {
    const std::string message = error ? error : sqlite3_errstr(rc);
    sqlite3_free(error);
    Check(rc, "cannot run \"" + sql.substr(0, 80) + "\" (" + message + ")");
  }
}

int64_t SqliteConnection::QueryInt64(const std::string& sql) {
  SqliteStatement statement(this, sql);
  if (!statement.Step()) return 0;
  return statement.ColumnInt64(0);
}

bool SqliteConnection::TableExists(const std::string& table) {
  SqliteStatement statement(
      this, "SELECT 1 FROM sqlite_master WHERE type='table' AND name=?");
  statement.Bind(1, table);
  return statement.Step();
}

std::vector<std::string> SqliteConnection::TableColumns(
    const std::string& table) {
  std::vector<std::string> columns;
  SqliteStatement statement(this, "PRAGMA table_info(\"" + table + "\")");
  while (statement.Step()) columns.push_back(statement.ColumnText(1));
  return columns;
}

int64_t SqliteConnection::LastInsertRowId() const {
  return sqlite3_last_insert_rowid(db_);
}

int SqliteConnection::Changes() const { return sqlite3_changes(db_); }

SqliteTransaction::SqliteTransaction(SqliteConnection* connection)
    : connection_(connection) {
  connection_->Execute("BEGIN IMMEDIATE");
}

SqliteTransaction::~SqliteTransaction() {
  if (active_) {
    sqlite3_exec(connection_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
}

void SqliteTransaction::Commit() {
  connection_->Execute("COMMIT");
  active_ = false;
}

void CopySqliteDatabase(const std::string& src_path,
                        const std::string& dst_path) {
  SqliteConnection src(src_path, SqliteConnection::Mode::kReadOnly);
  SqliteConnection dst(dst_path, SqliteConnection::Mode::kCreate);
  sqlite3_backup* backup =
      sqlite3_backup_init(dst.handle(), "main", src.handle(), "main");
  if (backup == nullptr) {
    dst.Check(sqlite3_errcode(dst.handle()), "cannot copy " + src_path);
  }
  const int rc = sqlite3_backup_step(backup, -1);
  sqlite3_backup_finish(backup);
  if (rc != SQLITE_DONE) dst.Check(rc, "cannot copy " + src_path);
}

}  // namespace bayon
