// SPDX-License-Identifier: BSD-3-Clause
#include "ext/colmap/control_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/targets/find_targets.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>

namespace bayon {

namespace fs = std::filesystem;

int RunTargets(int argc, char** argv) {
  std::string database_path, image_path, output_path, report_path, log_path;
  std::string print_path, codes_text = "0-11";
  double side_mm = 40;
  bool overwrite = false;
  int num_threads = -1;
  CodedTargetOptions options;
  CommandLine command(
      "targets",
      "Find, decode and measure coded targets (ArUco / AprilTag markers, "
      "through OpenCV's aruco module) in every photograph of a database: "
      "each target's centre where its four edge lines' diagonals meet, to a "
      "hundredth of a pixel, with its standard deviation. Writes the "
      "measurements as control/observations.txt lines (NAME IMAGE X Y "
      "SIGMA), for `tiepoints --manual_path` and control. With --print, "
      "writes a printable sheet of targets (SVG, A4) instead.");
  CLI::App& app = command.app();
  app.add_option("--database_path", database_path, "COLMAP database");
  app.add_option("--image_path", image_path, "Folder of the photographs");
  app.add_option("--output_path",
                 output_path,
                 "Measurements (control/observations.txt format)");
  command.AddOptions(&options);
  app.add_option("--print",
                 print_path,
                 "Write a printable sheet (SVG, A4) of --codes instead");
  app.add_option("--codes", codes_text, "--print: codes, e.g. 0-11 or 3,5,8");
  app.add_option(
      "--side_mm", side_mm, "--print: side of a marker's black square, mm");
  app.add_option("--num_threads", num_threads, "-1 = all cores");
  app.add_option(
      "--report_path", report_path, "Write the report (per image) as JSON");
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <workspace>/logs/targets.log)");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  if (!print_path.empty()) {
    CheckOutputPath(print_path, overwrite);
    const std::vector<int> codes = ParseCodedTargetCodes(codes_text);
    WriteCodedTargetSheet(options, codes, side_mm, print_path);
    command.PrintSummary(StrCat(codes.size(),
                                " targets of ",
                                side_mm,
                                " mm (",
                                options.dictionary,
                                ") -> ",
                                print_path));
    return 0;
  }
  if (database_path.empty() || image_path.empty() || output_path.empty()) {
    ThrowInputError(
        "--database_path, --image_path and --output_path are needed (or "
        "--print)");
  }
  CheckFileExists(database_path, "--database_path");
  CheckDirectoryExists(image_path, "--image_path");
  CheckOutputPath(output_path, overwrite);
  if (!report_path.empty()) CheckOutputPath(report_path, overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(database_path), "targets");
  }
  command.StartLog(log_path);

  const CodedTargetSummary summary =
      FindCodedTargets(database_path, image_path, options, num_threads);
  for (const std::string& path : {output_path, report_path}) {
    if (!path.empty()) fs::create_directories(fs::absolute(path).parent_path());
  }
  WriteImageMeasurements(output_path, summary.measurements);
  if (!report_path.empty()) {
    WriteFileAtomically(report_path,
                        CodedTargetReportJson(summary, options).dump(2) + "\n");
  }
  command.PrintSummary(summary.Summary() + "\n  -> " + output_path);
  return 0;
}

}  // namespace bayon
