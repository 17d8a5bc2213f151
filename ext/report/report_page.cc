// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/report_page.h"

#include "ext/core/statistics.h"
#include "ext/report/html.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace bayon {
namespace report {

namespace fs = std::filesystem;

std::string Page::Figure(const std::string& svg, const std::string& caption) {
  ++num_charts_;
  return "<figure>" + svg +
         (caption.empty() ? "" : "<figcaption>" + caption + "</figcaption>") +
         "</figure>\n";
}

std::string Page::Chart(const std::string& svg) {
  ++num_charts_;
  return svg;
}

std::string Page::Picture(const fs::path& path,
                          const std::string& alt,
                          int max_size_px,
                          const std::string& css_class) {
  const cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (bgr.empty()) {
    Problem(path.filename().string() + ": not a readable image");
    return "";
  }
  ++num_pictures_;
  return "<img class=\"" + css_class + "\" alt=\"" + HtmlEscape(alt) +
         "\" src=\"" + JpegDataUri(bgr, max_size_px, options_.jpeg_quality) +
         "\">";
}

std::string NotRun(const std::string& what) {
  return "<p class=\"not-run\">Not run: " + what + ".</p>\n";
}

// The "not run" or "unreadable" line for a missing or broken file; empty
// when the file is fine.
std::string FileStatus(const JsonFile& file,
                       const std::string& command,
                       Page* page) {
  if (!file.exists) {
    return NotRun("no <code>" + HtmlEscape(file.relative_path) + "</code> (" +
                  command + ")");
  }
  if (!file.error.empty()) {
    page->Problem(file.relative_path + ": " + file.error);
    return "<p class=\"problem\">Could not read <code>" +
           HtmlEscape(file.relative_path) +
           "</code>: " + HtmlEscape(file.error) + "</p>\n";
  }
  return "";
}

std::string Paragraph(const std::string& html) {
  return "<p>" + html + "</p>\n";
}

std::string ImageStem(const std::string& name) {
  return fs::path(name).stem().string();
}

// Images of the model in name order.
std::vector<const Image*> ImagesByName(const Scene& model) {
  std::vector<const Image*> images;
  for (const auto& [image_id, image] : model.images) images.push_back(&image);
  std::sort(images.begin(), images.end(), [](const Image* a, const Image* b) {
    return a->name < b->name;
  });
  return images;
}

double Rms(const std::vector<double>& values) {
  double sum = 0;
  int count = 0;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    sum += v * v;
    ++count;
  }
  return count > 0 ? std::sqrt(sum / count) : kNaN;
}

double Median(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(),
                              values.end(),
                              [](double v) { return !std::isfinite(v); }),
               values.end());
  return values.empty() ? kNaN : bayon::Median(std::move(values));
}

std::string Count(int64_t value) {
  return value < 0 ? "&ndash;" : FormatCount(value);
}
std::string CountNumber(double value) {
  return std::isfinite(value) ? Count(std::llround(value)) : Count(-1);
}
std::string CountOf(const Json& json, const char* key) {
  return Count(Integer(json, key));
}

std::string Triple(const Json& values, int decimals) {
  if (!values.is_array() || values.size() != 3) return "&ndash;";
  return FormatFixed(NumberAt(values, 0), decimals) + " / " +
         FormatFixed(NumberAt(values, 1), decimals) + " / " +
         FormatFixed(NumberAt(values, 2), decimals);
}

}  // namespace report
}  // namespace bayon
