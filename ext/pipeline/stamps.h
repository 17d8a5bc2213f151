// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// Which stages of `bayon pipeline` must run, like make. Completeness is
// judged by a stamp, W/pipeline/<stage>.done, written only after the stage
// returned successfully and removed before it starts. Each stage writes its
// own outputs atomically (or in one database transaction), so an
// interrupted stage leaves either its old outputs or none, and never a
// stamp: it is run again. A stamp is stale when the stage's command changed
// (config or flags), when it is older than the previous stage's stamp, or
// when an input outside the chain (the image folder, control/) changed
// later.

#include "ext/pipeline/stages.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace bayon {

// The newest modification time of a file, or of a folder and everything in
// it (a photograph replaced in the image folder counts as a change); nullopt
// where the path does not exist.
std::optional<std::filesystem::file_time_type> NewestTime(
    const std::string& path);

// W/pipeline/<stage>.done.
std::string StampPath(const std::string& workspace, const std::string& stage);

// Why the stage must run, or empty when its stamp (at stamp_path) says it is
// complete and nothing it depends on changed since: its command `words`,
// its outputs, the previous stage's stamp time and its inputs.
std::string WhyRun(
    const Stage& stage,
    const std::vector<std::string>& words,
    const std::string& stamp_path,
    const std::optional<std::filesystem::file_time_type>& previous_stamp);

// The stamp of a stage that succeeded: its command and time.
void WriteStamp(const std::string& stamp_path,
                const std::vector<std::string>& words,
                double seconds);

// Temporary files of the stage's outputs left by an interrupted run (the
// atomic writes' "<name>.tmp-<pid>-<n>"): they were never complete.
void RemoveStaleTemporaries(const Stage& stage);

// One stage of a run, for W/pipeline.json.
struct StageRun {
  std::string name, program, status;  // ran | skipped | failed | not selected
  double seconds = 0;
  std::vector<std::string> command;
  std::string reason;
};

// W/pipeline.json: the run's stages, status, times and commands.
void WriteRunJson(const PipelineContext& c,
                  const std::string& config,
                  const std::vector<StageRun>& runs,
                  double total_seconds);

}  // namespace bayon
