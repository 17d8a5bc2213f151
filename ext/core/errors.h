// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace bayon {

// Bad user input or data: a flag out of range, a missing or corrupt file, a
// database of the wrong kind. The `bayon` tool prints the message as one line
// and exits with code 2. Messages name the path or record and what was
// expected, e.g. "images/0042.jpg: listed in images.bin but missing on disk".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message)
      : std::runtime_error(message) {}
};

// A valid run that produced nothing usable (exit code 1), e.g. no image pair
// could be oriented. Partial failures are reported, not thrown.
class RunFailure : public std::runtime_error {
 public:
  explicit RunFailure(const std::string& message)
      : std::runtime_error(message) {}
};

// Concatenates its arguments with operator<<.
template <typename... Args>
std::string StrCat(Args&&... args) {
  std::ostringstream stream;
  (stream << ... << std::forward<Args>(args));
  return stream.str();
}

template <typename... Args>
[[noreturn]] void ThrowInputError(Args&&... args) {
  throw InputError(StrCat(std::forward<Args>(args)...));
}

// Throws InputError "<name> must be <rule> (got <value>)" unless `ok`.
template <typename T>
void CheckOption(bool ok, const char* name, const char* rule, const T& value) {
  if (!ok) ThrowInputError(name, " must be ", rule, " (got ", value, ")");
}

}  // namespace bayon
