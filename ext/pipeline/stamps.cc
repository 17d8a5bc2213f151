// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/stamps.h"

#include "ext/core/file_util.h"

#include <nlohmann/json.hpp>

#include <fstream>

namespace fs = std::filesystem;

namespace bayon {

std::optional<fs::file_time_type> NewestTime(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  fs::file_time_type newest = fs::last_write_time(path, ec);
  if (fs::is_directory(path, ec)) {
    for (const auto& entry : fs::recursive_directory_iterator(path, ec)) {
      const fs::file_time_type t = entry.last_write_time(ec);
      if (!ec) newest = std::max(newest, t);
    }
  }
  return newest;
}

std::string StampPath(const std::string& workspace, const std::string& stage) {
  return (fs::path(workspace) / "pipeline" / (stage + ".done")).string();
}

std::string WhyRun(const Stage& stage,
                   const std::vector<std::string>& words,
                   const std::string& stamp_path,
                   const std::optional<fs::file_time_type>& previous_stamp) {
  std::ifstream file(stamp_path);
  if (!file) return "not run yet";
  nlohmann::json stamp;
  try {
    stamp = nlohmann::json::parse(file);
  } catch (const std::exception&) {
    return "its stamp is unreadable";
  }
  if (stamp.value("command", std::vector<std::string>()) != words) {
    return "its options changed";
  }
  for (const std::string& output : stage.outputs) {
    if (!fs::exists(output)) return output + " is missing";
  }
  const fs::file_time_type done = fs::last_write_time(stamp_path);
  if (previous_stamp && *previous_stamp > done) {
    return "an earlier stage ran since";
  }
  for (const std::string& input : stage.inputs) {
    const auto t = NewestTime(input);
    if (t && *t > done) return input + " changed since";
  }
  return std::string();
}

void WriteStamp(const std::string& stamp_path,
                const std::vector<std::string>& words,
                double seconds) {
  nlohmann::ordered_json stamp;
  stamp["command"] = words;
  stamp["seconds"] = seconds;
  WriteFileAtomically(stamp_path, stamp.dump(2) + "\n");
}

void RemoveStaleTemporaries(const Stage& stage) {
  std::error_code ec;
  for (const std::string& output : stage.outputs) {
    const fs::path path(output);
    const fs::path folder = path.parent_path();
    if (!fs::is_directory(folder, ec)) continue;
    const std::string prefix = path.filename().string() + ".tmp-";
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      if (entry.path().filename().string().rfind(prefix, 0) == 0) {
        fs::remove_all(entry.path(), ec);
      }
    }
  }
}

void WriteRunJson(const PipelineContext& c,
                  const std::string& config,
                  const std::vector<StageRun>& runs,
                  double total_seconds) {
  nlohmann::ordered_json json;
  json["workspace_path"] = fs::absolute(c.workspace).string();
  json["image_path"] = fs::absolute(c.image_path).string();
  json["config"] = config;
  json["stages"] = nlohmann::ordered_json::array();
  for (const StageRun& run : runs) {
    nlohmann::ordered_json entry;
    entry["name"] = run.name;
    entry["program"] = run.program;
    entry["status"] = run.status;
    entry["seconds"] = run.seconds;
    entry["command"] = run.command;
    if (!run.reason.empty()) entry["reason"] = run.reason;
    json["stages"].push_back(entry);
  }
  json["total_seconds"] = total_seconds;
  WriteFileAtomically((fs::path(c.workspace) / "pipeline.json").string(),
                      json.dump(2) + "\n");
}

}  // namespace bayon
