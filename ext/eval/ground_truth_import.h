// SPDX-License-Identifier: BSD-3-Clause
//
// The calibrated cameras of real benchmark image sets as a bayon::Scene (and
// so as a COLMAP model): the truth that `bayon evaluate` compares results
// with. Two formats:
//
// Middlebury multi-view stereo (`*_par.txt`, Seitz et al. 2006): a line with
// the number of images, then one line per image
//   name k11 k12 k13 k21 k22 k23 k31 k32 k33 r11 ... r33 t1 t2 t3
// with the projection x ~ K [R | t] X, i.e. cam_from_world = (R, t). The file
// gives no image size: it is read from the image files (header only).
//
// Strecha et al. 2008 (`<image name>.camera`, one file per image): the
// lines K (3 x 3, row by row), a row of lens distortion (3 values), R (3 x 3,
// camera-to-world), the camera centre C, and `width height`, with
// x ~ K R^T (X - C), i.e. cam_from_world = (R^T, -R^T C). The image name is
// the file name without `.camera`.
//
// Conventions: both formats count pixels with the centre of the upper-left
// pixel at (0, 0); COLMAP puts it at (0.5, 0.5), so `pixel_origin_offset_px`
// (0.5) is added to the principal point. Cameras are PINHOLE, or
// SIMPLE_PINHOLE where fx == fy; images with identical intrinsics and size
// share one camera. COLMAP's models have neither skew nor these files'
// distortion, so a K with skew and a non-zero Strecha distortion row are
// refused, not dropped. Image ids follow the sorted names (as `bayon
// import` gives them), camera ids the order of first use.
//
// Every record is checked before anything is built: finite numbers, the
// number of fields on each line, R orthonormal with det +1, K upper
// triangular with positive focal lengths, no name twice, the count line of
// a Middlebury file against its lines, and, with an image folder, every
// listed image on disk (with the size a Strecha file states). A failure is
// an InputError "<file>:<line>: <what was found and what was expected>".
#pragma once

#include "ext/core/option_registry.h"
#include "ext/core/rigid3.h"
#include "ext/core/scene.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace bayon {

enum class GroundTruthFormat { kMiddlebury, kStrecha };

// "middlebury" / "strecha"; nullopt for anything else.
std::optional<GroundTruthFormat> GroundTruthFormatFromName(
    const std::string& name);
const char* GroundTruthFormatName(GroundTruthFormat format);

struct GroundTruthImportOptions {
  GroundTruthFormat format = GroundTruthFormat::kMiddlebury;
  // Middlebury: the *_par.txt file. Strecha: a folder of *.camera files or
  // one such file.
  std::string input_path;
  // Folder of the images. Empty: Middlebury looks in the folder of its file
  // (where the data set keeps them; it needs their sizes), Strecha does not
  // check the images.
  std::string image_path;
  // Largest entry of |R^T R - I| accepted as a rotation. Files give R to 6
  // to 20 digits (fountain-P11: about 1e-6); R is then made exactly
  // orthonormal. Larger deviations are a wrong or corrupt matrix.
  double max_rotation_error = 1e-4;
  // Largest |k12| (skew, pixels) taken as zero. COLMAP's camera models have
  // no skew, so anything above is refused.
  double max_skew_px = 1e-6;
  // Added to the principal point: 0.5 for files whose upper-left pixel
  // centre is (0, 0), 0 for files already in COLMAP's convention.
  double pixel_origin_offset_px = 0.5;

  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming the field
};

// One image of a truth file, in COLMAP's conventions.
struct GroundTruthView {
  std::string name;  // the image file name, as in the source
  // Intrinsics in COLMAP pixels: [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Rigid3d cam_from_world;
  int width = 0;  // 0: unknown (Middlebury before the images are read)
  int height = 0;
  std::string file;   // the file it came from
  int line = 0;       // the line of its record (Strecha: 1)
  int size_line = 0;  // the line giving width and height; 0: none
};

// Parsers; they read only the truth file(s). Throw InputError naming the
// file and line.
std::vector<GroundTruthView> ReadMiddleburyCameras(
    const std::string& path, const GroundTruthImportOptions& options);
// `path`: one .camera file or a folder of them (sorted by name).
std::vector<GroundTruthView> ReadStrechaCameras(
    const std::string& path, const GroundTruthImportOptions& options);

// Fills in the sizes of views from the images in `image_path` and checks
// that every image exists (and has the size a view states). Throws
// InputError "<file>:<line>: image <name> ...".
void CheckGroundTruthImages(const std::string& image_path,
                            std::vector<GroundTruthView>* views);

// The views as a scene: ids from the sorted names, one camera per distinct
// (K, width, height), no points. Every view must have a size.
Scene GroundTruthScene(const std::vector<GroundTruthView>& views);

// Reads, checks the images and builds the scene: what
// `bayon import_ground_truth` writes as a COLMAP model.
Scene ImportGroundTruth(const GroundTruthImportOptions& options);

}  // namespace bayon
