// SPDX-License-Identifier: BSD-3-Clause
#include "ext/targets/coded_targets.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/statistics.h"
#include "ext/image/interpolation.h"

#include <Eigen/Dense>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace bayon {
namespace {

struct DictionaryInfo {
  const char* name;
  int opencv_id;
  int cells;
};

constexpr DictionaryInfo kDictionaries[] = {
    {"aruco_4x4_50", cv::aruco::DICT_4X4_50, 4},
    {"aruco_5x5_100", cv::aruco::DICT_5X5_100, 5},
    {"aruco_6x6_250", cv::aruco::DICT_6X6_250, 6},
    {"apriltag_36h11", cv::aruco::DICT_APRILTAG_36h11, 6},
};

const DictionaryInfo& FindDictionary(const std::string& name) {
  std::string choices;
  for (const DictionaryInfo& info : kDictionaries) {
    if (name == info.name) return info;
    choices += choices.empty() ? "" : ", ";
    choices += info.name;
  }
  ThrowInputError(
      "unknown coded target dictionary '", name, "' (choices: ", choices, ")");
}

cv::Ptr<cv::aruco::Dictionary> OpenCvDictionary(const std::string& name) {
  return cv::aruco::getPredefinedDictionary(FindDictionary(name).opencv_id);
}

// A straight edge fitted to points: through `point` along `direction`
// (unit), with the variances of its offset along its normal and of its
// angle, both at `point` (the points' centroid, where the two are
// uncorrelated).
struct EdgeLine {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();
  double offset_variance = 0;  // pixels^2
  double angle_variance = 0;   // rad^2
  double sigma_px = 0;         // the points' scatter about the line
  int num_points = 0;
};

// The line moved by `offset` along its normal and turned by `angle` about
// its point.
EdgeLine Perturbed(const EdgeLine& line, double offset, double angle) {
  EdgeLine moved = line;
  const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
  moved.point += offset * normal;
  moved.direction = Eigen::Rotation2Dd(angle) * line.direction;
  return moved;
}

// Where two lines meet; nullopt for parallel ones.
std::optional<Eigen::Vector2d> Intersect(const Eigen::Vector2d& p1,
                                         const Eigen::Vector2d& d1,
                                         const Eigen::Vector2d& p2,
                                         const Eigen::Vector2d& d2) {
  Eigen::Matrix2d A;
  A << d1, -d2;
  if (std::abs(A.determinant()) < 1e-12) return std::nullopt;
  return p1 + A.inverse().row(0).dot(p2 - p1) * d1;
}

// The corners (line k - 1 meets line k at corner k) and the point where
// the diagonals meet.
std::optional<Eigen::Vector2d> CentreOf(const std::array<EdgeLine, 4>& lines,
                                        std::array<Eigen::Vector2d, 4>* out) {
  std::array<Eigen::Vector2d, 4> corners;
  for (int k = 0; k < 4; ++k) {
    const EdgeLine& before = lines[(k + 3) % 4];
    const std::optional<Eigen::Vector2d> corner = Intersect(
        before.point, before.direction, lines[k].point, lines[k].direction);
    if (!corner) return std::nullopt;
    corners[k] = *corner;
  }
  if (out != nullptr) *out = corners;
  return Intersect(
      corners[0], corners[2] - corners[0], corners[1], corners[3] - corners[1]);
}

// The least-squares line through points (at least 3).
EdgeLine FitLine(const std::vector<Eigen::Vector2d>& points) {
  EdgeLine line;
  line.num_points = static_cast<int>(points.size());
  for (const Eigen::Vector2d& p : points) line.point += p;
  line.point /= line.num_points;
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d& p : points) {
    scatter += (p - line.point) * (p - line.point).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
  line.direction = solver.eigenvectors().col(1);
  const double residual_sq = solver.eigenvalues()(0);
  const double spread_sq = solver.eigenvalues()(1);
  const double variance = residual_sq / (line.num_points - 2);
  line.sigma_px = std::sqrt(variance);
  line.offset_variance = variance / line.num_points;
  line.angle_variance = variance / spread_sq;
  return line;
}

// The edge along the side from `from` to `to`: where, across the side,
// the grey value falls towards `inside`. nullopt with `why` where
// too few points are found.
std::optional<EdgeLine> MeasureSide(const cv::Mat& grey,
                                    const Eigen::Vector2d& from,
                                    const Eigen::Vector2d& to,
                                    const Eigen::Vector2d& inside,
                                    double search_px,
                                    std::string* why) {
  const double length = (to - from).norm();
  const Eigen::Vector2d along = (to - from) / length;
  Eigen::Vector2d normal(-along.y(), along.x());
  if (normal.dot(inside - from) < 0) normal = -normal;
  // Samples a quarter pixel apart across the side; the ends of the side,
  // where the neighbouring sides' edges blur into the profile, are left.
  constexpr double kStep = 0.25;
  // The steepest sample is looked for within search_px; the profile
  // reaches kReach further, so that an edge near the end of that window
  // keeps its whole slope.
  constexpr double kReach = 1.5;
  const int half = static_cast<int>(std::floor(search_px / kStep));
  const int reach = half + static_cast<int>(kReach / kStep);
  const double end = std::max(0.1 * length, search_px + 1);
  std::vector<Eigen::Vector2d> points;
  std::vector<double> profile(2 * reach + 1);
  for (double t = end; t <= length - end; t += 1.0) {
    const Eigen::Vector2d on_side = from + t * along;
    bool inside_image = true;
    for (int i = -reach; i <= reach && inside_image; ++i) {
      const Eigen::Vector2d at = on_side + i * kStep * normal;
      ImageSample sample;
      inside_image =
          SampleImage(grey, at.x(), at.y(), Interpolation::kBilinear, &sample);
      profile[i + reach] = sample.dx * normal.x() + sample.dy * normal.y();
    }
    if (!inside_image) continue;
    const int lowest = static_cast<int>(
        std::min_element(profile.begin() + (reach - half),
                         profile.begin() + (reach + half + 1)) -
        profile.begin());
    if (profile[lowest] >= 0) continue;
    // The centroid of the falling slope around the steepest sample: for an
    // edge that the pixels integrate it is the edge, where the peak of an
    // interpolated profile is drawn towards the pixel grid (a bias that the
    // points of a side parallel to the rows or columns all share; with the
    // peak's parabola, 0.057 px RMS on the centres of the unit test's
    // markers). Its top part only, above 0.7 of the peak: the tails of the
    // edges a cell away (the margin's outer edge, a white cell inside the
    // border) reach into the slope of a blurred edge and draw a wider
    // centroid towards them. Measured on the unit test's markers, centre
    // RMS for fractions 0.25 / 0.5 / 0.7 / 0.8 / 0.85: 0.017 / 0.015 /
    // 0.012 / 0.017 / 0.027 px (with OpenCV's sub-pixel corners).
    const double floor = 0.7 * profile[lowest];
    int first = lowest, last = lowest;
    while (first > 0 && profile[first - 1] < floor) --first;
    while (last < 2 * reach && profile[last + 1] < floor) ++last;
    if (first == 0 || last == 2 * reach) continue;  // cut off
    double weight = 0, moment = 0;
    for (int i = first; i <= last; ++i) {
      weight += floor - profile[i];
      moment += (floor - profile[i]) * (i - reach);
    }
    points.push_back(on_side + moment / weight * kStep * normal);
  }
  if (points.size() < 5) {
    *why = StrCat("an edge was found at ", points.size(), " points (< 5)");
    return std::nullopt;
  }
  // A point on something else (a twig across the side, a joint beside a
  // narrow margin) is a blunder of the line: fitted, the points beyond
  // three robust standard deviations (1.4826 times the median residual, at
  // least kMinSigma) left out, and fitted again, as long as more than half
  // of them remain.
  constexpr double kMinSigma = 0.05;
  const size_t num_found = points.size();
  EdgeLine line = FitLine(points);
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
    std::vector<double> residuals;
    for (const Eigen::Vector2d& p : points) {
      residuals.push_back(std::abs(normal.dot(p - line.point)));
    }
    const double limit = 3 * std::max(kMinSigma, 1.4826 * Median(residuals));
    std::vector<Eigen::Vector2d> kept;
    for (size_t i = 0; i < points.size(); ++i) {
      if (residuals[i] <= limit) kept.push_back(points[i]);
    }
    if (kept.size() == points.size()) break;
    if (kept.size() < 5 || 2 * kept.size() <= num_found) {
      *why = StrCat("its edge is a line at ",
                    kept.size(),
                    " of ",
                    num_found,
                    " points only");
      return std::nullopt;
    }
    points = std::move(kept);
    line = FitLine(points);
  }
  return line;
}

// The target's centre and corners from OpenCV's corners (COLMAP
// coordinates), with the covariance; false with `why` where a side is no
// line.
bool MeasureTarget(const cv::Mat& grey,
                   const std::array<Eigen::Vector2d, 4>& approximate,
                   int cells,
                   const CodedTargetOptions& options,
                   CodedTarget* target,
                   std::string* why) {
  Eigen::Vector2d middle = Eigen::Vector2d::Zero();
  std::array<double, 4> length;
  for (int k = 0; k < 4; ++k) {
    middle += approximate[k] / 4;
    length[k] = (approximate[(k + 1) % 4] - approximate[k]).norm();
  }
  std::array<EdgeLine, 4> lines;
  for (int k = 0; k < 4; ++k) {
    // A cell across the side at most (the neighbouring sides' length over
    // the cells, foreshortened alike): the nearest edge that also falls
    // inwards is two cells in (the border's inner edge rises), and the
    // margin outside is a cell wide.
    const double cell_px =
        0.5 * (length[(k + 1) % 4] + length[(k + 3) % 4]) / (cells + 2);
    const double search_px = std::min(options.edge_search_px, cell_px);
    std::string side_why;
    const std::optional<EdgeLine> line = MeasureSide(grey,
                                                     approximate[k],
                                                     approximate[(k + 1) % 4],
                                                     middle,
                                                     search_px,
                                                     &side_why);
    if (!line) {
      *why = StrCat("side ", k + 1, ": ", side_why);
      return false;
    }
    if (line->sigma_px > options.max_line_sigma_px) {
      *why = StrCat("side ",
                    k + 1,
                    " is not straight (its edge scatters by ",
                    line->sigma_px,
                    " px > ",
                    options.max_line_sigma_px,
                    ")");
      return false;
    }
    lines[k] = *line;
    target->line_sigma_px[k] = line->sigma_px;
  }
  const std::optional<Eigen::Vector2d> centre =
      CentreOf(lines, &target->corners);
  if (!centre) {
    *why = "its sides do not meet";
    return false;
  }
  target->centre = *centre;
  // Propagation of the lines' offsets and angles, by central differences
  // (the centre is a smooth function of them).
  Eigen::Matrix<double, 2, 8> jacobian;
  Eigen::Matrix<double, 8, 1> variances;
  for (int k = 0; k < 4; ++k) {
    const double steps[2] = {1e-3, 1e-5};  // pixels, radians
    variances(2 * k) =
        lines[k].offset_variance + options.edge_bias_px * options.edge_bias_px;
    variances(2 * k + 1) = lines[k].angle_variance;
    for (int p = 0; p < 2; ++p) {
      const double offset = p == 0 ? steps[0] : 0,
                   angle = p == 1 ? steps[1] : 0;
      std::array<EdgeLine, 4> plus = lines, minus = lines;
      plus[k] = Perturbed(lines[k], offset, angle);
      minus[k] = Perturbed(lines[k], -offset, -angle);
      const std::optional<Eigen::Vector2d> a = CentreOf(plus, nullptr);
      const std::optional<Eigen::Vector2d> b = CentreOf(minus, nullptr);
      if (!a || !b) {
        *why = "its sides do not meet";
        return false;
      }
      jacobian.col(2 * k + p) = (*a - *b) / (2 * steps[p]);
    }
  }
  target->covariance = jacobian * variances.asDiagonal() * jacobian.transpose();
  return true;
}

}  // namespace

void CodedTargetOptions::Register(OptionRegistry* r) {
  r->Add("dictionary",
         &dictionary,
         "aruco_4x4_50, aruco_5x5_100, aruco_6x6_250 or "
         "apriltag_36h11");
  r->Add("name_prefix", &name_prefix, "Names are this and the code");
  r->Add("min_side_px",
         &min_side_px,
         "Markers with shorter sides are not looked for, px");
  r->Add("edge_search_px",
         &edge_search_px,
         "How far across a side its edge is looked for, px");
  r->Add("max_line_sigma_px",
         &max_line_sigma_px,
         "A side whose edge points scatter more is no measurement, "
         "px");
  r->Add("edge_bias_px",
         &edge_bias_px,
         "A side's error that its points' scatter does not show, "
         "added to each line's sigma, px");
}

void CodedTargetOptions::Check() const {
  FindDictionary(dictionary);
  CheckOption(min_side_px >= 8, "min_side_px", ">= 8", min_side_px);
  CheckOption(edge_search_px >= 1, "edge_search_px", ">= 1", edge_search_px);
  CheckOption(edge_bias_px >= 0, "edge_bias_px", ">= 0", edge_bias_px);
  CheckOption(
      max_line_sigma_px > 0, "max_line_sigma_px", "> 0", max_line_sigma_px);
}

int CodedTargetDictionarySize(const std::string& dictionary) {
  return OpenCvDictionary(dictionary)->bytesList.rows;
}

int CodedTargetCells(const std::string& dictionary) {
  return FindDictionary(dictionary).cells;
}

std::vector<int> ParseCodedTargetCodes(const std::string& text) {
  std::vector<int> codes;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    const size_t dash = item.find('-');
    try {
      size_t used = 0;
      const int first = std::stoi(item, &used);
      const int last = dash == std::string::npos
                           ? first
                           : std::stoi(item.substr(dash + 1), &used);
      if (last < first) throw std::invalid_argument(item);
      for (int code = first; code <= last; ++code) codes.push_back(code);
    } catch (const std::logic_error&) {
      ThrowInputError("codes: '", item, "' is not a code or a range a-b");
    }
    start = end + 1;
  }
  return codes;
}

cv::Mat CodedTargetPattern(const std::string& dictionary, int code) {
  const int size = CodedTargetDictionarySize(dictionary);
  if (code < 0 || code >= size) {
    ThrowInputError("code ",
                    code,
                    " is not in the dictionary ",
                    dictionary,
                    " (codes 0 to ",
                    size - 1,
                    ")");
  }
  cv::Mat pattern;
  const int side = CodedTargetCells(dictionary) + 2;
  cv::aruco::drawMarker(OpenCvDictionary(dictionary), code, side, pattern, 1);
  return pattern;
}

std::vector<CodedTarget> DetectCodedTargets(const cv::Mat& image,
                                            const CodedTargetOptions& options,
                                            const std::string& what,
                                            CodedTargetReport* report) {
  options.Check();
  CodedTargetReport local;
  if (report == nullptr) report = &local;
  *report = CodedTargetReport();
  if (image.empty() || image.depth() != CV_8U ||
      (image.channels() != 1 && image.channels() != 3)) {
    ThrowInputError(what,
                    ": coded targets are looked for in 8-bit grey or "
                    "colour images");
  }
  cv::Mat gray = image;
  if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  const cv::Ptr<cv::aruco::DetectorParameters> parameters =
      cv::aruco::DetectorParameters::create();
  parameters->minMarkerPerimeterRate =
      4.0 * options.min_side_px / std::max(gray.cols, gray.rows);
  // The corners of the contour's polygon, unrefined: the edges are
  // measured here. (OpenCV's sub-pixel refinement at times moved a corner
  // to another corner of the pattern, a cell or more off, and the edge
  // search then missed the side: on the rendered tower 183 of the 188
  // visible targets measured with it, 186 without.)
  parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  std::vector<std::vector<cv::Point2f>> found;
  std::vector<int> codes;
  cv::aruco::detectMarkers(
      gray, OpenCvDictionary(options.dictionary), found, codes, parameters);
  report->num_decoded = static_cast<int>(codes.size());

  // OpenCV's corners have the upper-left pixel's centre at (0, 0).
  const auto colmap = [](const cv::Point2f& p) {
    return Eigen::Vector2d(p.x + 0.5, p.y + 0.5);
  };
  std::vector<int> order(codes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return codes[a] < codes[b];
  });
  cv::Mat grey;
  gray.convertTo(grey, CV_32F);
  const int cells = CodedTargetCells(options.dictionary);
  std::vector<CodedTarget> targets;
  for (int k : order) {
    CodedTarget target;
    target.code = codes[k];
    target.name = StrCat(options.name_prefix, codes[k]);
    std::array<Eigen::Vector2d, 4> approximate;
    for (int c = 0; c < 4; ++c) approximate[c] = colmap(found[k][c]);
    std::string why;
    if (!MeasureTarget(grey, approximate, cells, options, &target, &why)) {
      report->refused.push_back(StrCat(target.name, ": ", why));
      continue;
    }
    targets.push_back(target);
  }
  // A code measured twice: a print shown twice (a decoding error that the
  // measurement took for a marker would be as bad). Two targets may not
  // share a name.
  for (size_t i = 1; i < targets.size(); ++i) {
    const CodedTarget& a = targets[i - 1];
    const CodedTarget& b = targets[i];
    if (a.code != b.code) continue;
    ThrowInputError(what,
                    ": target ",
                    a.name,
                    " is seen twice, at (",
                    a.centre.x(),
                    ", ",
                    a.centre.y(),
                    ") and (",
                    b.centre.x(),
                    ", ",
                    b.centre.y(),
                    ") px; print each code once");
  }
  report->num_measured = static_cast<int>(targets.size());
  return targets;
}

void WriteCodedTargetSheet(const CodedTargetOptions& options,
                           const std::vector<int>& codes,
                           double side_mm,
                           const std::string& path) {
  options.Check();
  CheckOption(side_mm > 0, "side_mm", "> 0", side_mm);
  constexpr double kPageWidth = 210, kPageHeight = 297, kPageMargin = 10;
  const int cells = CodedTargetCells(options.dictionary) + 2;
  const double cell = side_mm / cells;
  // A white margin of one cell around each marker, and a line for its name.
  const double label = std::max(4.0, 0.12 * side_mm);
  const double tile_width = side_mm + 2 * cell;
  const double tile_height = tile_width + label;
  const int columns =
      static_cast<int>((kPageWidth - 2 * kPageMargin) / tile_width);
  const int rows =
      static_cast<int>((kPageHeight - 2 * kPageMargin) / tile_height);
  if (static_cast<int>(codes.size()) > columns * rows) {
    ThrowInputError(codes.size(),
                    " targets of ",
                    side_mm,
                    " mm do not fit on an A4 page (at most ",
                    columns * rows,
                    "); print fewer or smaller ones");
  }
  std::ostringstream svg;
  svg << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kPageWidth
      << "mm\" height=\"" << kPageHeight << "mm\" viewBox=\"0 0 " << kPageWidth
      << " " << kPageHeight << "\">\n"
      << "<!-- bayon coded targets: " << options.dictionary << ", side "
      << side_mm << " mm (the black square's outer edge); print at 100 %"
      << " and check the side with a ruler -->\n"
      << "<rect width=\"" << kPageWidth << "\" height=\"" << kPageHeight
      << "\" fill=\"white\"/>\n";
  for (size_t i = 0; i < codes.size(); ++i) {
    const cv::Mat pattern = CodedTargetPattern(options.dictionary, codes[i]);
    const double x0 =
        kPageMargin + static_cast<double>(i % columns) * tile_width + cell;
    const double y0 =
        kPageMargin + static_cast<double>(i / columns) * tile_height + cell;
    svg << "<g id=\"" << options.name_prefix << codes[i]
        << "\" shape-rendering=\"crispEdges\">\n";
    for (int r = 0; r < cells; ++r) {
      for (int c = 0; c < cells; ++c) {
        if (pattern.at<uint8_t>(r, c) != 0) continue;
        svg << "<rect x=\"" << x0 + c * cell << "\" y=\"" << y0 + r * cell
            << "\" width=\"" << cell << "\" height=\"" << cell << "\"/>\n";
      }
    }
    svg << "<text x=\"" << x0 + side_mm / 2 << "\" y=\""
        << y0 + side_mm + cell + 0.7 * label
        << "\" font-family=\"sans-serif\" font-size=\"" << 0.6 * label
        << "\" text-anchor=\"middle\">" << options.name_prefix << codes[i]
        << "</text>\n</g>\n";
  }
  svg << "</svg>\n";
  WriteFileAtomically(path, svg.str());
}

}  // namespace bayon
