// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <string>
#include <vector>

namespace bayon {

// One function per command, each in tools/<command>.cc. argv[0] is the
// command name. They return the exit code: 0 done, 1 ran but produced
// nothing usable; bad input throws InputError (exit 2 in main).
int RunAdjust(int argc, char** argv);
int RunStripCommand(int argc, char** argv);
int RunImport(int argc, char** argv);
int RunImportBal(int argc, char** argv);
int RunImportGroundTruth(int argc, char** argv);
int RunInterior(int argc, char** argv);
int RunModelConverter(int argc, char** argv);
int RunSynth(int argc, char** argv);
int RunEvaluate(int argc, char** argv);
int RunFeatures(int argc, char** argv);
int RunDense(int argc, char** argv);
int RunEdit(int argc, char** argv);
int RunMesh(int argc, char** argv);
int RunSynthCloud(int argc, char** argv);
int RunMatch(int argc, char** argv);
int RunRelative(int argc, char** argv);
int RunDisparity(int argc, char** argv);
int RunTiePoints(int argc, char** argv);
int RunTargets(int argc, char** argv);
int RunImportControl(int argc, char** argv);
int RunRefineKeypoints(int argc, char** argv);
int RunRender(int argc, char** argv);
int RunTexture(int argc, char** argv);
int RunViewer(int argc, char** argv);
int RunPipeline(int argc, char** argv);
int RunCompareColmap(int argc, char** argv);
int RunReport(int argc, char** argv);

// The one table of commands: `bayon <name>` and the pipeline's stages run
// them.
struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* description;
};

// Every command, in the order of the processing chain (docs/architecture.md).
const std::vector<Command>& Commands();

// The command called `name`, or nullptr.
const Command* FindCommand(const std::string& name);

}  // namespace bayon
