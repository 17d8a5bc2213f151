// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/svg_plot.h"

#include "ext/report/html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace bayon {
namespace {

constexpr double kFontSize = 11;
// Average advance of a character of the sans-serif font at kFontSize, for
// laying out labels without measuring them.
constexpr double kCharWidth = 6.2;
constexpr char kAxisColor[] = "#444444";
constexpr char kGridColor[] = "#e4e4e4";

// A coordinate with one decimal (a tenth of a pixel is below what a screen
// shows), without a trailing ".0".
std::string Num(double value) {
  if (!std::isfinite(value)) value = 0;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.1f", value);
  std::string text = buffer;
  if (text.size() > 2 && text.compare(text.size() - 2, 2, ".0") == 0) {
    text.resize(text.size() - 2);
  }
  if (text == "-0") text = "0";
  return text;
}

double TextWidth(const std::string& text, double font_size = kFontSize) {
  return kCharWidth * font_size / kFontSize * static_cast<double>(text.size());
}

// Assembles one <svg> element.
class Svg {
 public:
  Svg(double width, double height, const std::string& title) {
    out_ =
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"chart\" width=\"" +
        Num(width) + "\" height=\"" + Num(height) + "\" viewBox=\"0 0 " +
        Num(width) + " " + Num(height) +
        "\" role=\"img\" font-family=\"sans-serif\" font-size=\"" +
        Num(kFontSize) + "\">";
    if (!title.empty()) out_ += "<title>" + HtmlEscape(title) + "</title>";
  }

  void Line(const Eigen::Vector2d& a,
            const Eigen::Vector2d& b,
            const std::string& color,
            double width = 1) {
    out_ += "<line x1=\"" + Num(a.x()) + "\" y1=\"" + Num(a.y()) + "\" x2=\"" +
            Num(b.x()) + "\" y2=\"" + Num(b.y()) + "\" stroke=\"" + color +
            "\" stroke-width=\"" + Num(width) + "\"/>";
  }

  void Rect(double x,
            double y,
            double w,
            double h,
            const std::string& fill,
            const std::string& stroke = "",
            const std::string& tooltip = "") {
    out_ += "<rect x=\"" + Num(x) + "\" y=\"" + Num(y) + "\" width=\"" +
            Num(std::max(w, 0.0)) + "\" height=\"" + Num(std::max(h, 0.0)) +
            "\" fill=\"" + fill + "\"";
    if (!stroke.empty()) out_ += " stroke=\"" + stroke + "\"";
    if (tooltip.empty()) {
      out_ += "/>";
    } else {
      out_ += "><title>" + HtmlEscape(tooltip) + "</title></rect>";
    }
  }

  void Circle(const Eigen::Vector2d& c, double r, const std::string& fill) {
    out_ += "<circle cx=\"" + Num(c.x()) + "\" cy=\"" + Num(c.y()) + "\" r=\"" +
            Num(r) + "\" fill=\"" + fill + "\"/>";
  }

  // Many dots of one colour as one group (small files: no repeated style).
  void Dots(const std::vector<Eigen::Vector2d>& centers,
            double r,
            const std::string& fill,
            double opacity) {
    if (centers.empty()) return;
    out_ += "<g fill=\"" + fill + "\"";
    if (opacity < 1) out_ += " fill-opacity=\"" + Num(opacity * 100) + "%\"";
    out_ += ">";
    char buffer[96];
    for (const Eigen::Vector2d& c : centers) {
      std::snprintf(buffer,
                    sizeof(buffer),
                    "<circle cx=\"%s\" cy=\"%s\" r=\"%g\"/>",
                    Num(c.x()).c_str(),
                    Num(c.y()).c_str(),
                    r);
      out_ += buffer;
    }
    out_ += "</g>";
  }

  void Polyline(const std::vector<Eigen::Vector2d>& points,
                const std::string& color,
                double width) {
    if (points.size() < 2) return;
    out_ += "<polyline fill=\"none\" stroke=\"" + color + "\" stroke-width=\"" +
            Num(width) + "\" points=\"";
    for (size_t i = 0; i < points.size(); ++i) {
      out_ +=
          (i > 0 ? " " : "") + Num(points[i].x()) + "," + Num(points[i].y());
    }
    out_ += "\"/>";
  }

  // A line from a to b with a filled head at b.
  void Arrow(const Eigen::Vector2d& a,
             const Eigen::Vector2d& b,
             const std::string& color,
             double width = 1.2) {
    const Eigen::Vector2d d = b - a;
    const double length = d.norm();
    if (length < 1e-9) return;
    const Eigen::Vector2d u = d / length, n(-u.y(), u.x());
    const double head = std::min(6.0, 0.45 * length);
    const Eigen::Vector2d base = b - head * u;
    Line(a, base, color, width);
    const Eigen::Vector2d p1 = base + 0.45 * head * n,
                          p2 = base - 0.45 * head * n;
    out_ += "<polygon fill=\"" + color + "\" points=\"" + Num(b.x()) + "," +
            Num(b.y()) + " " + Num(p1.x()) + "," + Num(p1.y()) + " " +
            Num(p2.x()) + "," + Num(p2.y()) + "\"/>";
  }

  // anchor: start, middle or end; rotate_deg about the anchor point.
  void Text(const Eigen::Vector2d& at,
            const std::string& text,
            const std::string& anchor = "start",
            double size = kFontSize,
            const std::string& color = kAxisColor,
            double rotate_deg = 0,
            bool bold = false) {
    out_ += "<text x=\"" + Num(at.x()) + "\" y=\"" + Num(at.y()) + "\"";
    if (anchor != "start") out_ += " text-anchor=\"" + anchor + "\"";
    if (size != kFontSize) out_ += " font-size=\"" + Num(size) + "\"";
    out_ += " fill=\"" + color + "\"";
    if (bold) out_ += " font-weight=\"bold\"";
    if (rotate_deg != 0) {
      out_ += " transform=\"rotate(" + Num(rotate_deg) + " " + Num(at.x()) +
              " " + Num(at.y()) + ")\"";
    }
    out_ += ">" + HtmlEscape(text) + "</text>";
  }

  std::string Finish() { return out_ + "</svg>"; }

 private:
  std::string out_;
};

// Maps [lo, hi] to pixels [p0, p1] (p1 < p0 for a y axis pointing up).
struct Axis {
  double lo = 0, hi = 1, p0 = 0, p1 = 1;
  double operator()(double v) const {
    return hi > lo ? p0 + (v - lo) / (hi - lo) * (p1 - p0) : p0;
  }
};

// The plot area inside a chart.
struct PlotArea {
  double left, top, right, bottom;
  double width() const { return right - left; }
  double height() const { return bottom - top; }
};

// The height above the plot: the title, and the note beside it or, where
// they would overlap, on a line of its own below it.
bool NoteBelowTitle(const ChartOptions& options, double left, double right) {
  return !options.title.empty() && !options.note.empty() &&
         TextWidth(options.title, 12) * 1.1 + TextWidth(options.note, 10) + 16 >
             right - left;
}

double HeaderHeight(const ChartOptions& options, double left, double right) {
  return NoteBelowTitle(options, left, right) ? 38 : 26;
}

// `chart` with "<num_left_out><what>" added to its note where any were left
// out of the plot.
ChartOptions WithLeftOutNote(const ChartOptions& chart,
                             size_t num_left_out,
                             const std::string& what) {
  ChartOptions framed = chart;
  if (num_left_out > 0) {
    framed.note +=
        (framed.note.empty() ? "" : "; ") + std::to_string(num_left_out) + what;
  }
  return framed;
}

// The plot area of a chart `height` pixels high with a y axis on the left
// and an x axis below.
PlotArea XyPlotArea(const ChartOptions& chart, double height) {
  return {52,
          HeaderHeight(chart, 52, chart.width_px - 12.0),
          chart.width_px - 12.0,
          height - 38};
}

void DrawTitleAndNote(const ChartOptions& options,
                      const PlotArea& area,
                      Svg* svg) {
  if (!options.title.empty()) {
    svg->Text({area.left, 15}, options.title, "start", 12, "#222222", 0, true);
  }
  if (!options.note.empty()) {
    const double y = NoteBelowTitle(options, area.left, area.right) ? 28 : 15;
    svg->Text({area.right, y}, options.note, "end", 10, "#666666");
  }
}

// Horizontal grid lines and labels of a y axis at `ticks` (inside the axis'
// range), and the axis label.
void DrawYAxis(const Axis& y,
               const std::vector<double>& ticks,
               const PlotArea& area,
               const std::string& label,
               Svg* svg) {
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1;
  for (const double t : ticks) {
    if (t < y.lo - 1e-9 * std::abs(step) || t > y.hi + 1e-9 * std::abs(step)) {
      continue;
    }
    const double py = y(t);
    svg->Line({area.left, py}, {area.right, py}, kGridColor);
    svg->Text({area.left - 4, py + 3.5}, TickLabel(t, step), "end", 10);
  }
  svg->Line({area.left, area.top}, {area.left, area.bottom}, kAxisColor);
  if (!label.empty()) {
    const Eigen::Vector2d at(12, (area.top + area.bottom) / 2);
    svg->Text(at, label, "middle", kFontSize, kAxisColor, -90);
  }
}

void DrawXAxis(const Axis& x,
               const std::vector<double>& ticks,
               const PlotArea& area,
               const std::string& label,
               double label_y,
               bool grid,
               Svg* svg) {
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1;
  for (const double t : ticks) {
    if (t < x.lo - 1e-9 * std::abs(step) || t > x.hi + 1e-9 * std::abs(step)) {
      continue;
    }
    const double px = x(t);
    if (grid) svg->Line({px, area.top}, {px, area.bottom}, kGridColor);
    svg->Line({px, area.bottom}, {px, area.bottom + 4}, kAxisColor);
    svg->Text({px, area.bottom + 15}, TickLabel(t, step), "middle", 10);
  }
  svg->Line({area.left, area.bottom}, {area.right, area.bottom}, kAxisColor);
  if (!label.empty()) {
    svg->Text({(area.left + area.right) / 2, label_y}, label, "middle");
  }
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1,
                            static_cast<size_t>(q * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

std::string FormatValue(double value, int decimals) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

// The legend of a chart with two or more series: entries flowing from
// `left` to `right` in rows of 14 px from `top` (below the title). Returns the
// height it takes (0 without a legend); draws only when `svg` is given.
double DrawLegend(const std::vector<BarSeries>& series,
                  double left,
                  double right,
                  double top,
                  Svg* svg) {
  if (series.size() < 2) return 0;
  constexpr double kRow = 14;
  const double baseline = top + 5;
  double x = left;
  int row = 0;
  for (const BarSeries& s : series) {
    const double width = 13 + TextWidth(s.name, 10) + 12;
    if (x + width > right && x > left) {
      x = left;
      ++row;
    }
    if (svg != nullptr) {
      const double y = baseline + row * kRow;
      svg->Rect(x, y - 8, 9, 9, s.color);
      svg->Text({x + 13, y}, s.name, "start", 10);
    }
    x += width;
  }
  return (row + 1) * kRow + 4;
}

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return {0, 1};
  if (hi < lo) std::swap(lo, hi);
  if (hi - lo < 1e-300) {
    const double pad = lo == 0 ? 1 : 0.5 * std::abs(lo);
    lo -= pad;
    hi += pad;
  }
  target = std::max(target, 2);
  const double raw = (hi - lo) / target;
  const int exponent = static_cast<int>(std::floor(std::log10(raw)));
  const double magnitude = std::pow(10.0, exponent);
  double multiple = 1;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    multiple = m;
    if (m * magnitude >= raw) break;
  }
  const double step = multiple * magnitude;
  // Tick k is k * multiple * 10^exponent; dividing by 10^-exponent keeps
  // 3 * 0.2 at 0.6 rather than 0.6000000000000001.
  const auto tick = [&](double k) {
    return exponent < 0 ? k * multiple / std::pow(10.0, -exponent)
                        : k * multiple * magnitude;
  };
  const double first = std::floor(lo / step + 1e-9);
  std::vector<double> ticks;
  for (int i = 0;; ++i) {
    const double t = tick(first + i);
    ticks.push_back(t == 0 ? 0.0 : t);  // no -0
    if (t >= hi - 1e-9 * step || i > 1000) break;
  }
  return ticks;
}

std::string TickLabel(double value, double step) {
  step = std::abs(step);
  int decimals = 0;
  if (step > 0 && step < 1) {
    decimals = static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
    // 0.25-like steps do not occur (1, 2, 5 only), but 0.5 needs one digit.
    decimals = std::min(std::max(decimals, 1), 12);
  }
  const double magnitude = std::max(std::abs(value), step);
  char buffer[48];
  if (magnitude >= 1e6 || (magnitude > 0 && magnitude < 1e-4)) {
    std::snprintf(buffer, sizeof(buffer), "%.3g", value);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  }
  std::string text = buffer;
  // "-0", "-0.00": a tick at zero.
  if (text.find_first_not_of("-0.") == std::string::npos) text = "0";
  return text;
}

std::string SvgHistogram(const std::vector<double>& values,
                         const HistogramOptions& options) {
  const ChartOptions& chart = options.chart;
  std::vector<double> finite;
  for (const double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  double lo = options.min, hi = options.max;
  if (!(lo < hi)) {
    lo = finite.empty() ? 0 : Percentile(finite, 0.005);
    hi = finite.empty() ? 1 : Percentile(finite, 0.995);
    if (options.symmetric) {
      hi = std::max(std::abs(lo), std::abs(hi));
      lo = -hi;
    }
    if (!(hi - lo > 1e-12 * std::max(1.0, std::abs(hi)))) {
      const double pad = std::abs(hi) > 0 ? 0.5 * std::abs(hi) : 1;
      lo -= pad;
      hi += pad;
    }
  }
  const int num_bins = std::max(options.num_bins, 1);
  const double bin_width = (hi - lo) / num_bins;
  std::vector<int> counts(num_bins, 0);
  int num_outside = 0;
  double sum = 0, sum_sq = 0;
  int num_inside = 0;
  for (const double v : finite) {
    if (v < lo || v > hi) {
      ++num_outside;
      continue;
    }
    const int bin =
        std::min(num_bins - 1, static_cast<int>((v - lo) / bin_width));
    ++counts[bin];
    sum += v;
    sum_sq += v * v;
    ++num_inside;
  }
  const double mean = num_inside > 0 ? sum / num_inside : 0;
  const double sd =
      num_inside > 1
          ? std::sqrt(std::max(
                0.0, (sum_sq - num_inside * mean * mean) / (num_inside - 1)))
          : 0;
  const auto density = [&](double x) {
    return sd > 0 ? num_inside * bin_width / (sd * std::sqrt(2 * M_PI)) *
                        std::exp(-0.5 * std::pow((x - mean) / sd, 2))
                  : 0.0;
  };
  double max_count = *std::max_element(counts.begin(), counts.end());
  if (options.show_normal) max_count = std::max(max_count, density(mean));

  const ChartOptions framed =
      WithLeftOutNote(chart, num_outside, " outside the range");
  const PlotArea area = XyPlotArea(framed, chart.height_px);
  Svg svg(chart.width_px, chart.height_px, chart.title);
  DrawTitleAndNote(framed, area, &svg);
  const std::vector<double> y_ticks = NiceTicks(0, std::max(max_count, 1.0), 5);
  const Axis y{0, y_ticks.back(), area.bottom, area.top};
  const Axis x{lo, hi, area.left, area.right};
  DrawYAxis(
      y, y_ticks, area, chart.y_label.empty() ? "count" : chart.y_label, &svg);
  for (int b = 0; b < num_bins; ++b) {
    if (counts[b] == 0) continue;
    const double x0 = x(lo + b * bin_width), x1 = x(lo + (b + 1) * bin_width);
    const double top = y(counts[b]);
    svg.Rect(x0 + 0.5,
             top,
             x1 - x0 - 1,
             area.bottom - top,
             options.color,
             "",
             TickLabel(lo + b * bin_width, bin_width / 10) + " to " +
                 TickLabel(lo + (b + 1) * bin_width, bin_width / 10) + ": " +
                 std::to_string(counts[b]));
  }
  if (options.show_normal && sd > 0) {
    std::vector<Eigen::Vector2d> curve;
    for (int i = 0; i <= 120; ++i) {
      const double v = lo + (hi - lo) * i / 120.0;
      curve.emplace_back(x(v), y(density(v)));
    }
    svg.Polyline(curve, "#e45756", 1.5);
  }
  DrawXAxis(x,
            NiceTicks(lo, hi, 6),
            area,
            chart.x_label,
            chart.height_px - 6.0,
            false,
            &svg);
  return svg.Finish();
}

namespace {

double BarTotal(const Bar& bar) {
  return std::accumulate(bar.values.begin(), bar.values.end(), 0.0);
}

std::string SeriesColor(const Bar& bar,
                        const BarChartOptions& options,
                        size_t s) {
  if (!bar.color.empty() && options.series.size() <= 1) return bar.color;
  if (s < options.series.size()) return options.series[s].color;
  return "#4c78a8";
}

std::string BarTooltip(const Bar& bar, const BarChartOptions& options) {
  if (!bar.tooltip.empty()) return bar.tooltip;
  std::string text = bar.label + ":";
  for (size_t s = 0; s < bar.values.size(); ++s) {
    text +=
        " " + FormatValue(bar.values[s], std::max(options.value_decimals, 0));
    if (options.series.size() > 1 && s < options.series.size()) {
      text += " " + options.series[s].name;
    }
  }
  return text;
}

std::string SvgHorizontalBars(const std::vector<Bar>& bars,
                              const BarChartOptions& options) {
  const ChartOptions& chart = options.chart;
  double label_width = 0;
  for (const Bar& bar : bars) {
    label_width = std::max(label_width, TextWidth(bar.label));
  }
  label_width = std::min(label_width, 200.0);
  const double header =
      HeaderHeight(chart, label_width + 14, chart.width_px - 56.0);
  const double legend =
      DrawLegend(options.series, 8, chart.width_px - 8.0, header, nullptr);
  const double height =
      chart.height_px > 0
          ? chart.height_px
          : header + legend + 20.0 * std::max<size_t>(bars.size(), 1) + 36;
  const PlotArea area{
      label_width + 14, header + legend, chart.width_px - 56.0, height - 36};
  Svg svg(chart.width_px, height, chart.title);
  DrawTitleAndNote(chart, area, &svg);
  DrawLegend(options.series, 8, chart.width_px - 8.0, header, &svg);
  double max_total = 0;
  for (const Bar& bar : bars) max_total = std::max(max_total, BarTotal(bar));
  const std::vector<double> ticks = NiceTicks(0, std::max(max_total, 1e-12), 5);
  const Axis x{0, ticks.back(), area.left, area.right};
  DrawXAxis(x, ticks, area, chart.x_label, height - 4, true, &svg);
  const double slot = area.height() / std::max<size_t>(bars.size(), 1);
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& bar = bars[i];
    const double top = area.top + i * slot + 0.15 * slot;
    const double mid = area.top + (i + 0.5) * slot;
    double start = 0;
    for (size_t s = 0; s < bar.values.size(); ++s) {
      svg.Rect(x(start),
               top,
               x(start + bar.values[s]) - x(start),
               0.7 * slot,
               SeriesColor(bar, options, s),
               "",
               BarTooltip(bar, options));
      start += bar.values[s];
    }
    svg.Text({area.left - 6, mid + 3.5}, bar.label, "end");
    if (options.value_decimals >= 0) {
      svg.Text({x(start) + 4, mid + 3.5},
               FormatValue(start, options.value_decimals) + options.value_unit,
               "start",
               10);
    }
  }
  svg.Line({area.left, area.top}, {area.left, area.bottom}, kAxisColor);
  return svg.Finish();
}

std::string SvgVerticalBars(const std::vector<Bar>& bars,
                            const BarChartOptions& options) {
  const ChartOptions& chart = options.chart;
  const double plot_width = chart.width_px - 52 - 12.0;
  const double slot = plot_width / std::max<size_t>(bars.size(), 1);
  double label_width = 0;
  for (const Bar& bar : bars) {
    label_width = std::max(label_width, TextWidth(bar.label, 10));
  }
  label_width = std::min(label_width, 140.0);
  const bool rotate = label_width > 0.9 * slot;
  // Every k-th label when even rotated labels (one text line, 12 px) would
  // overlap.
  const size_t every =
      rotate ? std::max<size_t>(1, static_cast<size_t>(std::ceil(12 / slot)))
             : 1;
  const double label_height = rotate ? 0.72 * label_width + 8 : 16;
  const double bottom =
      chart.height_px - label_height - (chart.x_label.empty() ? 6 : 22);
  const double header = HeaderHeight(chart, 52, chart.width_px - 12.0);
  const double legend =
      DrawLegend(options.series, 52, chart.width_px - 12.0, header, nullptr);
  const PlotArea area{52, header + legend, chart.width_px - 12.0, bottom};
  Svg svg(chart.width_px, chart.height_px, chart.title);
  DrawTitleAndNote(chart, area, &svg);
  DrawLegend(options.series, 52, chart.width_px - 12.0, header, &svg);
  double max_total = 0;
  for (const Bar& bar : bars) max_total = std::max(max_total, BarTotal(bar));
  const std::vector<double> ticks = NiceTicks(0, std::max(max_total, 1e-12), 5);
  const Axis y{0, ticks.back(), area.bottom, area.top};
  DrawYAxis(y, ticks, area, chart.y_label, &svg);
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& bar = bars[i];
    const double left = area.left + i * slot + 0.12 * slot;
    const double center = area.left + (i + 0.5) * slot;
    double start = 0;
    for (size_t s = 0; s < bar.values.size(); ++s) {
      const double top = y(start + bar.values[s]);
      svg.Rect(left,
               top,
               0.76 * slot,
               y(start) - top,
               SeriesColor(bar, options, s),
               "",
               BarTooltip(bar, options));
      start += bar.values[s];
    }
    if (options.value_decimals >= 0 && slot >= 22) {
      svg.Text({center, y(start) - 3},
               FormatValue(start, options.value_decimals) + options.value_unit,
               "middle",
               9);
    }
    if (i % every != 0) continue;
    if (rotate) {
      svg.Text(
          {center + 3, area.bottom + 8}, bar.label, "end", 10, kAxisColor, -45);
    } else {
      svg.Text({center, area.bottom + 13}, bar.label, "middle", 10);
    }
  }
  svg.Line({area.left, area.bottom}, {area.right, area.bottom}, kAxisColor);
  if (!chart.x_label.empty()) {
    svg.Text({(area.left + area.right) / 2, chart.height_px - 6.0},
             chart.x_label,
             "middle");
  }
  return svg.Finish();
}

}  // namespace

std::string SvgBarChart(const std::vector<Bar>& bars,
                        const BarChartOptions& options) {
  return options.horizontal ? SvgHorizontalBars(bars, options)
                            : SvgVerticalBars(bars, options);
}

std::string SvgStationView(const PointSeries& points,
                           const std::vector<ViewCamera>& cameras,
                           const StationViewOptions& options) {
  const ChartOptions& chart = options.chart;
  // The drawing's extent, from the cameras and the points.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300),
                  hi = Eigen::Vector2d::Constant(-1e300);
  const auto grow = [&](const Eigen::Vector2d& p) {
    if (!p.allFinite()) return;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  };
  std::vector<double> xs, ys;
  for (const Eigen::Vector2d& p : points.points) {
    if (!p.allFinite()) continue;
    xs.push_back(p.x());
    ys.push_back(p.y());
  }
  const double q = std::clamp(options.point_quantile, 0.0, 0.5);
  if (!xs.empty()) {
    grow({Percentile(xs, q), Percentile(ys, q)});
    grow({Percentile(xs, 1 - q), Percentile(ys, 1 - q)});
  }
  for (const ViewCamera& camera : cameras) grow(camera.center);
  if (!(lo.x() <= hi.x())) {
    lo.setZero();
    hi.setOnes();
  }
  // Points up to a tenth of the extent beyond the quantiles still count.
  const Eigen::Vector2d margin = 0.1 * (hi - lo);
  const Eigen::Vector2d keep_lo = lo - margin, keep_hi = hi + margin;
  std::vector<Eigen::Vector2d> kept;
  for (const Eigen::Vector2d& p : points.points) {
    if (p.allFinite() && (p.array() >= keep_lo.array()).all() &&
        (p.array() <= keep_hi.array()).all()) {
      kept.push_back(p);
      grow(p);
    }
  }
  const size_t num_left_out = xs.size() - kept.size();
  const double extent = std::max((hi - lo).maxCoeff(), 1e-9);
  const double arrow = options.arrow_fraction * extent;
  for (const ViewCamera& camera : cameras) {
    grow(camera.center + arrow * camera.direction);
  }
  const bool labels = options.max_labels > 0;
  double label_width = 0;
  for (const ViewCamera& camera : cameras) {
    if (labels)
      label_width = std::max(label_width, TextWidth(camera.label, 10));
  }
  // Room for the labels around the data, inside the axes.
  const double pad_x = std::min(label_width, 90.0) + 10,
               pad_y = labels ? 16 : 10;
  // The height for the data's aspect ratio at the full width.
  const double height =
      chart.height_px > 0
          ? chart.height_px
          : std::clamp((chart.width_px - 64 - 2 * pad_x) * (hi.y() - lo.y()) /
                               std::max(hi.x() - lo.x(), 1e-12) +
                           2 * pad_y + 64,
                       200.0,
                       static_cast<double>(chart.width_px));
  const ChartOptions framed = WithLeftOutNote(chart, num_left_out, " outside");
  const PlotArea area = XyPlotArea(framed, height);
  const double scale =
      std::min((area.width() - 2 * pad_x) / std::max(hi.x() - lo.x(), 1e-12),
               (area.height() - 2 * pad_y) / std::max(hi.y() - lo.y(), 1e-12));
  const Eigen::Vector2d center = 0.5 * (lo + hi);
  const double cx = 0.5 * (area.left + area.right),
               cy = 0.5 * (area.top + area.bottom);
  const Axis x{center.x() - (cx - area.left) / scale,
               center.x() + (area.right - cx) / scale,
               area.left,
               area.right};
  const Axis y{center.y() - (area.bottom - cy) / scale,
               center.y() + (cy - area.top) / scale,
               area.bottom,
               area.top};
  const auto to_px = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(x(p.x()), y(p.y()));
  };

  Svg svg(chart.width_px, height, chart.title);
  DrawTitleAndNote(framed, area, &svg);
  // Ticks at the same step on both axes (equal scale).
  const double target_x = std::max(2.0, area.width() / 70);
  std::vector<double> x_ticks = NiceTicks(x.lo, x.hi, target_x);
  const double step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1;
  std::vector<double> y_ticks;
  for (double t = std::floor(y.lo / step) * step; t <= y.hi + 1e-9 * step;
       t += step) {
    y_ticks.push_back(std::abs(t) < 1e-9 * step ? 0.0 : t);
  }
  DrawYAxis(y, y_ticks, area, chart.y_label, &svg);
  DrawXAxis(x, x_ticks, area, chart.x_label, height - 6, true, &svg);

  std::vector<Eigen::Vector2d> dots;
  dots.reserve(kept.size());
  for (const Eigen::Vector2d& p : kept) dots.push_back(to_px(p));
  svg.Dots(dots, points.radius_px, points.color, points.opacity);

  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const ViewCamera& camera : cameras) centroid += camera.center;
  if (!cameras.empty()) centroid /= static_cast<double>(cameras.size());
  const size_t every =
      !labels ? cameras.size() + 1
      : cameras.size() > static_cast<size_t>(options.max_labels)
          ? (cameras.size() + options.max_labels - 1) / options.max_labels
          : 1;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const ViewCamera& camera = cameras[i];
    const Eigen::Vector2d c = to_px(camera.center);
    svg.Arrow(c,
              to_px(camera.center + arrow * camera.direction),
              options.camera_color);
    svg.Circle(c, 3, options.camera_color);
    if (!labels || i % every != 0 || camera.label.empty()) continue;
    // Outwards from the centroid (in pixels: y flips).
    Eigen::Vector2d out = to_px(camera.center) - to_px(centroid);
    out = out.norm() > 1e-9 ? out.normalized() : Eigen::Vector2d(1, 0);
    const Eigen::Vector2d at = c + 9 * out + Eigen::Vector2d(0, 3.5);
    const std::string anchor =
        out.x() > 0.35 ? "start" : (out.x() < -0.35 ? "end" : "middle");
    svg.Text(at + Eigen::Vector2d(0, 4 * out.y()),
             camera.label,
             anchor,
             10,
             "#222222");
  }
  return svg.Finish();
}

std::string SvgImageFrame(const Eigen::Vector2d& image_size,
                          const std::vector<PointSeries>& series,
                          const std::vector<FrameArrow>& arrows,
                          const ImageFrameOptions& options) {
  const double w = std::max(image_size.x(), 1.0),
               h = std::max(image_size.y(), 1.0);
  const double frame_w = options.width_px - 2.0;
  const double scale = frame_w / w;
  const double frame_h = h * scale;
  const double top = options.title.empty() ? 1 : 15;
  const double height = top + frame_h + (options.note.empty() ? 1 : 15);
  Svg svg(options.width_px, height, options.title);
  if (!options.title.empty()) {
    svg.Text(
        {options.width_px / 2.0, 11}, options.title, "middle", 10, "#222222");
  }
  svg.Rect(1, top, frame_w, frame_h, "#f6f6f6", "#999999");
  const auto to_px = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(1 + p.x() * scale, top + p.y() * scale);
  };
  for (const PointSeries& s : series) {
    std::vector<Eigen::Vector2d> dots;
    dots.reserve(s.points.size());
    for (const Eigen::Vector2d& p : s.points) {
      if (!p.allFinite() || p.x() < 0 || p.y() < 0 || p.x() > w || p.y() > h) {
        continue;
      }
      dots.push_back(to_px(p));
    }
    svg.Dots(dots, s.radius_px, s.color, s.opacity);
  }
  for (const FrameArrow& a : arrows) {
    svg.Arrow(to_px(a.from), to_px(a.to), options.arrow_color, 1.2);
  }
  if (!options.note.empty()) {
    svg.Text({options.width_px / 2.0, top + frame_h + 12},
             options.note,
             "middle",
             9,
             "#555555");
  }
  return svg.Finish();
}

}  // namespace bayon
