// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/string_printf.h"

#include <gtest/gtest.h>

namespace bayon {
namespace {

TEST(StringPrintf, FormatsAsPrintf) {
  EXPECT_EQ(StringPrintf("%-6s|%5.2f|%d", "ab", 3.14159, -7),
            "ab    | 3.14|-7");
  EXPECT_EQ(StringPrintf("%s", ""), "");
}

TEST(StringPrintf, NeverTruncates) {
  const std::string long_text(5000, 'x');
  const std::string printed = StringPrintf("<%s>", long_text.c_str());
  ASSERT_EQ(printed.size(), 5002u);
  EXPECT_EQ(printed.substr(0, 2), "<x");
  EXPECT_EQ(printed.back(), '>');
}

}  // namespace
}  // namespace bayon
