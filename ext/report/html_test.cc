// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/html.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdint>

namespace bayon {
namespace {

TEST(Html, EscapesMarkup) {
  EXPECT_EQ(HtmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
}

TEST(Html, Base64MatchesRfc4648) {
  // RFC 4648, section 10.
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\x00", 2)), "/wA=");
}

TEST(Html, FormatsNumbersForPeople) {
  EXPECT_EQ(FormatCount(0), "0");
  EXPECT_EQ(FormatCount(999), "999");
  EXPECT_EQ(FormatCount(1000), "1,000");
  EXPECT_EQ(FormatCount(-1234567), "-1,234,567");
  EXPECT_EQ(FormatFixed(0.12345, 3), "0.123");
  EXPECT_EQ(FormatFixed(-0.0001, 2), "0.00");
  EXPECT_EQ(FormatFixed(std::nan(""), 2), "&ndash;");
  EXPECT_EQ(FormatSignificant(0.012345, 3), "0.0123");
  EXPECT_EQ(FormatSignificant(35.0004, 4), "35.00");
  EXPECT_EQ(FormatSignificant(-1.234e-5, 3),
            "-1.23&times;10<sup>&minus;5</sup>");
  EXPECT_EQ(FormatSignificant(9.996e-5, 3), "1.00&times;10<sup>&minus;4</sup>");
  EXPECT_EQ(FormatSignificant(2.5e7, 2), "2.5&times;10<sup>7</sup>");
  EXPECT_EQ(FormatSignificant(0, 3), "0");
  EXPECT_EQ(FormatSeconds(0.5), "0.50 s");
  EXPECT_EQ(FormatSeconds(75), "75.0 s");
  EXPECT_EQ(FormatSeconds(245), "4 min 05 s");
  EXPECT_EQ(FormatSeconds(3725), "1 h 02 min");
  EXPECT_EQ(FormatPercent(0.1234, 1), "12.3&nbsp;%");
}

TEST(Html, TablesAlignNumbersRight) {
  HtmlTable table({"name", "count"}, "lr");
  EXPECT_TRUE(table.empty());
  table.AddRow({"a", "1"}, "key");
  const std::string html = table.Html("t");
  EXPECT_EQ(html,
            "<table class=\"t\"><thead><tr><th>name</th><th "
            "class=\"num\">count</th></tr></thead><tbody>\n<tr "
            "class=\"key\"><td>a</td><td class=\"num\">1</td></tr>\n"
            "</tbody></table>\n");
}

TEST(Html, JpegDataUriScalesDown) {
  cv::Mat image(300, 1000, CV_8UC3, cv::Scalar(10, 200, 30));
  const std::string uri = JpegDataUri(image, 500, 85);
  const std::string prefix = "data:image/jpeg;base64,";
  ASSERT_EQ(uri.compare(0, prefix.size(), prefix), 0);
  // Decode the base64 back and the JPEG with it.
  std::string bytes;
  // Unsigned: the bits shifted out at the top are meant to be lost.
  int bits = 0;
  uint32_t value = 0;
  for (size_t i = prefix.size(); i < uri.size() && uri[i] != '='; ++i) {
    const std::string alphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    value = value << 6 | static_cast<uint32_t>(alphabet.find(uri[i]));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes += static_cast<char>((value >> bits) & 0xff);
    }
  }
  const cv::Mat decoded = cv::imdecode(
      std::vector<uchar>(bytes.begin(), bytes.end()), cv::IMREAD_COLOR);
  ASSERT_FALSE(decoded.empty());
  EXPECT_EQ(decoded.cols, 500);
  EXPECT_EQ(decoded.rows, 150);
  EXPECT_NEAR(decoded.at<cv::Vec3b>(75, 250)[1], 200, 4);
  EXPECT_EQ(JpegDataUri(cv::Mat(), 500, 85), "");
}

}  // namespace
}  // namespace bayon
