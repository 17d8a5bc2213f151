// SPDX-License-Identifier: BSD-3-Clause
//
// fuzz_config: INI/TOML config files, read the two ways bayon reads them
// (CLI11, header-only, so its parser is instrumented with bayon):
// - a command's --config (tools/command.cc): an App with set_config, extras
//   refused, options of every kind the commands declare (text, integers,
//   doubles, flags, lists, a choice); then the effective options are written
//   out, as each command's log does;
// - `bayon pipeline --config`: ReadPipelineConfigs (ext/pipeline/stages.h)
//   itself, which walks CLI::ConfigINI's items (section, dotted key, joined
//   inputs) into the stages' options.
// CLI::ParseError is a command's way to refuse a file (main.cc prints it),
// InputError the pipeline's.
#include "ext/core/errors.h"
#include "ext/pipeline/stages.h"

#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace {

void ParseAsCommand(const std::string& path) {
  CLI::App app("fuzz", "bayon fuzz");
  app.set_config("--config", "", "config")->check(CLI::ExistingFile);
  app.allow_config_extras(CLI::config_extras_mode::error);
  app.option_defaults()->always_capture_default();
  std::string text = "default";
  int count = 3;
  int64_t big = 0;
  double ratio = 0.5;
  bool flag = false;
  std::vector<std::string> names;
  std::vector<double> values;
  std::string method = "fast";
  app.add_option("--workspace_path", text, "text");
  app.add_option("--num_threads", count, "int")->check(CLI::Range(-1, 64));
  app.add_option("--max_num_points", big, "int64");
  app.add_option("--max_angle_deg", ratio, "double");
  app.add_flag("--overwrite", flag, "flag");
  app.add_option("--names", names, "list");
  app.add_option("--weights", values, "doubles")->expected(0, 8);
  app.add_option("--method", method, "choice")
      ->check(CLI::IsMember({"fast", "exact"}));
  const std::string config = "--config=" + path;
  const char* argv[] = {"bayon", config.c_str()};
  try {
    app.parse(2, const_cast<char**>(argv));
    app.config_to_str(true, false);
  } catch (const CLI::ParseError&) {
  }
}

void ReadAsPipeline(const std::string& path) {
  try {
    bayon::ReadPipelineConfigs({path});
  } catch (const bayon::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = bayon::fuzz::FreshPath("config.ini");
  bayon::fuzz::WriteFile(
      path, std::string(reinterpret_cast<const char*>(data), size));
  ParseAsCommand(path);
  ReadAsPipeline(path);
  return 0;
}
