// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/matching/keypoint_refinement.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <cstdio>

namespace bayon {

int RunRefineKeypoints(int argc, char** argv) {
  std::string database_path, image_path, output_path, report_path, log_path;
  bool overwrite = false;
  KeypointRefinementOptions options;
  CommandLine command(
      "refine_keypoints",
      "Least-squares refinement of the matched keypoints of a COLMAP "
      "database (e.g. SIFT from colmap feature_extractor + a matcher): "
      "tracks from the verified matches, the best-textured observation of "
      "each as reference, every other one matched to it by adaptive "
      "least-squares matching (affine + 2 radiometric parameters, started "
      "from the keypoints' affine frames), blunders rejected (convergence, "
      "sigma0, shape bounds, back-matching). Writes a new database with the "
      "refined keypoint positions and everything else unchanged; the input "
      "is never modified.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "Input COLMAP database")
      ->required();
  app.add_option("--image_path", image_path, "Folder of the images")
      ->required();
  app.add_option("--output_path", output_path, "The refined database to write")
      ->required();
  app.add_option("--overwrite", overwrite, "1: replace an existing output");
  command.AddOptions(&options,
                     {{"patch_radius", "lsm.patch_radius"},
                      {"interpolation", "lsm.interpolation"},
                      {"estimate_shape", "lsm.estimate_shape"},
                      {"max_iterations", "lsm.max_iterations"}});
  app.add_option("--report_path", report_path, "Write the summary as JSON");
  app.add_option(
      "--log_path",
      log_path,
      "Log file (default <output folder>/logs/refine_keypoints.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  CheckOutputPath(output_path, overwrite);
  // Not a COLMAP database: one line, before a log appears beside the output.
  Database(database_path, Database::Mode::kReadOnly);
  command.StartLog(DatabaseLogPath(log_path, output_path, "refine_keypoints"));

  const KeypointRefinementSummary summary = RefineDatabaseKeypoints(
      database_path, image_path, output_path, overwrite, options);
  if (!report_path.empty()) {
    WriteFileAtomically(
        report_path,
        KeypointRefinementSummaryJson(summary, database_path, output_path)
                .dump(2) +
            "\n");
  }
  std::printf("%s", KeypointRefinementTable(summary).c_str());
  std::fflush(stdout);
  command.PrintSummary(StrCat(summary.num_refined,
                              " of ",
                              summary.num_observations - summary.num_reference,
                              " observations refined (",
                              summary.num_rejected,
                              " rejected, ",
                              summary.num_tracks,
                              " tracks from ",
                              summary.num_pairs,
                              " pairs of ",
                              summary.match_source,
                              "), median shift ",
                              summary.median_shift_px,
                              " px, ",
                              summary.seconds,
                              " s -> ",
                              output_path));
  return summary.num_refined > 0 ? 0 : 1;
}

}  // namespace bayon
