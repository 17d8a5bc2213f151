// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon tiepoints` end to end on the rendered tower (issue 5): synth,
// features, match (ring), relative, disparity, tiepoints; every tie point
// is then intersected with the TRUE cameras and poses (gt/), and its
// observations' reprojection errors say how conjugate they really are.
// Also: the COLMAP export is a database stock `colmap point_triangulator`
// runs on with the true model, the tables round-trip, and manual
// measurements are merged (and refused with the line when wrong).
#include "ext/adjustment/triangulation.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/table_tie_points.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "tests/testing.h"
#include "tests/tower_fixture.h"

namespace bayon {
namespace {

struct TrueCameras {
  Camera camera;
  std::map<image_t, Rigid3d> poses;  // by database image id
};

TrueCameras ReadTruth(const std::string& gt, Database* database) {
  TrueCameras truth;
  truth.camera = ReadCalibrationJson(gt + "/calibration.json")[0].camera;
  const Scene model = ReadModel(gt + "/sparse");
  std::map<std::string, Rigid3d> by_name;
  for (const auto& [id, image] : model.images) {
    by_name[image.name] = image.cam_from_world;
  }
  for (const DatabaseImage& image : database->ReadAllImages()) {
    truth.poses[image.image_id] = by_name.at(image.name);
  }
  return truth;
}

// Reprojection residuals (pixels) of a point intersected from its
// observations with the true cameras: the midpoint of the rays, then
// Gauss-Newton on the reprojection errors (numeric derivatives).
std::vector<Eigen::Vector2d> TrueResiduals(const TrueCameras& truth,
                                           const TiePointRecord& point) {
  std::vector<Ray> rays;
  for (const TieObservation& o : point.observations) {
    const std::optional<Ray> ray =
        RayThroughPixel(truth.camera, truth.poses.at(o.image_id), o.xy);
    if (ray) rays.push_back(*ray);
  }
  const std::optional<Eigen::Vector3d> start = IntersectRays(rays, 0.5);
  if (!start) return {};
  Eigen::Vector3d X = *start;
  auto residuals = [&](const Eigen::Vector3d& point3d) {
    Eigen::VectorXd r(2 * point.observations.size());
    for (size_t i = 0; i < point.observations.size(); ++i) {
      const TieObservation& o = point.observations[i];
      const Eigen::Vector2d projected =
          truth.camera.ImgFromCam(truth.poses.at(o.image_id) * point3d);
      r.segment<2>(2 * i) = projected - o.xy;
    }
    return r;
  };
  for (int iteration = 0; iteration < 10; ++iteration) {
    const Eigen::VectorXd r = residuals(X);
    Eigen::MatrixXd J(r.size(), 3);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d step = Eigen::Vector3d::Zero();
      step(k) = 1e-6;
      J.col(k) = (residuals(X + step) - residuals(X - step)) / 2e-6;
    }
    X -= (J.transpose() * J).ldlt().solve(J.transpose() * r);
  }
  const Eigen::VectorXd r = residuals(X);
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < r.size() / 2; ++i) out.push_back(r.segment<2>(2 * i));
  return out;
}

TEST(TiePoints, TowerTiePointsAreConjugateToATenthOfAPixel) {
  const std::string fixture = testing::OrientedTowerFixture();
  const std::string dir = testing::TempDir("tiepoints_tower");
  const std::string db = dir + "/database.db";
  testing::CopyTree(fixture + "/ws/database.db", db);
  const std::string images = fixture + "/ws/images";
  testing::CommandResult result = testing::RunBayon(
      {"disparity", "--database_path", db, "--num_threads", "2"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::vector<std::string> args = {"tiepoints",
                                   "--database_path",
                                   db,
                                   "--image_path",
                                   images,
                                   "--colmap_output_path",
                                   dir + "/tiepoints.db",
                                   "--num_threads",
                                   "2"};
  result = testing::RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::printf("%s\n", result.LastLine().c_str());

  Database database(db, Database::Mode::kReadOnly);
  const std::vector<TiePointRecord> points = ReadTiePoints(&database);
  const TrueCameras truth = ReadTruth(fixture + "/ws/gt", &database);
  int64_t num_observations = 0;
  int num_multi = 0;
  double sum_sq = 0, max_residual = 0;
  int64_t num_residuals = 0;
  std::vector<double> norms;
  std::map<size_t, double> by_length_sq, by_length_max;
  std::map<size_t, int64_t> by_length_n;
  for (const TiePointRecord& point : points) {
    num_observations += point.observations.size();
    num_multi += point.observations.size() >= 3;
    const std::vector<Eigen::Vector2d> rs = TrueResiduals(truth, point);
    const size_t length = std::min<size_t>(point.observations.size(), 5);
    for (const Eigen::Vector2d& r : rs) {
      by_length_sq[length] += r.squaredNorm();
      by_length_n[length] += 1;
      by_length_max[length] = std::max(by_length_max[length], r.norm());
    }
    for (const Eigen::Vector2d& r : rs) {
      sum_sq += r.squaredNorm();
      num_residuals += 1;
      norms.push_back(r.norm());
      max_residual = std::max(max_residual, r.norm());
    }
  }
  ASSERT_GT(num_residuals, 0);
  std::sort(norms.begin(), norms.end());
  const double rms = std::sqrt(sum_sq / num_residuals);
  const double mean_images = double(num_observations) / points.size();
  std::printf(
      "tower tie points: %zu points (%d in 3+ images), %.2f images each, "
      "reprojection against the true cameras RMS %.4f px, median %.4f px, "
      "max %.3f px\n",
      points.size(),
      num_multi,
      mean_images,
      rms,
      norms[norms.size() / 2],
      max_residual);
  for (const auto& [length, sum] : by_length_sq) {
    std::printf(
        "  points in %zu%s images: %lld observations, RMS %.4f px, "
        "max %.3f px\n",
        length,
        length == 5 ? " or more" : "",
        static_cast<long long>(by_length_n[length]),
        std::sqrt(sum / by_length_n[length]),
        by_length_max[length]);
  }
  // Measured: 233 points, all in 3 or more images (3.35 on average), RMS
  // 0.069 px, max 0.37 px.
  EXPECT_GE(points.size(), 150u);
  EXPECT_GE(mean_images, 3.0);
  EXPECT_LT(rms, 0.1);
  EXPECT_LT(max_residual, 1.0);

  // The export: keypoints are the observations, one match per pair of
  // observations of a point, and stock COLMAP reads it.
  Database exported(dir + "/tiepoints.db", Database::Mode::kReadOnly);
  EXPECT_EQ(exported.NumKeypoints(), num_observations);
  EXPECT_EQ(exported.NumDescriptors(), 0);
  int64_t num_pairs = 0;
  for (const TiePointRecord& point : points) {
    const int64_t n = point.observations.size();
    num_pairs += n * (n - 1) / 2;
  }
  EXPECT_EQ(exported.NumInlierMatches(), num_pairs);

  // Stock COLMAP triangulates the exported tie points in the true model
  // (poses and the fitted COLMAP cameras fixed).
  const std::string triangulated = dir + "/triangulated";
  std::filesystem::create_directories(triangulated);
  const testing::CommandResult colmap =
      testing::RunColmap({"point_triangulator",
                          "--database_path",
                          dir + "/tiepoints.db",
                          "--image_path",
                          images,
                          "--input_path",
                          fixture + "/ws/gt/sparse",
                          "--output_path",
                          triangulated,
                          "--clear_points",
                          "1"});
  ASSERT_EQ(colmap.exit_code, 0) << colmap.output;
  const Scene model = ReadModel(triangulated);
  std::printf("colmap point_triangulator: %zu of %zu tie points\n",
              model.points3D.size(),
              points.size());
  EXPECT_GE(model.points3D.size(), points.size() * 9 / 10);  // all of them
}

TEST(TiePoints, ManualMeasurementsAreMergedAndCheckedByLine) {
  const std::string fixture = testing::OrientedTowerFixture();
  const std::string dir = testing::TempDir("tiepoints_manual");
  const std::string db = dir + "/database.db";
  testing::CopyTree(fixture + "/ws/database.db", db);
  const std::string images = fixture + "/ws/images";
  ASSERT_EQ(testing::RunBayon({"disparity", "--database_path", db}).exit_code,
            0);
  {
    std::ofstream out(dir + "/manual.txt");
    out << "# NAME IMAGE_NAME X Y [SIGMA]\n"
        << "M1 image_001.png 100.5 200.25 0.3\n"
        << "M1 image_002.png 140.0 210.0\n";
  }
  // `bayon tiepoints` on this database and its photographs, with `more`.
  const auto tiepoints = [&](const std::vector<std::string>& more) {
    std::vector<std::string> args = {
        "tiepoints", "--database_path", db, "--image_path", images};
    args.insert(args.end(), more.begin(), more.end());
    return testing::RunBayon(args);
  };
  testing::CommandResult result = tiepoints(
      {"--manual_path", dir + "/manual.txt", "--manual_sigma_px", "0.7"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  Database database(db, Database::Mode::kReadOnly);
  const std::vector<TiePointRecord> points = ReadTiePoints(&database);
  const auto manual =
      std::find_if(points.begin(), points.end(), [](const TiePointRecord& p) {
        return p.source == "manual";
      });
  ASSERT_NE(manual, points.end());
  EXPECT_EQ(manual->name, "M1");
  ASSERT_EQ(manual->observations.size(), 2u);
  EXPECT_NEAR(manual->observations[0].xy.y(), 200.25, 1e-9);
  EXPECT_NEAR(manual->observations[0].covariance(0, 0), 0.09, 1e-12);
  EXPECT_NEAR(manual->observations[1].covariance(1, 1), 0.49, 1e-12);

  // Bad files: one line naming what is wrong, exit 2, and the previous
  // tie points still there.
  const auto expect_refused = [&](const std::string& text,
                                  const std::string& named) {
    {
      std::ofstream out(dir + "/bad.txt");
      out << text;
    }
    const testing::CommandResult refused =
        tiepoints({"--manual_path", dir + "/bad.txt"});
    EXPECT_EQ(refused.exit_code, 2);
    EXPECT_NE(refused.LastLine().find(named), std::string::npos)
        << refused.output;
    EXPECT_EQ(ReadTiePoints(&database).size(), points.size());
  };
  expect_refused("M2 nosuch.png 1 2\n", "nosuch.png");     // unknown image
  expect_refused("# header\nM3 image_001.png 1\n", ":2");  // line 2

  // Coded targets (`bayon targets`' output) beside the manual points: named
  // points of source "target"; a name in both files is refused.
  const auto with_targets_file = [&](const std::string& name,
                                     const std::string& text) {
    {
      std::ofstream out(dir + "/" + name);
      out << text;
    }
    return tiepoints({"--manual_path",
                      dir + "/manual.txt",
                      "--targets_path",
                      dir + "/" + name});
  };
  result = with_targets_file("targets.txt",
                             "CT4 image_001.png 300.5 310.25 0.02\n"
                             "CT4 image_002.png 320.5 305.75 0.03\n");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("1 manual points, 1 coded targets"),
            std::string::npos)
      << result.output;
  const std::vector<TiePointRecord> with_targets = ReadTiePoints(&database);
  const auto target = std::find_if(
      with_targets.begin(), with_targets.end(), [](const TiePointRecord& p) {
        return p.source == "target";
      });
  ASSERT_NE(target, with_targets.end());
  EXPECT_EQ(target->name, "CT4");
  ASSERT_EQ(target->observations.size(), 2u);
  EXPECT_NEAR(target->observations[1].covariance(0, 0), 0.0009, 1e-12);
  const testing::CommandResult clash =
      with_targets_file("clash.txt", "M1 image_001.png 300.5 310.25 0.02\n");
  EXPECT_EQ(clash.exit_code, 2) << clash.output;
  EXPECT_NE(clash.LastLine().find("M1 is also a manual point"),
            std::string::npos)
      << clash.LastLine();
}

TEST(TiePoints, RefusesADatabaseWithoutSurfaces) {
  const std::string fixture = testing::OrientedTowerFixture();
  const std::string dir = testing::TempDir("tiepoints_nosurfaces");
  const std::string db = dir + "/database.db";
  testing::CopyTree(fixture + "/ws/database.db", db);
  const testing::CommandResult result =
      testing::RunBayon({"tiepoints",
                         "--database_path",
                         db,
                         "--image_path",
                         fixture + "/ws/images"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.LastLine().find("bayon disparity"), std::string::npos)
      << result.output;
}

}  // namespace
}  // namespace bayon
