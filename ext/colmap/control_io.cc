// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/control_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>

namespace bayon {
namespace {

// Calls `parse(tokens, fail)` for every data line of a text file.
template <typename ParseLine>
void ForEachLine(const std::string& path, const ParseLine& parse) {
  std::istringstream text(ReadFileToString(path));
  std::string line;
  int line_number = 0;
  while (std::getline(text, line)) {
    ++line_number;
    const size_t comment = line.find('#');
    if (comment != std::string::npos) line.resize(comment);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    std::string word;
    while (words >> word) tokens.push_back(word);
    if (tokens.empty()) continue;
    auto fail = [&](const std::string& message) {
      ThrowInputError(path, ":", line_number, ": ", message);
    };
    parse(tokens, fail);
  }
}

template <typename Fail>
double Number(const std::string& token, const char* what, const Fail& fail) {
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  if (end == token.c_str() || *end != '\0') {
    fail(StrCat(what, " '", token, "' is not a number"));
  }
  if (!std::isfinite(value)) fail(StrCat(what, " is not finite"));
  return value;
}

std::ostringstream Stream() {
  std::ostringstream out;
  out.precision(std::numeric_limits<double>::max_digits10);
  return out;
}

}  // namespace

std::vector<ControlPoint> ReadControlPoints(const std::string& path) {
  std::vector<ControlPoint> points;
  std::set<std::string> names;
  ForEachLine(path, [&](const std::vector<std::string>& t, const auto& fail) {
    if (t.size() != 4 && t.size() != 7 && t.size() != 8) {
      fail("expected NAME X Y Z [SX SY SZ [TYPE]]");
    }
    ControlPoint point;
    point.name = t[0];
    for (int k = 0; k < 3; ++k)
      point.xyz(k) = Number(t[1 + k], "coordinate", fail);
    if (t.size() >= 7) {
      for (int k = 0; k < 3; ++k) {
        point.sigma(k) = Number(t[4 + k], "standard deviation", fail);
        if (point.sigma(k) < 0)
          fail("standard deviations must not be negative");
      }
    }
    if (t.size() == 8) {
      if (t[7] == "control")
        point.type = ControlPointType::kControl;
      else if (t[7] == "check")
        point.type = ControlPointType::kCheck;
      else
        fail("TYPE must be 'control' or 'check', not '" + t[7] + "'");
    }
    if (!names.insert(point.name).second)
      fail("point '" + point.name + "' appears twice");
    points.push_back(point);
  });
  return points;
}

std::vector<ImageMeasurement> ReadImageMeasurements(const std::string& path) {
  std::vector<ImageMeasurement> measurements;
  std::set<std::pair<std::string, std::string>> seen;
  ForEachLine(path, [&](const std::vector<std::string>& t, const auto& fail) {
    if (t.size() != 4 && t.size() != 5)
      fail("expected NAME IMAGE_NAME X Y [SIGMA]");
    ImageMeasurement measurement;
    measurement.point_name = t[0];
    measurement.image_name = t[1];
    measurement.xy.x() = Number(t[2], "X", fail);
    measurement.xy.y() = Number(t[3], "Y", fail);
    if (t.size() == 5) {
      measurement.sigma_px = Number(t[4], "SIGMA", fail);
      if (measurement.sigma_px <= 0) fail("SIGMA must be positive");
    }
    if (!seen.insert({t[0], t[1]}).second) {
      fail("point '" + t[0] + "' is measured twice in image '" + t[1] + "'");
    }
    measurements.push_back(measurement);
  });
  return measurements;
}

std::vector<DistanceObservation> ReadDistances(const std::string& path) {
  std::vector<DistanceObservation> distances;
  ForEachLine(path, [&](const std::vector<std::string>& t, const auto& fail) {
    if (t.size() < 3 || t.size() > 5) {
      fail("expected NAME_A NAME_B DISTANCE [SIGMA [vertical]]");
    }
    DistanceObservation distance;
    distance.name1 = t[0];
    distance.name2 = t[1];
    if (distance.name1 == distance.name2)
      fail("a distance needs two different points");
    distance.distance_m = Number(t[2], "DISTANCE", fail);
    if (distance.distance_m <= 0) fail("DISTANCE must be positive");
    if (t.size() >= 4) {
      distance.sigma_m = Number(t[3], "SIGMA", fail);
      if (distance.sigma_m < 0) fail("SIGMA must not be negative");
    }
    if (t.size() == 5) {
      if (t[4] != "vertical") fail("the last field may only be 'vertical'");
      distance.vertical = true;
    }
    distances.push_back(distance);
  });
  return distances;
}

void WriteControlPoints(const std::string& path,
                        const std::vector<ControlPoint>& points) {
  std::ostringstream out = Stream();
  out << "# bayon control points: NAME X Y Z SX SY SZ TYPE\n"
      << "# metres; SX SY SZ standard deviations (0 = fixed); TYPE control or "
         "check\n";
  for (const ControlPoint& p : points) {
    out << p.name << " " << p.xyz.x() << " " << p.xyz.y() << " " << p.xyz.z()
        << " " << p.sigma.x() << " " << p.sigma.y() << " " << p.sigma.z() << " "
        << (p.type == ControlPointType::kCheck ? "check" : "control") << "\n";
  }
  WriteFileAtomically(path, out.str());
}

void WriteImageMeasurements(const std::string& path,
                            const std::vector<ImageMeasurement>& measurements) {
  std::ostringstream out = Stream();
  out << "# bayon image measurements: NAME IMAGE_NAME X Y [SIGMA]\n"
      << "# COLMAP pixels (upper-left pixel centre at 0.5 0.5); SIGMA in "
         "pixels\n";
  for (const ImageMeasurement& m : measurements) {
    out << m.point_name << " " << m.image_name << " " << m.xy.x() << " "
        << m.xy.y();
    if (m.sigma_px > 0) out << " " << m.sigma_px;
    out << "\n";
  }
  WriteFileAtomically(path, out.str());
}

void WriteDistances(const std::string& path,
                    const std::vector<DistanceObservation>& distances) {
  std::ostringstream out = Stream();
  out << "# bayon distances: NAME_A NAME_B DISTANCE SIGMA [vertical]\n"
      << "# metres; 'vertical' marks a levelling bar (defines the vertical "
         "axis)\n";
  for (const DistanceObservation& d : distances) {
    out << d.name1 << " " << d.name2 << " " << d.distance_m << " " << d.sigma_m;
    if (d.vertical) out << " vertical";
    out << "\n";
  }
  WriteFileAtomically(path, out.str());
}

double MeasurementSigma(const Eigen::Matrix2d& covariance) {
  return std::sqrt(
      std::max(0.0,
               Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance)
                   .eigenvalues()
                   .maxCoeff()));
}

}  // namespace bayon
