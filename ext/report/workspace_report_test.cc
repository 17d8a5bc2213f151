// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/workspace_report.h"

#include "ext/colmap/model_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/core/scene.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>

#include "tests/xml_testing.h"

namespace bayon {
namespace {

namespace fs = std::filesystem;

// A fresh folder for one test.
std::string TestDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("bayon_workspace_report_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// 8 stations on a circle of radius 5 around 64 points in the cube [-1, 1]^3,
// looking at the centre, upright (z up); every point seen by every image,
// observed 0.5 px left or right of its projection (alternating), so that
// the residuals in x have an RMS of exactly 0.5 px and those in y are 0.
Scene RingScene() {
  Scene scene;
  Camera camera = Camera::Create(CameraModelId::kPinhole, 500, 640, 480);
  camera.camera_id = 1;
  scene.cameras.Set(1, camera);
  for (int i = 0; i < 8; ++i) {
    const double angle = 2 * M_PI * i / 8;
    const Eigen::Vector3d center(5 * std::cos(angle), 5 * std::sin(angle), 0);
    const Eigen::Vector3d z = -center.normalized();
    const Eigen::Vector3d y(0, 0, -1);
    const Eigen::Vector3d x = y.cross(z);
    Eigen::Matrix3d cam_from_world_rotation;
    cam_from_world_rotation << x.transpose(), y.transpose(), z.transpose();
    Image image;
    image.image_id = i + 1;
    image.camera_id = 1;
    image.name = "ring_" + std::to_string(i) + ".png";
    image.cam_from_world = Rigid3d(Eigen::Quaterniond(cam_from_world_rotation),
                                   -cam_from_world_rotation * center);
    scene.images.Set(image.image_id, image);
  }
  int observation = 0;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      for (int c = 0; c < 4; ++c) {
        const Eigen::Vector3d xyz(
            -1 + a * 2 / 3.0, -1 + b * 2 / 3.0, -1 + c * 2 / 3.0);
        std::vector<TrackElement> track;
        for (auto& [image_id, image] : scene.images) {
          Eigen::Vector2d pixel;
          EXPECT_TRUE(scene.Project(image, xyz, &pixel));
          Point2D point2D;
          point2D.xy =
              pixel + Eigen::Vector2d(observation++ % 2 ? 0.5 : -0.5, 0);
          image.points2D.push_back(point2D);
          track.push_back(
              {image_id, static_cast<point2D_t>(image.points2D.size() - 1)});
        }
        scene.AddPoint3D(xyz, track);
      }
    }
  }
  return scene;
}

std::string MakeWorkspace(const std::string& name) {
  const std::string dir = TestDir(name);
  fs::create_directories(dir + "/sparse/adjusted");
  WriteModel(RingScene(), dir + "/sparse/adjusted", ModelFormat::kBinary);
  return dir;
}

std::vector<std::string> SvgElements(const std::string& html) {
  std::vector<std::string> svgs;
  for (size_t start = html.find("<svg"); start != std::string::npos;
       start = html.find("<svg", start + 1)) {
    const size_t end = html.find("</svg>", start);
    if (end == std::string::npos) break;
    svgs.push_back(html.substr(start, end + 6 - start));
  }
  return svgs;
}

TEST(WorkspaceReport, MissingWorkspaceOrModelIsAnInputError) {
  const std::string dir = TestDir("missing");
  try {
    BuildWorkspaceReport(dir + "/nothing", WorkspaceReportOptions());
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(dir + "/nothing"),
              std::string::npos)
        << error.what();
  }
  try {
    BuildWorkspaceReport(dir, WorkspaceReportOptions());
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("sparse/adjusted"),
              std::string::npos);
    EXPECT_NE(std::string(error.what())
                  .find("run bayon pipeline or bayon adjust first"),
              std::string::npos)
        << error.what();
  }
  WorkspaceReportOptions options;
  options.jpeg_quality = 0;
  EXPECT_THROW(options.Check(), InputError);
}

TEST(WorkspaceReport, AModelAloneGivesTheSparseSectionsAndNotRunLines) {
  const std::string dir = MakeWorkspace("model_only");
  const WorkspaceReport report =
      BuildWorkspaceReport(dir, WorkspaceReportOptions());
  EXPECT_EQ(report.num_images, 8);
  EXPECT_EQ(report.num_points3D, 64);
  EXPECT_EQ(report.num_observations, 8 * 64);
  EXPECT_TRUE(report.problems.empty());
  const std::vector<std::string> ids = {"pipeline",
                                        "network",
                                        "tiepoints",
                                        "residuals",
                                        "calibration",
                                        "precision",
                                        "dense",
                                        "edit",
                                        "mesh",
                                        "texture",
                                        "renders",
                                        "colmap",
                                        "evaluation"};
  EXPECT_EQ(report.section_ids, ids);
  for (const std::string& id : ids) {
    EXPECT_NE(report.html.find("<section id=\"" + id + "\""), std::string::npos)
        << id;
    EXPECT_NE(report.html.find("href=\"#" + id + "\""), std::string::npos);
  }
  for (const std::string title : {"Pipeline run",
                                  "Dense points",
                                  "Surface mesh",
                                  "Texture",
                                  "Comparison with stock COLMAP"}) {
    EXPECT_NE(std::find(report.not_run.begin(), report.not_run.end(), title),
              report.not_run.end())
        << title;
  }
  for (const std::string title :
       {"Image network", "Tie-point distribution", "Image residuals"}) {
    EXPECT_EQ(std::find(report.not_run.begin(), report.not_run.end(), title),
              report.not_run.end())
        << title;
  }
  // The residuals as constructed.
  EXPECT_NE(report.html.find("RMS 0.500 px"), std::string::npos);
  EXPECT_NE(report.html.find("RMS 0.000 px"), std::string::npos);
  // Every station named in the plan view, every image with its frame.
  for (int i = 0; i < 8; ++i) {
    EXPECT_NE(report.html.find(">ring_" + std::to_string(i) + "</text>"),
              std::string::npos);
  }
  // Charts: plan, side, observations per image, rays, 8 frames, two
  // histograms, the residual field.
  const std::vector<std::string> svgs = SvgElements(report.html);
  EXPECT_EQ(static_cast<int>(svgs.size()), report.num_charts);
  EXPECT_EQ(report.num_charts, 2 + 2 + 8 + 3);
  for (const std::string& svg : svgs) {
    EXPECT_EQ(testing::XmlWellFormednessError(svg), "") << svg.substr(0, 300);
  }
  // Nothing loaded from elsewhere.
  EXPECT_EQ(report.html.find("src="), std::string::npos);
  EXPECT_EQ(report.html.find("href=\"http"), std::string::npos);
  EXPECT_EQ(report.html.find("href=\"//"), std::string::npos);
  EXPECT_EQ(report.html.find("<script"), std::string::npos);
}

TEST(WorkspaceReport, ShowsWhatExistsAndSaysWhatCannotBeRead) {
  const std::string dir = MakeWorkspace("parts");
  fs::create_directories(dir + "/dense");
  WriteFileAtomically(dir + "/dense/points.json", "{\"num_points\": ");
  WriteFileAtomically(
      dir + "/sparse/adjusted/adjustment.json",
      R"({"datum": {"type": "free", "description": "inner constraints"},
          "statistics": {"num_tie_points": 64, "n": 1024, "u": 240, "d": 7,
                         "r": 791, "r_over_n": 0.7725, "sigma0_px": 0.512,
                         "sigma0_apriori_px": 1.0,
                         "tie_points_by_rays": {"8": 64},
                         "point_precision_rms_mm": [5.8, 3.7, 8.8]},
          "check_points": {"num": 0}})");
  fs::create_directories(dir + "/renders");
  cv::imwrite(dir + "/renders/shaded_0.png",
              cv::Mat(600, 1200, CV_8UC3, cv::Scalar(90, 90, 90)));
  cv::imwrite(dir + "/renders/interleaved_0.png",
              cv::Mat(60, 120, CV_8UC3, cv::Scalar(90, 90, 90)));
  fs::create_directories(dir + "/viewer");
  WriteFileAtomically(dir + "/viewer/index.html", "<html></html>");
  fs::create_directories(dir + "/out");
  WorkspaceReportOptions options;
  options.report_dir = dir + "/out";
  options.max_render_size_px = 400;
  const WorkspaceReport report = BuildWorkspaceReport(dir, options);

  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_NE(report.problems[0].find("dense/points.json"), std::string::npos);
  EXPECT_NE(report.html.find("Could not read <code>dense/points.json</code>"),
            std::string::npos);
  // The precision table beside the paper's.
  EXPECT_NE(report.html.find("0.772"), std::string::npos);
  EXPECT_NE(report.html.find("0.512 px"), std::string::npos);
  EXPECT_NE(report.html.find("5.80 / 3.70 / 8.80"), std::string::npos);
  EXPECT_NE(report.html.find("20.3 &micro;m"), std::string::npos);
  // One render (the interleaved stereo picture is left out), scaled down.
  EXPECT_EQ(report.num_pictures, 1);
  EXPECT_NE(report.html.find("data:image/jpeg;base64,"), std::string::npos);
  EXPECT_NE(report.html.find("href=\"../viewer/index.html\""),
            std::string::npos);
  for (const std::string& svg : SvgElements(report.html)) {
    EXPECT_EQ(testing::XmlWellFormednessError(svg), "");
  }
}

TEST(WorkspaceReport, SaysWhatTheStripLeftOut) {
  const std::string dir = MakeWorkspace("strip_notes");
  fs::create_directories(dir + "/sparse/initial");
  WriteFileAtomically(
      dir + "/sparse/initial/strip.json",
      R"({"closed_ring": false, "unoriented_images": ["ring_9.png"],
          "resected_images": [{"name": "ring_7.png", "num_inliers": 40,
                               "num_points": 45, "rms_px": 0.81}],
          "dropped_pairs": [
            "ring_2.png - ring_6.png: its rotation disagrees <loop>"]})");
  const WorkspaceReport report =
      BuildWorkspaceReport(dir, WorkspaceReportOptions());
  EXPECT_TRUE(report.problems.empty());
  EXPECT_NE(report.html.find("The strip is open"), std::string::npos);
  EXPECT_NE(report.html.find("Not oriented by the strip (no model attached "
                             "them and too few intersected tie points placed "
                             "them): ring_9.png."),
            std::string::npos);
  EXPECT_NE(report.html.find("Placed by spatial resection from the tie "
                             "points: ring_7.png (40 of 45 points, RMS 0.81 "
                             "px)."),
            std::string::npos);
  EXPECT_NE(report.html.find("1 image pair left out before the strip"),
            std::string::npos);
  EXPECT_NE(report.html.find("<li>ring_2.png - ring_6.png: its rotation "
                             "disagrees"),
            std::string::npos);
  EXPECT_NE(report.html.find("&lt;loop&gt;"), std::string::npos);
}

TEST(WorkspaceReport, ShowsTheComparisonWithColmap) {
  const std::string dir = MakeWorkspace("comparison");
  fs::create_directories(dir + "/colmap");
  // The layout `bayon compare_colmap` writes.
  WriteFileAtomically(dir + "/colmap/comparison.json", R"({
    "image_path": "/images", "num_images": 16,
    "bayon": {"model_path": "sparse/adjusted", "model_display": "sparse/adjusted",
              "registered": 16, "points3D": 1397, "observations": 3736,
              "mean_track_length": 2.67, "mean_reprojection_error_px": 0.266,
              "rms_reprojection_error_px": 0.371, "sigma0_px": 0.412,
              "adjustment_sigma0": 0.0497,
              "stage_seconds": {"features": 0.7, "match": 11.3},
              "total_seconds": 12.0},
    "colmap": {"model_path": "colmap/sparse/0", "model_display": "colmap/sparse/0",
               "registered": 13, "points3D": 2100, "observations": 9000,
               "mean_track_length": 4.3, "mean_reprojection_error_px": 0.61,
               "rms_reprojection_error_px": 0.8, "sigma0_px": 0.9,
               "adjustment_sigma0": null,
               "stage_seconds": {"feature_extractor": 3.1,
                                 "exhaustive_matcher": 4.0, "mapper": 3.6},
               "total_seconds": 10.7},
    "agreement": {"num_common": 13, "center_rms": 0.0123, "center_max": 0.03,
                  "center_rms_percent": 0.51, "rotation_rms_deg": 0.84},
    "truth": {"path": "/truth",
              "bayon": {"registered": 16, "center_rms": 0.00116,
                        "center_max": 0.003, "center_rms_percent": 0.207,
                        "rotation_rms_deg": 0.135},
              "colmap": {"registered": 13, "center_rms": 0.00312,
                         "center_max": 0.008, "center_rms_percent": 0.557,
                         "rotation_rms_deg": 0.845}}})");
  const WorkspaceReport report =
      BuildWorkspaceReport(dir, WorkspaceReportOptions());
  EXPECT_TRUE(report.problems.empty());
  EXPECT_EQ(std::find(report.not_run.begin(),
                      report.not_run.end(),
                      "Comparison with stock COLMAP"),
            report.not_run.end());
  const std::string& html = report.html;
  for (const std::string cells :
       {"<td>Images registered</td><td class=\"num\">16 / 16</td><td "
        "class=\"num\">13 / 16</td>",
        "<td>Time: mapper</td><td class=\"num\"></td><td "
        "class=\"num\">3.60 s</td>",
        "<td>Camera centres, RMS [truth units]</td><td "
        "class=\"num\">0.001160</td><td class=\"num\">0.003120</td>",
        "<td>Rotations, RMS [&deg;]</td><td class=\"num\">0.135</td><td "
        "class=\"num\">0.845</td>",
        "<td>&sigma;<sub>0</sub> of the adjustment [px]</td><td "
        "class=\"num\">0.050</td><td class=\"num\">&ndash;</td>"}) {
    EXPECT_NE(html.find(cells), std::string::npos) << cells;
  }
}

}  // namespace
}  // namespace bayon
