// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon render` end to end: a textured box written by WriteTexturedModel,
// rendered from orbit viewpoints and from a photograph's station in every
// mode and stereo form; the pictures read back and judged (sizes, the
// atlas's colours on the box, lines in the wireframe, the stereo images
// composed from the left and right views); and bad input refused with one
// line and nothing written.
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/file_util.h"
#include "ext/render/model_export.h"
#include "ext/render/views.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The six colours of the box's sides (BGR), none near white or grey.
const cv::Vec3b kSideColors[6] = {{40, 40, 200},
                                  {40, 180, 40},
                                  {200, 60, 30},
                                  {30, 200, 220},
                                  {200, 40, 200},
                                  {220, 200, 40}};

// A box 2 x 1.5 x 3 m standing on z = 10 in a local datum, each side one
// chart of a 3 x 2 atlas filled with that side's colour.
TexturedModel ColouredBox() {
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.positions.emplace_back(
        50 + 2.0 * (i & 1), 20 + 1.5 * ((i >> 1) & 1), 10 + 3.0 * (i >> 2));
  }
  const int sides[6][4] = {{0, 2, 3, 1},
                           {4, 5, 7, 6},
                           {0, 1, 5, 4},
                           {2, 6, 7, 3},
                           {0, 4, 6, 2},
                           {1, 3, 7, 5}};
  model.atlas.create(128, 192, CV_8UC3);
  for (int s = 0; s < 6; ++s) {
    const int col = s % 3, row = s / 3;
    // Atlas rows count down from the top, v up from the bottom.
    model.atlas(cv::Rect(64 * col, 64 * (1 - row), 64, 64))
        .setTo(cv::Scalar(
            kSideColors[s][0], kSideColors[s][1], kSideColors[s][2]));
    const float u0 = col / 3.0f + 0.02f, v0 = row / 2.0f + 0.03f;
    const float du = 1 / 3.0f - 0.04f, dv = 0.5f - 0.06f;
    const Eigen::Vector2f uv[4] = {
        {u0, v0}, {u0 + du, v0}, {u0 + du, v0 + dv}, {u0, v0 + dv}};
    const int* c = sides[s];
    mesh.faces.emplace_back(c[0], c[1], c[2]);
    mesh.face_texcoords.push_back({uv[0], uv[1], uv[2]});
    mesh.faces.emplace_back(c[0], c[2], c[3]);
    mesh.face_texcoords.push_back({uv[0], uv[2], uv[3]});
  }
  return model;
}

// A workspace with model/model.{obj,glb,...} of the coloured box.
std::string BoxWorkspace(const std::string& name) {
  const std::string ws = testing::TempDir(name);
  WriteTexturedModel(ColouredBox(), ws + "/model", ModelExportOptions());
  return ws;
}

cv::Mat Read(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty()) << path;
  return image;
}

bool Near(const cv::Vec3b& a, const cv::Vec3b& b, int tolerance) {
  for (int c = 0; c < 3; ++c) {
    if (std::abs(int(a[c]) - int(b[c])) > tolerance) return false;
  }
  return true;
}

bool IsWhite(const cv::Vec3b& pixel) {
  return Near(pixel, cv::Vec3b(255, 255, 255), 2);
}

testing::CommandResult Render(const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"render",
                                   "--num_views",
                                   "2",
                                   "--width",
                                   "160",
                                   "--height",
                                   "120",
                                   "--supersampling",
                                   "2",
                                   "--num_threads",
                                   "4"};
  args.insert(args.end(), extra.begin(), extra.end());
  return testing::RunBayon(args);
}

TEST(RenderCommand, DrawsEveryModeAndStereoForm) {
  const std::string ws = BoxWorkspace("render_all");
  const std::string out = ws + "/renders";
  const testing::CommandResult result = Render({"--model_path",
                                                ws + "/model/model.obj",
                                                "--output_path",
                                                out,
                                                "--stereo",
                                                "anaglyph,side_by_side,"
                                                "interleaved"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("2 orbit views, 12 images"), std::string::npos)
      << result.output;
  // 2 views x (3 modes + 3 stereo forms), nothing else.
  EXPECT_EQ(ListFilesRecursive(out).size(), 12u);
  for (const std::string view : {"000", "001"}) {
    SCOPED_TRACE(view);
    const cv::Mat wireframe = Read(out + "/wireframe_" + view + ".png");
    const cv::Mat shaded = Read(out + "/shaded_" + view + ".png");
    const cv::Mat textured = Read(out + "/textured_" + view + ".png");
    const cv::Mat anaglyph = Read(out + "/anaglyph_" + view + ".png");
    const cv::Mat pair = Read(out + "/side_by_side_" + view + ".png");
    const cv::Mat interleaved = Read(out + "/interleaved_" + view + ".png");
    for (const cv::Mat& image :
         {wireframe, shaded, textured, anaglyph, interleaved}) {
      EXPECT_EQ(image.size(), cv::Size(160, 120));
    }
    ASSERT_EQ(pair.size(), cv::Size(320, 120));

    // Textured: the box fills a good part of the frame, and nearly every
    // pixel on it has one of the atlas's colours (edges are blends).
    int on_box = 0, atlas_coloured = 0;
    for (int y = 0; y < 120; ++y) {
      for (int x = 0; x < 160; ++x) {
        const cv::Vec3b pixel = textured.at<cv::Vec3b>(y, x);
        if (IsWhite(pixel)) continue;
        ++on_box;
        for (const cv::Vec3b& color : kSideColors) {
          if (Near(pixel, color, 3)) {
            ++atlas_coloured;
            break;
          }
        }
      }
    }
    EXPECT_GT(on_box, 160 * 120 / 5);
    EXPECT_GT(atlas_coloured, 0.9 * on_box);

    // Wireframe: dark lines on white, a few per cent of the pixels, and
    // only where the box is (its silhouette included).
    int dark = 0, dark_off_box = 0;
    for (int y = 0; y < 120; ++y) {
      for (int x = 0; x < 160; ++x) {
        const cv::Vec3b pixel = wireframe.at<cv::Vec3b>(y, x);
        if (pixel[0] < 128) {
          ++dark;
          bool near_box = false;
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              const int yy = std::clamp(y + dy, 0, 119);
              const int xx = std::clamp(x + dx, 0, 159);
              near_box |= !IsWhite(textured.at<cv::Vec3b>(yy, xx));
            }
          }
          dark_off_box += !near_box;
        } else {
          EXPECT_TRUE(pixel[0] > 128 && pixel[1] > 128 && pixel[2] > 128);
        }
      }
    }
    EXPECT_GT(dark, 200);
    EXPECT_LT(dark, 160 * 120 / 8);
    EXPECT_EQ(dark_off_box, 0);

    // Shaded: grey (no texture colours), lighter and darker sides.
    double min_grey = 255, max_grey = 0;
    for (int y = 0; y < 120; ++y) {
      for (int x = 0; x < 160; ++x) {
        if (IsWhite(textured.at<cv::Vec3b>(y, x))) continue;
        const cv::Vec3b pixel = shaded.at<cv::Vec3b>(y, x);
        EXPECT_LT(std::abs(int(pixel[0]) - int(pixel[2])), 40);
        min_grey = std::min<double>(min_grey, pixel[1]);
        max_grey = std::max<double>(max_grey, pixel[1]);
      }
    }
    EXPECT_GT(max_grey - min_grey, 20);

    // Stereo: the side-by-side pair is left | right; the anaglyph takes red
    // from the left and green and blue from the right; the interleaved
    // image takes even rows from the left and odd rows from the right.
    const cv::Mat left = pair.colRange(0, 160), right = pair.colRange(160, 320);
    EXPECT_GT(cv::norm(left, right, cv::NORM_L1), 1000.0)
        << "left and right views are the same";
    cv::Mat anaglyph_channels[3], left_channels[3], right_channels[3];
    cv::split(anaglyph, anaglyph_channels);
    cv::split(left.clone(), left_channels);
    cv::split(right.clone(), right_channels);
    EXPECT_EQ(cv::norm(anaglyph_channels[2], left_channels[2], cv::NORM_INF),
              0);
    EXPECT_EQ(cv::norm(anaglyph_channels[1], right_channels[1], cv::NORM_INF),
              0);
    EXPECT_EQ(cv::norm(anaglyph_channels[0], right_channels[0], cv::NORM_INF),
              0);
    // Where the box is, the red (left) and cyan (right) images disagree.
    EXPECT_GT(cv::norm(left_channels[2], right_channels[2], cv::NORM_L1),
              1000.0);
    for (int y = 0; y < 120; ++y) {
      const cv::Mat& source = y % 2 == 0 ? left : right;
      EXPECT_EQ(cv::norm(interleaved.row(y), source.row(y), cv::NORM_INF), 0)
          << "row " << y;
    }
  }
  // The two orbit views see the box from different sides.
  EXPECT_GT(cv::norm(Read(out + "/textured_000.png"),
                     Read(out + "/textured_001.png"),
                     cv::NORM_L1),
            1000.0);
}

TEST(RenderCommand, RendersTheGlbFromAPhotographsStation) {
  const std::string ws = BoxWorkspace("render_stations");
  // One photograph 15 m south of the box, looking north at its centre; one
  // looking away (no picture of it).
  Scene scene;
  Camera camera =
      Camera::Create(CameraModelId::kSimpleRadial, 2400, 3000, 2000);
  camera.camera_id = 1;
  scene.cameras.Set(1, camera);
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "IMG_0007.JPG";
  image.cam_from_world = LookAt(Eigen::Vector3d(51, 5, 11.5),
                                Eigen::Vector3d(51, 20.75, 11.5),
                                Eigen::Vector3d::UnitZ());
  scene.images.Set(1, image);
  image.image_id = 2;
  image.name = "away.jpg";
  image.cam_from_world = LookAt(Eigen::Vector3d(51, 5, 11.5),
                                Eigen::Vector3d(51, 0, 11.5),
                                Eigen::Vector3d::UnitZ());
  scene.images.Set(2, image);
  fs::create_directories(ws + "/sparse/adjusted");
  WriteModel(scene, ws + "/sparse/adjusted", ModelFormat::kBinary);

  const testing::CommandResult result = Render({"--model_path",
                                                ws + "/model/model.glb",
                                                "--output_path",
                                                ws + "/renders",
                                                "--viewpoints",
                                                "stations",
                                                "--input_path",
                                                ws + "/sparse/adjusted",
                                                "--max_image_size",
                                                "300",
                                                "--modes",
                                                "textured"});
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_EQ(ListFilesRecursive(ws + "/renders"),
            std::vector<std::string>{"textured_IMG_0007.png"});
  const cv::Mat textured = Read(ws + "/renders/textured_IMG_0007.png");
  ASSERT_EQ(textured.size(), cv::Size(300, 200));
  // The camera looks at the middle of the south side (side 2, y = 20).
  EXPECT_TRUE(Near(textured.at<cv::Vec3b>(100, 150), kSideColors[2], 3))
      << textured.at<cv::Vec3b>(100, 150);
  EXPECT_TRUE(IsWhite(textured.at<cv::Vec3b>(5, 5)));
}

// Exit code 2, one line naming `expected`, nothing written to `output`.
void ExpectRefused(const std::vector<std::string>& args,
                   const std::string& expected,
                   const std::string& output) {
  const testing::CommandResult result = Render(args);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.LastLine().find("error: "), std::string::npos)
      << result.output;
  EXPECT_NE(result.LastLine().find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << result.output;
  EXPECT_FALSE(fs::exists(output)) << output << " was written";
}

TEST(RenderCommand, RefusesBadInputWithOneLine) {
  const std::string ws = BoxWorkspace("render_bad_input");
  const std::string model = ws + "/model/model.obj";
  const std::string out = ws + "/renders";
  ExpectRefused({"--model_path", ws + "/model/none.obj", "--output_path", out},
                "none.obj",
                out);
  ExpectRefused(
      {"--model_path", model, "--output_path", out, "--modes", "shaded,xray"},
      "--modes: 'xray' is not one of wireframe, shaded, textured",
      out);
  ExpectRefused(
      {"--model_path", model, "--output_path", out, "--stereo", "hologram"},
      "hologram",
      out);
  ExpectRefused(
      {"--model_path", model, "--output_path", out, "--viewpoints", "stations"},
      "--input_path",
      out);
  // A view too large to render (16000 x 16000 at 8 x 8 samples a pixel):
  // refused before any work instead of running out of memory.
  const testing::CommandResult huge = testing::RunBayon({"render",
                                                         "--model_path",
                                                         model,
                                                         "--output_path",
                                                         out,
                                                         "--width",
                                                         "16000",
                                                         "--height",
                                                         "16000",
                                                         "--supersampling",
                                                         "8"});
  EXPECT_EQ(huge.exit_code, 2) << huge.output;
  EXPECT_NE(huge.LastLine().find("too large to render"), std::string::npos)
      << huge.LastLine();
  EXPECT_FALSE(fs::exists(out));
  // A mesh without texture: textured mode asked for by name is refused; by
  // default it is left out.
  TriangleMesh plain = ColouredBox().mesh;
  plain.face_texcoords.clear();
  fs::create_directories(ws + "/mesh");
  WriteMeshPly(plain, ws + "/mesh/mesh.ply");
  ExpectRefused({"--model_path",
                 ws + "/mesh/mesh.ply",
                 "--output_path",
                 out,
                 "--modes",
                 "shaded,textured"},
                "has no texture",
                out);
  const testing::CommandResult plain_result =
      Render({"--model_path", ws + "/mesh/mesh.ply", "--output_path", out});
  ASSERT_EQ(plain_result.exit_code, 0) << plain_result.output;
  EXPECT_EQ(ListFilesRecursive(out).size(), 4u);  // wireframe, shaded x 2
  // An existing output folder is kept unless --overwrite.
  const auto before = testing::HashTree(out);
  const testing::CommandResult again =
      Render({"--model_path", model, "--output_path", out});
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_EQ(testing::HashTree(out), before);
  // A truncated model.
  const std::string glb = ReadFileToString(ws + "/model/model.glb");
  WriteFileAtomically(ws + "/model/cut.glb", glb.substr(0, glb.size() / 2));
  ExpectRefused({"--model_path",
                 ws + "/model/cut.glb",
                 "--output_path",
                 ws + "/renders2"},
                "cut.glb",
                ws + "/renders2");
}

}  // namespace
}  // namespace bayon
