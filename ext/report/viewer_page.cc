// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/viewer_page.h"

#include "ext/core/errors.h"
#include "ext/report/html.h"

#include <nlohmann/json.hpp>

#include <cstring>

namespace bayon {

void ViewerOptions::Register(OptionRegistry* r) {
  r->Add("title", &title, "Page title (default: model name)");
  r->AddChoice("mode",
               &mode,
               {{"textured", "textured"},
                {"shaded", "shaded"},
                {"wireframe", "wireframe"},
                {"anaglyph", "anaglyph"}},
               "First display mode");
  r->AddChoice("up_axis",
               &up_axis,
               {{"x", "x"}, {"y", "y"}, {"z", "z"}},
               "The model's vertical axis in the glTF scene: y (glTF's "
               "convention, as bayon texture writes it), z for a .glb in z-up "
               "object coordinates");
  r->Add("azimuth_deg",
         &azimuth_deg,
         "First view: azimuth around the up axis, from the datum's +x "
         "towards +y (counter-clockwise seen from above)");
  r->Add("elevation_deg",
         &elevation_deg,
         "First view: elevation above the horizontal");
  r->Add("fov_deg",
         &fov_deg,
         "First view: horizontal field of view (as bayon render)");
}

void ViewerOptions::Check() const {
  CheckOption(elevation_deg >= -89 && elevation_deg <= 89,
              "elevation_deg",
              "in [-89, 89]",
              elevation_deg);
  CheckOption(fov_deg > 1 && fov_deg < 170, "fov_deg", "in (1, 170)", fov_deg);
}

std::string BuildViewerPage(const ViewerOptions& options,
                            const std::string& glb,
                            const char* bundle_js) {
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
  page.reserve(glb.size() * 4 / 3 + std::strlen(bundle_js) + 1024);
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
  page += bundle_js;
  page += "\n</script>\n</body>\n</html>\n";
  return page;
}

}  // namespace bayon
