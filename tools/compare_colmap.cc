// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon compare_colmap`: stock COLMAP on the photographs of a bayon
// workspace, in W/colmap/, set beside bayon's model
// (ext/eval/colmap_comparison.h). Prints the table and writes
// W/colmap/comparison.json and comparison.txt.
//
// W/database.db is only read (bayon's scanned frames, for its model); COLMAP
// works on W/colmap/database.db. When the mapper makes no model (it
// registers nothing, or fewer images than its minimum model size) the
// comparison is still written, with COLMAP's column at 0 registered and no
// figures (null) beside it, and the command exits 1.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/eval/colmap_comparison.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <cstdio>
#include <string>

namespace bayon {

int RunCompareColmap(int argc, char** argv) {
  CompareColmapOptions options;
  CommandLine command(
      "compare_colmap",
      "Run stock COLMAP (CPU SIFT, exhaustive or sequential matching, "
      "mapper) on the images of a bayon workspace in <workspace>/colmap/ and "
      "set its model beside bayon's: registered images, points, "
      "observations, track length, reprojection errors, sigma0, the "
      "agreement of the cameras, the time of every stage, and with "
      "--ground_truth_path both against the truth. Writes "
      "colmap/comparison.json and colmap/comparison.txt; reuses a finished "
      "earlier COLMAP run unless --overwrite 1. The workspace's database.db "
      "is not touched.");
  CLI::App& app = command.app();
  command.AddOptions(&options);
  if (!command.Parse(argc, argv)) return 0;

  // Everything is checked before COLMAP runs.
  const ComparisonInputs inputs =
      ReadComparisonInputs(&options,
                           app.count("--camera_params") > 0,
                           app.count("--camera_model") > 0);
  command.StartLog(WorkspaceLogPath(options.workspace_path, "compare_colmap"));

  const ComparisonOutcome outcome = RunComparison(options, inputs);
  if (outcome.run.reused) {
    std::printf(
        "COLMAP: reusing the finished run in %s (colmap.json; --overwrite 1 "
        "runs it again)\n",
        (inputs.workspace / "colmap").string().c_str());
  }
  std::printf("\n%s\n", outcome.table.c_str());
  if (!outcome.failure.empty()) throw RunFailure(outcome.failure);
  command.PrintSummary(ComparisonSummary(
      outcome.comparison, outcome.run.reused, outcome.json_path));
  return 0;
}

}  // namespace bayon
