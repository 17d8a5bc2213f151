// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon pipeline`: every stage in order on one workspace, each with its
// options from a config file, like `make`: a stage whose outputs are complete
// and newer than its inputs is skipped, so a run that was interrupted (even
// by kill -9) resumes where it stopped. The stages, the configs and the
// staleness rules are ext/pipeline's (stages.h, stamps.h); this runs them.
//
// The stages run in this process (kill -9 of the pipeline stops the stage
// with it); stock COLMAP stages, swapped in by the config, run as a child.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/pipeline/pipeline_run.h"
#include "ext/pipeline/stages.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>
#include <iostream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The in-process entry point of a bayon stage.
int RunBayonCommand(const std::string& command,
                    const std::vector<std::string>& words) {
  // words[0] is "bayon": the command function sees argv[0] = its name.
  std::vector<std::string> args(words.begin() + 1, words.end());
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  return FindCommand(command)->run(static_cast<int>(args.size()), argv.data());
}

// Each stage checks its options (CommandLine::SetCheckOnly) before any
// stage runs: a misspelt key in a config stops the run at once.
void CheckStageOptions(const std::vector<Stage>& stages,
                       const std::string& config) {
  // Back to running the stages however this ends.
  struct CheckOnly {
    CheckOnly() { CommandLine::SetCheckOnly(true); }
    ~CheckOnly() { CommandLine::SetCheckOnly(false); }
  } check_only;
  for (const Stage& stage : stages) {
    if (stage.program != "bayon") continue;
    try {
      RunBayonCommand(stage.command, CommandWords(stage, true));
    } catch (const CLI::ParseError& error) {
      ThrowInputError(config.empty() ? "pipeline" : config,
                      ": stage ",
                      stage.name,
                      ": ",
                      error.what());
    }
  }
}

// The command line of `bayon pipeline`.
struct PipelineArguments {
  PipelineContext context;
  std::vector<std::string> config_paths;
  std::string from_stage, to_stage;
  bool force = false;
  int compare_colmap = -1;  // -1: as the config says

  void AddOptions(CLI::App& app) {
    // The pipeline's --config has sections per stage, not this command's
    // own options, so it is read here rather than by CLI11.
    app.set_config();
    app.add_option(
           "--workspace_path", context.workspace, "Workspace folder (created)")
        ->required();
    app.add_option("--image_path",
                   context.image_path,
                   "Folder of the photographs (default: <workspace>/images); "
                   "never modified");
    app.add_option("--config",
                   config_paths,
                   "INI/TOML with a section per stage ([dense] num_masters = "
                   "5) and [pipeline] (features = colmap_sift, sparse = "
                   "colmap_mapper, compare_colmap = 1); several: later ones "
                   "win")
        ->check(CLI::ExistingFile);
    app.add_option("--from_stage",
                   from_stage,
                   "Run from this stage on, even where up to date; earlier "
                   "stages are left as they are");
    app.add_option("--to_stage", to_stage, "Stop after this stage");
    app.add_option("--force", force, "1: run every selected stage again");
    app.add_option("--compare_colmap",
                   compare_colmap,
                   "1: also run stock COLMAP and compare (overrides the "
                   "config's [pipeline] compare_colmap)")
        ->check(CLI::Range(0, 1));
    app.add_option(
           "--num_threads", context.num_threads, "Threads for every stage")
        ->check(CLI::Range(1, 1024));
  }
};

// Every stage logs in full to W/logs/<stage>.log; the terminal shows the
// pipeline's progress, the stages' progress bars, summaries and warnings.
void LogStagesToTheirFiles() {
  FLAGS_logtostderr = false;
  FLAGS_stderrthreshold = google::GLOG_WARNING;
  for (int severity = 0; severity < google::NUM_SEVERITIES; ++severity) {
    google::SetLogDestination(severity, "");
  }
}

}  // namespace

int RunPipeline(int argc, char** argv) {
  CommandLine command("pipeline",
                      "Runs every stage in order, from photographs to the "
                      "textured model and its report, skipping stages whose "
                      "outputs are complete and newer than their inputs.");
  PipelineArguments arguments;
  arguments.AddOptions(command.app());
  if (!command.Parse(argc, argv)) return 0;

  for (const std::string* stage :
       {&arguments.from_stage, &arguments.to_stage}) {
    if (!stage->empty() && !IsStageName(*stage)) {
      ThrowInputError("--from_stage/--to_stage: unknown stage '", *stage, "'");
    }
  }
  PipelineConfig config = ReadPipelineConfigs(arguments.config_paths);
  if (arguments.compare_colmap >= 0) {
    config.settings.compare_colmap = std::to_string(arguments.compare_colmap);
  }
  PipelineContext& c = arguments.context;
  const size_t num_images = ResolveWorkspace(&c);
  const std::vector<Stage> stages = MakeStages(c, config);
  const StageSelection selection = SelectStages(
      stages, arguments.from_stage, arguments.to_stage, arguments.force);
  CheckStageOptions(stages, config.description);
  // Matching and everything after it need a second photograph.
  if (num_images < 2 && stages[selection.last].name != "import" &&
      stages[selection.last].name != "interior" &&
      stages[selection.last].name != "features") {
    ThrowInputError(c.image_path,
                    ": one image; a model needs two or more overlapping "
                    "photographs (--to_stage features stops before matching)");
  }

  LogStagesToTheirFiles();
  fs::create_directories(JoinPath(c.workspace, "pipeline"));
  // One run per workspace: a second would run the same stages into the
  // same files.
  const FileLock lock(JoinPath(c.workspace, "pipeline/lock"),
                      StrCat("workspace ", c.workspace));
  command.StartLog(WorkspaceLogPath(c.workspace, "pipeline"));
  LOG(INFO) << "config: "
            << (config.description.empty() ? "(built-in defaults)"
                                           : config.description);
  PipelineRun run(c, config.description, stages, selection, RunBayonCommand);
  if (!run.Run()) return 1;
  std::cout << StageTable(run.runs()) << std::endl;
  command.PrintSummary(PipelineSummaryLine(run, c.workspace));
  return 0;
}

}  // namespace bayon
