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

// A JPEG 2000 codestream's first markers: SOC, then SIZ for a gray image of
// `size` x `size` pixels in `tile` x `tile` tiles, then COD, QCD, one empty
// tile part and EOC.
std::string Jpeg2000Header(uint32_t size, uint32_t tile) {
  std::string bytes("\xFF\x4F\xFF\x51\x00\x29\x00\x00", 8);
  for (uint32_t word : {size, size, 0u, 0u, tile, tile, 0u, 0u}) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes += char(word >> shift);
  }
  bytes += std::string("\x00\x01\x07\x01\x01", 5);
  bytes += std::string(
      "\xFF\x52\x00\x0C\x00\x00\x00\x01\x00\x05\x04\x04\x00\x00", 14);
  bytes += std::string("\xFF\x5C\x00\x04\x40\x40", 6);
  bytes += std::string("\xFF\x90\x00\x0A\x00\x00\x00\x00\x00\x0E\x00\x01", 12);
  bytes += std::string("\xFF\x93\xFF\xD9", 4);
  return bytes;
}

TEST(ImageIo, ReadsJpeg2000AndRefusesForgedTileCounts) {
  const std::string dir = testing::TempDir("image_io_jpeg2000");
  // A JP2 file as OpenCV writes it: the codestream in its 'jp2c' box.
  WriteImage(dir + "/good.jp2", Pattern(CV_8U));
  EXPECT_EQ(ReadImage(dir + "/good.jp2").cols, 80);
  // OpenJPEG would allocate about 4 KB for each of 65,025 tiles (800 MB)
  // before OpenCV looked at the image's size.
  WriteFileAtomically(dir + "/forged.jp2", Jpeg2000Header(2040, 8));
  try {
    ReadImage(dir + "/forged.jp2");
    ADD_FAILURE() << "a JPEG 2000 of 65,025 tiles was read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("65025 tiles"), std::string::npos)
        << error.what();
  }
  // The same header with one tile passes the check and reaches OpenJPEG.
  WriteFileAtomically(dir + "/one_tile.jp2", Jpeg2000Header(2040, 2040));
  try {
    ReadImage(dir + "/one_tile.jp2");
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).find("tiles"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace bayon
