// SPDX-License-Identifier: BSD-3-Clause
//
// ../shared/data/temple-ring as the end-to-end tests share it (built once per
// build of bayon, see SharedFixture).
#pragma once

#include <string>
#include <vector>

namespace bayon {
namespace testing {

// Whether these tests (and so the bayon they run) are built with
// AddressSanitizer.
bool SanitizedBuild();

struct TempleSetup {
  // The photographs (never written): all 16, or in a sanitizer build an arc
  // of 8 consecutive stations (see kSanitizerArc in temple_fixture.cc).
  std::string images;
  int num_images = 0;
  std::string truth;  // the calibrated cameras, a COLMAP text model
  // A config to read after configs/ring.ini: the calibrated camera, every
  // pair matched, a free network with the significant additional
  // parameters, depth maps at half size, a Poisson mesh and two small
  // renders.
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

// The one run of stock COLMAP on the temple ring that the tests share:
// `bayon compare_colmap` beside a copy of TemplePipelineWorkspace(), on one
// thread so that the matcher's RANSAC, and so the tracks, are the same in
// every run (feature_extractor with one SIMPLE_RADIAL camera, SIFT on the
// CPU, exhaustive_matcher, mapper).
struct TempleColmap {
  std::string workspace;  // the copy, with colmap/ made by compare_colmap
  std::string database;   // stock COLMAP's database.db in it
  std::string model;      // the mapper's largest model (binary)
  std::string output;     // compare_colmap's output
  // Content hashes of the workspace's database and of its adjusted model
  // before compare_colmap ran, one file a line.
  std::string database_digest;
  std::string adjusted_digest;
};
TempleColmap TempleColmapFixture();

// Every file's name and content hash under a folder, one per line.
std::string TreeDigest(const std::string& path);

}  // namespace testing
}  // namespace bayon
