// SPDX-License-Identifier: BSD-3-Clause
//
// Pieces of a self-contained HTML page: escaping, numbers formatted for
// people (thousands separated, units, powers of ten), tables, and pictures
// embedded as base64 data URIs.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

// &, <, >, " and ' as entities; control characters other than tab and
// newline, which XML 1.0 (inline SVG) does not allow, are dropped.
std::string HtmlEscape(const std::string& text);

std::string Base64(const std::string& bytes);

// A picture as a JPEG data URI ("data:image/jpeg;base64,..."), scaled down
// (area interpolation) so that its longer side is at most `max_size_px`.
// Empty for an empty image.
std::string JpegDataUri(const cv::Mat& bgr, int max_size_px, int quality);

// Numbers for people. Non-finite values print as an en dash.
// 1234567 -> "1,234,567".
std::string FormatCount(int64_t value);
// Fixed decimals: (0.12345, 3) -> "0.123".
std::string FormatFixed(double value, int decimals);
// `significant` digits, in scientific notation as HTML ("1.23&times;10<sup>
// -5</sup>") when the value is below 1e-3 or from 1e6 in magnitude.
std::string FormatSignificant(double value, int significant);
// Seconds as "0.42 s", "12.3 s", "4 min 05 s", "1 h 02 min".
std::string FormatSeconds(double seconds);
// A fraction as a percentage: (0.1234, 1) -> "12.3 %".
std::string FormatPercent(double fraction, int decimals);

// A table written row by row; cells are HTML (escape text first).
class HtmlTable {
 public:
  // `align`: one letter per column, 'l' (text), 'n' (text kept on one
  // line) or 'r' (numbers: right-aligned, on one line).
  HtmlTable(const std::vector<std::string>& header, const std::string& align);

  void AddRow(const std::vector<std::string>& cells,
              const std::string& row_class = "");
  bool empty() const { return num_rows_ == 0; }
  std::string Html(const std::string& table_class = "") const;

 private:
  std::string Open(const char* tag, size_t column) const;

  std::string align_;
  std::string head_;
  std::string body_;
  int num_rows_ = 0;
};

// A two-column table of quantities: name, value (HTML).
class KeyValueTable {
 public:
  void Add(const std::string& name, const std::string& value_html);
  bool empty() const { return rows_.empty(); }
  std::string Html() const;

 private:
  std::string rows_;
};

}  // namespace bayon
