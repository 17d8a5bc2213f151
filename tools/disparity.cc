// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/disparity.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <algorithm>
#include <vector>

namespace bayon {

int RunDisparity(int argc, char** argv) {
  std::string database_path, log_path;
  DisparityOptions options;
  CommandLine command(
      "disparity",
      "Disparity surfaces of every oriented pair, both directions: inverse "
      "depth over the first image on a grid of bilinear cells with a "
      "thin-plate smoothness chosen by cross-validation, fitted robustly to "
      "the inlier conjugate points; the search band along the epipolar line "
      "from the cross-validated prediction errors, the nearest points' "
      "inverse depths and a depth tolerance for unsampled relief. Writes "
      "bayon_disparity_surfaces.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  command.AddOptions(&options);
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/disparity.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "disparity"));

  const DisparitySummary summary = FitDisparitySurfaces(database_path, options);
  command.PrintSummary(
      StrCat(DisparitySummaryLine(summary), " -> ", database_path));
  return summary.num_fitted + summary.num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
