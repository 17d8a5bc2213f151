// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon viewer`'s page: a textured model (.glb) as one self-contained web
// page, three.js with orbit controls and the textured, shaded, wireframe and
// anaglyph modes (tools/viewer/src/viewer.js, bundled at build time), the
// model inside it.
#pragma once

#include "ext/core/option_registry.h"

#include <string>

namespace bayon {

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
  void Register(OptionRegistry* registry);
  void Check() const;
};

// The page: the options as JSON, the model as base64 and the script
// `bundle_js`, all inline. The model is embedded rather than referenced
// because browsers block fetch() and XMLHttpRequest of local files on
// file:// pages; base64 costs a third more bytes but keeps the page one
// file that opens anywhere.
std::string BuildViewerPage(const ViewerOptions& options,
                            const std::string& glb,
                            const char* bundle_js);

}  // namespace bayon
