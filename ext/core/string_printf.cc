// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/string_printf.h"

#include <cstdarg>
#include <cstdio>

namespace bayon {

std::string StringPrintf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list sizing;
  va_copy(sizing, args);
  const int size = std::vsnprintf(nullptr, 0, format, sizing);
  va_end(sizing);
  std::string text(size > 0 ? size : 0, '\0');
  if (size > 0) std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  return text;
}

}  // namespace bayon
