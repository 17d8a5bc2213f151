// SPDX-License-Identifier: BSD-3-Clause
#include "ext/image/image_io.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

// Exiv2 0.27 (Debian 12) still hands out std::auto_ptr.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>
#pragma GCC diagnostic pop
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string LowerExtension(const std::string& name) {
  std::string ext = fs::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) {
    return std::tolower(c);
  });
  return ext;
}

bool StartsWith(const std::string& data, const char* magic, size_t n) {
  return data.size() >= n && std::memcmp(data.data(), magic, n) == 0;
}

uint32_t BigEndian32(const std::string& data, size_t offset) {
  return (uint32_t(uint8_t(data[offset])) << 24) |
         (uint32_t(uint8_t(data[offset + 1])) << 16) |
         (uint32_t(uint8_t(data[offset + 2])) << 8) |
         uint32_t(uint8_t(data[offset + 3]));
}

// A JPEG 2000 codestream starts with its SOC and SIZ markers; a JP2 file
// with its signature box.
constexpr char kJpeg2000Codestream[] = "\xFF\x4F\xFF\x51";
constexpr char kJp2Signature[] = "\0\0\0\x0CjP  \r\n\x87\n";

bool IsJpeg2000(const std::string& data) {
  return StartsWith(data, kJpeg2000Codestream, 4) ||
         StartsWith(data, kJp2Signature, 12);
}

// Where a JPEG 2000 file's codestream starts: at once for a raw codestream,
// in the top-level 'jp2c' box of a JP2 file. npos if none.
size_t Jpeg2000Codestream(const std::string& data) {
  if (StartsWith(data, kJpeg2000Codestream, 4)) return 0;
  // A box: its length (1: a 64-bit length follows the type; 0: to the end of
  // the file), its type, its content.
  for (size_t at = 0; at + 8 <= data.size();) {
    uint64_t length = BigEndian32(data, at);
    size_t header = 8;
    if (length == 1) {
      if (at + 16 > data.size()) break;
      length = (uint64_t(BigEndian32(data, at + 8)) << 32) |
               BigEndian32(data, at + 12);
      header = 16;
    } else if (length == 0) {
      length = data.size() - at;
    }
    if (data.compare(at + 4, 4, "jp2c") == 0) return at + header;
    if (length < header || length > data.size() - at) break;
    at += length;
  }
  return std::string::npos;
}

// OpenJPEG allocates its structures for every tile and component that the
// SIZ header claims, about 4 KB each, before OpenCV checks the image size
// (and OpenCV decodes by signature, whatever the file's name): a 3 KB
// codestream claiming 65,025 tiles of 1,000 components took 23 GB. A
// 100-megapixel photograph in 256 x 256 tiles has 1,600.
std::string CheckJpeg2000(const std::string& data) {
  constexpr uint64_t kMaxTiles = 4096;
  constexpr uint32_t kMaxComponents = 4;
  const size_t start = Jpeg2000Codestream(data);
  // SOC, SIZ, Lsiz, Rsiz, then the sizes and offsets as 32-bit words.
  if (start == std::string::npos || start + 42 > data.size() ||
      data.compare(start, 4, kJpeg2000Codestream, 4) != 0) {
    return "JPEG 2000 without its image and tile size header (SIZ)";
  }
  auto word = [&](int k) {
    return uint64_t(BigEndian32(data, start + 8 + 4 * k));
  };
  const uint64_t width = word(0), height = word(1);
  const uint64_t tile_width = word(4), tile_height = word(5);
  const uint64_t tile_x = word(6), tile_y = word(7);
  const uint32_t components =
      (uint32_t(uint8_t(data[start + 40])) << 8) | uint8_t(data[start + 41]);
  if (tile_width == 0 || tile_height == 0 || tile_x >= width ||
      tile_y >= height) {
    return "JPEG 2000 with an invalid tile grid";
  }
  const uint64_t tiles = ((width - tile_x + tile_width - 1) / tile_width) *
                         ((height - tile_y + tile_height - 1) / tile_height);
  if (tiles > kMaxTiles || components == 0 || components > kMaxComponents) {
    return StrCat("JPEG 2000 header claims ",
                  tiles,
                  " tiles of ",
                  components,
                  " components (read: at most ",
                  kMaxTiles,
                  " tiles of 1 to ",
                  kMaxComponents,
                  ")");
  }
  return "";
}

// Checks the container so that truncated files are refused: libjpeg and
// libpng decode what they get and only warn. Returns an error or "".
std::string CheckContainer(const std::string& data) {
  if (StartsWith(data, "\xFF\xD8", 2)) {
    // JPEG ends with EOI (FF D9); some writers append padding after it.
    const size_t tail_start = data.size() > 4096 ? data.size() - 4096 : 0;
    if (data.rfind("\xFF\xD9", std::string::npos) == std::string::npos ||
        data.rfind("\xFF\xD9") < tail_start) {
      return "truncated JPEG (no end-of-image marker)";
    }
    return "";
  }
  if (StartsWith(data, "\x89PNG\r\n\x1a\n", 8)) {
    if (data.find("IEND") == std::string::npos) {
      return "truncated PNG (no IEND chunk)";
    }
    return "";
  }
  if (IsJpeg2000(data)) return CheckJpeg2000(data);
  return "";
}

}  // namespace

bool HasImageExtension(const std::string& name) {
  static const char* kExtensions[] = {".jpg",
                                      ".jpeg",
                                      ".png",
                                      ".tif",
                                      ".tiff",
                                      ".bmp",
                                      ".pgm",
                                      ".ppm",
                                      ".pnm",
                                      ".webp",
                                      ".jp2",
                                      ".exr",
                                      ".hdr"};
  const std::string ext = LowerExtension(name);
  return std::any_of(std::begin(kExtensions),
                     std::end(kExtensions),
                     [&](const char* known) { return ext == known; });
}

std::vector<std::string> ListImages(const std::string& folder) {
  CheckDirectoryExists(folder, "image folder");
  std::vector<std::string> names;
  for (const std::string& file : ListFilesRecursive(folder)) {
    if (HasImageExtension(file)) names.push_back(file);
  }
  return names;
}

cv::Mat ReadImage(const std::string& path, ImageReadMode mode) {
  return DecodeImage(ReadFileToString(path), mode, path);
}

cv::Mat DecodeImage(const std::string& data,
                    ImageReadMode mode,
                    const std::string& path) {
  if (data.empty()) ThrowInputError(path, ": empty file, not an image");
  const std::string problem = CheckContainer(data);
  if (!problem.empty()) ThrowInputError(path, ": ", problem);
  int flags = cv::IMREAD_UNCHANGED;
  if (mode == ImageReadMode::kGray)
    flags = cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE;
  if (mode == ImageReadMode::kColor)
    flags = cv::IMREAD_ANYDEPTH | cv::IMREAD_COLOR;
  cv::Mat image;
  try {
    image = cv::imdecode(cv::Mat(1,
                                 static_cast<int>(data.size()),
                                 CV_8U,
                                 const_cast<char*>(data.data())),
                         flags);
  } catch (const cv::Exception& error) {
    ThrowInputError(path, ": cannot decode image: ", error.what());
  }
  if (image.empty()) {
    ThrowInputError(
        path, ": not an image OpenCV can read (", data.size(), " bytes)");
  }
  return image;
}

cv::Mat ReadImageColor8(const std::string& path) {
  cv::Mat bgr = ReadImage(path, ImageReadMode::kColor);
  if (bgr.depth() == CV_16U) {
    bgr.convertTo(bgr, CV_8U, 1.0 / 257.0);
  } else if (bgr.depth() != CV_8U) {
    ThrowInputError(path, ": needs 8 or 16 bits per channel");
  }
  return bgr;
}

cv::Mat ReadImageGrayFloat(const std::string& path) {
  cv::Mat image = ReadImage(path, ImageReadMode::kUnchanged);
  if (image.channels() == 4) {
    cv::cvtColor(image, image, cv::COLOR_BGRA2GRAY);
  } else if (image.channels() == 3) {
    cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  } else if (image.channels() != 1) {
    ThrowInputError(path, ": ", image.channels(), " channels not supported");
  }
  double scale = 1.0;
  switch (image.depth()) {
    case CV_8U:
      scale = 1.0;
      break;
    case CV_16U:
      scale = 1.0 / 257.0;
      break;
    case CV_32F:
    case CV_64F:
      scale = 255.0;  // float images are taken as 0..1
      break;
    default:
      scale = 1.0;
  }
  cv::Mat gray;
  image.convertTo(gray, CV_32F, scale);
  return gray;
}

ImageSize ReadImageSize(const std::string& path) {
  // PNG: IHDR right after the signature. JPEG: the first SOF marker.
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    std::error_code ec;
    if (!fs::exists(path, ec)) ThrowInputError(path, ": image not found");
    ThrowInputError(path, ": cannot open image");
  }
  std::string head(65536, '\0');
  file.read(&head[0], head.size());
  head.resize(file.gcount());
  if (StartsWith(head, "\x89PNG\r\n\x1a\n", 8) && head.size() >= 24) {
    ImageSize size{static_cast<int>(BigEndian32(head, 16)),
                   static_cast<int>(BigEndian32(head, 20))};
    if (size.width > 0 && size.height > 0) return size;
  }
  if (StartsWith(head, "\xFF\xD8", 2)) {
    size_t pos = 2;
    while (pos + 9 < head.size()) {
      if (uint8_t(head[pos]) != 0xFF) break;
      const uint8_t marker = uint8_t(head[pos + 1]);
      const size_t length =
          (uint8_t(head[pos + 2]) << 8) | uint8_t(head[pos + 3]);
      const bool sof = (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 &&
                        marker != 0xC8 && marker != 0xCC);
      if (sof) {
        ImageSize size{(uint8_t(head[pos + 7]) << 8) | uint8_t(head[pos + 8]),
                       (uint8_t(head[pos + 5]) << 8) | uint8_t(head[pos + 6])};
        if (size.width > 0 && size.height > 0) return size;
        break;
      }
      pos += 2 + length;
    }
  }
  const cv::Mat image = ReadImage(path);
  return ImageSize{image.cols, image.rows};
}

std::optional<ExifFocal> ReadExifFocal(const std::string& path) {
  try {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    auto image = Exiv2::ImageFactory::open(path);
#pragma GCC diagnostic pop
    if (image.get() == nullptr) return std::nullopt;
    image->readMetadata();
    const Exiv2::ExifData& exif = image->exifData();
    if (exif.empty()) return std::nullopt;
    ExifFocal focal;
    auto read = [&](const char* key) -> double {
      auto it = exif.findKey(Exiv2::ExifKey(key));
      if (it == exif.end() || it->count() == 0) return 0.0;
      const double value = it->toFloat();
      return std::isfinite(value) && value > 0 ? value : 0.0;
    };
    focal.focal_length_mm = read("Exif.Photo.FocalLength");
    focal.focal_length_35mm = read("Exif.Photo.FocalLengthIn35mmFilm");
    const double x_res = read("Exif.Photo.FocalPlaneXResolution");
    if (x_res > 0) {
      // Resolution unit: 2 = inch (default), 3 = cm, 4 = mm.
      auto unit_it =
          exif.findKey(Exiv2::ExifKey("Exif.Photo.FocalPlaneResolutionUnit"));
      const long unit = unit_it != exif.end() ? unit_it->toLong() : 2;
      const double mm_per_unit = unit == 3 ? 10.0 : unit == 4 ? 1.0 : 25.4;
      focal.focal_plane_x_res_per_mm = x_res / mm_per_unit;
    }
    return focal;
  } catch (const std::exception&) {
    return std::nullopt;  // no or unreadable EXIF is not an error
  }
}

double FocalLengthPxFromExif(const ExifFocal& exif, int width, int height) {
  const double max_size = std::max(width, height);
  if (exif.focal_length_35mm > 0)
    return exif.focal_length_35mm / 35.0 * max_size;
  if (exif.focal_length_mm > 0 && exif.focal_plane_x_res_per_mm > 0) {
    return exif.focal_length_mm * exif.focal_plane_x_res_per_mm;
  }
  return 0.0;
}

void WriteImage(const std::string& path,
                const cv::Mat& image,
                const std::vector<int>& params) {
  std::vector<uchar> buffer;
  bool ok = false;
  try {
    ok = cv::imencode(
        fs::path(path).extension().string(), image, buffer, params);
  } catch (const cv::Exception& error) {
    ThrowInputError(path, ": cannot encode image: ", error.what());
  }
  if (!ok) ThrowInputError(path, ": cannot encode image");
  WriteFileAtomically(path, std::string(buffer.begin(), buffer.end()));
}

void CheckImagesOnDisk(const std::string& folder,
                       const std::vector<ExpectedImage>& images,
                       const std::string& source) {
  std::vector<std::string> missing;
  for (const ExpectedImage& image : images) {
    const std::string path = (fs::path(folder) / image.name).string();
    if (!fs::is_regular_file(path)) {
      missing.push_back(path);
      continue;
    }
    if (image.width <= 0 || image.height <= 0) continue;
    const ImageSize size = ReadImageSize(path);
    if (size.width != image.width || size.height != image.height) {
      ThrowInputError(path,
                      ": ",
                      size.width,
                      "x",
                      size.height,
                      " pixels, but its camera in ",
                      source,
                      " is ",
                      image.width,
                      "x",
                      image.height);
    }
  }
  if (!missing.empty()) {
    ThrowInputError(missing.front(),
                    ": listed in ",
                    source,
                    " but missing on disk (",
                    missing.size(),
                    " of ",
                    images.size(),
                    " images missing)");
  }
}

}  // namespace bayon
