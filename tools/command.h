// SPDX-License-Identifier: BSD-3-Clause
//
// What every `bayon <command>` shares: a CLI11 parser with --config (the same
// option names in an INI or TOML file), a log file, the effective options
// written beside it, and the summary printed at the end. Commands stay thin:
// parse, check, call one ext/ function, write, summarise.
#pragma once

#include "ext/core/option_registry.h"

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <glog/logging.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace bayon {

class CommandLine {
 public:
  CommandLine(const std::string& command, const std::string& description);

  CLI::App& app() { return app_; }
  const std::string& command() const { return command_; }

  // The fields an options struct registers (option_registry.h), as
  // --field or --nested.field. `legacy` maps a flag name of earlier
  // releases (without the dashes) to the field's registered name: it stays
  // accepted, on the command line and in configs, but is not listed.
  template <typename Options>
  void AddOptions(Options* options,
                  const std::map<std::string, std::string>& legacy = {});
  // The same for a nested struct on its own, as --prefix.field.
  template <typename Options>
  void AddOptions(const std::string& prefix,
                  Options* options,
                  const std::map<std::string, std::string>& legacy = {});

  // Parses argv (argv[0] is the command name). Returns false when help was
  // asked for and printed (the command then returns 0). Other CLI11 errors
  // propagate as CLI::ParseError; main() makes them one line and exit code 2.
  bool Parse(int argc, char** argv);

  // While set, Parse() returns false after a successful parse, so a command
  // checks its options and does nothing else: `bayon pipeline` runs every
  // stage this way first, so that a typo in a config stops it before any
  // work starts.
  static void SetCheckOnly(bool check_only);

  // Starts logging to `log_path` (appending) and writes the effective options
  // next to it as <stem>.options. Empty `log_path` logs to stderr only.
  void StartLog(const std::string& log_path);

  // The effective options as INI text (what --config would read back).
  std::string EffectiveOptions() const;

  // Prints "<command>: <text>" to stdout and writes it to the log file.
  void PrintSummary(const std::string& text) const;

 private:
  // Adds the legacy names to those EffectiveOptions leaves out.
  void NoteEarlierNames(const std::map<std::string, std::string>& legacy);

  std::string command_;
  CLI::App app_;
  std::shared_ptr<google::LogSink> log_sink_;
  std::vector<std::string> earlier_names_;  // accepted, not written out
};

// An OptionRegistry that puts every field on a CLI11 command line.
class CliOptionRegistry : public OptionRegistry {
 public:
  CliOptionRegistry(CLI::App* app,
                    const std::map<std::string, std::string>& legacy);
  void Add(const std::string& name,
           bool* value,
           const std::string& help) override;
  void Add(const std::string& name,
           int* value,
           const std::string& help) override;
  void Add(const std::string& name,
           double* value,
           const std::string& help) override;
  void Add(const std::string& name,
           std::string* value,
           const std::string& help) override;
  void Add(const std::string& name,
           std::vector<std::string>* value,
           const std::string& help) override;

 protected:
  void AddText(const std::string& name,
               const Text& text,
               const std::string& help) override;

 private:
  // The option as --name, and hidden under each legacy name of it.
  template <typename T>
  void AddOption(const std::string& name, T* value, const std::string& help);
  // `name`, then its legacy names.
  std::vector<std::string> NamesOf(const std::string& name) const;

  CLI::App* app_;
  std::map<std::string, std::string> legacy_;  // old name -> name
};

template <typename Options>
void CommandLine::AddOptions(Options* options,
                             const std::map<std::string, std::string>& legacy) {
  CliOptionRegistry registry(&app_, legacy);
  options->Register(&registry);
  NoteEarlierNames(legacy);
}

template <typename Options>
void CommandLine::AddOptions(const std::string& prefix,
                             Options* options,
                             const std::map<std::string, std::string>& legacy) {
  CliOptionRegistry registry(&app_, legacy);
  registry.AddNested(prefix, options);
  NoteEarlierNames(legacy);
}

// For commands on a workspace: <workspace>/logs/<command>.log, creating the
// folder; empty when workspace is empty.
std::string WorkspaceLogPath(const std::string& workspace,
                             const std::string& command);

// The workspace a stage file belongs to: W for W/dense/x, W/mesh/x or
// W/model/x, else the file's own folder.
std::string WorkspaceOfStageFile(const std::string& path);
// The inputs of a stage that reads oriented photographs, with a workspace's
// defaults: images/, sparse/adjusted and database.db (where it exists).
struct OrientedInput {
  std::string workspace_path, image_path, input_path, database_path;

  // --workspace_path (described by `workspace_help`), --image_path,
  // --input_path, --database_path.
  void AddOptions(CLI::App& app, const std::string& workspace_help);
  // Fills what was not given from --workspace_path (checking that it
  // exists); returns whether a workspace was given.
  bool ApplyWorkspace();
  // Checks the folders and the database that were given.
  void Check() const;
};

// For commands on a database: `log_path` if given, else
// <database folder>/logs/<command>.log.
std::string DatabaseLogPath(const std::string& log_path,
                            const std::string& database_path,
                            const std::string& command);

}  // namespace bayon
