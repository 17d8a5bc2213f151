// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/synth/synth_workspace.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunSynth(int argc, char** argv) {
  std::string output_path;
  bool overwrite = false;
  SynthOptions options;
  CommandLine command("synth",
                      "Write a synthetic workspace with known truth: the true "
                      "cameras, calibration and points (points scene) or "
                      "surface (tower scene) in gt/, and a COLMAP database.");
  CLI::App& app = command.app();
  app.add_option("--output_path", output_path, "Workspace folder to create")
      ->required();
  app.add_option("--overwrite", overwrite, "Replace an existing workspace");
  command.AddOptions(&options);
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  command.PrintSummary(WriteSynthWorkspace(options, output_path, overwrite));
  return 0;
}

}  // namespace bayon
