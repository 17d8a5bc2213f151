// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/image_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/testing.h"

namespace bayon {
namespace {

cv::Mat Pattern(int depth) {
  cv::Mat image(60, 80, CV_MAKETYPE(depth, 3));
  cv::randu(image, 0, depth == CV_16U ? 65535 : 255);
  return image;
}

TEST(ImageIo, ReadsWhatItWritesInEveryDepth) {
  const std::string dir = testing::TempDir("image_io");
  WriteImage(dir + "/a.png", Pattern(CV_8U));
  WriteImage(dir + "/b.png", Pattern(CV_16U));
  std::filesystem::create_directories(dir + "/sub");
  WriteImage(dir + "/sub/c.jpg", Pattern(CV_8U));
  EXPECT_EQ(ListImages(dir),
            (std::vector<std::string>{"a.png", "b.png", "sub/c.jpg"}));
  EXPECT_EQ(ReadImage(dir + "/b.png").depth(), CV_16U);
  const cv::Mat gray = ReadImageGrayFloat(dir + "/b.png");
  EXPECT_EQ(gray.type(), CV_32F);
  double max_value;
  cv::minMaxLoc(gray, nullptr, &max_value);
  EXPECT_LE(max_value, 255.0 + 1e-3);
  const ImageSize size = ReadImageSize(dir + "/sub/c.jpg");
  EXPECT_EQ(size.width, 80);
  EXPECT_EQ(size.height, 60);
  EXPECT_EQ(ReadImageSize(dir + "/a.png").width, 80);
}

TEST(ImageIo, RefusesTruncatedAndFakeImages) {
  const std::string dir = testing::TempDir("image_io_bad");
  WriteImage(dir + "/good.jpg", Pattern(CV_8U));
  const std::string data = ReadFileToString(dir + "/good.jpg");
  WriteFileAtomically(dir + "/truncated.jpg", data.substr(0, data.size() / 2));
  WriteFileAtomically(dir + "/text.png", "this is not an image\n");
  WriteFileAtomically(dir + "/empty.png", "");
  for (const char* name :
       {"truncated.jpg", "text.png", "empty.png", "missing.png"}) {
    try {
      ReadImage(dir + "/" + name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(name), std::string::npos)
          << error.what();
    }
  }
}

}  // namespace
}  // namespace bayon
