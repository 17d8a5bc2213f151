// SPDX-License-Identifier: BSD-3-Clause
//
// Image files: listing, reading with clear errors (a truncated JPEG, a text
// file named .png), header-only size queries, EXIF focal lengths, and atomic
// writing. OpenCV decodes; bayon checks what OpenCV lets through silently
// (libjpeg pads a truncated file with grey and only warns).
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

// Image files under `folder` (recursively), as names relative to it with '/'
// separators, sorted. Recognised by extension, case-insensitive: jpg, jpeg,
// png, tif, tiff, bmp, pgm, ppm, pnm, webp, jp2, exr, hdr.
std::vector<std::string> ListImages(const std::string& folder);
bool HasImageExtension(const std::string& name);

enum class ImageReadMode {
  kUnchanged,  // as stored: any depth, 1-4 channels
  kGray,       // one channel, stored depth
  kColor,      // three channels (BGR), stored depth
};

// Reads an image. Throws InputError naming the file when it is missing,
// empty, not an image, truncated or has a zero size.
cv::Mat ReadImage(const std::string& path,
                  ImageReadMode mode = ImageReadMode::kUnchanged);

// ReadImage for an image already in memory (embedded in a model file, say):
// `what` names it in errors.
cv::Mat DecodeImage(const std::string& data,
                    ImageReadMode mode,
                    const std::string& what);

// Three channels (BGR), CV_8U: 16-bit images divided by 257. Throws
// InputError like ReadImage, and for another depth.
cv::Mat ReadImageColor8(const std::string& path);

// One channel, CV_32F, values scaled to [0, 255] whatever the stored depth
// (16-bit images are divided by 257), colour converted by luminance.
cv::Mat ReadImageGrayFloat(const std::string& path);

struct ImageSize {
  int width = 0;
  int height = 0;
};
// Width and height, from the file header for JPEG and PNG (no decoding);
// other formats are decoded. Throws InputError like ReadImage.
ImageSize ReadImageSize(const std::string& path);

struct ExifFocal {
  double focal_length_mm = 0;    // 0: absent
  double focal_length_35mm = 0;  // 35 mm equivalent, 0: absent
  double focal_plane_x_res_per_mm =
      0;  // pixels per mm on the sensor, 0: absent
};
// An image a stage is about to read, with the size its camera claims.
struct ExpectedImage {
  std::string name;  // relative to the image folder
  int width = 0;     // 0: any size
  int height = 0;
};

// Checks, before any work, that every image is on disk under `folder` with
// the expected size (from the file headers). Throws InputError naming the
// first missing file (and how many are missing) or the first whose size
// differs; `source` names where the list came from (e.g. the database).
void CheckImagesOnDisk(const std::string& folder,
                       const std::vector<ExpectedImage>& images,
                       const std::string& source);

// Reads the EXIF focal length tags; nullopt when the file has no EXIF.
std::optional<ExifFocal> ReadExifFocal(const std::string& path);

// The focal length in pixels that EXIF implies for an image of `max_size`
// pixels on its long side, as COLMAP computes it (35 mm equivalent / 35 *
// max_size, or focal mm times the focal-plane resolution); 0 if unknown.
double FocalLengthPxFromExif(const ExifFocal& exif, int width, int height);

// Writes an image atomically; the format follows the extension.
void WriteImage(const std::string& path,
                const cv::Mat& image,
                const std::vector<int>& params = {});

}  // namespace bayon
