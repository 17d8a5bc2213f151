// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon report` end to end on the temple ring (16 x 640x480, real
// photographs with Middlebury's calibration as truth): the workspace
// `bayon pipeline` makes of it (tests/temple_fixture.h), then the report: one
// self-contained page with every section, well-formed charts, figures that
// agree with adjustment.json, a page that a real browser (headless chromium)
// draws, and bad input refused in one line.
#include "ext/colmap/model_io.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <regex>
#include <set>
#include <stdexcept>

#include "tests/temple_fixture.h"
#include "tests/testing.h"
#include "tests/xml_testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

using Json = nlohmann::ordered_json;

// Every <svg>...</svg> element of a page.
std::vector<std::string> SvgElements(const std::string& html) {
  std::vector<std::string> svgs;
  for (size_t start = html.find("<svg"); start != std::string::npos;
       start = html.find("<svg", start + 1)) {
    const size_t end = html.find("</svg>", start);
    if (end == std::string::npos) break;
    svgs.push_back(html.substr(start, end + 6 - start));
  }
  return svgs;
}

// The values of every `name="..."` attribute (std::regex recurses per
// character and overflows the stack on the long data URIs).
std::vector<std::string> AttributeValues(const std::string& html,
                                         const std::string& name) {
  std::vector<std::string> values;
  const std::string key = " " + name + "=\"";
  for (size_t at = html.find(key); at != std::string::npos;
       at = html.find(key, at + 1)) {
    const size_t start = at + key.size();
    const size_t end = html.find('"', start);
    if (end == std::string::npos) break;
    values.push_back(html.substr(start, end - start));
  }
  return values;
}

// The table row (<tr>...</tr>) that contains `text`; empty if none.
std::string RowWith(const std::string& html, const std::string& text) {
  const size_t at = html.find(text);
  if (at == std::string::npos) return "";
  const size_t start = html.rfind("<tr", at);
  const size_t end = html.find("</tr>", at);
  if (start == std::string::npos || end == std::string::npos) return "";
  return html.substr(start, end + 5 - start);
}

std::string Fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string FindChromium() {
  if (const char* env = std::getenv("BAYON_CHROMIUM")) return env;
  for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser"}) {
    if (fs::exists(path)) return path;
  }
  return "";
}

TEST(Report, TempleRingPageIsCompleteAndSelfContained) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string ws = testing::TemplePipelineWorkspace();
  const std::string dir = testing::TempDir("report_test/page");
  const std::string page = dir + "/report.html";
  const testing::CommandResult result = testing::RunBayon(
      {"report", "--workspace_path", ws, "--output_path", page});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::cout << result.output;
  EXPECT_NE(result.output.find("16 images"), std::string::npos);
  EXPECT_NE(result.output.find("not run: Comparison with stock COLMAP)"),
            std::string::npos)
      << result.output;
  EXPECT_EQ(result.output.find("could not show"), std::string::npos);
  const std::string html = ReadFileToString(page);
  EXPECT_LT(html.size(), 3u << 20);

  // Every section, in order, and only the comparison not run.
  size_t at = 0;
  for (const char* id : {"pipeline",
                         "network",
                         "tiepoints",
                         "residuals",
                         "calibration",
                         "precision",
                         "dense",
                         "edit",
                         "mesh",
                         "texture",
                         "renders",
                         "colmap",
                         "evaluation"}) {
    const size_t found = html.find("<section id=\"" + std::string(id) + "\"");
    ASSERT_NE(found, std::string::npos) << id;
    EXPECT_GT(found, at) << id << " out of order";
    at = found;
    EXPECT_NE(html.find("<a href=\"#" + std::string(id) + "\""),
              std::string::npos)
        << id;
  }
  EXPECT_NE(html.find("<section id=\"colmap\" class=\"absent\">"),
            std::string::npos);
  EXPECT_EQ(html.find("class=\"problem\""), std::string::npos);

  // Self-contained: no script, stylesheet or picture from anywhere; the
  // only link out of the page is the viewer, relative, and it exists.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(html.find("url("), std::string::npos);
  int num_pictures = 0;
  for (const std::string& src : AttributeValues(html, "src")) {
    EXPECT_EQ(src.rfind("data:image/jpeg;base64,", 0), 0u) << src.substr(0, 80);
    ++num_pictures;
  }
  EXPECT_GE(num_pictures, 4);  // textured, shaded, wireframe, anaglyph, atlas
  std::set<std::string> links;
  for (const std::string& href : AttributeValues(html, "href")) {
    if (href[0] == '#') continue;
    EXPECT_EQ(href.find("//"), std::string::npos) << href;
    links.insert(href);
  }
  ASSERT_EQ(links.size(), 1u);
  EXPECT_TRUE(fs::equivalent(fs::path(dir) / *links.begin(),
                             fs::path(ws) / "viewer" / "index.html"))
      << *links.begin();

  // Well-formed charts: plan and side view, time per stage, observations
  // per image, rays, a frame per photograph, four residual histograms, the
  // residual field, |t|, dense (3), faces per image.
  const std::vector<std::string> svgs = SvgElements(html);
  EXPECT_GE(svgs.size(), 2u + 1 + 2 + 16 + 4 + 1 + 1 + 3 + 1);
  for (const std::string& svg : svgs) {
    EXPECT_EQ(testing::XmlWellFormednessError(svg), "") << svg.substr(0, 400);
  }
  for (int i = 1; i <= 16; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), ">templeSR%04d</text>", i);
    EXPECT_NE(html.find(name), std::string::npos) << name;
  }

  // The figures agree with adjust's own: the residuals the page recomputes
  // from the model, n, r/n, sigma0 and every estimated parameter.
  const Json adjustment =
      Json::parse(ReadFileToString(ws + "/sparse/adjusted/adjustment.json"));
  const Json& s = adjustment["statistics"];
  const std::string all_row = RowWith(html, "<td>all</td>");
  std::smatch all;
  ASSERT_TRUE(std::regex_search(
      all_row,
      all,
      std::regex("<td>all</td><td class=\"num\">([0-9,]+)</td><td "
                 "class=\"num\">([0-9.]+)</td><td class=\"num\">([0-9.]+)"
                 "</td>")))
      << all_row;
  EXPECT_EQ(std::regex_replace(all.str(1), std::regex(","), ""),
            std::to_string(s["n_image_coordinates"].get<int>() / 2));
  EXPECT_NEAR(
      std::stod(all.str(2)), s["residual_rms_px"][0].get<double>(), 0.002);
  EXPECT_NEAR(
      std::stod(all.str(3)), s["residual_rms_px"][1].get<double>(), 0.002);
  EXPECT_NE(html.find(Fixed(s["r_over_n"].get<double>(), 3)),
            std::string::npos);
  EXPECT_NE(html.find(Fixed(s["sigma0_px"].get<double>(), 3) + " px"),
            std::string::npos);
  for (const Json& p : adjustment["self_calibration"]["parameters"]) {
    const std::string name = p["name"].get<std::string>();
    const bool significant =
        std::abs(p["t"].get<double>()) >
        adjustment["self_calibration"]["significance_t"].get<double>();
    const std::string row = RowWith(html, "<td><b>" + name + "</b></td>");
    ASSERT_FALSE(row.empty()) << name;
    if (significant) {
      EXPECT_EQ(row.rfind("<tr class=\"significant\">", 0), 0u) << row;
      EXPECT_NE(row.find("estimated, significant"), std::string::npos) << row;
    }
  }
  // The paper's column beside ours.
  EXPECT_NE(html.find("20.3 &micro;m"), std::string::npos);
}

TEST(Report, ChromiumDrawsThePage) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    BAYON_SKIP(
        "chromium not installed (scripts/setup.sh installs it; or set "
        "BAYON_CHROMIUM)");
  }
  const std::string ws = testing::TemplePipelineWorkspace();
  const std::string dir = testing::TempDir("report_test/chromium");
  const std::string page = dir + "/report.html";
  ASSERT_EQ(testing::RunBayon(
                {"report", "--workspace_path", ws, "--output_path", page})
                .exit_code,
            0);
  const std::string png = dir + "/report.png";
  const testing::CommandResult result =
      testing::RunCommand({chromium,
                           "--headless",
                           "--no-sandbox",
                           "--disable-gpu",
                           "--disable-background-networking",
                           "--disable-component-update",
                           "--disable-sync",
                           "--disable-extensions",
                           "--no-first-run",
                           "--user-data-dir=" + dir + "/profile",
                           "--hide-scrollbars",
                           "--window-size=1200,4000",
                           "--virtual-time-budget=3000",
                           "--screenshot=" + png,
                           "file://" + fs::absolute(page).string()});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const cv::Mat bgr = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(bgr.empty()) << result.output;
  std::cout << "screenshot: " << png << std::endl;
  // Not blank: text, tables and charts cover a good part of the page, in
  // the charts' colours (the cameras' red, the bars' blue).
  int num_ink = 0, num_red = 0, num_blue = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      if (p[0] + p[1] + p[2] < 3 * 200) ++num_ink;
      if (p[2] > 180 && p[1] < 80 && p[0] < 80) ++num_red;         // #d62728
      if (p[0] > 140 && p[1] > 100 && p[1] < 140 && p[2] < 100) {  // #4c78a8
        ++num_blue;
      }
    }
  }
  const double total = static_cast<double>(bgr.total());
  EXPECT_GT(num_ink / total, 0.02);
  EXPECT_GT(num_red, 200);
  EXPECT_GT(num_blue, 2000);
}

TEST(Report, WritesIntoTheWorkspaceAndRefusesToOverwrite) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string dir = testing::TempDir("report_test/default");
  const std::string ws = dir + "/ws";
  // The parts the page reads (not the photographs or the database's size).
  testing::CopyTree(testing::TemplePipelineWorkspace(), ws);
  fs::remove(ws + "/report.html");  // the pipeline's own
  auto result = testing::RunBayon({"report", "--workspace_path", ws});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(fs::is_regular_file(ws + "/report.html"));
  EXPECT_TRUE(fs::is_regular_file(ws + "/logs/report.log"));
  EXPECT_NE(ReadFileToString(ws + "/report.html")
                .find("<a href=\"viewer/index.html\">"),
            std::string::npos);
  const uint64_t hash = FileHash(ws + "/report.html");
  result = testing::RunBayon({"report", "--workspace_path", ws});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(ws + "/report.html"), std::string::npos)
      << result.output;
  EXPECT_EQ(FileHash(ws + "/report.html"), hash);
  result = testing::RunBayon(
      {"report", "--workspace_path", ws, "--overwrite", "1", "--title", "T"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(ReadFileToString(ws + "/report.html").find("<title>T</title>"),
            std::string::npos);
}

TEST(Report, BadInputIsRefusedInOneLine) {
  const std::string dir = testing::TempDir("report_test/bad");
  // No workspace.
  auto result =
      testing::RunBayon({"report", "--workspace_path", dir + "/missing"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(dir + "/missing"), std::string::npos)
      << result.output;
  // A workspace without the adjusted model.
  fs::create_directories(dir + "/ws/sparse/initial");
  result = testing::RunBayon({"report", "--workspace_path", dir + "/ws"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("sparse/adjusted"), std::string::npos);
  EXPECT_NE(result.LastLine().find("run bayon pipeline or bayon adjust first"),
            std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(dir + "/ws/report.html"));
  // An output folder that does not exist.
  fs::create_directories(dir + "/ws/sparse/adjusted");
  result = testing::RunBayon({"report",
                              "--workspace_path",
                              dir + "/ws",
                              "--output_path",
                              dir + "/nowhere/report.html"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(dir + "/nowhere"), std::string::npos)
      << result.output;
  // An adjusted folder without a model.
  result = testing::RunBayon({"report", "--workspace_path", dir + "/ws"});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("sparse/adjusted"), std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(dir + "/ws/report.html"));
}

}  // namespace
}  // namespace bayon
