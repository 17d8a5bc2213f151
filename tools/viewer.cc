// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon viewer`: a textured model (.glb) as one self-contained web page,
// <output_path>/index.html (ext/report/viewer_page.h), with the script
// bundled at build time into kViewerBundleJs.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/render/model_export.h"
#include "ext/report/viewer_page.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <glog/logging.h>

#include <cctype>
#include <filesystem>
#include <string>

namespace bayon {

// tools/viewer/src/viewer.js with three.js, one minified classic script
// (generated: viewer_bundle.cc in the build folder, see tools/CMakeLists.txt).
extern const char kViewerBundleJs[];

namespace fs = std::filesystem;

int RunViewer(int argc, char** argv) {
  std::string model_path, output_path, log_path;
  bool overwrite = false;
  ViewerOptions options;
  CommandLine command(
      "viewer",
      "A textured model (glTF binary, .glb, as bayon texture writes it) as a "
      "self-contained web page, <output_path>/index.html: three.js with orbit "
      "controls (drag: orbit, right drag: pan, wheel: zoom) and textured, "
      "shaded, wireframe and red-cyan anaglyph modes (buttons or keys 1-4). "
      "The model and the script are inside the page, so it works offline, "
      "from the file system or any static server. URL parameters ?mode=, "
      "&azimuth=, &elevation=, &fov= override the first view, which is "
      "framed as bayon render's orbit views: the same --azimuth_deg "
      "(render's --start_azimuth_deg), --elevation_deg and --fov_deg in a "
      "window of render's shape show what render's view shows.");
  CLI::App& app = command.app();
  app.add_option("--model_path", model_path, "Textured model (.glb)")
      ->required();
  app.add_option("--output_path", output_path, "Folder to create (index.html)")
      ->required();
  command.AddOptions(&options);
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  app.add_option("--log_path",
                 log_path,
                 "Append the log to this file (default: logs/viewer.log "
                 "beside the output folder)");
  if (!command.Parse(argc, argv)) return 0;

  options.Check();
  CheckFileExists(model_path, "--model_path");
  CheckOutputPath(output_path, overwrite);
  std::string extension = fs::path(model_path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(c));
  if (extension != ".glb") {
    ThrowInputError(model_path, ": not a glTF binary (.glb) file");
  }
  // Read in full, as the page will: a model the reader refuses (truncated,
  // inconsistent, its texture undecodable) is refused here, in one line.
  const TexturedModel model = ReadTexturedModel(model_path);
  const std::string glb = ReadFileToString(model_path);
  if (options.title.empty()) {
    options.title = fs::path(model_path).filename().string();
  }
  if (log_path.empty()) {
    fs::path output = fs::absolute(output_path).lexically_normal();
    if (!output.has_filename()) output = output.parent_path();
    log_path = WorkspaceLogPath(output.parent_path().string(), "viewer");
  }
  command.StartLog(log_path);
  if (model.atlas.empty()) {
    LOG(WARNING) << model_path
                 << ": the model has no texture image; the textured mode "
                    "shows its base colour";
  }

  OutputDirectory output(output_path, overwrite);
  const std::string page = BuildViewerPage(options, glb, kViewerBundleJs);
  WriteFileAtomically(output.File("index.html"), page);
  output.Commit();
  command.PrintSummary(StrCat(model.mesh.NumVertices(),
                              " vertices, ",
                              model.mesh.NumFaces(),
                              " faces, ",
                              model.atlas.empty() ? "no texture" : "textured",
                              "; page ",
                              (page.size() + 1023) / 1024,
                              " KiB\n  -> ",
                              output.final_path(),
                              "/index.html"));
  return 0;
}

}  // namespace bayon
