// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/html.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>

namespace bayon {
namespace {

constexpr char kDash[] = "&ndash;";

}  // namespace

std::string HtmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        // Control characters are not allowed in XML 1.0 (inline SVG).
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\n' || c == '\t') {
          out += c;
        }
    }
  }
  return out;
}

std::string Base64(const std::string& bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t triple = uint32_t(uint8_t(bytes[i])) << 16 |
                            uint32_t(uint8_t(bytes[i + 1])) << 8 |
                            uint8_t(bytes[i + 2]);
    out += kAlphabet[triple >> 18];
    out += kAlphabet[(triple >> 12) & 63];
    out += kAlphabet[(triple >> 6) & 63];
    out += kAlphabet[triple & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const uint32_t triple = uint32_t(uint8_t(bytes[i])) << 16 |
                            (two ? uint32_t(uint8_t(bytes[i + 1])) << 8 : 0);
    out += kAlphabet[triple >> 18];
    out += kAlphabet[(triple >> 12) & 63];
    out += two ? kAlphabet[(triple >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string JpegDataUri(const cv::Mat& bgr, int max_size_px, int quality) {
  if (bgr.empty()) return "";
  cv::Mat image = bgr;
  const int longest = std::max(image.cols, image.rows);
  if (longest > max_size_px) {
    const double scale = static_cast<double>(max_size_px) / longest;
    cv::resize(bgr, image, cv::Size(), scale, scale, cv::INTER_AREA);
  }
  std::vector<uchar> bytes;
  cv::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  return "data:image/jpeg;base64," +
         Base64(std::string(bytes.begin(), bytes.end()));
}

std::string FormatCount(int64_t value) {
  std::string digits = std::to_string(value < 0 ? -value : value);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return value < 0 ? "-" + out : out;
}

std::string FormatFixed(double value, int decimals) {
  if (!std::isfinite(value)) return kDash;
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  std::string text = buffer;
  if (text.find_first_not_of("-0.") == std::string::npos && text[0] == '-') {
    text.erase(0, 1);  // "-0.00"
  }
  return text;
}

std::string FormatSignificant(double value, int significant) {
  if (!std::isfinite(value)) return kDash;
  if (value == 0) return "0";
  const double magnitude = std::abs(value);
  if (magnitude >= 1e-3 && magnitude < 1e6) {
    const int exponent = static_cast<int>(std::floor(std::log10(magnitude)));
    return FormatFixed(value, std::max(0, significant - 1 - exponent));
  }
  int exponent = static_cast<int>(std::floor(std::log10(magnitude)));
  double mantissa = value / std::pow(10.0, exponent);
  // 9.996e-5 with three digits is 1.00e-4.
  if (std::abs(std::stod(FormatFixed(mantissa, significant - 1))) >= 10) {
    mantissa /= 10;
    ++exponent;
  }
  return FormatFixed(mantissa, significant - 1) + "&times;10<sup>" +
         (exponent < 0 ? "&minus;" + std::to_string(-exponent)
                       : std::to_string(exponent)) +
         "</sup>";
}

std::string FormatSeconds(double seconds) {
  if (!std::isfinite(seconds)) return kDash;
  if (seconds < 10) return FormatFixed(seconds, 2) + " s";
  if (seconds < 120) return FormatFixed(seconds, 1) + " s";
  char buffer[64];
  const long total = std::lround(seconds);
  if (total < 3600) {
    std::snprintf(
        buffer, sizeof(buffer), "%ld min %02ld s", total / 60, total % 60);
  } else {
    std::snprintf(buffer,
                  sizeof(buffer),
                  "%ld h %02ld min",
                  total / 3600,
                  total % 3600 / 60);
  }
  return buffer;
}

std::string FormatPercent(double fraction, int decimals) {
  if (!std::isfinite(fraction)) return kDash;
  return FormatFixed(100 * fraction, decimals) + "&nbsp;%";
}

HtmlTable::HtmlTable(const std::vector<std::string>& header,
                     const std::string& align)
    : align_(align) {
  head_ = "<thead><tr>";
  for (size_t i = 0; i < header.size(); ++i) {
    head_ += Open("th", i) + header[i] + "</th>";
  }
  head_ += "</tr></thead>";
}

std::string HtmlTable::Open(const char* tag, size_t column) const {
  const char align = column < align_.size() ? align_[column] : 'l';
  const std::string open = std::string("<") + tag;
  if (align == 'r') return open + " class=\"num\">";
  if (align == 'n') return open + " class=\"nowrap\">";
  return open + ">";
}

void HtmlTable::AddRow(const std::vector<std::string>& cells,
                       const std::string& row_class) {
  body_ += row_class.empty() ? "<tr>" : "<tr class=\"" + row_class + "\">";
  for (size_t i = 0; i < cells.size(); ++i) {
    body_ += Open("td", i) + cells[i] + "</td>";
  }
  body_ += "</tr>\n";
  ++num_rows_;
}

std::string HtmlTable::Html(const std::string& table_class) const {
  return (table_class.empty() ? "<table>"
                              : "<table class=\"" + table_class + "\">") +
         head_ + "<tbody>\n" + body_ + "</tbody></table>\n";
}

void KeyValueTable::Add(const std::string& name,
                        const std::string& value_html) {
  rows_ += "<tr><th>" + name + "</th><td class=\"num\">" + value_html +
           "</td></tr>\n";
}

std::string KeyValueTable::Html() const {
  return "<table class=\"kv\"><tbody>\n" + rows_ + "</tbody></table>\n";
}

}  // namespace bayon
