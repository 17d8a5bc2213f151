// SPDX-License-Identifier: BSD-3-Clause
#include "tests/tower_fixture.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/testing.h"

namespace bayon {
namespace testing {
namespace {

void RunOrFail(const std::vector<std::string>& args) {
  const CommandResult result = RunBayon(args);
  ASSERT_EQ(result.exit_code, 0) << result.output;
}

}  // namespace

std::string OrientedTowerFixture() {
  return SharedFixture("disparity_tower", [](const std::string& dir) {
    const std::string ws = dir + "/ws";
    RunOrFail({"synth", "--scene",          "tower", "--output_path",
               ws,      "--num_views",      "16",    "--image_width",
               "1200",  "--mesh_spacing_m", "0.04",  "--texel_size_m",
               "0.01",  "--supersampling",  "1",     "--num_heldout_views",
               "0",     "--seed",           "2",     "--num_threads",
               "2"});
    const std::string db = ws + "/database.db";
    RunOrFail(
        {"features", "--database_path", db, "--image_path", ws + "/images"});
    RunOrFail({"match",
               "--database_path",
               db,
               "--image_path",
               ws + "/images",
               "--pairing",
               "ring",
               "--num_neighbors",
               "1",
               "--num_threads",
               "2"});
    RunOrFail({"relative", "--database_path", db, "--num_threads", "2"});
  });
}

}  // namespace testing
}  // namespace bayon
