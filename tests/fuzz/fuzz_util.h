// SPDX-License-Identifier: BSD-3-Clause
//
// Helpers shared by the libFuzzer harnesses of tests/fuzz: a scratch folder
// for the files a reader must find on disk, the split of one input into
// several files, a cursor over the input for structured harnesses, and the
// rule every harness follows: bad input may throw InputError and nothing
// else. Anything that escapes (another exception, a crash, a sanitizer
// report, an allocation over libFuzzer's limit) is a finding.
#pragma once

#include "ext/core/errors.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace bayon {
class Database;
}

namespace bayon::fuzz {

// $TMPDIR/bayon-fuzz-<pid> (created on first use, removed at exit).
const std::string& ScratchDir();
// ScratchDir()/name, after removing whatever was there.
std::string FreshPath(const std::string& name);
void WriteFile(const std::string& path, const std::string& data);

// Splits the input at lines reading exactly kSplit into `num_parts` parts
// (missing parts are empty; the last part takes the rest).
constexpr const char kSplit[] = "\n=====\n";
std::vector<std::string> SplitInput(const uint8_t* data,
                                    size_t size,
                                    int num_parts);

// Reads values off the front of the input; past its end every value is 0.
class InputCursor {
 public:
  InputCursor(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  size_t remaining() const { return size_ - pos_; }
  uint8_t Byte();
  uint16_t Uint16();
  int64_t Int64();
  double Double();
  std::string Bytes(size_t count);  // fewer at the end of the input

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

// Runs `read` and swallows InputError: the one way a reader may refuse.
template <typename Function>
void Expect(Function&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
}

// Every read bayon makes of a database: COLMAP's tables through Database
// (each camera, image, keypoints, descriptors, matches and geometry, in both
// image orders) and each bayon_* table. Each read may fail on its own.
void ReadWholeDatabase(Database* database);

}  // namespace bayon::fuzz
