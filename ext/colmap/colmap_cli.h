// SPDX-License-Identifier: BSD-3-Clause
//
// The one way bayon runs the stock `colmap` binary: arguments from a struct,
// the exact command line logged, COLMAP's output kept in a log file, and
// success judged by the exit code AND the files the command must produce
// (several COLMAP commands exit 0 on failure: mapper without an initial
// pair, poisson_mesher without normals, stereo_fusion without depth maps).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace bayon {

struct ColmapCall {
  std::string command;  // e.g. "mapper"
  // In order, e.g. {"--database_path", "db.db"}; values are passed verbatim.
  std::vector<std::pair<std::string, std::string>> options;
  // Files or folders that must exist after a successful run.
  std::vector<std::string> expected_outputs;
};

struct ColmapRunOptions {
  // The binary; empty means $BAYON_COLMAP or else `colmap` on the PATH.
  std::string executable;
  // COLMAP's stdout and stderr go here (appended); empty: a file in /tmp.
  std::string log_path;
};

struct ColmapResult {
  bool success = false;
  int exit_code = -1;
  double seconds = 0;
  std::string command_line;  // shell-quoted, for logs and reports
  std::string log_path;
  std::string message;  // why it failed, one line
};

// Runs COLMAP and waits for it. Never throws for COLMAP's own failures (they
// are reported in the result); throws InputError if the binary is missing.
ColmapResult RunColmap(const ColmapCall& call,
                       const ColmapRunOptions& options = {});

// "COLMAP 3.8 ..." from `colmap -h`, or empty if it cannot be run.
std::string ColmapVersion(const ColmapRunOptions& options = {});

// COLMAP rewrites user_version and the journal mode of every database it
// opens (colmap-interop.md 1.1): hand it a consistent copy, made with
// SQLite's backup API, whenever the original must stay untouched.
void CopyDatabaseForColmap(const std::string& database_path,
                           const std::string& copy_path);

// The model of `colmap mapper --output_path mapper_output` with the most
// registered images (COLMAP numbers its models 0, 1, ...; the first by name
// on a tie), as a path; empty when no subfolder holds a binary model
// (cameras.bin, images.bin, points3D.bin). Reads only the count at the head
// of each images.bin.
std::string LargestModel(const std::string& mapper_output);

}  // namespace bayon
