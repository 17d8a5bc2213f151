// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// One run of `bayon pipeline` over its stages: each selected stage runs, or
// is skipped where its stamp says it is up to date (stamps.h); every stage
// is recorded in W/pipeline.json as it ends. The bayon commands are run
// through a function the caller gives (tools/ runs them in its process).

#include "ext/pipeline/stages.h"
#include "ext/pipeline/stamps.h"

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

// Runs bayon `command` with its command line `words` (words[0] "bayon");
// returns its exit code (0 done, 1 nothing usable); bad input throws
// InputError.
using BayonCommandRunner = std::function<int(
    const std::string& command, const std::vector<std::string>& words)>;

// Which stages a run covers.
struct StageSelection {
  int first = 0, last = 0;  // indices into the stages, inclusive
  bool force = false;       // --force: run every selected stage again
  bool from_stage = false;  // --from_stage: run the first one again
};

class PipelineRun {
 public:
  PipelineRun(const PipelineContext& c,
              const std::string& config,
              const std::vector<Stage>& stages,
              const StageSelection& selection,
              BayonCommandRunner run_bayon);

  // Runs the stages that must run and skips the others; false when a stage
  // produced nothing usable. Bad input throws, naming the stage; a failed
  // stage is in pipeline.json first, and keeps no stamp.
  bool Run();

  const std::vector<StageRun>& runs() const { return runs_; }
  double seconds() const;

 private:
  void NotSelected(const Stage& stage);
  // Why stage i must run, or empty where it is up to date.
  std::string WhyRunStage(int i, const std::vector<std::string>& words) const;
  bool RunOrSkip(int i);

  const PipelineContext& c_;
  const std::string config_;
  const std::vector<Stage>& stages_;
  const StageSelection selection_;
  const BayonCommandRunner run_bayon_;
  const std::chrono::steady_clock::time_point start_;
  std::vector<StageRun> runs_;
  std::optional<std::filesystem::file_time_type> previous_stamp_;
  bool ran_any_ = false;
};

// The stages from `from_stage` to `to_stage` (empty: the first, the last);
// InputError for a stage not among `stages`, or a first after the last.
StageSelection SelectStages(const std::vector<Stage>& stages,
                            const std::string& from_stage,
                            const std::string& to_stage,
                            bool force);

// "12.3 s", or "2 min 05 s" from a minute on: the terminal's times.
std::string FormatRunSeconds(double seconds);

// The table of the selected stages (name, program, status, time), as the
// terminal shows it at the end of a run.
std::string StageTable(const std::vector<StageRun>& runs);

// What ran, how long it took, and where the products are that this run or
// an earlier one made: the report, the model and the viewer.
std::string PipelineSummaryLine(const PipelineRun& run,
                                const std::string& workspace);

}  // namespace bayon
