// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/interior.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <algorithm>
#include <cmath>

namespace bayon {

int RunInterior(int argc, char** argv) {
  std::string database_path, image_path, log_path;
  InteriorOptions options;
  VirtualFiducialOptions& fiducials = options.fiducials;
  CommandLine command(
      "interior",
      "Interior orientation of every image of a COLMAP database, to "
      "bayon_interior: digital images from the pixel pitch and the image "
      "centre; scanned film (--film_scan 1) by virtual fiducials, the "
      "corners where the straight frame edges, fitted robustly to sub-pixel "
      "edge points, intersect.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
  app.add_option("--film_scan",
                 options.film_scan,
                 "1: scanned film frames (virtual fiducials); 0: digital");
  app.add_option("--frame_width_mm",
                 fiducials.frame_width_mm,
                 "Nominal frame width (film gate), mm");
  app.add_option("--frame_height_mm",
                 fiducials.frame_height_mm,
                 "Nominal frame height, mm");
  app.add_option("--scan_resolution_um",
                 fiducials.scan_resolution_um,
                 "Scanner pixel size, um: fixes the scale (the frame size "
                 "is then a check); 0: scale from the nominal frame size "
                 "(affine)");
  app.add_option("--decode_srgb",
                 fiducials.decode_srgb,
                 "1: decode the sRGB curve before measuring; 0: values are "
                 "linear");
  app.add_option("--search_fraction",
                 fiducials.search_fraction,
                 "How far into the scan each edge is searched (fraction of "
                 "its width or height)");
  app.add_option("--min_contrast",
                 fiducials.min_contrast,
                 "Smallest step from the border to the photograph (linear "
                 "intensity, 0..1)");
  app.add_option("--edge_half_width_px",
                 fiducials.edge_half_width_px,
                 "Half width of the edge window, pixels (covers the blur)");
  app.add_option("--min_edge_points",
                 fiducials.min_edge_points,
                 "Fewest points on an accepted edge line");
  app.add_option("--corner_margin_px",
                 fiducials.corner_margin_px,
                 "Edge points this close to a corner are left out, pixels");
  app.add_option("--max_rms_px",
                 fiducials.max_rms_px,
                 "Largest residual RMS of an accepted edge, pixels");
  app.add_option("--max_rotation_deg",
                 fiducials.max_rotation_deg,
                 "Largest rotation of the frame in the scan, degrees");
  app.add_option("--max_corner_angle_deviation_deg",
                 fiducials.max_corner_angle_deviation_deg,
                 "Largest deviation of a corner angle from 90 degrees");
  app.add_option("--max_pixel_aspect_deviation",
                 fiducials.max_pixel_aspect_deviation,
                 "Without a scan resolution: largest relative difference of "
                 "the x and y pixel sizes");
  app.add_option("--max_frame_size_deviation_mm",
                 fiducials.max_frame_size_deviation_mm,
                 "With a scan resolution: largest difference of a measured "
                 "side from the nominal frame size, mm");
  app.add_option("--overwrite",
                 options.overwrite,
                 "1: replace existing bayon_interior rows");
  app.add_option(
      "--num_threads", options.num_threads, "Images in parallel (-1 = all)");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/interior.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "interior"));

  const InteriorSummary summary =
      OrientInteriors(database_path, image_path, options);
  double sum_rms = 0, max_rotation = 0;
  for (const ImageInteriorReport& image : summary.images) {
    if (image.status != InteriorStatus::kDone || !options.film_scan) continue;
    sum_rms += image.fiducials.rms_px;
    max_rotation =
        std::max(max_rotation, std::abs(image.fiducials.rotation_deg));
  }
  const std::string film = options.film_scan && summary.num_done > 0
                               ? StrCat(" (mean edge RMS ",
                                        sum_rms / summary.num_done,
                                        " px, largest rotation ",
                                        max_rotation,
                                        " deg)")
                               : "";
  command.PrintSummary(
      StrCat(summary.num_done,
             options.film_scan ? " film frames measured" : " digital frames",
             film,
             ", ",
             summary.num_kept,
             " kept, ",
             summary.num_failed,
             " failed, ",
             summary.seconds,
             " s -> ",
             database_path));
  return summary.num_done + summary.num_kept > 0 ? 0 : 1;
}

}  // namespace bayon
