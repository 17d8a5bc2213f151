// SPDX-License-Identifier: BSD-3-Clause
//
// printf into a std::string, of any length: the tables that the commands
// print are built as strings, so that a library can return them and a test
// can read them.
#pragma once

#include <string>

namespace bayon {

std::string StringPrintf(const char* format, ...)
    __attribute__((format(printf, 1, 2)));

}  // namespace bayon
