// SPDX-License-Identifier: BSD-3-Clause
#include "tools/command.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <type_traits>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// Appends every log message to a file, one line each, with a timestamp.
class FileLogSink : public google::LogSink {
 public:
  explicit FileLogSink(const std::string& path) : file_(path, std::ios::app) {}
  void send(google::LogSeverity severity,
            const char* /*full_filename*/,
            const char* /*base_filename*/,
            int /*line*/,
            const struct ::tm* time,
            const char* message,
            size_t message_len) override {
    std::lock_guard<std::mutex> lock(mutex_);
    char stamp[32];
    std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S", time);
    file_ << stamp << " " << google::GetLogSeverityName(severity)[0] << " "
          << std::string(message, message_len) << "\n";
    file_.flush();
  }

 private:
  std::ofstream file_;
  std::mutex mutex_;
};

bool check_only = false;

}  // namespace

void CommandLine::SetCheckOnly(bool value) { check_only = value; }

CommandLine::CommandLine(const std::string& command,
                         const std::string& description)
    : command_(command), app_(description, "bayon " + command) {
  app_.set_config("--config", "", "Read options from an INI or TOML file")
      ->check(CLI::ExistingFile);
  // Keys are option names, dotted ones included (mpgc.lsm.patch_radius):
  // a dot does not open a section.
  auto config = std::make_shared<CLI::ConfigINI>();
  config->parentSeparator('\x1f');
  app_.config_formatter(config);
  // A key the command does not know is a typo, not something to ignore.
  app_.allow_config_extras(CLI::config_extras_mode::error);
  app_.get_formatter()->column_width(40);
  app_.option_defaults()->always_capture_default();
}

bool CommandLine::Parse(int argc, char** argv) {
  try {
    app_.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() != 0) throw;
    app_.exit(error);
    return false;
  }
  return !check_only;
}

void CommandLine::StartLog(const std::string& log_path) {
  if (log_path.empty()) return;
  std::error_code ec;
  const fs::path path(log_path);
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec) {
      ThrowInputError(path.parent_path().string(),
                      ": cannot create the log folder: ",
                      ec.message());
    }
  }
  auto sink = std::make_shared<FileLogSink>(log_path);
  google::AddLogSink(sink.get());
  log_sink_ = std::shared_ptr<google::LogSink>(
      sink.get(), [sink](google::LogSink* s) { google::RemoveLogSink(s); });
  fs::path options_path = path;
  options_path.replace_extension(".options");
  WriteFileAtomically(options_path.string(), EffectiveOptions());
  LOG(INFO) << "bayon " << command_ << " started";
}

std::string CommandLine::EffectiveOptions() const {
  // Each field once, under its name: an earlier name's line would carry its
  // default back over the value given.
  std::istringstream lines(app_.config_to_str(true, false));
  std::string options;
  for (std::string line; std::getline(lines, line);) {
    const std::string key = line.substr(0, line.find('='));
    if (std::find(earlier_names_.begin(), earlier_names_.end(), key) !=
        earlier_names_.end()) {
      continue;
    }
    options += line + "\n";
  }
  return options;
}

void CommandLine::NoteEarlierNames(
    const std::map<std::string, std::string>& legacy) {
  for (const auto& [old_name, name] : legacy) {
    earlier_names_.push_back(old_name);
  }
}

CliOptionRegistry::CliOptionRegistry(
    CLI::App* app, const std::map<std::string, std::string>& legacy)
    : app_(app), legacy_(legacy) {}

std::vector<std::string> CliOptionRegistry::NamesOf(
    const std::string& name) const {
  std::vector<std::string> names = {name};
  for (const auto& [old_name, new_name] : legacy_) {
    if (new_name == name) names.push_back(old_name);
  }
  return names;
}

template <typename T>
void CliOptionRegistry::AddOption(const std::string& name,
                                  T* value,
                                  const std::string& help) {
  const std::vector<std::string> names = NamesOf(name);
  for (size_t k = 0; k < names.size(); ++k) {
    CLI::Option* option = app_->add_option("--" + names[k], *value, help);
    if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      option->delimiter(',');
    }
    if (k > 0) option->group("");
  }
}

void CliOptionRegistry::Add(const std::string& name,
                            bool* value,
                            const std::string& help) {
  AddOption(name, value, help);
}

void CliOptionRegistry::Add(const std::string& name,
                            int* value,
                            const std::string& help) {
  AddOption(name, value, help);
}

void CliOptionRegistry::Add(const std::string& name,
                            double* value,
                            const std::string& help) {
  AddOption(name, value, help);
}

void CliOptionRegistry::Add(const std::string& name,
                            std::string* value,
                            const std::string& help) {
  AddOption(name, value, help);
}

void CliOptionRegistry::Add(const std::string& name,
                            std::vector<std::string>* value,
                            const std::string& help) {
  AddOption(name, value, help);
}

void CliOptionRegistry::AddText(const std::string& name,
                                const Text& text,
                                const std::string& help) {
  const std::vector<std::string> names = NamesOf(name);
  for (size_t k = 0; k < names.size(); ++k) {
    const std::string flag = "--" + names[k];
    auto set = [flag, set = text.set](const std::string& given) {
      try {
        set(given);
      } catch (const InputError& error) {
        ThrowInputError(flag, ": ", error.what());
      }
    };
    CLI::Option* option =
        app_->add_option_function<std::string>(flag, set, help);
    if (!text.choices.empty()) option->check(CLI::IsMember(text.choices));
    option->default_str(text.get());
    if (k > 0) option->group("");
  }
}

std::string WorkspaceLogPath(const std::string& workspace,
                             const std::string& command) {
  if (workspace.empty()) return std::string();
  return (fs::path(workspace) / "logs" / (command + ".log")).string();
}

std::string WorkspaceOfStageFile(const std::string& path) {
  const fs::path folder = fs::absolute(path).parent_path();
  const std::string name = folder.filename().string();
  if (name == "dense" || name == "mesh" || name == "model") {
    return folder.parent_path().string();
  }
  return folder.string();
}

void OrientedInput::AddOptions(CLI::App& app,
                               const std::string& workspace_help) {
  app.add_option("--workspace_path", workspace_path, workspace_help);
  app.add_option("--image_path", image_path, "Folder of the images");
  app.add_option("--input_path", input_path, "Oriented sparse model");
  app.add_option("--database_path",
                 database_path,
                 "COLMAP database with bayon_interior (scanned frames); "
                 "optional");
}

bool OrientedInput::ApplyWorkspace() {
  if (workspace_path.empty()) return false;
  CheckDirectoryExists(workspace_path, "--workspace_path");
  if (image_path.empty()) image_path = workspace_path + "/images";
  if (input_path.empty()) input_path = workspace_path + "/sparse/adjusted";
  if (database_path.empty() && fs::exists(workspace_path + "/database.db")) {
    database_path = workspace_path + "/database.db";
  }
  return true;
}

void OrientedInput::Check() const {
  CheckDirectoryExists(image_path, "--image_path");
  CheckDirectoryExists(input_path, "--input_path");
  if (!database_path.empty()) CheckFileExists(database_path, "--database_path");
}

std::string DatabaseLogPath(const std::string& log_path,
                            const std::string& database_path,
                            const std::string& command) {
  if (!log_path.empty()) return log_path;
  return WorkspaceLogPath(fs::absolute(database_path).parent_path().string(),
                          command);
}

void CommandLine::PrintSummary(const std::string& text) const {
  std::cout << command_ << ": " << text << std::endl;
  if (log_sink_) {
    LOG_TO_SINK_BUT_NOT_TO_LOGFILE(log_sink_.get(), INFO)
        << "summary: " << text;
  }
}

}  // namespace bayon
