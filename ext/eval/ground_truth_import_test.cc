// SPDX-License-Identifier: BSD-3-Clause
#include "ext/eval/ground_truth_import.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/image/image_io.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A true camera as the files state it: x = K [R | t] X with the centre of
// the upper-left pixel at (0, 0).
struct FileCamera {
  std::string name;
  Eigen::Matrix3d K;
  Eigen::Matrix3d R;  // world to camera
  Eigen::Vector3d t;
};

FileCamera MakeCamera(const std::string& name,
                      double fx,
                      double fy,
                      double angle) {
  FileCamera camera;
  camera.name = name;
  camera.K << fx, 0, 31.25, 0, fy, 23.75, 0, 0, 1;
  camera.R = Eigen::AngleAxisd(angle, Eigen::Vector3d(0.2, 1, 0.3).normalized())
                 .toRotationMatrix();
  camera.t = Eigen::Vector3d(0.1, -0.2, 2.0 + angle);
  return camera;
}

std::string Number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string MiddleburyLine(const FileCamera& camera) {
  std::string line = camera.name;
  for (int k = 0; k < 9; ++k) line += " " + Number(camera.K(k / 3, k % 3));
  for (int k = 0; k < 9; ++k) line += " " + Number(camera.R(k / 3, k % 3));
  for (int k = 0; k < 3; ++k) line += " " + Number(camera.t(k));
  return line + "\n";
}

std::string StrechaFile(const FileCamera& camera, int width, int height) {
  // R is camera-to-world there, C the centre.
  const Eigen::Matrix3d R = camera.R.transpose();
  const Eigen::Vector3d C = -R * camera.t;
  std::string text;
  for (int r = 0; r < 3; ++r) {
    text += Number(camera.K(r, 0)) + " " + Number(camera.K(r, 1)) + " " +
            Number(camera.K(r, 2)) + " \n";
  }
  text += "0 0 0\n";
  for (int r = 0; r < 3; ++r) {
    text +=
        Number(R(r, 0)) + " " + Number(R(r, 1)) + " " + Number(R(r, 2)) + " \n";
  }
  text += Number(C(0)) + " " + Number(C(1)) + " " + Number(C(2)) + " \n";
  return text + std::to_string(width) + " " + std::to_string(height) + "\n";
}

void WriteTestImage(const std::string& path, int width, int height) {
  WriteImage(path, cv::Mat(height, width, CV_8UC3, cv::Scalar(40, 90, 200)));
}

// The pixel (COLMAP convention) where the file's camera sees X.
Eigen::Vector2d FileProjection(const FileCamera& camera,
                               const Eigen::Vector3d& X) {
  const Eigen::Vector3d x = camera.K * (camera.R * X + camera.t);
  return x.hnormalized() + Eigen::Vector2d(0.5, 0.5);
}

// Expects an InputError whose message contains every one of `parts`.
void ExpectRefused(const std::function<void()>& call,
                   const std::vector<std::string>& parts) {
  try {
    call();
    ADD_FAILURE() << "no InputError; expected '" << parts.front() << "'";
  } catch (const InputError& error) {
    const std::string message = error.what();
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos)
          << "expected '" << part << "' in: " << message;
    }
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

// A Middlebury folder: images a.png, b.png, c.png (64 x 48) and a par file
// with the given text.
std::string MiddleburyFolder(const std::string& name, const std::string& par) {
  const std::string dir = testing::TempDir(name);
  for (const char* image : {"a.png", "b.png", "c.png"}) {
    WriteTestImage(dir + "/" + image, 64, 48);
  }
  WriteFileAtomically(dir + "/test_par.txt", par);
  return dir;
}

Scene ImportMiddlebury(const std::string& dir) {
  GroundTruthImportOptions options;
  options.format = GroundTruthFormat::kMiddlebury;
  options.input_path = dir + "/test_par.txt";
  return ImportGroundTruth(options);
}

const std::vector<Eigen::Vector3d>& TestPoints() {
  static const std::vector<Eigen::Vector3d> points = {
      {0, 0, 0}, {0.05, -0.03, 0.1}, {-0.04, 0.02, -0.06}};
  return points;
}

TEST(GroundTruthImport, MiddleburyProjectsAsTheFileAndIdsFollowNames) {
  const FileCamera b = MakeCamera("b.png", 80, 82, 0.3);
  const FileCamera a = MakeCamera("a.png", 80, 81, -0.2);
  const std::string dir = MiddleburyFolder(
      "gt_import_middlebury", "2\n" + MiddleburyLine(b) + MiddleburyLine(a));
  const Scene scene = ImportMiddlebury(dir);
  ASSERT_EQ(scene.images.size(), 2u);
  ASSERT_EQ(scene.cameras.size(), 2u);
  EXPECT_EQ(scene.images.at(1).name, "a.png");
  EXPECT_EQ(scene.images.at(2).name, "b.png");
  EXPECT_EQ(scene.images.at(1).camera_id, 1u);
  EXPECT_EQ(scene.images.at(2).camera_id, 2u);
  const Camera& camera = scene.cameras.at(1);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.width, 64u);
  EXPECT_EQ(camera.height, 48u);
  EXPECT_TRUE(camera.has_prior_focal_length);
  EXPECT_EQ(camera.params, (std::vector<double>{80, 81, 31.75, 24.25}));
  for (const FileCamera* truth : {&a, &b}) {
    const Image& image = *scene.FindImageByName(truth->name);
    for (const Eigen::Vector3d& X : TestPoints()) {
      Eigen::Vector2d pixel;
      ASSERT_TRUE(scene.Project(image, X, &pixel));
      EXPECT_LT((pixel - FileProjection(*truth, X)).norm(), 1e-9)
          << truth->name;
    }
  }
  scene.CheckConsistency("imported truth");
}

TEST(GroundTruthImport, IdenticalIntrinsicsShareOneSimplePinhole) {
  std::string par = "3\n";
  for (const char* name : {"c.png", "a.png", "b.png"}) {
    par += MiddleburyLine(MakeCamera(name, 90, 90, name[0] * 0.01));
  }
  const Scene scene =
      ImportMiddlebury(MiddleburyFolder("gt_import_shared", par));
  ASSERT_EQ(scene.cameras.size(), 1u);
  const Camera& camera = scene.cameras.at(1);
  EXPECT_EQ(camera.model_id, CameraModelId::kSimplePinhole);
  EXPECT_EQ(camera.params, (std::vector<double>{90, 31.75, 24.25}));
  for (const auto& [id, image] : scene.images) EXPECT_EQ(image.camera_id, 1u);
  EXPECT_EQ(scene.images.at(3).name, "c.png");
}

TEST(GroundTruthImport, NearRotationsAreMadeOrthonormal) {
  FileCamera a = MakeCamera("a.png", 80, 81, 0.4);
  const Eigen::Matrix3d exact = a.R;
  a.R(0, 1) += 3e-6;  // within the default 1e-4, as 6-digit files are
  const Scene scene = ImportMiddlebury(
      MiddleburyFolder("gt_import_near_rotation", "1\n" + MiddleburyLine(a)));
  const Eigen::Matrix3d R =
      scene.images.at(1).cam_from_world.rotation.toRotationMatrix();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((R - exact).cwiseAbs().maxCoeff(), 3e-6);
}

TEST(GroundTruthImport, StrechaProjectsAsTheFile) {
  const std::string dir = testing::TempDir("gt_import_strecha");
  fs::create_directories(dir + "/cameras");
  fs::create_directories(dir + "/images");
  const FileCamera b = MakeCamera("b.jpg", 120, 121, 0.5);
  const FileCamera a = MakeCamera("a.jpg", 120, 121, -0.1);
  WriteFileAtomically(dir + "/cameras/b.jpg.camera", StrechaFile(b, 64, 48));
  WriteFileAtomically(dir + "/cameras/a.jpg.camera", StrechaFile(a, 64, 48));
  WriteFileAtomically(dir + "/cameras/notes.txt", "not a camera\n");
  WriteTestImage(dir + "/images/a.jpg", 64, 48);
  WriteTestImage(dir + "/images/b.jpg", 64, 48);
  GroundTruthImportOptions options;
  options.format = GroundTruthFormat::kStrecha;
  options.input_path = dir + "/cameras";
  // Without an image folder the sizes come from the files.
  const Scene scene = ImportGroundTruth(options);
  ASSERT_EQ(scene.images.size(), 2u);
  ASSERT_EQ(scene.cameras.size(), 1u);
  EXPECT_EQ(scene.images.at(1).name, "a.jpg");
  EXPECT_EQ(scene.cameras.at(1).params,
            (std::vector<double>{120, 121, 31.75, 24.25}));
  for (const FileCamera* truth : {&a, &b}) {
    const Image& image = *scene.FindImageByName(truth->name);
    for (const Eigen::Vector3d& X : TestPoints()) {
      Eigen::Vector2d pixel;
      ASSERT_TRUE(scene.Project(image, X, &pixel));
      EXPECT_LT((pixel - FileProjection(*truth, X)).norm(), 1e-9);
    }
    EXPECT_LT((image.cam_from_world.Center() + truth->R.transpose() * truth->t)
                  .norm(),
              1e-12);
  }
  // With it, every image must be there in the stated size.
  options.image_path = dir + "/images";
  EXPECT_EQ(ImportGroundTruth(options).images.size(), 2u);
  WriteTestImage(dir + "/images/b.jpg", 32, 24);
  ExpectRefused([&] { ImportGroundTruth(options); },
                {"b.jpg.camera:9: image size 64x48", "is 32x24"});
  fs::remove(dir + "/images/b.jpg");
  ExpectRefused([&] { ImportGroundTruth(options); },
                {"b.jpg.camera:1: image b.jpg not found in"});
  options.pixel_origin_offset_px = 0;
  options.image_path.clear();
  EXPECT_EQ(ImportGroundTruth(options).cameras.at(1).params,
            (std::vector<double>{120, 121, 31.25, 23.75}));
}

// The par file of MiddleburyFolder with line `line` (1-based) replaced.
std::string ParWithLine(int line, const std::string& text) {
  std::vector<std::string> lines = {
      "2\n",
      MiddleburyLine(MakeCamera("a.png", 80, 81, 0.1)),
      MiddleburyLine(MakeCamera("b.png", 80, 81, 0.2))};
  if (line >= 1 && line <= 3) lines[line - 1] = text;
  std::string par;
  for (const std::string& l : lines) par += l;
  return par;
}

// Line 3 with field `field` (0 = name) replaced by `value`.
std::string ReplaceField(int field, const std::string& value) {
  std::istringstream stream(MiddleburyLine(MakeCamera("b.png", 80, 81, 0.2)));
  std::vector<std::string> tokens;
  std::string token;
  while (stream >> token) tokens.push_back(token);
  tokens[field] = value;
  std::string line;
  for (const std::string& t : tokens) line += (line.empty() ? "" : " ") + t;
  return line + "\n";
}

void ExpectMiddleburyRefused(const std::string& par,
                             const std::vector<std::string>& parts) {
  const std::string dir = MiddleburyFolder("gt_import_bad_middlebury", par);
  const auto before = testing::HashTree(dir);
  ExpectRefused([&] { ImportMiddlebury(dir); }, parts);
  EXPECT_EQ(testing::HashTree(dir), before);
}

TEST(GroundTruthImport, RefusesBadMiddleburyFilesWithTheLine) {
  ExpectMiddleburyRefused(ParWithLine(3, ReplaceField(3, "nan")),
                          {"test_par.txt:3: k13 is 'nan', not a finite"});
  ExpectMiddleburyRefused(ParWithLine(3, ReplaceField(20, "-inf")),
                          {"test_par.txt:3: t2 is '-inf'"});
  ExpectMiddleburyRefused(ParWithLine(3, ReplaceField(12, "0.5x")),
                          {"test_par.txt:3: r13 is '0.5x', not a number"});
  ExpectMiddleburyRefused(ParWithLine(1, "3\n"),
                          {"test_par.txt:1: the count line says 3 images, but "
                           "2 image lines follow"});
  ExpectMiddleburyRefused(ParWithLine(1, "2 images\n"),
                          {"test_par.txt:1: expected the number of images"});
  ExpectMiddleburyRefused(ParWithLine(1, "-2\n"), {"test_par.txt:1:"});
  ExpectMiddleburyRefused("", {"test_par.txt:1: empty file"});
  {
    std::string line = ReplaceField(21, "");
    line.erase(line.find_last_not_of(" \n") + 1);
    ExpectMiddleburyRefused(ParWithLine(3, line + "\n"),
                            {"test_par.txt:3: expected 22 fields", "got 21"});
  }
  // A scaled R, a reflection and a shear are not rotations.
  FileCamera bad = MakeCamera("b.png", 80, 81, 0.2);
  bad.R *= 1.01;
  ExpectMiddleburyRefused(
      ParWithLine(3, MiddleburyLine(bad)),
      {"test_par.txt:3: R (r11..r33) is not a rotation matrix"});
  bad = MakeCamera("b.png", 80, 81, 0.2);
  bad.R.row(2) *= -1;
  ExpectMiddleburyRefused(ParWithLine(3, MiddleburyLine(bad)),
                          {"test_par.txt:3: R", "det = -1"});
  bad = MakeCamera("b.png", 80, 81, 0.2);
  bad.R(0, 1) += 0.01;
  ExpectMiddleburyRefused(ParWithLine(3, MiddleburyLine(bad)),
                          {"test_par.txt:3: R", "not a rotation"});
  // K: skew, a lower-left entry, a negative focal length.
  bad = MakeCamera("b.png", 80, 81, 0.2);
  bad.K(0, 1) = 0.25;
  ExpectMiddleburyRefused(ParWithLine(3, MiddleburyLine(bad)),
                          {"test_par.txt:3: K has skew k12 = 0.25 px"});
  bad = MakeCamera("b.png", 80, 81, 0.2);
  bad.K(2, 0) = 0.001;
  ExpectMiddleburyRefused(ParWithLine(3, MiddleburyLine(bad)),
                          {"test_par.txt:3: K is not upper triangular"});
  bad = MakeCamera("b.png", -80, 81, 0.2);
  ExpectMiddleburyRefused(ParWithLine(3, MiddleburyLine(bad)),
                          {"test_par.txt:3: K has focal lengths"});
  // Names: listed twice, missing on disk.
  ExpectMiddleburyRefused(
      ParWithLine(3, ReplaceField(0, "a.png")),
      {"test_par.txt:3: image a.png is listed twice", "test_par.txt:2)"});
  ExpectMiddleburyRefused(ParWithLine(3, ReplaceField(0, "d.png")),
                          {"test_par.txt:3: image d.png not found in"});
}

TEST(GroundTruthImport, RefusesBadStrechaFilesWithTheLine) {
  const std::string good =
      StrechaFile(MakeCamera("a.jpg", 120, 121, 0.3), 64, 48);
  std::vector<std::string> lines;
  {
    std::istringstream stream(good);
    std::string line;
    while (std::getline(stream, line)) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 9u);
  const auto with_line = [&](int number, const std::string& text) {
    std::string file;
    for (int i = 0; i < 9; ++i) {
      file += (i + 1 == number ? text : lines[i]) + "\n";
    }
    return file;
  };
  const std::string dir = testing::TempDir("gt_import_bad_strecha");
  const std::string path = dir + "/a.jpg.camera";
  const auto expect = [&](const std::string& text,
                          const std::vector<std::string>& parts) {
    WriteFileAtomically(path, text);
    GroundTruthImportOptions options;
    options.format = GroundTruthFormat::kStrecha;
    options.input_path = dir;
    ExpectRefused([&] { ImportGroundTruth(options); }, parts);
  };
  expect(with_line(8, "1 nan 2"),
         {"a.jpg.camera:8: the camera centre C value 2 is 'nan'"});
  expect(with_line(8, "1 2"),
         {"a.jpg.camera:8: expected 3 values (the camera centre C), got 2"});
  expect(with_line(4, "0.1 0 0"), {"a.jpg.camera:4: distortion", "not zero"});
  expect(with_line(6, "0 0 1"),
         {"a.jpg.camera:5: R (lines 5-7) is not a rotation matrix"});
  expect(with_line(9, "64.5 48"),
         {"a.jpg.camera:9: width is '64.5', expected a whole number"});
  {
    std::string first_eight;
    for (int i = 0; i < 8; ++i) first_eight += lines[i] + "\n";
    expect(first_eight, {"a.jpg.camera:9: file ends, expected the image size"});
  }
  expect(good + "1 2 3\n", {"a.jpg.camera:10: unexpected line"});
  expect(with_line(1, "120 0.5 31.25"), {"a.jpg.camera:1: K has skew"});
  fs::remove(path);
  GroundTruthImportOptions options;
  options.format = GroundTruthFormat::kStrecha;
  options.input_path = dir;
  ExpectRefused([&] { ImportGroundTruth(options); },
                {"no *.camera files (Strecha cameras) in folder"});
  options.input_path = dir + "/a.jpg";
  WriteFileAtomically(options.input_path, good);
  ExpectRefused([&] { ImportGroundTruth(options); },
                {"a.jpg: a Strecha camera file is named <image name>.camera"});
}

TEST(GroundTruthImport, OptionsAreChecked) {
  GroundTruthImportOptions options;
  ExpectRefused([&] { options.Check(); }, {"input_path"});
  options.input_path = "x";
  options.max_rotation_error = 0;
  ExpectRefused([&] { options.Check(); },
                {"max_rotation_error must be in "
                 "(0, 1) (got 0)"});
  EXPECT_EQ(GroundTruthFormatFromName("strecha"), GroundTruthFormat::kStrecha);
  EXPECT_FALSE(GroundTruthFormatFromName("bundler").has_value());
}

}  // namespace
}  // namespace bayon
