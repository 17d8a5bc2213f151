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
#include "ext/image/image_io.h"
#include "ext/pipeline/stages.h"
#include "ext/pipeline/stamps.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string In(const std::string& folder, const std::string& name) {
  return (fs::path(folder) / name).string();
}

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

std::string FormatSeconds(double seconds) {
  std::ostringstream out;
  if (seconds < 60) {
    out << std::fixed << std::setprecision(1) << seconds << " s";
  } else {
    out << static_cast<int>(seconds) / 60 << " min " << std::setw(2)
        << std::setfill('0') << static_cast<int>(seconds) % 60 << " s";
  }
  return out.str();
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

}  // namespace

int RunPipeline(int argc, char** argv) {
  CommandLine command("pipeline",
                      "Runs every stage in order, from photographs to the "
                      "textured model and its report, skipping stages whose "
                      "outputs are complete and newer than their inputs.");
  CLI::App& app = command.app();
  // The pipeline's --config has sections per stage, not this command's own
  // options, so it is read here rather than by CLI11.
  app.set_config();
  PipelineContext c;
  std::vector<std::string> config_paths;
  std::string from_stage, to_stage;
  bool force = false;
  int compare_colmap = -1;
  app.add_option("--workspace_path", c.workspace, "Workspace folder (created)")
      ->required();
  app.add_option("--image_path",
                 c.image_path,
                 "Folder of the photographs (default: <workspace>/images); "
                 "never modified");
  app.add_option("--config",
                 config_paths,
                 "INI/TOML with a section per stage ([dense] num_masters = 5) "
                 "and [pipeline] (features = colmap_sift, sparse = "
                 "colmap_mapper, compare_colmap = 1); several: later ones win")
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
  app.add_option("--num_threads", c.num_threads, "Threads for every stage")
      ->check(CLI::Range(1, 1024));
  if (!command.Parse(argc, argv)) return 0;

  for (const std::string* stage : {&from_stage, &to_stage}) {
    if (!stage->empty() && !IsStageName(*stage)) {
      ThrowInputError("--from_stage/--to_stage: unknown stage '", *stage, "'");
    }
  }
  PipelineConfig config = ReadPipelineConfigs(config_paths);
  if (compare_colmap >= 0) {
    config.settings.compare_colmap = std::to_string(compare_colmap);
  }
  if (c.image_path.empty()) c.image_path = In(c.workspace, "images");
  CheckDirectoryExists(c.image_path, "--image_path");
  const size_t num_images = ListImages(c.image_path).size();
  if (num_images == 0) {
    ThrowInputError(c.image_path,
                    ": no images found (looked for jpg, png, tif, bmp, "
                    "pgm/ppm, webp, jp2, exr, hdr)");
  }
  c.image_path = fs::absolute(c.image_path).lexically_normal().string();
  c.workspace = fs::absolute(c.workspace).lexically_normal().string();
  c.database = In(c.workspace, "database.db");
  if (fs::is_directory(In(c.workspace, "control"))) {
    c.control = In(c.workspace, "control");
  }
  const std::vector<Stage> stages = MakeStages(c, config);
  auto index_of = [&](const std::string& name) {
    for (size_t i = 0; i < stages.size(); ++i) {
      if (stages[i].name == name) return static_cast<int>(i);
    }
    ThrowInputError("stage ", name, " is not part of this pipeline's run");
  };
  const int first = from_stage.empty() ? 0 : index_of(from_stage);
  const int last = to_stage.empty() ? static_cast<int>(stages.size()) - 1
                                    : index_of(to_stage);
  if (first > last) {
    ThrowInputError(
        "--from_stage ", from_stage, " comes after --to_stage ", to_stage);
  }
  CheckStageOptions(stages, config.description);
  // Matching and everything after it need a second photograph.
  if (num_images < 2 && stages[last].name != "import" &&
      stages[last].name != "interior" && stages[last].name != "features") {
    ThrowInputError(c.image_path,
                    ": one image; a model needs two or more overlapping "
                    "photographs (--to_stage features stops before matching)");
  }

  // Every stage logs in full to W/logs/<stage>.log; the terminal shows the
  // pipeline's progress, the stages' progress bars, summaries and warnings.
  FLAGS_logtostderr = false;
  FLAGS_stderrthreshold = google::GLOG_WARNING;
  for (int severity = 0; severity < google::NUM_SEVERITIES; ++severity) {
    google::SetLogDestination(severity, "");
  }
  fs::create_directories(In(c.workspace, "pipeline"));
  // One run per workspace: a second would run the same stages into the
  // same files.
  const FileLock lock(In(c.workspace, "pipeline/lock"),
                      StrCat("workspace ", c.workspace));
  command.StartLog(WorkspaceLogPath(c.workspace, "pipeline"));
  LOG(INFO) << "config: "
            << (config.description.empty() ? "(built-in defaults)"
                                           : config.description);

  const auto start = std::chrono::steady_clock::now();
  auto seconds_since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
        .count();
  };
  auto elapsed = [&] { return seconds_since(start); };
  std::vector<StageRun> runs;
  std::optional<fs::file_time_type> previous_stamp;
  const int num_selected = last - first + 1;
  bool ran_any = false;
  for (int i = 0; i < static_cast<int>(stages.size()); ++i) {
    const Stage& stage = stages[i];
    StageRun run;
    run.name = stage.name;
    run.program = stage.program;
    if (i < first || i > last) {
      run.status = "not selected";
      runs.push_back(run);
      if (const auto t = NewestTime(StampPath(c.workspace, stage.name)))
        previous_stamp = t;
      continue;
    }
    const std::vector<std::string> words = CommandWords(stage, true);
    run.command = words;
    std::string why = WhyRun(
        stage, words, StampPath(c.workspace, stage.name), previous_stamp);
    if (force || (i == first && !from_stage.empty())) {
      why = force ? "--force" : "--from_stage";
    } else if (ran_any && why.empty()) {
      why = "an earlier stage ran";
    }
    const std::string counter =
        StrCat("[", i - first + 1, "/", num_selected, "] ");
    if (why.empty()) {
      std::cout << "pipeline: " << counter << stage.name
                << ": up to date, skipped" << std::endl;
      run.status = "skipped";
      runs.push_back(run);
      previous_stamp = NewestTime(StampPath(c.workspace, stage.name));
      continue;
    }
    std::cout << "pipeline: " << counter << stage.name << " (" << why << "), "
              << FormatSeconds(elapsed()) << " so far" << std::endl;
    LOG(INFO) << "stage " << stage.name << ": " << why;
    fs::remove(StampPath(c.workspace, stage.name));
    RemoveStaleTemporaries(stage);
    const auto stage_start = std::chrono::steady_clock::now();
    // A stage that fails is recorded in pipeline.json before the run stops:
    // bad input (exit 2, the stage named), or nothing usable (exit 1).
    auto record_failure = [&](const std::string& reason) {
      run.seconds = seconds_since(stage_start);
      run.status = "failed";
      run.reason = reason;
      runs.push_back(run);
      WriteRunJson(c, config.description, runs, elapsed());
    };
    std::string failure;
    try {
      if (stage.program == "colmap") {
        RunColmapStage(
            stage, WorkspaceLogPath(c.workspace, "colmap_" + stage.command));
      } else if (RunBayonCommand(stage.command, words) != 0) {
        failure = "produced nothing usable (exit 1)";
      }
    } catch (const InputError& error) {
      record_failure(error.what());
      ThrowInputError("stage ", stage.name, ": ", error.what());
    } catch (const std::exception& error) {
      failure = error.what();
    }
    if (!failure.empty()) {
      record_failure(failure);
      std::cerr << "pipeline: stage " << stage.name << " failed: " << failure
                << "; its log is in " << In(c.workspace, "logs") << std::endl;
      return 1;
    }
    run.seconds = seconds_since(stage_start);
    WriteStamp(StampPath(c.workspace, stage.name), words, run.seconds);
    previous_stamp = NewestTime(StampPath(c.workspace, stage.name));
    ran_any = true;
    run.status = "ran";
    runs.push_back(run);
    // After every stage, so that later stages (compare_colmap, report) and
    // an interrupted run's reader see the times so far.
    WriteRunJson(c, config.description, runs, elapsed());
    std::cout << "pipeline: " << counter << stage.name << " done in "
              << FormatSeconds(run.seconds) << std::endl;
  }
  const double total = elapsed();
  WriteRunJson(c, config.description, runs, total);

  std::ostringstream table;
  table << "\n  stage            program  status         time\n";
  int num_ran = 0, num_skipped = 0;
  for (const StageRun& run : runs) {
    if (run.status == "not selected") continue;
    num_ran += run.status == "ran";
    num_skipped += run.status == "skipped";
    table << "  " << std::left << std::setw(17) << run.name << std::setw(9)
          << run.program << std::setw(10) << run.status << std::right
          << std::setw(10)
          << (run.status == "ran" ? FormatSeconds(run.seconds) : "-") << "\n";
  }
  std::cout << table.str() << std::endl;
  // Where the products are, those this run (or an earlier one) made.
  std::string products;
  for (const auto& [label, path] :
       std::vector<std::pair<std::string, std::string>>{
           {"report", "report.html"},
           {"model", "model/model.glb"},
           {"viewer", "viewer/index.html"}}) {
    if (fs::exists(In(c.workspace, path))) {
      products += StrCat("; ", label, ": ", In(c.workspace, path));
    }
  }
  command.PrintSummary(
      StrCat(num_ran,
             " stages ran, ",
             num_skipped,
             " up to date, in ",
             FormatSeconds(total),
             products.empty() ? StrCat(" -> ", c.workspace) : products));
  return 0;
}

}  // namespace bayon
