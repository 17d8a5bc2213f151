// SPDX-License-Identifier: BSD-3-Clause
//
// ../shared/data/temple-ring as the end-to-end tests share it (built once per
// build of bayon, see SharedFixture).
#pragma once

#include <string>
#include <vector>

namespace bayon {
namespace testing {

struct TempleSetup {
  std::string images;  // the photographs (never written)
  std::string truth;   // the calibrated cameras, a COLMAP text model
  // A config to read after configs/ring.ini: the calibrated camera, every
  // pair matched, a free network with the significant additional
  // parameters, a Poisson mesh and two small renders.
  std::string config;
};
TempleSetup TempleConfigFixture();

// `bayon pipeline` on temple-ring into `workspace`: configs/ring.ini, the
// setup's config, then `more_configs`, on 2 threads.
std::vector<std::string> TemplePipelineCommand(
    const TempleSetup& setup,
    const std::string& workspace,
    const std::vector<std::string>& more_configs = {});

// The workspace `bayon pipeline` makes of temple-ring with configs/ring.ini
// and that config (about 60 s on 2 cores), with `bayon evaluate`'s
// evaluation.json against the truth.
std::string TemplePipelineWorkspace();

}  // namespace testing
}  // namespace bayon
