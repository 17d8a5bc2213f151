// SPDX-License-Identifier: BSD-3-Clause
//
// Inside `bayon report` (workspace_report.h): the sections of the page and
// what they share: the page's counters (charts, pictures, problems), the
// "not run" line, colours, and small formatting helpers.
#pragma once

#include "ext/core/scene.h"
#include "ext/report/report_workspace.h"
#include "ext/report/workspace_report.h"

#include <filesystem>
#include <string>
#include <vector>

namespace bayon {
namespace report {

// Keypoint tracks and LSM tie points in every chart.
constexpr char kTrackColor[] = "#4c78a8";
constexpr char kTieColor[] = "#f58518";
// Tableau 10 and four more, for categories (reject reasons).
constexpr const char* kPalette[] = {"#4c78a8",
                                    "#f58518",
                                    "#e45756",
                                    "#72b7b2",
                                    "#54a24b",
                                    "#eeca3b",
                                    "#b279a2",
                                    "#ff9da6",
                                    "#9d755d",
                                    "#bab0ac",
                                    "#8cd17d",
                                    "#b6992d",
                                    "#499894",
                                    "#d37295"};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

// One section of the page.
struct Section {
  std::string id;
  std::string title;
  bool ran = true;        // false: shown as "not run" in the contents
  std::string html = "";  // the body, without the heading
};

// Collects what the sections produce.
class Page {
 public:
  explicit Page(const WorkspaceReportOptions& options) : options_(options) {}

  const WorkspaceReportOptions& options() const { return options_; }

  // A chart in a <figure> with a caption (HTML).
  std::string Figure(const std::string& svg, const std::string& caption = "");
  // A chart without a figure (small multiples).
  std::string Chart(const std::string& svg);
  // A picture from disk, scaled down and embedded as JPEG; empty (and a
  // problem noted) if it cannot be read.
  std::string Picture(const std::filesystem::path& path,
                      const std::string& alt,
                      int max_size_px,
                      const std::string& css_class);
  // Something that exists but could not be read or shown.
  void Problem(const std::string& text) { problems_.push_back(text); }

  int num_charts() const { return num_charts_; }
  int num_pictures() const { return num_pictures_; }
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  const WorkspaceReportOptions& options_;
  int num_charts_ = 0;
  int num_pictures_ = 0;
  std::vector<std::string> problems_;
};

// "<p class=not-run>Not run: <what>.</p>"
std::string NotRun(const std::string& what);
// The "not run" line for a missing file (`command` says what makes it),
// or the "could not read" line for a broken one; empty for a good file.
std::string FileStatus(const JsonFile& file,
                       const std::string& command,
                       Page* page);
std::string Paragraph(const std::string& html);

// "29,370", or a dash for a negative count or NaN.
std::string Count(int64_t value);
std::string CountNumber(double value);
std::string CountOf(const Json& json, const char* key);
// "5.80 / 3.70 / 8.80" from a JSON array of three numbers.
std::string Triple(const Json& values, int decimals);

// "images/IMG_0001.JPG" -> "IMG_0001".
std::string ImageStem(const std::string& name);
// The model's images in name order.
std::vector<const Image*> ImagesByName(const Scene& model);
// Of the finite values; NaN when there are none.
double Rms(const std::vector<double>& values);
double Median(std::vector<double> values);

}  // namespace report
}  // namespace bayon
