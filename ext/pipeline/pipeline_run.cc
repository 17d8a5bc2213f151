// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/pipeline_run.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <glog/logging.h>

#include <iomanip>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

PipelineRun::PipelineRun(const PipelineContext& c,
                         const std::string& config,
                         const std::vector<Stage>& stages,
                         const StageSelection& selection,
                         BayonCommandRunner run_bayon)
    : c_(c),
      config_(config),
      stages_(stages),
      selection_(selection),
      run_bayon_(std::move(run_bayon)),
      start_(std::chrono::steady_clock::now()) {}

bool PipelineRun::Run() {
  for (int i = 0; i < static_cast<int>(stages_.size()); ++i) {
    if (i < selection_.first || i > selection_.last) {
      NotSelected(stages_[i]);
    } else if (!RunOrSkip(i)) {
      return false;
    }
  }
  WriteRunJson(c_, config_, runs_, SecondsSince(start_));
  return true;
}

double PipelineRun::seconds() const { return SecondsSince(start_); }

void PipelineRun::NotSelected(const Stage& stage) {
  runs_.push_back({stage.name, stage.program, "not selected", 0, {}, ""});
  if (const auto t = NewestTime(StampPath(c_.workspace, stage.name))) {
    previous_stamp_ = t;
  }
}

std::string PipelineRun::WhyRunStage(
    int i, const std::vector<std::string>& words) const {
  // The flags decide before the stamp is read and the inputs (the whole
  // image folder) are walked.
  if (selection_.force) return "--force";
  if (i == selection_.first && selection_.from_stage) return "--from_stage";
  const Stage& stage = stages_[i];
  const std::string why = WhyRun(
      stage, words, StampPath(c_.workspace, stage.name), previous_stamp_);
  if (ran_any_ && why.empty()) return "an earlier stage ran";
  return why;
}

bool PipelineRun::RunOrSkip(int i) {
  const Stage& stage = stages_[i];
  StageRun run{stage.name, stage.program, "", 0, {}, ""};
  const std::vector<std::string> words = CommandWords(stage, true);
  run.command = words;
  const std::string why = WhyRunStage(i, words);
  const std::string counter = StrCat("[",
                                     i - selection_.first + 1,
                                     "/",
                                     selection_.last - selection_.first + 1,
                                     "] ");
  const std::string stamp = StampPath(c_.workspace, stage.name);
  if (why.empty()) {
    std::cout << "pipeline: " << counter << stage.name
              << ": up to date, skipped" << std::endl;
    run.status = "skipped";
    runs_.push_back(run);
    previous_stamp_ = NewestTime(stamp);
    return true;
  }
  std::cout << "pipeline: " << counter << stage.name << " (" << why << "), "
            << FormatRunSeconds(seconds()) << " so far" << std::endl;
  LOG(INFO) << "stage " << stage.name << ": " << why;
  fs::remove(stamp);
  RemoveStaleTemporaries(stage);
  const auto stage_start = std::chrono::steady_clock::now();
  // A stage that fails is recorded in pipeline.json before the run stops:
  // bad input (exit 2, the stage named), or nothing usable (exit 1).
  auto record_failure = [&](const std::string& reason) {
    run.seconds = SecondsSince(stage_start);
    run.status = "failed";
    run.reason = reason;
    runs_.push_back(run);
    WriteRunJson(c_, config_, runs_, seconds());
  };
  std::string failure;
  try {
    if (stage.program == "colmap") {
      RunColmapStage(stage,
                     JoinPath(JoinPath(c_.workspace, "logs"),
                              "colmap_" + stage.command + ".log"));
    } else if (run_bayon_(stage.command, words) != 0) {
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
              << "; its log is in " << JoinPath(c_.workspace, "logs")
              << std::endl;
    return false;
  }
  run.seconds = SecondsSince(stage_start);
  WriteStamp(stamp, words, run.seconds);
  previous_stamp_ = NewestTime(stamp);
  ran_any_ = true;
  run.status = "ran";
  runs_.push_back(run);
  // After every stage, so that later stages (compare_colmap, report) and
  // an interrupted run's reader see the times so far.
  WriteRunJson(c_, config_, runs_, seconds());
  std::cout << "pipeline: " << counter << stage.name << " done in "
            << FormatRunSeconds(run.seconds) << std::endl;
  return true;
}

std::string FormatRunSeconds(double seconds) {
  std::ostringstream out;
  if (seconds < 60) {
    out << std::fixed << std::setprecision(1) << seconds << " s";
  } else {
    out << static_cast<int>(seconds) / 60 << " min " << std::setw(2)
        << std::setfill('0') << static_cast<int>(seconds) % 60 << " s";
  }
  return out.str();
}

StageSelection SelectStages(const std::vector<Stage>& stages,
                            const std::string& from_stage,
                            const std::string& to_stage,
                            bool force) {
  auto index_of = [&](const std::string& name) {
    for (size_t i = 0; i < stages.size(); ++i) {
      if (stages[i].name == name) return static_cast<int>(i);
    }
    ThrowInputError("stage ", name, " is not part of this pipeline's run");
  };
  StageSelection selection;
  selection.first = from_stage.empty() ? 0 : index_of(from_stage);
  selection.last = to_stage.empty() ? static_cast<int>(stages.size()) - 1
                                    : index_of(to_stage);
  if (selection.first > selection.last) {
    ThrowInputError(
        "--from_stage ", from_stage, " comes after --to_stage ", to_stage);
  }
  selection.force = force;
  selection.from_stage = !from_stage.empty();
  return selection;
}

std::string StageTable(const std::vector<StageRun>& runs) {
  std::ostringstream table;
  table << "\n  stage            program  status         time\n";
  for (const StageRun& stage : runs) {
    if (stage.status == "not selected") continue;
    table << "  " << std::left << std::setw(17) << stage.name << std::setw(9)
          << stage.program << std::setw(10) << stage.status << std::right
          << std::setw(10)
          << (stage.status == "ran" ? FormatRunSeconds(stage.seconds) : "-")
          << "\n";
  }
  return table.str();
}

std::string PipelineSummaryLine(const PipelineRun& run,
                                const std::string& workspace) {
  int num_ran = 0, num_skipped = 0;
  for (const StageRun& stage : run.runs()) {
    num_ran += stage.status == "ran";
    num_skipped += stage.status == "skipped";
  }
  std::string products;
  for (const auto& [label, path] :
       std::vector<std::pair<std::string, std::string>>{
           {"report", "report.html"},
           {"model", "model/model.glb"},
           {"viewer", "viewer/index.html"}}) {
    if (std::filesystem::exists(JoinPath(workspace, path))) {
      products += StrCat("; ", label, ": ", JoinPath(workspace, path));
    }
  }
  return StrCat(num_ran,
                " stages ran, ",
                num_skipped,
                " up to date, in ",
                FormatRunSeconds(run.seconds()),
                products.empty() ? StrCat(" -> ", workspace) : products);
}

}  // namespace bayon
