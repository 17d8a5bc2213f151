// SPDX-License-Identifier: BSD-3-Clause
//
// Shared helpers for unit and end-to-end tests: where the real data is, fresh
// temporary folders, running the `bayon` and `colmap` binaries with their
// output captured, and checksums of whole folders ("nothing changed").
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace bayon {
namespace testing {

// ../shared/data (or $BAYON_DATA_DIR); empty if it does not exist.
std::string DataDir();
// DataDir() + "/" + relative, or empty if that path does not exist.
std::string DataPath(const std::string& relative);

// A file of the source tree's configs/ folder (e.g. "ring.ini").
std::string ConfigPath(const std::string& name);

// A fresh, empty folder for this test (removed and recreated).
std::string TempDir(const std::string& name);

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
  // The last non-empty line of the output (the one-line error message).
  std::string LastLine() const;
};

// Runs a program with arguments, no shell, capturing its output.
CommandResult RunCommand(const std::vector<std::string>& argv);
// The bayon binary built with these tests ($BAYON_BIN).
std::string BayonBin();
// Runs the bayon binary built with these tests ($BAYON_BIN).
CommandResult RunBayon(const std::vector<std::string>& args);
// Runs stock COLMAP ($BAYON_COLMAP or `colmap`).
CommandResult RunColmap(const std::vector<std::string>& args);

// Content hashes of every file under a folder (or of one file).
std::map<std::string, uint64_t> HashTree(const std::string& path);

// A folder built once per build of bayon and shared by the test processes
// that need it (ctest runs every test in its own process, two at a time): the
// first caller runs `build(dir)` under a file lock, later ones reuse the
// result. Keyed by the bayon binary's modification time, so a rebuild makes
// fresh fixtures.
std::string SharedFixture(const std::string& name,
                          const std::function<void(const std::string&)>& build);

// Copies a folder or file.
void CopyTree(const std::string& from, const std::string& to);

// "v1,v2,...": numbers as a comma-separated command-line value, to the last
// digit (e.g. import --camera_params).
std::string CommaSeparated(const std::vector<double>& values);

// Whether BAYON_TEST_STRICT=1 is set (CI sets it): then every skip fails.
bool StrictTests();

}  // namespace testing
}  // namespace bayon

// Skips the test with `reason` (a program or a data folder this machine lacks,
// say on a user's own clone), or, with BAYON_TEST_STRICT=1, fails it with that
// reason: in CI everything is installed and the data is there, so a test that
// cannot run is a broken setup, not a pass. For a TEST body or SetUp().
#define BAYON_SKIP(reason)                                            \
  do {                                                                \
    if (::bayon::testing::StrictTests()) {                            \
      GTEST_FAIL() << "cannot run (BAYON_TEST_STRICT=1): " << reason; \
    }                                                                 \
    GTEST_SKIP() << reason;                                           \
  } while (0)

// Skips (or in CI fails) the test where ../shared/data/<relative> is absent.
#define BAYON_REQUIRE_DATA(relative)                                          \
  do {                                                                        \
    if (::bayon::testing::DataPath(relative).empty()) {                       \
      BAYON_SKIP("shared test data '" << relative                             \
                                      << "' not found (set BAYON_DATA_DIR)"); \
    }                                                                         \
  } while (0)
