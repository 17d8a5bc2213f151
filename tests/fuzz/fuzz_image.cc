// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_image: an image file through bayon's loader (image_io.h): the size
// from the header (ReadImageSize, bayon's own JPEG/PNG header parser), the
// container check and OpenCV's decoding in every read mode, the grey float
// conversion, and the EXIF focal length (Exiv2).
//
// OpenCV allocates what a header claims, up to OPENCV_IO_MAX_IMAGE_PIXELS
// (2^30 by default, read when the library loads): scripts/fuzz.sh and the
// replay test set it to 2^22 so that a forged header stays under the
// fuzzer's memory limit.
#include "ext/image/image_io.h"

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::setNumThreads(0);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace bayon;
  const std::string path = fuzz::FreshPath("image.jpg");
  fuzz::WriteFile(path, std::string(reinterpret_cast<const char*>(data), size));
  fuzz::Expect([&] { ReadImageSize(path); });
  fuzz::Expect([&] { ReadImage(path, ImageReadMode::kGray); });
  fuzz::Expect([&] { ReadImage(path, ImageReadMode::kColor); });
  fuzz::Expect([&] { ReadImageGrayFloat(path); });
  ReadExifFocal(path);  // never throws: no EXIF is not an error
  return 0;
}
