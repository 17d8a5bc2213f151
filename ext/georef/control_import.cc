// SPDX-License-Identifier: BSD-3-Clause
#include "ext/georef/control_import.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace bayon {
namespace {

namespace fs = std::filesystem;

// A point as the file gives it, in the survey's CRS.
struct SurveyPoint {
  std::string name;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  // NaN: not given (the --sigma_m default).
  Eigen::Vector3d sigma =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  ControlPointType type = ControlPointType::kControl;
  int line = 0;
};

struct SurveyFile {
  std::string crs;
  std::string crs_source;  // where the CRS was named, for messages
  std::vector<SurveyPoint> points;
  std::vector<ImageMeasurement> measurements;
  std::vector<int> measurement_lines;
};

std::string Trimmed(std::string text) {
  const auto blank = [](unsigned char c) {
    return std::isspace(c) || c == '"';
  };
  while (!text.empty() && blank(text.back())) text.pop_back();
  size_t start = 0;
  while (start < text.size() && blank(text[start])) ++start;
  return text.substr(start);
}

std::vector<std::string> Fields(const std::string& line, bool commas) {
  std::vector<std::string> fields;
  if (commas) {
    std::stringstream stream(line);
    std::string field;
    while (std::getline(stream, field, ',')) fields.push_back(Trimmed(field));
  } else {
    std::istringstream stream(line);
    std::string field;
    while (stream >> field) fields.push_back(field);
  }
  return fields;
}

// bayon's control files separate fields by white space: Metashape's
// "point 1" becomes "point_1".
std::string NameWithoutSpaces(std::string name) {
  for (char& c : name) {
    if (std::isspace(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

bool IsNumber(const std::string& text) {
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

double Number(const std::string& text,
              const std::string& path,
              int line,
              const char* what) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() ||
      !std::isfinite(value)) {
    ThrowInputError(path, ":", line, ": ", what, " '", text, "' is no number");
  }
  return value;
}

// The file's lines that carry data (no blank lines, no comments), with
// their line numbers.
std::vector<std::pair<int, std::string>> DataLines(const std::string& path) {
  CheckFileExists(path, "input_path");
  std::ifstream in(path);
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string trimmed = Trimmed(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    lines.emplace_back(number, trimmed);
  }
  return lines;
}

// One position per name: a name given again must be where it was.
void AddPoint(const std::string& path,
              SurveyPoint point,
              std::map<std::string, size_t>* by_name,
              std::vector<SurveyPoint>* points) {
  const auto found = by_name->find(point.name);
  if (found == by_name->end()) {
    (*by_name)[point.name] = points->size();
    points->push_back(std::move(point));
    return;
  }
  const SurveyPoint& first = (*points)[found->second];
  if ((first.xyz - point.xyz).norm() > 1e-6) {
    ThrowInputError(path,
                    ":",
                    point.line,
                    ": point ",
                    point.name,
                    " is given at two positions (also on line ",
                    first.line,
                    ")");
  }
}

SurveyFile ReadOdm(const std::string& path) {
  const std::vector<std::pair<int, std::string>> lines = DataLines(path);
  if (lines.empty()) ThrowInputError(path, ": empty (no CRS line)");
  SurveyFile file;
  file.crs = lines[0].second;
  file.crs_source = StrCat(path, ":", lines[0].first);
  std::map<std::string, size_t> by_name;
  std::map<std::tuple<double, double, double>, std::string> unnamed;
  for (size_t i = 1; i < lines.size(); ++i) {
    const auto& [number, line] = lines[i];
    const std::vector<std::string> f = Fields(line, false);
    if (f.size() < 6) {
      ThrowInputError(path,
                      ":",
                      number,
                      ": a GCP line is geo_x geo_y geo_z im_x im_y "
                      "image_name [gcp_name], not '",
                      line,
                      "'");
    }
    SurveyPoint point;
    point.line = number;
    point.xyz = Eigen::Vector3d(Number(f[0], path, number, "geo_x"),
                                Number(f[1], path, number, "geo_y"),
                                Number(f[2], path, number, "geo_z"));
    if (f.size() >= 7) {
      point.name = f[6];
    } else {
      const auto key =
          std::make_tuple(point.xyz.x(), point.xyz.y(), point.xyz.z());
      auto [it, added] =
          unnamed.emplace(key, StrCat("GCP", unnamed.size() + 1));
      point.name = it->second;
    }
    ImageMeasurement m;
    m.point_name = point.name;
    m.image_name = f[5];
    // OpenSfM's pixels have the upper-left pixel's centre at (0, 0),
    // COLMAP's (bayon's) at (0.5, 0.5).
    m.xy = Eigen::Vector2d(Number(f[3], path, number, "im_x") + 0.5,
                           Number(f[4], path, number, "im_y") + 0.5);
    file.measurements.push_back(m);
    file.measurement_lines.push_back(number);
    AddPoint(path, std::move(point), &by_name, &file.points);
  }
  if (file.points.empty())
    ThrowInputError(path, ": no GCP lines after the CRS");
  return file;
}

SurveyFile ReadCsv(const std::string& path, bool metashape) {
  SurveyFile file;
  file.crs_source = "--crs";
  std::map<std::string, size_t> by_name;
  bool first = true;
  for (const auto& [number, line] : DataLines(path)) {
    const std::vector<std::string> f = Fields(line, true);
    // A header ("Label,X/East,...") has no number where x is; only the
    // first line may be one.
    const bool header = first && f.size() >= 2 && !IsNumber(f[1]);
    first = false;
    if (header) continue;
    if (f.size() < 4) {
      ThrowInputError(path,
                      ":",
                      number,
                      metashape ? ": a reference line is label,x,y,z"
                                  "[,accuracy], not '"
                                : ": a line is name,x,y,z[,sx,sy,sz"
                                  "[,control|check]], not '",
                      line,
                      "'");
    }
    SurveyPoint point;
    point.line = number;
    point.name = NameWithoutSpaces(f[0]);
    point.xyz = Eigen::Vector3d(Number(f[1], path, number, "x"),
                                Number(f[2], path, number, "y"),
                                Number(f[3], path, number, "z"));
    if (metashape) {
      if (f.size() >= 5 && !f[4].empty()) {
        point.sigma.setConstant(Number(f[4], path, number, "accuracy"));
      }
    } else if (f.size() >= 7) {
      for (int k = 0; k < 3; ++k) {
        point.sigma[k] = Number(f[4 + k], path, number, "sigma");
      }
      if (f.size() >= 8) {
        if (f[7] != "control" && f[7] != "check") {
          ThrowInputError(path,
                          ":",
                          number,
                          ": type '",
                          f[7],
                          "' is neither control nor check");
        }
        point.type = f[7] == "check" ? ControlPointType::kCheck
                                     : ControlPointType::kControl;
      }
    }
    if (point.sigma.allFinite() && (point.sigma.array() < 0).any()) {
      ThrowInputError(path, ":", number, ": a negative standard deviation");
    }
    AddPoint(path, std::move(point), &by_name, &file.points);
  }
  if (file.points.empty()) ThrowInputError(path, ": no points");
  return file;
}

// Every measurement's photograph must be one of the project's.
void CheckImages(const std::string& path,
                 const SurveyFile& file,
                 const std::vector<std::string>& image_names) {
  if (image_names.empty()) return;
  const std::set<std::string> known(image_names.begin(), image_names.end());
  for (size_t i = 0; i < file.measurements.size(); ++i) {
    const ImageMeasurement& m = file.measurements[i];
    if (known.count(m.image_name)) continue;
    ThrowInputError(path,
                    ":",
                    file.measurement_lines[i],
                    ": GCP ",
                    m.point_name,
                    " is measured in ",
                    m.image_name,
                    ", which is not among the photographs");
  }
}

}  // namespace

void ControlImportOptions::Register(OptionRegistry* r) {
  r->Add("format", &format, "odm, metashape or csv");
  r->Add("crs",
         &crs,
         "The coordinates' CRS (EPSG:xxxx, a PROJ string); csv and "
         "metashape need it, for odm it replaces the file's");
  r->Add("sigma_m",
         &sigma_m,
         "Standard deviation of coordinates that state none, m");
  r->Add("check_names",
         &check_names,
         "Points that are check points (comma-separated)");
}

void ControlImportOptions::Check() const {
  CheckOption(format == "odm" || format == "metashape" || format == "csv",
              "format",
              "odm, metashape or csv",
              format);
  CheckOption(format == "odm" || !crs.empty(),
              "crs",
              "given for csv and metashape (EPSG:xxxx)",
              crs);
  CheckOption(sigma_m >= 0, "sigma_m", ">= 0", sigma_m);
}

ImportedControl ImportControl(const std::string& path,
                              const ControlImportOptions& options,
                              const std::vector<std::string>& image_names) {
  options.Check();
  SurveyFile file = options.format == "odm"
                        ? ReadOdm(path)
                        : ReadCsv(path, options.format == "metashape");
  if (!options.crs.empty()) {
    file.crs = options.crs;
    file.crs_source = "--crs";
  }
  CheckImages(path, file, image_names);

  // The model's frame: the survey's own projected CRS where it is in
  // metres, else the UTM zone of the points; its origin the points'
  // centroid, to the metre.
  ImportedControl control;
  control.frame.source_crs = file.crs;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const SurveyPoint& point : file.points) mean += point.xyz;
  mean /= static_cast<double>(file.points.size());
  std::vector<Eigen::Vector3d> projected;
  try {
    const std::string source = NormalizeCrs(file.crs);
    control.frame.crs = LocalFrameCrs(source, mean);
    const CrsTransform transform(source, control.frame.crs);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const SurveyPoint& point : file.points) {
      projected.push_back(transform.Forward(point.xyz));
      sum += projected.back();
    }
    control.frame.origin =
        (sum / static_cast<double>(projected.size())).array().round().matrix();
  } catch (const InputError& error) {
    // Where the CRS was named: the file's first line, or --crs.
    ThrowInputError(file.crs_source, ": ", error.what());
  }
  std::set<std::string> checks;
  for (const std::string& name : Fields(options.check_names, true)) {
    if (!name.empty()) checks.insert(name);
  }
  for (size_t i = 0; i < file.points.size(); ++i) {
    const SurveyPoint& survey = file.points[i];
    ControlPoint point;
    point.name = survey.name;
    point.xyz = projected[i] - control.frame.origin;
    point.sigma = survey.sigma.allFinite()
                      ? survey.sigma
                      : Eigen::Vector3d::Constant(options.sigma_m);
    point.type =
        checks.erase(survey.name) ? ControlPointType::kCheck : survey.type;
    control.points.push_back(point);
  }
  if (!checks.empty()) {
    ThrowInputError(
        "check_names: '", *checks.begin(), "' is no point of ", path);
  }
  control.measurements = std::move(file.measurements);
  return control;
}

void WriteImportedControl(const std::string& folder,
                          const ImportedControl& control) {
  fs::create_directories(folder);
  WriteControlPoints(folder + "/points.txt", control.points);
  if (!control.measurements.empty()) {
    WriteImageMeasurements(folder + "/observations.txt", control.measurements);
  } else {
    // An earlier import's measurements are not this survey's.
    fs::remove(folder + "/observations.txt");
  }
  WriteGeoFrame(folder + "/crs.json", control.frame);
}

}  // namespace bayon
