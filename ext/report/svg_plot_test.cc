// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/svg_plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "tests/xml_testing.h"

namespace bayon {
namespace {

using testing::XmlWellFormednessError;

int CountOf(const std::string& text, const std::string& what) {
  int count = 0;
  for (size_t at = text.find(what); at != std::string::npos;
       at = text.find(what, at + 1)) {
    ++count;
  }
  return count;
}

TEST(NiceTicks, CoverTheRangeInStepsOfOneTwoOrFive) {
  for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{
           {0, 1}, {-0.37, 0.41}, {3, 1234}, {1e-6, 7e-6}, {-250, -20}}) {
    SCOPED_TRACE(std::to_string(lo) + " " + std::to_string(hi));
    const std::vector<double> ticks = NiceTicks(lo, hi, 5);
    ASSERT_GE(ticks.size(), 3u);
    ASSERT_LE(ticks.size(), 12u);
    EXPECT_LE(ticks.front(), lo);
    EXPECT_GE(ticks.back(), hi);
    const double step = ticks[1] - ticks[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-6 ||
                std::abs(mantissa - 2) < 1e-6 || std::abs(mantissa - 5) < 1e-6)
        << step;
  }
  EXPECT_EQ(NiceTicks(0, 1, 5),
            (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1}));
  // A single value still gets an axis.
  EXPECT_GE(NiceTicks(3, 3, 5).size(), 2u);
  EXPECT_GE(NiceTicks(0, 0, 5).size(), 2u);
}

TEST(NiceTicks, LabelsHaveTheDigitsOfTheStep) {
  EXPECT_EQ(TickLabel(0.2, 0.2), "0.2");
  EXPECT_EQ(TickLabel(0.05, 0.05), "0.05");
  EXPECT_EQ(TickLabel(1000, 500), "1000");
  EXPECT_EQ(TickLabel(-1e-17, 0.1), "0");
  EXPECT_EQ(TickLabel(2.5e-6, 1e-6), "2.5e-06");
}

TEST(SvgHistogram, CountsTheValuesInBins) {
  // 30 values at 1.5, 10 at 2.5, and two far away.
  std::vector<double> values(30, 1.5);
  values.insert(values.end(), 10, 2.5);
  values.push_back(100);
  values.push_back(std::nan(""));
  HistogramOptions options;
  options.min = 1;
  options.max = 3;
  options.num_bins = 2;
  options.chart.title = "residuals <x> & more";
  const std::string svg = SvgHistogram(values, options);
  EXPECT_EQ(XmlWellFormednessError(svg), "") << svg;
  EXPECT_NE(svg.find(": 30</title>"), std::string::npos) << svg;
  EXPECT_NE(svg.find(": 10</title>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("1 outside the range"), std::string::npos) << svg;
  EXPECT_NE(svg.find("residuals &lt;x&gt; &amp; more"), std::string::npos);
}

TEST(SvgHistogram, AutomaticRangeIsSymmetricForResiduals) {
  std::vector<double> values;
  for (int i = -50; i <= 100; ++i) values.push_back(0.01 * i);
  HistogramOptions options;
  options.symmetric = true;
  options.show_normal = true;
  const std::string svg = SvgHistogram(values, options);
  EXPECT_EQ(XmlWellFormednessError(svg), "");
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  // Ticks at -1 and 1 (the range is [-1, 1] minus the 0.5 % tails).
  EXPECT_NE(svg.find(">-0.5</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">0.5</text>"), std::string::npos) << svg;
  // Nothing at all still draws an empty chart.
  EXPECT_EQ(XmlWellFormednessError(SvgHistogram({}, options)), "");
}

TEST(SvgBarChart, DrawsStackedBarsWithEscapedLabels) {
  BarChartOptions options;
  options.series = {{"tracks", "#111111"}, {"ties", "#222222"}};
  options.value_decimals = 0;
  std::vector<Bar> bars;
  for (int i = 0; i < 16; ++i) {
    bars.push_back(
        {"image<" + std::to_string(i) + ">&", {10.0 + i, 5}, "", ""});
  }
  const std::string svg = SvgBarChart(bars, options);
  EXPECT_EQ(XmlWellFormednessError(svg), "") << svg;
  EXPECT_EQ(CountOf(svg, "fill=\"#111111\""), 16 + 1);  // + legend
  EXPECT_EQ(CountOf(svg, "fill=\"#222222\""), 16 + 1);
  EXPECT_NE(svg.find("image&lt;15&gt;&amp;"), std::string::npos);
  EXPECT_NE(svg.find(">tracks</text>"), std::string::npos);
  // Long labels on narrow bars are turned.
  EXPECT_NE(svg.find("rotate(-45"), std::string::npos);

  options.horizontal = true;
  options.chart.height_px = 0;
  const std::string horizontal = SvgBarChart(bars, options);
  EXPECT_EQ(XmlWellFormednessError(horizontal), "");
  // 20 px per bar and the frame.
  const std::regex height("height=\"([0-9.]+)\"");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(horizontal, match, height));
  EXPECT_GE(std::stod(match[1]), 16 * 20);
  EXPECT_NE(horizontal.find(">15</text>"), std::string::npos);  // 10 + 5
}

TEST(SvgStationView, KeepsEqualScaleAndNamesTheStations) {
  PointSeries points;
  for (int i = 0; i < 50; ++i) points.points.emplace_back(0.02 * i, 0.01 * i);
  // Three stations at (0,0), (4,0), (0,2), looking at the origin.
  std::vector<ViewCamera> cameras = {
      {{0, 0}, {1, 0}, "a"}, {{4, 0}, {-1, 0}, "b"}, {{0, 2}, {0, -1}, "c"}};
  StationViewOptions options;
  options.chart.width_px = 500;
  options.chart.height_px = 300;
  const std::string svg = SvgStationView(points, cameras, options);
  EXPECT_EQ(XmlWellFormednessError(svg), "") << svg;
  for (const char* name : {">a</text>", ">b</text>", ">c</text>"}) {
    EXPECT_NE(svg.find(name), std::string::npos) << name;
  }
  // The camera dots (r="3"): b is 4 units right of a, c 2 units above it,
  // at the same scale.
  const std::regex dot("<circle cx=\"([-0-9.]+)\" cy=\"([-0-9.]+)\" r=\"3\"");
  std::vector<Eigen::Vector2d> centers;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), dot);
       it != std::sregex_iterator();
       ++it) {
    centers.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  }
  ASSERT_EQ(centers.size(), 3u);
  const double right = centers[1].x() - centers[0].x();
  const double up = centers[0].y() - centers[2].y();  // SVG y points down
  EXPECT_GT(right, 100);
  EXPECT_NEAR(right / 4, up / 2, 0.2);
  EXPECT_NEAR(centers[1].y(), centers[0].y(), 0.2);
  EXPECT_EQ(CountOf(svg, "<polygon"), 3);  // one arrow head each
}

TEST(SvgImageFrame, FollowsTheImageAndDropsPointsOutsideIt) {
  PointSeries inside;
  inside.points = {{10, 10}, {630, 470}, {-5, 10}, {700, 10}};
  ImageFrameOptions options;
  options.width_px = 162;
  options.title = "IMG_0001";
  options.note = "2 points";
  const std::string svg =
      SvgImageFrame({640, 480}, {inside}, {{{320, 240}, {330, 250}}}, options);
  EXPECT_EQ(XmlWellFormednessError(svg), "") << svg;
  EXPECT_EQ(CountOf(svg, "<circle"), 2);
  EXPECT_EQ(CountOf(svg, "<polygon"), 1);
  // 160 px frame of a 4:3 image: 120 px high, plus title and note.
  EXPECT_NE(svg.find("height=\"150\""), std::string::npos) << svg;
}

}  // namespace
}  // namespace bayon
