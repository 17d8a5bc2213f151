// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/ground_truth_import.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <tuple>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A non-blank line of a text file, split at white space.
struct TextLine {
  int number = 0;  // 1-based
  std::vector<std::string> tokens;
};

std::vector<TextLine> ReadTextLines(const std::string& path) {
  const std::string text = ReadFileToString(path);
  std::vector<TextLine> lines;
  std::istringstream stream(text);
  std::string line;
  int number = 0;
  while (std::getline(stream, line)) {
    ++number;
    std::istringstream fields(line);
    TextLine entry;
    entry.number = number;
    std::string token;
    while (fields >> token) entry.tokens.push_back(token);
    if (!entry.tokens.empty()) lines.push_back(std::move(entry));
  }
  return lines;
}

// The token as a finite number; `field` names it in the message.
double ParseNumber(const std::string& token,
                   const std::string& path,
                   int line,
                   const std::string& field) {
  const char* start = token.c_str();
  char* end = nullptr;
  const double value = std::strtod(start, &end);
  if (end == start || *end != '\0') {
    ThrowInputError(
        path, ":", line, ": ", field, " is '", token, "', not a number");
  }
  if (!std::isfinite(value)) {
    ThrowInputError(
        path, ":", line, ": ", field, " is '", token, "', not a finite number");
  }
  return value;
}

// A positive whole number (a count or an image size).
int ParseCount(const std::string& token,
               const std::string& path,
               int line,
               const std::string& field,
               int min_value) {
  const double value = ParseNumber(token, path, line, field);
  if (value != std::floor(value) || value < min_value || value > 1e9) {
    ThrowInputError(path,
                    ":",
                    line,
                    ": ",
                    field,
                    " is '",
                    token,
                    "', expected a whole number >= ",
                    min_value);
  }
  return static_cast<int>(value);
}

// R as a rotation, made exactly orthonormal; refused unless it already is
// within the tolerance, with det +1.
Eigen::Quaterniond CheckedRotation(const Eigen::Matrix3d& R,
                                   const GroundTruthImportOptions& options,
                                   const std::string& path,
                                   int line,
                                   const std::string& what) {
  const double error =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (!(error <= options.max_rotation_error) || !(det > 0)) {
    ThrowInputError(path,
                    ":",
                    line,
                    ": ",
                    what,
                    " is not a rotation matrix: max |R^T R - I| = ",
                    error,
                    " (at most ",
                    options.max_rotation_error,
                    " expected), det = ",
                    det,
                    " (expected +1)");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d nearest = svd.matrixU() * svd.matrixV().transpose();
  return Eigen::Quaterniond(nearest).normalized();
}

// K as COLMAP pixel intrinsics [fx 0 cx; 0 fy cy; 0 0 1], or refused.
Eigen::Matrix3d CheckedIntrinsics(Eigen::Matrix3d K,
                                  const GroundTruthImportOptions& options,
                                  const std::string& path,
                                  int line) {
  if (!(K(2, 2) > 0)) {
    ThrowInputError(
        path, ":", line, ": K has k33 = ", K(2, 2), ", expected 1 (or > 0)");
  }
  K /= K(2, 2);
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0)) {
    ThrowInputError(path,
                    ":",
                    line,
                    ": K has focal lengths k11 = ",
                    K(0, 0),
                    ", k22 = ",
                    K(1, 1),
                    ", expected both > 0");
  }
  const double zero_tolerance = 1e-9 * std::max(K(0, 0), K(1, 1));
  if (std::abs(K(1, 0)) > zero_tolerance ||
      std::abs(K(2, 0)) > zero_tolerance ||
      std::abs(K(2, 1)) > zero_tolerance) {
    ThrowInputError(path,
                    ":",
                    line,
                    ": K is not upper triangular (k21 = ",
                    K(1, 0),
                    ", k31 = ",
                    K(2, 0),
                    ", k32 = ",
                    K(2, 1),
                    ", expected 0)");
  }
  if (std::abs(K(0, 1)) > options.max_skew_px) {
    ThrowInputError(path,
                    ":",
                    line,
                    ": K has skew k12 = ",
                    K(0, 1),
                    " px; COLMAP's camera models have none (at most ",
                    options.max_skew_px,
                    " px accepted as zero)");
  }
  Eigen::Matrix3d colmap_K = Eigen::Matrix3d::Identity();
  colmap_K(0, 0) = K(0, 0);
  colmap_K(1, 1) = K(1, 1);
  colmap_K(0, 2) = K(0, 2) + options.pixel_origin_offset_px;
  colmap_K(1, 2) = K(1, 2) + options.pixel_origin_offset_px;
  return colmap_K;
}

void CheckUniqueNames(const std::vector<GroundTruthView>& views) {
  std::map<std::string, const GroundTruthView*> seen;
  for (const GroundTruthView& view : views) {
    const auto [it, inserted] = seen.emplace(view.name, &view);
    if (!inserted) {
      ThrowInputError(view.file,
                      ":",
                      view.line,
                      ": image ",
                      view.name,
                      " is listed twice (first at ",
                      it->second->file,
                      ":",
                      it->second->line,
                      ")");
    }
  }
}

constexpr int kMiddleburyFields = 22;  // name, K (9), R (9), t (3)

GroundTruthView ParseStrechaFile(const std::string& path,
                                 const GroundTruthImportOptions& options) {
  const std::string filename = fs::path(path).filename().string();
  const std::string suffix = ".camera";
  if (filename.size() <= suffix.size() ||
      filename.compare(
          filename.size() - suffix.size(), suffix.size(), suffix) != 0) {
    ThrowInputError(path,
                    ": a Strecha camera file is named <image name>.camera");
  }
  // What each non-blank line holds, in order.
  struct Row {
    const char* what;
    int num_values;
  };
  static const Row kRows[] = {{"K row 1", 3},
                              {"K row 2", 3},
                              {"K row 3", 3},
                              {"the distortion row", 3},
                              {"R row 1", 3},
                              {"R row 2", 3},
                              {"R row 3", 3},
                              {"the camera centre C", 3},
                              {"the image size (width height)", 2}};
  constexpr int kNumRows = sizeof(kRows) / sizeof(kRows[0]);
  const std::vector<TextLine> lines = ReadTextLines(path);
  for (int row = 0; row < kNumRows; ++row) {
    if (row >= static_cast<int>(lines.size())) {
      ThrowInputError(path,
                      ":",
                      lines.empty() ? 1 : lines.back().number + 1,
                      ": file ends, expected ",
                      kRows[row].what);
    }
    const int num_tokens = static_cast<int>(lines[row].tokens.size());
    if (num_tokens != kRows[row].num_values) {
      ThrowInputError(path,
                      ":",
                      lines[row].number,
                      ": expected ",
                      kRows[row].num_values,
                      " values (",
                      kRows[row].what,
                      "), got ",
                      num_tokens);
    }
  }
  if (static_cast<int>(lines.size()) > kNumRows) {
    ThrowInputError(path,
                    ":",
                    lines[kNumRows].number,
                    ": unexpected line after the image size (a Strecha camera "
                    "file has 9 lines)");
  }
  const auto value = [&](int row, int col) {
    return ParseNumber(lines[row].tokens[col],
                       path,
                       lines[row].number,
                       StrCat(kRows[row].what, " value ", col + 1));
  };
  Eigen::Matrix3d K, R;
  Eigen::Vector3d distortion, center;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      K(r, c) = value(r, c);
      R(r, c) = value(4 + r, c);
    }
    distortion(r) = value(3, r);
    center(r) = value(7, r);
  }
  GroundTruthView view;
  view.name = filename.substr(0, filename.size() - suffix.size());
  view.file = path;
  view.line = 1;
  view.size_line = lines[8].number;
  view.width = ParseCount(lines[8].tokens[0], path, view.size_line, "width", 1);
  view.height =
      ParseCount(lines[8].tokens[1], path, view.size_line, "height", 1);
  if (distortion.cwiseAbs().maxCoeff() != 0) {
    ThrowInputError(path,
                    ":",
                    lines[3].number,
                    ": distortion ",
                    distortion.transpose(),
                    " is not zero; only undistorted images (0 0 0, as the "
                    "dense benchmark sets) can be imported as PINHOLE "
                    "cameras");
  }
  view.K = CheckedIntrinsics(K, options, path, lines[0].number);
  // x ~ K R^T (X - C): the world-to-camera rotation is R^T.
  const Eigen::Quaterniond world_from_cam = CheckedRotation(
      R,
      options,
      path,
      lines[4].number,
      StrCat("R (lines ", lines[4].number, "-", lines[6].number, ")"));
  view.cam_from_world.rotation = world_from_cam.inverse();
  view.cam_from_world.translation = -(view.cam_from_world.rotation * center);
  return view;
}

}  // namespace

std::optional<GroundTruthFormat> GroundTruthFormatFromName(
    const std::string& name) {
  if (name == "middlebury") return GroundTruthFormat::kMiddlebury;
  if (name == "strecha") return GroundTruthFormat::kStrecha;
  return std::nullopt;
}

const char* GroundTruthFormatName(GroundTruthFormat format) {
  return format == GroundTruthFormat::kMiddlebury ? "middlebury" : "strecha";
}

void GroundTruthImportOptions::Register(OptionRegistry* r) {
  r->Add("image_path",
         &image_path,
         "Image folder: every listed image must be there (default: "
         "Middlebury the folder of its file, Strecha unchecked)");
  r->Add("max_rotation_error",
         &max_rotation_error,
         "Largest entry of |R^T R - I| accepted as a rotation");
  r->Add("max_skew_px",
         &max_skew_px,
         "Largest skew k12 (pixels) taken as zero; more is refused");
  r->Add("pixel_origin_offset_px",
         &pixel_origin_offset_px,
         "Added to the principal point: 0.5 when the file's upper-left "
         "pixel centre is (0, 0), 0 when it is COLMAP's (0.5, 0.5)");
}

void GroundTruthImportOptions::Check() const {
  if (input_path.empty()) {
    ThrowInputError("input_path must be given");
  }
  CheckOption(max_rotation_error > 0 && max_rotation_error < 1,
              "max_rotation_error",
              "in (0, 1)",
              max_rotation_error);
  CheckOption(max_skew_px >= 0 && std::isfinite(max_skew_px),
              "max_skew_px",
              ">= 0",
              max_skew_px);
  CheckOption(std::isfinite(pixel_origin_offset_px),
              "pixel_origin_offset_px",
              "finite",
              pixel_origin_offset_px);
}

std::vector<GroundTruthView> ReadMiddleburyCameras(
    const std::string& path, const GroundTruthImportOptions& options) {
  CheckFileExists(path, "Middlebury camera file");
  const std::vector<TextLine> lines = ReadTextLines(path);
  if (lines.empty()) {
    ThrowInputError(path, ":1: empty file, expected the number of images");
  }
  const TextLine& count_line = lines.front();
  if (count_line.tokens.size() != 1) {
    ThrowInputError(path,
                    ":",
                    count_line.number,
                    ": expected the number of images alone on the first line, "
                    "got ",
                    count_line.tokens.size(),
                    " fields");
  }
  const int count = ParseCount(
      count_line.tokens[0], path, count_line.number, "the number of images", 1);
  std::vector<GroundTruthView> views;
  for (size_t i = 1; i < lines.size(); ++i) {
    const TextLine& line = lines[i];
    if (line.tokens.size() != kMiddleburyFields) {
      ThrowInputError(path,
                      ":",
                      line.number,
                      ": expected ",
                      kMiddleburyFields,
                      " fields (name k11..k33 r11..r33 t1 t2 t3), got ",
                      line.tokens.size());
    }
    Eigen::Matrix3d K, R;
    Eigen::Vector3d t;
    for (int k = 0; k < 9; ++k) {
      K(k / 3, k % 3) = ParseNumber(line.tokens[1 + k],
                                    path,
                                    line.number,
                                    StrCat("k", k / 3 + 1, k % 3 + 1));
      R(k / 3, k % 3) = ParseNumber(line.tokens[10 + k],
                                    path,
                                    line.number,
                                    StrCat("r", k / 3 + 1, k % 3 + 1));
    }
    for (int k = 0; k < 3; ++k) {
      t(k) = ParseNumber(
          line.tokens[19 + k], path, line.number, StrCat("t", k + 1));
    }
    GroundTruthView view;
    view.name = line.tokens[0];
    view.file = path;
    view.line = line.number;
    view.K = CheckedIntrinsics(K, options, path, line.number);
    view.cam_from_world.rotation =
        CheckedRotation(R, options, path, line.number, "R (r11..r33)");
    view.cam_from_world.translation = t;
    views.push_back(std::move(view));
  }
  if (static_cast<int>(views.size()) != count) {
    ThrowInputError(path,
                    ":",
                    count_line.number,
                    ": the count line says ",
                    count,
                    " images, but ",
                    views.size(),
                    " image lines follow");
  }
  CheckUniqueNames(views);
  return views;
}

std::vector<GroundTruthView> ReadStrechaCameras(
    const std::string& path, const GroundTruthImportOptions& options) {
  std::vector<std::string> files;
  if (fs::is_directory(path)) {
    for (const std::string& name : ListFilesRecursive(path)) {
      const std::string suffix = ".camera";
      if (name.size() > suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) ==
              0 &&
          name.find('/') == std::string::npos) {
        files.push_back((fs::path(path) / name).string());
      }
    }
    if (files.empty()) {
      ThrowInputError(path, ": no *.camera files (Strecha cameras) in folder");
    }
  } else {
    CheckFileExists(path, "Strecha camera file");
    files.push_back(path);
  }
  std::vector<GroundTruthView> views;
  for (const std::string& file : files) {
    views.push_back(ParseStrechaFile(file, options));
  }
  CheckUniqueNames(views);
  return views;
}

void CheckGroundTruthImages(const std::string& image_path,
                            std::vector<GroundTruthView>* views) {
  CheckDirectoryExists(image_path, "image folder");
  for (GroundTruthView& view : *views) {
    const std::string path = (fs::path(image_path) / view.name).string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
      ThrowInputError(view.file,
                      ":",
                      view.line,
                      ": image ",
                      view.name,
                      " not found in ",
                      image_path);
    }
    const ImageSize size = ReadImageSize(path);
    if (view.width > 0 &&
        (size.width != view.width || size.height != view.height)) {
      ThrowInputError(view.file,
                      ":",
                      view.size_line > 0 ? view.size_line : view.line,
                      ": image size ",
                      view.width,
                      "x",
                      view.height,
                      ", but ",
                      path,
                      " is ",
                      size.width,
                      "x",
                      size.height);
    }
    view.width = size.width;
    view.height = size.height;
  }
}

Scene GroundTruthScene(const std::vector<GroundTruthView>& views) {
  std::vector<const GroundTruthView*> sorted;
  for (const GroundTruthView& view : views) sorted.push_back(&view);
  std::sort(sorted.begin(),
            sorted.end(),
            [](const GroundTruthView* a, const GroundTruthView* b) {
              return a->name < b->name;
            });
  Scene scene;
  // Cameras keyed by (fx, fy, cx, cy, width, height), exact equality.
  using CameraKey = std::tuple<double, double, double, double, int, int>;
  std::map<CameraKey, camera_t> camera_ids;
  image_t next_image_id = 1;
  for (const GroundTruthView* view : sorted) {
    if (view->width <= 0 || view->height <= 0) {
      ThrowInputError(view->file,
                      ":",
                      view->line,
                      ": the size of image ",
                      view->name,
                      " is unknown (give the image folder)");
    }
    const Eigen::Matrix3d& K = view->K;
    const CameraKey key(
        K(0, 0), K(1, 1), K(0, 2), K(1, 2), view->width, view->height);
    auto it = camera_ids.find(key);
    if (it == camera_ids.end()) {
      Camera camera;
      camera.camera_id = static_cast<camera_t>(camera_ids.size() + 1);
      camera.width = view->width;
      camera.height = view->height;
      if (K(0, 0) == K(1, 1)) {
        camera.model_id = CameraModelId::kSimplePinhole;
        camera.params = {K(0, 0), K(0, 2), K(1, 2)};
      } else {
        camera.model_id = CameraModelId::kPinhole;
        camera.params = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
      }
      camera.has_prior_focal_length = true;
      camera.Check();
      scene.cameras.Set(camera.camera_id, camera);
      it = camera_ids.emplace(key, camera.camera_id).first;
    }
    Image image;
    image.image_id = next_image_id++;
    image.name = view->name;
    image.camera_id = it->second;
    image.cam_from_world = view->cam_from_world;
    scene.images.Set(image.image_id, image);
  }
  return scene;
}

Scene ImportGroundTruth(const GroundTruthImportOptions& options) {
  options.Check();
  std::vector<GroundTruthView> views;
  std::string image_path = options.image_path;
  if (options.format == GroundTruthFormat::kMiddlebury) {
    views = ReadMiddleburyCameras(options.input_path, options);
    if (image_path.empty()) {
      image_path = fs::path(options.input_path).parent_path().string();
      if (image_path.empty()) image_path = ".";
    }
  } else {
    views = ReadStrechaCameras(options.input_path, options);
  }
  if (!image_path.empty()) CheckGroundTruthImages(image_path, &views);
  return GroundTruthScene(views);
}

}  // namespace bayon
