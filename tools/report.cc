// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon report`: a workspace's results as one self-contained web page,
// W/report.html (ext/report/workspace_report.h).
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/report/workspace_report.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>
#include <string>

namespace bayon {

namespace fs = std::filesystem;

int RunReport(int argc, char** argv) {
  std::string workspace_path, output_path;
  bool overwrite = false;
  WorkspaceReportOptions options;
  CommandLine command(
      "report",
      "A workspace's results as one self-contained web page (default "
      "<workspace>/report.html): the pipeline run, the image network (plan "
      "and side views of the camera stations), the tie-point distribution "
      "per image, histograms of the image residuals, the additional "
      "parameters with their standard deviations and significance, the "
      "precision table of the bundle adjustment as in the Bayon paper (n, "
      "r/n, sigma0, sx, sy, sz, check points), dense point, editing, mesh "
      "and texture statistics, renders of the model, a link to the viewer "
      "and the comparison with stock COLMAP. Charts are inline SVG, "
      "pictures embedded JPEG: the page opens without a server. Parts of "
      "the pipeline that did not run are listed as not run.");
  CLI::App& app = command.app();
  app.add_option("--workspace_path",
                 workspace_path,
                 "Workspace (sparse/adjusted is required, the rest optional)")
      ->required();
  app.add_option("--output_path",
                 output_path,
                 "The page (default <workspace>/report.html)");
  command.AddOptions(&options);
  app.add_option("--overwrite", overwrite, "Replace an existing page");
  if (!command.Parse(argc, argv)) return 0;

  options.Check();
  CheckDirectoryExists(workspace_path, "--workspace_path");
  const fs::path adjusted = fs::path(workspace_path) / "sparse" / "adjusted";
  if (!fs::is_directory(adjusted)) {
    ThrowInputError(adjusted.string(),
                    ": no adjusted model (run bayon pipeline or bayon adjust "
                    "first)");
  }
  if (output_path.empty()) {
    output_path = (fs::path(workspace_path) / "report.html").string();
  }
  CheckOutputPath(output_path, overwrite);
  const fs::path output_dir = fs::absolute(output_path).parent_path();
  if (!fs::is_directory(output_dir)) {
    ThrowInputError(
        output_path, ": the folder ", output_dir.string(), " does not exist");
  }
  options.report_dir = output_dir.string();
  command.StartLog(WorkspaceLogPath(workspace_path, "report"));

  const WorkspaceReport report = BuildWorkspaceReport(workspace_path, options);
  WriteFileAtomically(output_path, report.html);

  std::string not_run;
  for (const std::string& title : report.not_run) {
    not_run += (not_run.empty() ? "" : ", ") + title;
  }
  std::string problems;
  for (const std::string& problem : report.problems) {
    LOG(WARNING) << "report: " << problem;
    problems += "\n  could not show: " + problem;
  }
  command.PrintSummary(StrCat(report.num_images,
                              " images, ",
                              report.num_points3D,
                              " tie points, ",
                              report.num_observations,
                              " observations; ",
                              report.section_ids.size(),
                              " sections (not run: ",
                              not_run.empty() ? "none" : not_run,
                              "), ",
                              report.num_charts,
                              " charts, ",
                              report.num_pictures,
                              " pictures, ",
                              (report.html.size() + 512) / 1024,
                              " KB",
                              problems,
                              "\n  -> ",
                              output_path));
  return 0;
}

}  // namespace bayon
