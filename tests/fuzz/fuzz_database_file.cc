// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_database_file: the input is a whole database.db. bayon opens it
// read-only (as every stage opens the user's database first) and reads
// every COLMAP and bayon_* table through its readers. Seeds are small real
// databases; libFuzzer mutates pages, the schema and the rows alike.
#include "ext/colmap/database.h"

#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  const std::string path = fuzz::FreshPath("database.db");
  fuzz::FreshPath("database.db-journal");
  fuzz::FreshPath("database.db-wal");
  fuzz::FreshPath("database.db-shm");
  fuzz::WriteFile(path, std::string(reinterpret_cast<const char*>(data), size));
  fuzz::Expect([&] {
    Database database(path, Database::Mode::kReadOnly);
    fuzz::ReadWholeDatabase(&database);
  });
  return 0;
}
