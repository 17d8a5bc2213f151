// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon <command> [options]`: dispatch, logging set-up, and the exit codes
// every command shares: 0 success, 1 ran but produced nothing usable,
// 2 bad input (one line naming what is wrong).
#include "ext/core/errors.h"
#include "tools/commands.h"

#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include <algorithm>
#include <cstring>
#include <iostream>
#include <string>

namespace {

void PrintUsage() {
  std::cout << "bayon: photogrammetric reconstruction on COLMAP's data\n\n"
               "Usage: bayon <command> [options]   (bayon <command> -h for "
               "its options)\n\nCommands:\n";
  for (const bayon::Command& command : bayon::Commands()) {
    std::cout << "  " << command.name
              << std::string(
                     22 - std::min<size_t>(20, std::strlen(command.name)), ' ')
              << command.description << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  FLAGS_log_prefix = false;
  FLAGS_colorlogtostderr = false;

  if (argc < 2 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "--help") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  if (const bayon::Command* command = bayon::FindCommand(name)) {
    try {
      return command->run(argc - 1, argv + 1);
    } catch (const CLI::ParseError& error) {
      std::cerr << "bayon " << name << ": error: " << error.what()
                << " (see bayon " << name << " -h)" << std::endl;
      return 2;
    } catch (const bayon::InputError& error) {
      std::cerr << "bayon " << name << ": error: " << error.what() << std::endl;
      return 2;
    } catch (const bayon::RunFailure& error) {
      std::cerr << "bayon " << name << ": failed: " << error.what()
                << std::endl;
      return 1;
    } catch (const std::exception& error) {
      std::cerr << "bayon " << name << ": internal error: " << error.what()
                << std::endl;
      return 1;
    }
  }
  std::cerr << "bayon: unknown command '" << name
            << "' (bayon -h lists the commands)" << std::endl;
  return 2;
}
