// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon import_ground_truth` on the real truth files in ../shared/data: the
// temple ring (Middlebury) and fountain-P11 (Strecha) imported through the
// command, read back, checked against what the data sets document, read by
// stock COLMAP; and corrupted copies refused with the file and line.
#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::vector<std::string> ReadLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

std::vector<std::string> Split(const std::string& line) {
  std::istringstream stream(line);
  std::vector<std::string> tokens;
  std::string token;
  while (stream >> token) tokens.push_back(token);
  return tokens;
}

std::string Join(const std::vector<std::string>& tokens) {
  std::string line;
  for (const std::string& token : tokens) {
    line += (line.empty() ? "" : " ") + token;
  }
  return line;
}

void WriteLines(const std::string& path,
                const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  WriteFileAtomically(path, text);
}

Scene Import(const std::vector<std::string>& args) {
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return ReadModel(args[6]);  // args: command --format F --input_path I
                              //       --output_path O ...
}

// The raw projection of templeSR_par.txt: x = K [R | t] X, upper-left pixel
// centre (0, 0).
struct RawMiddlebury {
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
};

std::map<std::string, RawMiddlebury> ReadRawTemple(const std::string& path) {
  std::map<std::string, RawMiddlebury> cameras;
  const std::vector<std::string> lines = ReadLines(path);
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> t = Split(lines[i]);
    if (t.size() != 22) continue;
    RawMiddlebury camera;
    for (int k = 0; k < 9; ++k) {
      camera.K(k / 3, k % 3) = std::stod(t[1 + k]);
      camera.R(k / 3, k % 3) = std::stod(t[10 + k]);
    }
    for (int k = 0; k < 3; ++k) camera.t(k) = std::stod(t[19 + k]);
    cameras[t[0]] = camera;
  }
  return cameras;
}

// The temple's tight bounding box (README.txt).
const Eigen::AlignedBox3d kTempleBox(
    Eigen::Vector3d(-0.073568, 0.021728, -0.012445),
    Eigen::Vector3d(0.028855, 0.181892, 0.062736));

double WrapDeg(double angle) { return std::remainder(angle, 360.0); }

TEST(GroundTruth, TempleRingImportsAsDocumented) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string data = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("ground_truth_temple");
  const auto data_before = testing::HashTree(data);
  const Scene truth = Import({"import_ground_truth",
                              "--format",
                              "middlebury",
                              "--input_path",
                              data + "/templeSR_par.txt",
                              "--output_path",
                              dir + "/truth"});
  EXPECT_EQ(testing::HashTree(data), data_before);
  for (const char* file : {"cameras.txt", "images.txt", "points3D.txt"}) {
    EXPECT_TRUE(fs::exists(dir + "/truth/" + file)) << file;
  }
  // One PINHOLE camera (fx != fy), the file's K in COLMAP pixels.
  ASSERT_EQ(truth.cameras.size(), 1u);
  const Camera& camera = truth.cameras.at(1);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.width, 640u);
  EXPECT_EQ(camera.height, 480u);
  const std::vector<double> expected = {1520.4, 1525.9, 302.82, 247.37};
  ASSERT_EQ(camera.params.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(camera.params[i], expected[i], 1e-12) << i;
  }
  // Ids follow the sorted names, the names of the files on disk.
  ASSERT_EQ(truth.images.size(), 16u);
  image_t id = 1;
  for (const auto& [image_id, image] : truth.images) {
    EXPECT_EQ(image_id, id);
    char name[32];
    std::snprintf(name, sizeof(name), "templeSR%04d.png", id);
    EXPECT_EQ(image.name, name);
    EXPECT_TRUE(fs::exists(data + "/" + image.name));
    EXPECT_TRUE(image.points2D.empty());
    ++id;
  }
  EXPECT_TRUE(truth.points3D.empty());

  // The model projects as P = K [R t] (plus COLMAP's half pixel), and the
  // whole tight bounding box is in front of every camera and inside its
  // image.
  const auto raw = ReadRawTemple(data + "/templeSR_par.txt");
  ASSERT_EQ(raw.size(), 16u);
  for (const auto& [image_id, image] : truth.images) {
    const RawMiddlebury& p = raw.at(image.name);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d X = kTempleBox.corner(
          static_cast<Eigen::AlignedBox3d::CornerType>(corner));
      Eigen::Vector2d pixel;
      ASSERT_TRUE(truth.Project(image, X, &pixel)) << image.name;
      const Eigen::Vector3d x = p.K * (p.R * X + p.t);
      EXPECT_GT(x.z(), 0);
      EXPECT_LT((pixel - x.hnormalized() - Eigen::Vector2d(0.5, 0.5)).norm(),
                1e-6)
          << image.name;
      EXPECT_TRUE(pixel.x() > 0 && pixel.x() < 640 && pixel.y() > 0 &&
                  pixel.y() < 480)
          << image.name << " corner " << corner << ": " << pixel.transpose();
    }
  }

  // The spherical gantry: every centre at one distance from a common point
  // (sphere fitted linearly: |C|^2 = 2 c.C + k).
  std::vector<Eigen::Vector3d> centers;
  for (const auto& [image_id, image] : truth.images) {
    centers.push_back(image.cam_from_world.Center());
  }
  Eigen::MatrixXd A(centers.size(), 4);
  Eigen::VectorXd b(centers.size());
  for (size_t i = 0; i < centers.size(); ++i) {
    A.row(i) << 2 * centers[i].transpose(), 1;
    b(i) = centers[i].squaredNorm();
  }
  const Eigen::Vector4d sphere = A.colPivHouseholderQr().solve(b);
  const Eigen::Vector3d sphere_center = sphere.head<3>();
  const double radius = std::sqrt(sphere(3) + sphere_center.squaredNorm());
  // Measured: 0.56790 m, the temple inside it.
  EXPECT_NEAR(radius, 0.5679, 5e-4);
  EXPECT_LT((sphere_center - kTempleBox.center()).norm(), 0.1);
  for (size_t i = 0; i < centers.size(); ++i) {
    EXPECT_NEAR((centers[i] - sphere_center).norm(), radius, 1e-4) << i;
  }

  // On one ring of that sphere, at the longitudes of templeSR_ang.txt:
  // (lat, lon) is the station (-lat, lon + 180) turned upside down.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : centers) mean += c / centers.size();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& c : centers) {
    scatter += (c - mean) * (c - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  const Eigen::Vector3d normal = eigen.eigenvectors().col(0);
  const Eigen::Vector3d u = eigen.eigenvectors().col(2);
  const Eigen::Vector3d v = normal.cross(u);
  // The ring's centre: the sphere's centre moved into the ring's plane (the
  // mean of the centres is off it, the stations being uneven).
  const Eigen::Vector3d ring_center =
      sphere_center + normal * normal.dot(mean - sphere_center);
  std::map<std::string, std::pair<double, double>> lat_lon;
  for (const std::string& line : ReadLines(data + "/templeSR_ang.txt")) {
    const std::vector<std::string> t = Split(line);
    if (t.size() == 3) lat_lon[t[2]] = {std::stod(t[0]), std::stod(t[1])};
  }
  ASSERT_EQ(lat_lon.size(), 16u);
  std::vector<double> azimuth_deg, longitude_deg;
  std::vector<bool> upside_down;
  for (const auto& [image_id, image] : truth.images) {
    const Eigen::Vector3d c = image.cam_from_world.Center() - ring_center;
    EXPECT_LT(std::abs(c.dot(normal)), 2e-3) << image.name;  // on the ring
    azimuth_deg.push_back(std::atan2(c.dot(v), c.dot(u)) * 180 / M_PI);
    const auto [lat, lon] = lat_lon.at(image.name);
    upside_down.push_back(lat > 0);
    longitude_deg.push_back(lat > 0 ? lon + 180 : lon);
  }
  // The longitudes run one way or the other round the ring.
  double best_error = 1e9;
  for (const double sign : {1.0, -1.0}) {
    double error = 0;
    for (size_t i = 1; i < centers.size(); ++i) {
      error = std::max(
          error,
          std::abs(WrapDeg((azimuth_deg[i] - azimuth_deg[0]) -
                           sign * (longitude_deg[i] - longitude_deg[0]))));
    }
    best_error = std::min(best_error, error);
  }
  std::printf(
      "temple: centres on a sphere of radius %.5f m; ring positions "
      "within %.3f deg of the longitudes\n",
      radius,
      best_error);
  // Measured 0.355 deg, at the upside-down stations (the others: 0.04).
  EXPECT_LT(best_error, 0.5);
  // The upside-down stations have their image y axis (down) the other way
  // along the ring's axis.
  const Eigen::Vector3d down0 =
      truth.images.at(1).cam_from_world.rotation.inverse() *
      Eigen::Vector3d::UnitY();
  for (const auto& [image_id, image] : truth.images) {
    const Eigen::Vector3d down =
        image.cam_from_world.rotation.inverse() * Eigen::Vector3d::UnitY();
    EXPECT_EQ(down.dot(normal) * down0.dot(normal) < 0,
              upside_down[image_id - 1] != upside_down[0])
        << image.name;
  }
}

// Strecha's files, read directly: K, R (camera-to-world), C, size.
struct RawStrecha {
  Eigen::Matrix3d K, R;
  Eigen::Vector3d C;
  int width = 0, height = 0;
};

RawStrecha ReadRawStrecha(const std::string& path) {
  std::ifstream in(path);
  RawStrecha camera;
  double distortion[3];
  for (int k = 0; k < 9; ++k) in >> camera.K(k / 3, k % 3);
  for (double& d : distortion) in >> d;
  for (int k = 0; k < 9; ++k) in >> camera.R(k / 3, k % 3);
  for (int k = 0; k < 3; ++k) in >> camera.C(k);
  in >> camera.width >> camera.height;
  EXPECT_TRUE(in) << path;
  return camera;
}

TEST(GroundTruth, FountainImportsAsDocumented) {
  BAYON_REQUIRE_DATA("fountain-P11");
  const std::string data = testing::DataPath("fountain-P11");
  const std::string dir = testing::TempDir("ground_truth_fountain");
  const auto data_before = testing::HashTree(data);
  const Scene truth = Import({"import_ground_truth",
                              "--format",
                              "strecha",
                              "--input_path",
                              data + "/gt_dense_cameras",
                              "--output_path",
                              dir + "/truth",
                              "--image_path",
                              data + "/images"});
  EXPECT_EQ(testing::HashTree(data), data_before);
  ASSERT_EQ(truth.images.size(), 11u);
  ASSERT_EQ(truth.cameras.size(), 1u);
  const Camera& camera = truth.cameras.at(1);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.width, 3072u);
  EXPECT_EQ(camera.height, 2048u);
  // Rays through the centre of the camera frame: the optical axes, which
  // converge on the fountain (PROVENANCE.md: 0.33 m from one point).
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  image_t id = 1;
  for (const auto& [image_id, image] : truth.images) {
    char name[32];
    std::snprintf(name, sizeof(name), "%04d.jpg", id - 1);
    EXPECT_EQ(image_id, id++);
    EXPECT_EQ(image.name, name);
    const RawStrecha raw =
        ReadRawStrecha(data + "/gt_dense_cameras/" + image.name + ".camera");
    // The file's K, the principal point moved by COLMAP's half pixel.
    EXPECT_EQ(
        camera.params,
        (std::vector<double>{
            raw.K(0, 0), raw.K(1, 1), raw.K(0, 2) + 0.5, raw.K(1, 2) + 0.5}));
    EXPECT_EQ(raw.width, 3072);
    EXPECT_LT((image.cam_from_world.Center() - raw.C).norm(), 1e-9);
    const Eigen::Matrix3d world_from_cam =
        image.cam_from_world.rotation.inverse().toRotationMatrix();
    EXPECT_LT((world_from_cam - raw.R).cwiseAbs().maxCoeff(), 1e-5);
    // A point 5 m along the file's optical axis projects to the principal
    // point.
    Eigen::Vector2d pixel;
    ASSERT_TRUE(truth.Project(image, raw.C + 5 * raw.R.col(2), &pixel));
    // (R is given to 6 digits and made orthonormal: about 1e-6 rad.)
    EXPECT_LT((pixel - camera.PrincipalPointPx()).norm(), 0.01);
    const Eigen::Vector3d axis = world_from_cam.col(2);
    const Eigen::Matrix3d across =
        Eigen::Matrix3d::Identity() - axis * axis.transpose();
    normal += across;
    rhs += across * raw.C;
  }
  const Eigen::Vector3d meeting = normal.ldlt().solve(rhs);
  double mean_distance = 0;
  for (const auto& [image_id, image] : truth.images) {
    const Eigen::Vector3d c = image.cam_from_world.Center();
    const Eigen::Vector3d axis =
        image.cam_from_world.rotation.inverse() * Eigen::Vector3d::UnitZ();
    EXPECT_GT((meeting - c).dot(axis), 0) << image.name;  // in front
    mean_distance += (meeting - c).cross(axis).norm() / truth.images.size();
  }
  EXPECT_LT(mean_distance, 0.5);
}

TEST(GroundTruth, ColmapReadsTheImportedModel) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string data = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("ground_truth_colmap");
  const Scene truth = Import({"import_ground_truth",
                              "--format",
                              "middlebury",
                              "--input_path",
                              data + "/templeSR_par.txt",
                              "--output_path",
                              dir + "/truth"});
  fs::create_directories(dir + "/bin");
  const testing::CommandResult result = testing::RunColmap({"model_converter",
                                                            "--input_path",
                                                            dir + "/truth",
                                                            "--output_path",
                                                            dir + "/bin",
                                                            "--output_type",
                                                            "BIN"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const Scene converted = ReadModel(dir + "/bin");
  ASSERT_EQ(converted.images.size(), truth.images.size());
  ASSERT_EQ(converted.cameras.size(), 1u);
  EXPECT_EQ(converted.cameras.at(1).ModelName(), "PINHOLE");
  EXPECT_EQ(converted.cameras.at(1).params, truth.cameras.at(1).params);
  for (const auto& [image_id, image] : truth.images) {
    const Image* other = converted.FindImageByName(image.name);
    ASSERT_NE(other, nullptr) << image.name;
    EXPECT_EQ(other->image_id, image_id);
    EXPECT_LT(
        (other->cam_from_world.Center() - image.cam_from_world.Center()).norm(),
        1e-12);
    EXPECT_LT(other->cam_from_world.rotation.angularDistance(
                  image.cam_from_world.rotation),
              1e-12);
  }

  // An existing model is replaced only with --overwrite 1.
  const std::vector<std::string> again = {"import_ground_truth",
                                          "--format",
                                          "middlebury",
                                          "--input_path",
                                          data + "/templeSR_par.txt",
                                          "--output_path",
                                          dir + "/truth"};
  const auto before = testing::HashTree(dir + "/truth");
  const testing::CommandResult refused = testing::RunBayon(again);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.LastLine().find("exists already"), std::string::npos)
      << refused.output;
  EXPECT_EQ(testing::HashTree(dir + "/truth"), before);
  std::vector<std::string> overwrite = again;
  overwrite.insert(overwrite.end(), {"--overwrite", "1"});
  const testing::CommandResult replaced = testing::RunBayon(overwrite);
  EXPECT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_EQ(testing::HashTree(dir + "/truth"), before);  // same content
}

// Runs the command, expects exit 2 with a one-line message containing
// `expected`, no output folder, and `inputs` unchanged.
void ExpectRefused(const std::vector<std::string>& args,
                   const std::string& output_path,
                   const std::string& expected,
                   const std::vector<std::string>& inputs) {
  std::vector<std::map<std::string, uint64_t>> before;
  for (const std::string& input : inputs) {
    before.push_back(testing::HashTree(input));
  }
  const testing::CommandResult result = testing::RunBayon(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  const std::string line = result.LastLine();
  EXPECT_NE(line.find("bayon import_ground_truth: error: "), std::string::npos)
      << result.output;
  EXPECT_NE(line.find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.output;
  EXPECT_FALSE(fs::exists(output_path)) << output_path;
  for (size_t i = 0; i < inputs.size(); ++i) {
    EXPECT_EQ(testing::HashTree(inputs[i]), before[i])
        << inputs[i] << " changed";
  }
  // Nothing left behind under a temporary name either.
  for (const auto& entry :
       fs::directory_iterator(fs::path(output_path).parent_path())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
        << entry.path();
  }
}

TEST(GroundTruth, CorruptTempleFilesAreRefusedWithTheLine) {
  BAYON_REQUIRE_DATA("temple-ring");
  const std::string data = testing::DataPath("temple-ring");
  const std::string dir = testing::TempDir("ground_truth_bad_temple");
  const std::vector<std::string> lines = ReadLines(data + "/templeSR_par.txt");
  ASSERT_EQ(lines.size(), 17u);
  const std::string par = dir + "/templeSR_par.txt";
  const std::string output = dir + "/truth";
  // Line `number` (1-based) with token `field` replaced by `value`.
  const auto corrupt = [&](int number, int field, const std::string& value) {
    std::vector<std::string> copy = lines;
    std::vector<std::string> tokens = Split(copy[number - 1]);
    tokens[field] = value;
    copy[number - 1] = Join(tokens);
    WriteLines(par, copy);
  };
  const std::vector<std::string> args = {"import_ground_truth",
                                         "--format",
                                         "middlebury",
                                         "--input_path",
                                         par,
                                         "--output_path",
                                         output,
                                         "--image_path",
                                         data};
  const std::vector<std::string> inputs = {par, data};

  corrupt(5, 12, "nan");  // r13 of templeSR0004.png
  ExpectRefused(args,
                output,
                "templeSR_par.txt:5: r13 is 'nan', not a finite number",
                inputs);
  // A rotation with one entry changed by 0.05 is no rotation.
  corrupt(7, 11, std::to_string(std::stod(Split(lines[6])[11]) + 0.05));
  ExpectRefused(args,
                output,
                "templeSR_par.txt:7: R (r11..r33) is not a rotation matrix",
                inputs);
  corrupt(3, 0, "templeSR0099.png");
  ExpectRefused(
      args,
      output,
      "templeSR_par.txt:3: image templeSR0099.png not found in " + data,
      inputs);
  corrupt(1, 0, "17");
  ExpectRefused(args,
                output,
                "templeSR_par.txt:1: the count line says 17 images, but 16 "
                "image lines follow",
                inputs);
  {
    std::vector<std::string> copy = lines;
    std::vector<std::string> tokens = Split(copy[9]);
    tokens.pop_back();
    copy[9] = Join(tokens);
    WriteLines(par, copy);
  }
  ExpectRefused(args,
                output,
                "templeSR_par.txt:10: expected 22 fields (name k11..k33 "
                "r11..r33 t1 t2 t3), got 21",
                inputs);
  ExpectRefused({"import_ground_truth",
                 "--format",
                 "bundler",
                 "--input_path",
                 par,
                 "--output_path",
                 output},
                output,
                "--format 'bundler' is unknown (known: middlebury, strecha)",
                inputs);
}

TEST(GroundTruth, CorruptFountainFilesAreRefusedWithTheLine) {
  BAYON_REQUIRE_DATA("fountain-P11");
  const std::string data = testing::DataPath("fountain-P11");
  const std::string dir = testing::TempDir("ground_truth_bad_fountain");
  const std::string cameras = dir + "/gt_dense_cameras";
  testing::CopyTree(data + "/gt_dense_cameras", cameras);
  const std::string file = cameras + "/0003.jpg.camera";
  const std::vector<std::string> lines = ReadLines(file);
  ASSERT_EQ(lines.size(), 9u);
  const std::string output = dir + "/truth";
  const std::vector<std::string> args = {"import_ground_truth",
                                         "--format",
                                         "strecha",
                                         "--input_path",
                                         cameras,
                                         "--output_path",
                                         output,
                                         "--image_path",
                                         data + "/images"};
  const std::vector<std::string> inputs = {cameras, data};
  const auto corrupt = [&](int number, const std::string& text) {
    std::vector<std::string> copy = lines;
    copy[number - 1] = text;
    WriteLines(file, copy);
  };

  corrupt(8, "-6.0 nan 0.2");
  ExpectRefused(args,
                output,
                "0003.jpg.camera:8: the camera centre C value 2 is 'nan'",
                inputs);
  corrupt(6, "0.1 0.2 0.3");
  ExpectRefused(args,
                output,
                "0003.jpg.camera:5: R (lines 5-7) is not a rotation matrix",
                inputs);
  corrupt(9, "3072");
  ExpectRefused(
      args,
      output,
      "0003.jpg.camera:9: expected 2 values (the image size (width height)), "
      "got 1",
      inputs);
  corrupt(9, "1536 1024");
  ExpectRefused(args,
                output,
                "0003.jpg.camera:9: image size 1536x1024, but " + data +
                    "/images/0003.jpg is 3072x2048",
                inputs);
  WriteLines(file, lines);
  testing::CopyTree(file, cameras + "/0099.jpg.camera");
  ExpectRefused(
      args,
      output,
      "0099.jpg.camera:1: image 0099.jpg not found in " + data + "/images",
      inputs);
}

}  // namespace
}  // namespace bayon
