// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon viewer`: a textured model (.glb) as one self-contained web page,
// <output_path>/index.html: three.js with orbit controls and the textured,
// shaded, wireframe and anaglyph modes (tools/viewer/src/viewer.js, bundled
// at build time into kViewerBundleJs), and the model itself.
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/render/model_export.h"
#include "ext/report/html.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <glog/logging.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

namespace bayon {

// tools/viewer/src/viewer.js with three.js, one minified classic script
// (generated: viewer_bundle.cc in the build folder, see tools/CMakeLists.txt).
extern const char kViewerBundleJs[];

namespace {

namespace fs = std::filesystem;

struct ViewerOptions {
  std::string title;  // default: the model's file name
  std::string mode = "textured";
  // The model's vertical in the glTF scene: y, glTF's convention, which
  // bayon's .glb writer follows by turning the z-up datum with a node
  // rotation.
  std::string up_axis = "y";
  double azimuth_deg = 30;    // first view, from the up axis' e1 towards e2
  double elevation_deg = 20;  // above the horizontal
  double fov_deg = 40;        // horizontal field of view, as bayon render

  void Check() const {
    CheckOption(elevation_deg >= -89 && elevation_deg <= 89,
                "--elevation_deg",
                "in [-89, 89]",
                elevation_deg);
    CheckOption(
        fov_deg > 1 && fov_deg < 170, "--fov_deg", "in (1, 170)", fov_deg);
  }
};

// The page: options as JSON, the model as base64 and the bundled script, all
// inline. The model is embedded rather than referenced because browsers block
// fetch() and XMLHttpRequest of local files on file:// pages; base64 costs a
// third more bytes but keeps the page one file that opens anywhere.
std::string BuildPage(const ViewerOptions& options, const std::string& glb) {
  nlohmann::ordered_json config;
  config["title"] = options.title;
  config["mode"] = options.mode;
  config["up_axis"] = options.up_axis;
  config["azimuth_deg"] = options.azimuth_deg;
  config["elevation_deg"] = options.elevation_deg;
  config["fov_deg"] = options.fov_deg;
  // '<' only occurs inside JSON strings, where \u003c means the same and
  // cannot close the <script> element.
  std::string config_text;
  for (const char c :
       config.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)) {
    config_text += c == '<' ? std::string("\\u003c") : std::string(1, c);
  }
  std::string page;
  page.reserve(glb.size() * 4 / 3 + std::strlen(kViewerBundleJs) + 1024);
  page +=
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  page +=
      "<meta name=\"viewport\" content=\"width=device-width, "
      "initial-scale=1\">\n";
  page += "<meta name=\"generator\" content=\"bayon viewer\">\n";
  page += "<title>" + HtmlEscape(options.title) + "</title>\n</head>\n<body>\n";
  page += "<script type=\"application/json\" id=\"bayon-viewer-config\">" +
          config_text + "</script>\n";
  page += "<script type=\"application/octet-stream\" id=\"bayon-model\">";
  page += Base64(glb);
  page += "</script>\n<script>\n";
  page += kViewerBundleJs;
  page += "\n</script>\n</body>\n</html>\n";
  return page;
}

}  // namespace

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
  app.add_option("--title", options.title, "Page title (default: model name)");
  app.add_option("--mode", options.mode, "First display mode")
      ->transform(
          CLI::IsMember({"textured", "shaded", "wireframe", "anaglyph"}));
  app.add_option("--up_axis",
                 options.up_axis,
                 "The model's vertical axis in the glTF scene: y (glTF's "
                 "convention, as bayon texture writes it), z for a .glb "
                 "in z-up object coordinates")
      ->transform(CLI::IsMember({"x", "y", "z"}));
  app.add_option("--azimuth_deg",
                 options.azimuth_deg,
                 "First view: azimuth around the up axis, from the datum's "
                 "+x towards +y (counter-clockwise seen from above)");
  app.add_option("--elevation_deg",
                 options.elevation_deg,
                 "First view: elevation above the horizontal");
  app.add_option("--fov_deg",
                 options.fov_deg,
                 "First view: horizontal field of view (as bayon render)");
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
  const std::string page = BuildPage(options, glb);
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
