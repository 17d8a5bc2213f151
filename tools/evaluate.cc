// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon evaluate`: every product of a run against the truth
// (ext/eval/evaluation.h).
#include "ext/core/file_util.h"
#include "ext/eval/evaluation.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <cstdio>

namespace bayon {

int RunEvaluate(int argc, char** argv) {
  EvaluationOptions o;
  std::string output_path;
  CommandLine command(
      "evaluate",
      "Compare results with the ground truth: a sparse model (registered "
      "images, camera centre and rotation errors after a 7-parameter "
      "similarity, calibration per parameter, 3D points against the true "
      "surface), a dense cloud and a mesh (accuracy, completeness over the "
      "visible true surface, topology) and a textured model (PSNR and SSIM "
      "of renders from held-out viewpoints), and a database's pair "
      "orientations (rotation and base direction errors). Prints tables, "
      "writes JSON.");
  CLI::App& app = command.app();
  command.AddOptions(&o);
  app.add_option("--output_path", output_path, "Write the report as JSON here");
  if (!command.Parse(argc, argv)) return 0;

  const nlohmann::ordered_json report = RunEvaluation(o, stdout);
  if (!output_path.empty()) {
    WriteFileAtomically(output_path, report.dump(2) + "\n");
  }
  return 0;
}

}  // namespace bayon
