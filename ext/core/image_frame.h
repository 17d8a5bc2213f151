// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>  // inverse() and determinant() below

#include <cmath>

namespace bayon {

// The interior orientation of one image in the narrow sense: the affine
// transformation between image coordinates (mm in the image frame, x right,
// y up, origin at the frame centre) and COLMAP pixel coordinates (the centre
// of the upper-left pixel is (0.5, 0.5), y down). This is the one place where
// pixels and millimetres meet (architecture.md, "Conventions").
//
// For a digital camera it follows from the pixel pitch and the image centre;
// for a scanned film frame it is found from the frame's edges ("virtual
// fiducials", ext/orientation) and includes the scan's rotation and shift.
struct ImageFrame {
  // pixel = pixel_from_frame * (x_mm, y_mm, 1).
  Eigen::Matrix<double, 2, 3> pixel_from_frame;

  ImageFrame() {
    pixel_from_frame.setZero();
    pixel_from_frame(0, 0) = 1.0;
    pixel_from_frame(1, 1) = -1.0;
  }

  // Square pixels of `pitch_mm`, frame origin at the image centre.
  static ImageFrame Digital(double width_px,
                            double height_px,
                            double pitch_mm) {
    ImageFrame frame;
    frame.pixel_from_frame << 1.0 / pitch_mm, 0.0, 0.5 * width_px, 0.0,
        -1.0 / pitch_mm, 0.5 * height_px;
    return frame;
  }

  template <typename T>
  void PixelFromFrame(const T* xy_mm, T* pixel) const {
    const auto& a = pixel_from_frame;
    pixel[0] = T(a(0, 0)) * xy_mm[0] + T(a(0, 1)) * xy_mm[1] + T(a(0, 2));
    pixel[1] = T(a(1, 0)) * xy_mm[0] + T(a(1, 1)) * xy_mm[1] + T(a(1, 2));
  }

  Eigen::Vector2d PixelFromFrame(const Eigen::Vector2d& xy_mm) const {
    return pixel_from_frame.leftCols<2>() * xy_mm + pixel_from_frame.col(2);
  }

  Eigen::Vector2d FrameFromPixel(const Eigen::Vector2d& pixel) const {
    return pixel_from_frame.leftCols<2>().inverse() *
           (pixel - pixel_from_frame.col(2));
  }

  // Mean pixel size in mm (square root of the area of one pixel).
  double MeanPitchMm() const {
    return 1.0 /
           std::sqrt(std::abs(pixel_from_frame.leftCols<2>().determinant()));
  }
};

}  // namespace bayon
