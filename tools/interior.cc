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
  command.AddOptions(&options);
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
  command.PrintSummary(
      StrCat(InteriorSummaryLine(summary, options), " -> ", database_path));
  return summary.num_done + summary.num_kept > 0 ? 0 : 1;
}

}  // namespace bayon
