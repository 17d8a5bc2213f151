// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon viewer` end to end: a textured box written by the model exporter
// (ext/render/model_export.h) becomes a web page, and a real browser (Debian
// chromium, headless, WebGL on SwiftShader) opens it from file://. The page
// must come up without console errors, draw the model in the atlas' colours,
// and each display mode must draw a different picture.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/render/model_export.h"
#include "ext/render/model_views.h"
#include "ext/render/views.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <sstream>

#include "tests/testing.h"

namespace bayon {
namespace {

namespace fs = std::filesystem;
using testing::RunBayon;
using testing::RunCommand;
using testing::TempDir;

// The box's faces and their colours (RGB), one cell each of a 3 x 2 atlas.
struct BoxFace {
  Eigen::Vector3d normal, u, v;  // outward normal; u x v = normal
  cv::Vec3b rgb;
  const char* name;
};
const std::array<BoxFace, 6> kBoxFaces = {{
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {220, 40, 40}, "red +x"},
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}, {40, 170, 40}, "green -x"},
    {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, {40, 70, 220}, "blue +y"},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}, {230, 200, 40}, "yellow -y"},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {200, 40, 200}, "magenta +z"},
    {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}, {40, 200, 210}, "cyan -z"},
}};
// The page's background (tools/viewer/src/viewer.js), RGB.
const cv::Vec3b kBackground(0x26, 0x2a, 0x31);

// A 2 x 1 x 3 box (x, y, z; z up), each face one colour of the atlas: the
// faces seen from the viewer's default view (azimuth 30, elevation 20 from
// +x towards +y) are red, blue and magenta; green, yellow and cyan face away.
TexturedModel ColouredBox() {
  constexpr int kCell = 32;
  TexturedModel model;
  model.atlas = cv::Mat(2 * kCell, 3 * kCell, CV_8UC3);
  const Eigen::Vector3d half(1.0, 0.5, 1.5);
  TriangleMesh& mesh = model.mesh;
  for (size_t f = 0; f < kBoxFaces.size(); ++f) {
    const BoxFace& face = kBoxFaces[f];
    const int column = f % 3, row = f / 3;
    const cv::Vec3b& c = face.rgb;
    model.atlas(cv::Rect(column * kCell, row * kCell, kCell, kCell))
        .setTo(cv::Scalar(c[2], c[1], c[0]));
    // The cell's centre in texture coordinates (v up from the bottom row).
    const Eigen::Vector2f centre((column + 0.5f) / 3, 1 - (row + 0.5f) / 2);
    const int base = int(mesh.vertices.positions.size());
    const std::array<std::array<int, 2>, 4> corners = {
        {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
    std::array<Eigen::Vector2f, 4> uv;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p =
          face.normal + corners[k][0] * face.u + corners[k][1] * face.v;
      mesh.vertices.positions.push_back(p.cwiseProduct(half));
      uv[k] = centre + 0.3f * Eigen::Vector2f(corners[k][0] / 3.0f,
                                              corners[k][1] / 2.0f);
    }
    mesh.faces.emplace_back(base, base + 1, base + 2);
    mesh.face_texcoords.push_back({uv[0], uv[1], uv[2]});
    mesh.faces.emplace_back(base, base + 2, base + 3);
    mesh.face_texcoords.push_back({uv[0], uv[2], uv[3]});
  }
  return model;
}

// The .glb of the box, as bayon texture writes it.
std::string WriteBoxGlb(const std::string& dir) {
  ModelExportOptions options;
  options.stem = "box";
  options.obj = options.ply = options.vrml = false;
  for (const std::string& path :
       WriteTexturedModel(ColouredBox(), dir, options)) {
    if (fs::path(path).extension() == ".glb") return path;
  }
  ADD_FAILURE() << "WriteTexturedModel wrote no .glb";
  return "";
}

// Debian's chromium, or $BAYON_CHROMIUM; empty if there is none.
std::string FindChromium() {
  if (const char* env = std::getenv("BAYON_CHROMIUM")) return env;
  for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser"}) {
    if (fs::exists(path)) return path;
  }
  return "";
}

struct PageRun {
  std::string body_tag;  // <body ...> as the page left it
  std::string log;       // the browser's stderr, console messages included
  cv::Mat rgb;           // the screenshot, RGB
};

// The value of an attribute in an HTML tag, or empty.
std::string Attribute(const std::string& tag, const std::string& name) {
  std::smatch match;
  if (std::regex_search(tag, match, std::regex(" " + name + "=\"([^\"]*)\""))) {
    return match[1];
  }
  return "";
}

// Opens the page in headless chromium (a fresh profile each time, WebGL on
// SwiftShader, no network services), lets it run for a few seconds of virtual
// time, and returns its final <body> tag and a screenshot (kept as
// <work_dir>/<name>.png for a person to look at).
PageRun OpenPageOnce(const std::string& chromium,
                     const std::string& html_path,
                     const std::string& query,
                     const std::string& work_dir,
                     const std::string& name) {
  const std::string profile = work_dir + "/profile";
  const std::string png = work_dir + "/" + name + ".png";
  fs::remove_all(profile);
  fs::remove(png);
  const testing::CommandResult result =
      RunCommand({chromium,
                  "--headless",
                  "--no-sandbox",
                  "--disable-gpu",
                  "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader",
                  "--disable-background-networking",
                  "--disable-component-update",
                  "--disable-sync",
                  "--disable-extensions",
                  "--no-first-run",
                  "--user-data-dir=" + profile,
                  "--enable-logging=stderr",
                  "--v=0",
                  "--hide-scrollbars",
                  "--window-size=640,480",
                  "--virtual-time-budget=8000",
                  "--dump-dom",
                  "--screenshot=" + png,
                  "file://" + fs::absolute(html_path).string() + query});
  PageRun run;
  run.log = result.output;
  std::smatch match;
  if (std::regex_search(result.output, match, std::regex("<body[^>]*>"))) {
    run.body_tag = match.str();
  }
  const cv::Mat bgr = cv::imread(png, cv::IMREAD_COLOR);
  if (!bgr.empty()) cv::cvtColor(bgr, run.rgb, cv::COLOR_BGR2RGB);
  EXPECT_EQ(result.exit_code, 0) << result.output.substr(0, 4000);
  EXPECT_FALSE(run.rgb.empty()) << "no screenshot for " << query;
  return run;
}

// Chromium dumps the DOM when the virtual time runs out, which does not wait
// for work off the main thread (decoding the texture): on a busy machine the
// page may still be loading then, so it is opened again, three times at most.
PageRun OpenPage(const std::string& chromium,
                 const std::string& html_path,
                 const std::string& query,
                 const std::string& work_dir,
                 const std::string& name) {
  PageRun run;
  for (int attempt = 0; attempt < 3; ++attempt) {
    run = OpenPageOnce(chromium, html_path, query, work_dir, name);
    if (Attribute(run.body_tag, "data-status") != "loading") break;
  }
  return run;
}

// Console messages that report errors: uncaught exceptions and the page's own
// "bayon viewer:" messages (chromium logs every console level as INFO, so
// the page also counts console.error calls in data-errors).
std::vector<std::string> ConsoleErrors(const std::string& log) {
  std::vector<std::string> errors;
  std::istringstream stream(log);
  for (std::string line; std::getline(stream, line);) {
    if (line.find(":CONSOLE") == std::string::npos) continue;
    if (line.find("Uncaught") != std::string::npos ||
        line.find("bayon viewer:") != std::string::npos) {
      errors.push_back(line);
    }
  }
  return errors;
}

int ColourDistance(const cv::Vec3b& a, const cv::Vec3b& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

// The part of the screenshot the page's controls do not cover: below the mode
// buttons, above the info line.
cv::Mat Canvas(const cv::Mat& rgb) {
  return rgb(cv::Range(64, rgb.rows - 28), cv::Range::all());
}

// Pixels that are not the background.
cv::Mat ModelMask(const cv::Mat& canvas) {
  cv::Mat mask(canvas.size(), CV_8U);
  for (int y = 0; y < canvas.rows; ++y) {
    for (int x = 0; x < canvas.cols; ++x) {
      mask.at<uint8_t>(y, x) =
          ColourDistance(canvas.at<cv::Vec3b>(y, x), kBackground) > 30 ? 255
                                                                       : 0;
    }
  }
  return mask;
}

double Fraction(const cv::Mat& mask) {
  return double(cv::countNonZero(mask)) / mask.total();
}

// Mean absolute difference of two pictures, in grey levels per channel.
double MeanDifference(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const cv::Scalar mean = cv::mean(diff);
  return (mean[0] + mean[1] + mean[2]) / 3;
}

class ViewerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test: ctest runs the tests of this file in parallel.
    dir_ = TempDir(
        std::string("viewer_test/") +
        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    glb_path_ = WriteBoxGlb(dir_);
    ASSERT_FALSE(glb_path_.empty());
  }
  std::string dir_;
  std::string glb_path_;
};

TEST_F(ViewerTest, WritesOneSelfContainedPage) {
  const std::string out = dir_ + "/viewer";
  const auto result = RunBayon({"viewer",
                                "--model_path",
                                glb_path_,
                                "--output_path",
                                out,
                                "--title",
                                "Box <&> test"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("12 faces"), std::string::npos) << result.output;
  EXPECT_EQ(fs::exists(dir_ + "/logs/viewer.log"), true);
  const std::string html = ReadFileToString(out + "/index.html");
  // One file: no script, stylesheet or model loaded from anywhere else.
  EXPECT_FALSE(std::regex_search(html, std::regex("<script[^>]* src=")));
  EXPECT_FALSE(std::regex_search(html, std::regex("<link[ >]")));
  EXPECT_NE(html.find("<title>Box &lt;&amp;&gt; test</title>"),
            std::string::npos);
  EXPECT_NE(html.find("id=\"bayon-model\""), std::string::npos);
  // The page is the model in base64 (4/3 of its bytes) plus three.js.
  EXPECT_GT(html.size(), fs::file_size(glb_path_) * 4 / 3 + 300000);
  EXPECT_EQ(ListFilesRecursive(out), std::vector<std::string>{"index.html"});

  // A second run refuses to replace it, then replaces it on request.
  const auto again =
      RunBayon({"viewer", "--model_path", glb_path_, "--output_path", out});
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_NE(again.LastLine().find(out), std::string::npos) << again.output;
  const auto overwrite = RunBayon({"viewer",
                                   "--model_path",
                                   glb_path_,
                                   "--output_path",
                                   out,
                                   "--overwrite",
                                   "1"});
  EXPECT_EQ(overwrite.exit_code, 0) << overwrite.output;
}

TEST_F(ViewerTest, BadModelsAreRefusedWithOneLine) {
  const std::string out = dir_ + "/viewer";
  const std::string missing = dir_ + "/missing.glb";
  auto result =
      RunBayon({"viewer", "--model_path", missing, "--output_path", out});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find(missing), std::string::npos)
      << result.output;

  const std::string png = dir_ + "/atlas.png";
  cv::imwrite(png, cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  result = RunBayon({"viewer", "--model_path", png, "--output_path", out});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("not a glTF binary"), std::string::npos)
      << result.output;

  const std::string truncated = dir_ + "/truncated.glb";
  const std::string bytes = ReadFileToString(glb_path_);
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, 200);
  result =
      RunBayon({"viewer", "--model_path", truncated, "--output_path", out});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("truncated"), std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(ViewerTest, ChromiumDrawsEveryMode) {
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    BAYON_SKIP(
        "chromium not installed (scripts/setup.sh installs it; or set "
        "BAYON_CHROMIUM)");
  }
  const std::string out = dir_ + "/viewer";
  const auto result =
      RunBayon({"viewer", "--model_path", glb_path_, "--output_path", out});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string html = out + "/index.html";

  std::map<std::string, cv::Mat> canvases;
  for (const std::string mode :
       {"textured", "shaded", "wireframe", "anaglyph"}) {
    SCOPED_TRACE(mode);
    const PageRun run = OpenPage(chromium, html, "?mode=" + mode, dir_, mode);
    ASSERT_FALSE(run.rgb.empty());
    EXPECT_EQ(Attribute(run.body_tag, "data-status"), "ready")
        << run.body_tag << " " << Attribute(run.body_tag, "data-error");
    EXPECT_EQ(Attribute(run.body_tag, "data-mode"), mode);
    EXPECT_EQ(Attribute(run.body_tag, "data-errors"), "")
        << "console errors: " << run.body_tag;
    EXPECT_EQ(ConsoleErrors(run.log), std::vector<std::string>{});
    // 6 faces of 2 triangles; corners shared within a face only.
    EXPECT_EQ(Attribute(run.body_tag, "data-faces"), "12");
    EXPECT_EQ(Attribute(run.body_tag, "data-vertices"), "24");
    // The background where the model is not (right edge, half way down);
    // the anaglyph's colour matrices shift it a little.
    EXPECT_LE(ColourDistance(
                  run.rgb.at<cv::Vec3b>(run.rgb.rows / 2, run.rgb.cols - 3),
                  kBackground),
              12);
    canvases[mode] = Canvas(run.rgb).clone();
  }

  // Textured: the box covers a good part of the window, and its pixels are
  // the atlas colours of the three faces towards the viewer.
  const cv::Mat& textured = canvases["textured"];
  const cv::Mat mask = ModelMask(textured);
  EXPECT_GT(Fraction(mask), 0.15);
  EXPECT_LT(Fraction(mask), 0.7);
  std::map<std::string, int> counts;
  int num_model = 0, num_atlas = 0;
  for (int y = 0; y < textured.rows; ++y) {
    for (int x = 0; x < textured.cols; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      ++num_model;
      const cv::Vec3b pixel = textured.at<cv::Vec3b>(y, x);
      for (const BoxFace& face : kBoxFaces) {
        if (ColourDistance(pixel, face.rgb) < 40) {
          ++counts[face.name];
          ++num_atlas;
        }
      }
    }
  }
  ASSERT_GT(num_model, 0);
  // Edges are antialiased against the background; the rest is the atlas.
  EXPECT_GT(double(num_atlas) / num_model, 0.9);
  EXPECT_GT(counts["red +x"], num_model / 5);
  EXPECT_GT(counts["blue +y"], num_model / 5);
  EXPECT_GT(counts["magenta +z"], num_model / 50);
  for (const char* hidden : {"green -x", "yellow -y", "cyan -z"}) {
    EXPECT_EQ(counts[hidden], 0) << hidden;
  }

  // Shaded: the same outline in lit grey, the faces in different shades.
  const cv::Mat& shaded = canvases["shaded"];
  const cv::Mat shaded_mask = ModelMask(shaded);
  EXPECT_LT(cv::norm(mask, shaded_mask, cv::NORM_L1) / 255 / mask.total(),
            0.02);
  std::vector<int> greys;
  for (int y = 0; y < shaded.rows; ++y) {
    for (int x = 0; x < shaded.cols; ++x) {
      if (!shaded_mask.at<uint8_t>(y, x)) continue;
      const cv::Vec3b p = shaded.at<cv::Vec3b>(y, x);
      EXPECT_LE(std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}), 12)
          << "colour in the shaded view at " << x << "," << y;
      greys.push_back(p[1]);
    }
  }
  ASSERT_FALSE(greys.empty());
  std::sort(greys.begin(), greys.end());
  EXPECT_GT(greys[greys.size() * 9 / 10] - greys[greys.size() / 10], 20);

  // Wireframe: thin lines, nothing filled.
  const double wire_fraction = Fraction(ModelMask(canvases["wireframe"]));
  EXPECT_GT(wire_fraction, 0.003);
  EXPECT_LT(wire_fraction, 0.05);

  // Anaglyph: red-cyan recolouring of the textured view (the red face loses
  // its red in the left eye's matrix), with the box in the same place.
  const cv::Mat& anaglyph = canvases["anaglyph"];
  EXPECT_LT(
      cv::norm(mask, ModelMask(anaglyph), cv::NORM_L1) / 255 / mask.total(),
      0.05);

  // Every pair of modes draws a substantially different picture.
  for (auto a = canvases.begin(); a != canvases.end(); ++a) {
    for (auto b = std::next(a); b != canvases.end(); ++b) {
      EXPECT_GT(MeanDifference(a->second, b->second), 8)
          << a->first << " vs " << b->first;
    }
  }
}

TEST_F(ViewerTest, ChromiumMatchesARenderOrbitView) {
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    BAYON_SKIP(
        "chromium not installed (scripts/setup.sh installs it; or set "
        "BAYON_CHROMIUM)");
  }
  // bayon render's textured orbit view (the library calls the command makes)
  // and the page in a window of the same size with the same view.
  const TexturedModel box = ColouredBox();
  OrbitOptions orbit;
  orbit.num_views = 1;
  orbit.start_azimuth_deg = 30;
  orbit.elevation_deg = 20;
  orbit.fov_deg = 40;
  orbit.width = 640;
  orbit.height = 480;
  ModelRenderOptions render_options;
  render_options.modes = {RenderMode::kTextured};
  cv::Mat render_rgb;
  RenderModelViews(box,
                   OrbitViewpoints(box.mesh.vertices.positions, orbit),
                   render_options,
                   [&](const std::string& name, const cv::Mat& bgr) {
                     cv::imwrite(dir_ + "/render_" + name, bgr);
                     cv::cvtColor(bgr, render_rgb, cv::COLOR_BGR2RGB);
                   });
  ASSERT_EQ(render_rgb.size(), cv::Size(640, 480));

  const std::string out = dir_ + "/viewer";
  ASSERT_EQ(
      RunBayon({"viewer", "--model_path", glb_path_, "--output_path", out})
          .exit_code,
      0);
  const PageRun run = OpenPage(chromium,
                               out + "/index.html",
                               "?mode=textured&azimuth=30&elevation=20&fov=40",
                               dir_,
                               "viewer");
  ASSERT_FALSE(run.rgb.empty());
  ASSERT_EQ(Attribute(run.body_tag, "data-status"), "ready") << run.body_tag;

  // The same silhouette (render's background is white, the page's dark)...
  const cv::Mat page = Canvas(run.rgb), render = Canvas(render_rgb);
  const cv::Mat page_mask = ModelMask(page);
  cv::Mat render_mask(render.size(), CV_8U);
  for (int y = 0; y < render.rows; ++y) {
    for (int x = 0; x < render.cols; ++x) {
      render_mask.at<uint8_t>(y, x) =
          ColourDistance(render.at<cv::Vec3b>(y, x), {255, 255, 255}) > 30 ? 255
                                                                           : 0;
    }
  }
  cv::Mat both, either;
  cv::bitwise_and(page_mask, render_mask, both);
  cv::bitwise_or(page_mask, render_mask, either);
  ASSERT_GT(cv::countNonZero(either), 0);
  const double iou = double(cv::countNonZero(both)) / cv::countNonZero(either);
  EXPECT_GT(iou, 0.95) << "page " << cv::countNonZero(page_mask)
                       << " px, render " << cv::countNonZero(render_mask)
                       << " px";
  // ... in the same colours where both draw the model (edges aside).
  cv::Mat inner;
  cv::erode(both, inner, cv::Mat::ones(5, 5, CV_8U));
  ASSERT_GT(cv::countNonZero(inner), 0);
  cv::Mat diff;
  cv::absdiff(page, render, diff);
  const cv::Scalar mean = cv::mean(diff, inner);
  std::cout << "page vs render: silhouette IoU " << iou
            << ", mean colour difference (RGB) " << mean[0] << " " << mean[1]
            << " " << mean[2] << std::endl;
  EXPECT_LT((mean[0] + mean[1] + mean[2]) / 3, 6)
      << "mean colour difference " << mean;
}

TEST_F(ViewerTest, ChromiumReportsBadUrlParameters) {
  // The error channels the test above relies on, seen to work.
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    BAYON_SKIP(
        "chromium not installed (scripts/setup.sh installs it; or set "
        "BAYON_CHROMIUM)");
  }
  const std::string out = dir_ + "/viewer";
  ASSERT_EQ(
      RunBayon({"viewer", "--model_path", glb_path_, "--output_path", out})
          .exit_code,
      0);
  const PageRun run =
      OpenPage(chromium, out + "/index.html", "?mode=x", dir_, "bad_mode");
  EXPECT_EQ(Attribute(run.body_tag, "data-status"), "error") << run.body_tag;
  EXPECT_EQ(Attribute(run.body_tag, "data-errors"), "1") << run.body_tag;
  EXPECT_NE(Attribute(run.body_tag, "data-error").find("unknown mode 'x'"),
            std::string::npos)
      << run.body_tag;
  EXPECT_EQ(ConsoleErrors(run.log).size(), 1u) << run.log;
}

}  // namespace
}  // namespace bayon
