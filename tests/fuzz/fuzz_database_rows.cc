// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_database_rows: fuzzed rows inside a valid database. The input picks
// one of the schemas bayon reads (COLMAP 3.8, 3.10, 3.12, 4.x, each with all
// bayon_* tables) and then describes rows: a table, and per column a value
// (NULL, integers small or any, doubles, text, blobs, or a blob whose size
// is the product of the two integers before it times 1, 4 or 8 bytes, so
// that rows x cols x sizeof blobs come out consistent as often as not). The
// rows are written with SQLite directly (bayon's writers would refuse most
// of them) and the file is then read through bayon's readers.
#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/database.h"
#include "ext/colmap/table_disparity.h"
#include "ext/colmap/table_features.h"
#include "ext/colmap/table_matches.h"
#include "ext/colmap/table_relative.h"
#include "ext/colmap/table_tie_points.h"

#include <sqlite3.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace {

using namespace bayon;

constexpr int kNumSchemas = 4;
constexpr int64_t kMaxBlobBytes = 1 << 20;

struct Table {
  std::string name;
  int num_columns = 0;
};

// A template database per schema: its bytes and its tables.
struct Template {
  std::string bytes;
  std::vector<Table> tables;
};

void Exec(sqlite3* db, const char* sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    std::fprintf(stderr, "fuzz_database_rows: %s: %s\n", sql, message);
    std::abort();
  }
}

Template MakeTemplate(int schema) {
  const std::string path =
      fuzz::FreshPath("template" + std::to_string(schema) + ".db");
  {
    Database database(path, Database::Mode::kCreate);
    for (const BayonTable* table : {&kCalibrationTable,
                                    &kInteriorTable,
                                    &kKeypointInterestTable,
                                    &kMatchesTable,
                                    &kRelativeOrientationTable,
                                    &kDisparitySurfacesTable,
                                    &kTiePointsTable,
                                    &kTieObservationsTable}) {
      EnsureBayonTable(&database, *table);
    }
  }
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  if (schema >= 1) {
    // 3.10: the prior_* columns moved to a pose_priors table.
    for (const char* column : {"prior_qw",
                               "prior_qx",
                               "prior_qy",
                               "prior_qz",
                               "prior_tx",
                               "prior_ty",
                               "prior_tz"}) {
      Exec(db,
           (std::string("ALTER TABLE images DROP COLUMN ") + column).c_str());
    }
    Exec(db,
         "CREATE TABLE pose_priors (image_id INTEGER PRIMARY KEY NOT NULL, "
         "position BLOB, coordinate_system INTEGER NOT NULL, "
         "position_covariance BLOB)");
  }
  if (schema >= 2) {
    Exec(db,
         "CREATE TABLE rigs (rig_id INTEGER PRIMARY KEY NOT NULL, "
         "ref_sensor_id INTEGER NOT NULL, ref_sensor_type INTEGER NOT NULL)");
    Exec(db,
         "CREATE TABLE frames (frame_id INTEGER PRIMARY KEY NOT NULL, "
         "rig_id INTEGER NOT NULL)");
  }
  if (schema >= 3) {
    Exec(db,
         "ALTER TABLE descriptors ADD COLUMN type INTEGER NOT NULL DEFAULT 0");
  }
  Template result;
  sqlite3_stmt* statement = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT name FROM sqlite_master WHERE type = 'table' AND "
                     "name NOT LIKE 'sqlite_%' ORDER BY name",
                     -1,
                     &statement,
                     nullptr);
  while (sqlite3_step(statement) == SQLITE_ROW) {
    result.tables.push_back(
        {reinterpret_cast<const char*>(sqlite3_column_text(statement, 0)), 0});
  }
  sqlite3_finalize(statement);
  for (Table& table : result.tables) {
    sqlite3_prepare_v2(db,
                       ("SELECT * FROM \"" + table.name + "\"").c_str(),
                       -1,
                       &statement,
                       nullptr);
    table.num_columns = sqlite3_column_count(statement);
    sqlite3_finalize(statement);
  }
  sqlite3_close(db);
  std::ifstream file(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << file.rdbuf();
  result.bytes = bytes.str();
  return result;
}

const std::vector<Template>& Templates() {
  static const std::vector<Template> templates = [] {
    std::vector<Template> all;
    for (int schema = 0; schema < kNumSchemas; ++schema) {
      all.push_back(MakeTemplate(schema));
    }
    return all;
  }();
  return templates;
}

// Binds one column's value as the input describes it.
void BindValue(fuzz::InputCursor* in,
               sqlite3_stmt* statement,
               int idx,
               std::vector<int64_t>* integers) {
  switch (in->Byte() % 8) {
    case 0:
      sqlite3_bind_null(statement, idx);
      return;
    case 1:
    case 2: {
      const int64_t value = in->Byte();
      integers->push_back(value);
      sqlite3_bind_int64(statement, idx, value);
      return;
    }
    case 3: {
      const int64_t value = in->Int64();
      integers->push_back(value);
      sqlite3_bind_int64(statement, idx, value);
      return;
    }
    case 4:
      sqlite3_bind_double(statement, idx, in->Double());
      return;
    case 5: {
      const std::string text = in->Bytes(in->Byte());
      sqlite3_bind_text(statement,
                        idx,
                        text.data(),
                        static_cast<int>(text.size()),
                        SQLITE_TRANSIENT);
      return;
    }
    case 6: {
      const std::string blob = in->Bytes(in->Uint16());
      sqlite3_bind_blob(statement,
                        idx,
                        blob.data(),
                        static_cast<int>(blob.size()),
                        SQLITE_TRANSIENT);
      return;
    }
    case 7: {
      // rows x cols x element size, filled from the input, then zeros.
      static constexpr int64_t kElementSizes[] = {1, 4, 8};
      const int64_t element = kElementSizes[in->Byte() % 3];
      const size_t n = integers->size();
      int64_t num_bytes = 0;
      if (n >= 2 && (*integers)[n - 1] >= 0 && (*integers)[n - 2] >= 0 &&
          (*integers)[n - 1] <= kMaxBlobBytes &&
          (*integers)[n - 2] <= kMaxBlobBytes) {
        num_bytes = (*integers)[n - 1] * (*integers)[n - 2] * element;
      }
      if (num_bytes > kMaxBlobBytes) num_bytes = 0;
      std::string blob = in->Bytes(num_bytes);
      blob.resize(num_bytes, '\0');
      sqlite3_bind_blob(statement,
                        idx,
                        blob.data(),
                        static_cast<int>(blob.size()),
                        SQLITE_TRANSIENT);
      return;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::InputCursor in(data, size);
  const Template& schema = Templates()[in.Byte() % kNumSchemas];
  const std::string path = fuzz::FreshPath("rows.db");
  fuzz::FreshPath("rows.db-journal");
  fuzz::WriteFile(path, schema.bytes);

  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) std::abort();
  Exec(db, "PRAGMA synchronous = OFF");
  Exec(db, "BEGIN");
  while (!in.empty()) {
    const Table& table = schema.tables[in.Byte() % schema.tables.size()];
    std::string sql = "INSERT OR REPLACE INTO \"" + table.name + "\" VALUES(";
    for (int i = 0; i < table.num_columns; ++i) sql += i == 0 ? "?" : ", ?";
    sql += ")";
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) !=
        SQLITE_OK) {
      std::abort();
    }
    std::vector<int64_t> integers;
    for (int i = 0; i < table.num_columns; ++i) {
      BindValue(&in, statement, i + 1, &integers);
    }
    sqlite3_step(statement);  // constraint failures just drop the row
    sqlite3_finalize(statement);
  }
  Exec(db, "COMMIT");
  sqlite3_close(db);

  fuzz::Expect([&] {
    Database database(path, Database::Mode::kReadOnly);
    fuzz::ReadWholeDatabase(&database);
  });
  return 0;
}
