// SPDX-License-Identifier: BSD-3-Clause
#include "ext/orientation/relative.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunRelative(int argc, char** argv) {
  std::string database_path, log_path;
  RelativeOptions options;
  CommandLine command(
      "relative",
      "Relative orientation of every matched pair: the DRT (Chang 1986) "
      "solved linearly, LMedS over 1024 random 8-point samples, 2.5-sigma "
      "blunder weights, weighted least squares, then the rigorous "
      "coplanarity adjustment of the five elements. Writes COLMAP's "
      "two_view_geometries and bayon_relative_orientation.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database")
      ->required();
  command.AddOptions(&options);
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <database folder>/logs/relative.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  command.StartLog(DatabaseLogPath(log_path, database_path, "relative"));

  const RelativeSummary summary = OrientImagePairs(database_path, options);
  command.PrintSummary(
      StrCat(RelativeSummaryLine(summary), " -> ", database_path));
  return 0;
}

}  // namespace bayon
