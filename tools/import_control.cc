// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/georef/control_import.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <cmath>
#include <filesystem>

namespace bayon {

namespace fs = std::filesystem;

namespace {

// The photographs under `folder`, by their names relative to it (as a
// database names them).
std::vector<std::string> ImageNames(const std::string& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) {
      names.push_back(fs::relative(entry.path(), folder).generic_string());
    }
  }
  return names;
}

}  // namespace

int RunImportControl(int argc, char** argv) {
  std::string input_path, output_path, image_path;
  bool overwrite = false;
  ControlImportOptions options;
  CommandLine command(
      "import_control",
      "Ground control from the tools surveyors use: OpenDroneMap's "
      "gcp_list.txt (its first line names the CRS; points and their image "
      "measurements), Metashape's reference CSV or a plain CSV (points; "
      "--crs names their CRS). Geographic and projected coordinates go "
      "through PROJ into a local projected frame (the survey's projected "
      "CRS where it is in metres, the UTM zone of geographic points) with an "
      "origin near the "
      "points subtracted; writes points.txt, observations.txt and crs.json "
      "(the CRS and the origin) into --output_path, a workspace's control/.");
  CLI::App& app = command.app();
  command.AddOptions(&options);
  app.add_option("--input_path", input_path, "The survey's file");
  app.add_option("--output_path", output_path, "Control folder to write");
  app.add_option("--image_path",
                 image_path,
                 "Folder of the photographs: every measurement's must be "
                 "there");
  app.add_option("--overwrite", overwrite, "1: replace existing files");
  if (!command.Parse(argc, argv)) return 0;
  options.Check();
  if (input_path.empty()) ThrowInputError("--input_path is required");
  if (output_path.empty()) ThrowInputError("--output_path is required");
  CheckFileExists(input_path, "--input_path");
  std::vector<std::string> image_names;
  if (!image_path.empty()) {
    CheckDirectoryExists(image_path, "--image_path");
    image_names = ImageNames(image_path);
  }
  for (const char* file : {"points.txt", "observations.txt", "crs.json"}) {
    CheckOutputPath((fs::path(output_path) / file).string(), overwrite);
  }

  const ImportedControl control =
      ImportControl(input_path, options, image_names);
  WriteImportedControl(output_path, control);
  int num_check = 0;
  for (const ControlPoint& point : control.points) {
    num_check += point.type == ControlPointType::kCheck;
  }
  command.PrintSummary(StrCat(control.points.size(),
                              " points (",
                              num_check,
                              " check), ",
                              control.measurements.size(),
                              " image measurements; ",
                              control.frame.source_crs,
                              " -> ",
                              control.frame.crs,
                              ", origin (",
                              // Whole metres (crs.json has it).
                              std::llround(control.frame.origin.x()),
                              ", ",
                              std::llround(control.frame.origin.y()),
                              ", ",
                              std::llround(control.frame.origin.z()),
                              ") -> ",
                              output_path));
  return 0;
}

}  // namespace bayon
