// SPDX-License-Identifier: BSD-3-Clause
#include "tests/temple_fixture.h"

#include "ext/core/file_util.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace testing {
namespace {

// Throws, so that a broken fixture is not taken for a finished one.
void RunOrThrow(const std::vector<std::string>& args) {
  const CommandResult result = RunBayon(args);
  if (result.exit_code != 0) {
    throw std::runtime_error("bayon " + args[0] + " failed:\n" + result.output);
  }
}

// The sanitizer lane's photographs: 8 consecutive stations of the ring,
// from 138 to 302 degrees about its axis (22 degrees apart, 32 between 0016
// and 0012), five of them upside down. Instrumented pixel loops run 10 to 20
// times slower, and an arc takes every stage through the same code as the
// whole ring (the normal lane runs all 16).
constexpr const char* kSanitizerArc[] = {"templeSR0009.png",
                                         "templeSR0008.png",
                                         "templeSR0007.png",
                                         "templeSR0006.png",
                                         "templeSR0015.png",
                                         "templeSR0016.png",
                                         "templeSR0012.png",
                                         "templeSR0013.png"};

}  // namespace

bool SanitizedBuild() {
#if defined(__SANITIZE_ADDRESS__)
  return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return true;
#endif
#endif
  return false;
}

TempleSetup TempleConfigFixture() {
  TempleSetup setup;
  const std::string data = DataPath("temple-ring");
  const std::string dir =
      SharedFixture("temple_config", [&](const std::string& d) {
        if (SanitizedBuild()) {
          fs::create_directories(d + "/images");
          for (const char* name : kSanitizerArc) {
            fs::copy_file(data + "/" + name, d + "/images/" + name);
          }
        }
        RunOrThrow({"import_ground_truth",
                    "--format",
                    "middlebury",
                    "--input_path",
                    data + "/templeSR_par.txt",
                    "--output_path",
                    d + "/truth"});
        // The truth's one PINHOLE camera: fx, fy, cx, cy.
        std::ifstream cameras(d + "/truth/cameras.txt");
        std::string line;
        while (std::getline(cameras, line) &&
               (line.empty() || line[0] == '#')) {
        }
        std::istringstream fields(line);
        std::string id, model, width, height;
        std::vector<double> params(4);
        fields >> id >> model >> width >> height >> params[0] >> params[1] >>
            params[2] >> params[3];
        if (model != "PINHOLE" || !fields) {
          throw std::runtime_error("temple truth: unexpected camera " + line);
        }
        std::ofstream(d + "/temple.ini")
            << "[import]\ncamera_model = PINHOLE\ncamera_params = "
            << CommaSeparated(params)
            << "\n[match]\npairing = exhaustive\n"
               "[adjust]\ndatum = free\nself_calibration = significant\n"
               // Depth maps at half size (320 x 240): the multiview
               // path of the demo at a quarter of its work (the demo's own
               // figures: scripts/bench.sh dense).
               "[dense]\nmax_image_size = 320\n"
               "[mesh]\nmethod = poisson\n"
               "[render]\nnum_views = 2\nsupersampling = 2\nwidth = 480\n"
               "height = 360\nstereo = anaglyph\n";
      });
  setup.images = SanitizedBuild() ? dir + "/images" : data;
  setup.num_images = SanitizedBuild() ? std::size(kSanitizerArc) : 16;
  setup.truth = dir + "/truth";
  setup.config = dir + "/temple.ini";
  return setup;
}

std::vector<std::string> TemplePipelineCommand(
    const TempleSetup& setup,
    const std::string& workspace,
    const std::vector<std::string>& more_configs) {
  std::vector<std::string> args = {"pipeline",
                                   "--workspace_path",
                                   workspace,
                                   "--image_path",
                                   setup.images,
                                   "--config",
                                   ConfigPath("ring.ini"),
                                   "--config",
                                   setup.config,
                                   "--num_threads",
                                   "2"};
  for (const std::string& config : more_configs) {
    args.push_back("--config");
    args.push_back(config);
  }
  return args;
}

std::string TemplePipelineWorkspace() {
  const TempleSetup setup = TempleConfigFixture();
  const std::string dir =
      SharedFixture("temple_pipeline", [&](const std::string& d) {
        const std::string ws = d + "/ws";
        RunOrThrow(TemplePipelineCommand(setup, ws));
        RunOrThrow({"evaluate",
                    "--input_path",
                    ws + "/sparse/adjusted",
                    "--ground_truth_path",
                    setup.truth,
                    "--output_path",
                    ws + "/evaluation.json"});
      });
  return dir + "/ws";
}

std::string TreeDigest(const std::string& path) {
  std::string digest;
  for (const auto& [name, hash] : HashTree(path)) {
    digest += name + " " + std::to_string(hash) + "\n";
  }
  return digest;
}

TempleColmap TempleColmapFixture() {
  const std::string dir =
      SharedFixture("temple_colmap", [](const std::string& d) {
        const std::string ws = d + "/ws";
        CopyTree(TemplePipelineWorkspace(), ws);
        WriteFileAtomically(d + "/database.digest",
                            TreeDigest(ws + "/database.db"));
        WriteFileAtomically(d + "/adjusted.digest",
                            TreeDigest(ws + "/sparse/adjusted"));
        const CommandResult result = RunBayon({"compare_colmap",
                                               "--workspace_path",
                                               ws,
                                               "--ground_truth_path",
                                               TempleConfigFixture().truth,
                                               "--num_threads",
                                               "1"});
        WriteFileAtomically(d + "/compare.txt", result.output);
        if (result.exit_code != 0) {
          throw std::runtime_error("bayon compare_colmap failed:\n" +
                                   result.output);
        }
      });
  TempleColmap colmap;
  colmap.workspace = dir + "/ws";
  colmap.database = colmap.workspace + "/colmap/database.db";
  const nlohmann::json record = nlohmann::json::parse(
      ReadFileToString(colmap.workspace + "/colmap/colmap.json"));
  colmap.model = colmap.workspace + "/colmap/" +
                 record.at("model_path").get<std::string>();
  colmap.output = ReadFileToString(dir + "/compare.txt");
  colmap.database_digest = ReadFileToString(dir + "/database.digest");
  colmap.adjusted_digest = ReadFileToString(dir + "/adjusted.digest");
  return colmap;
}

}  // namespace testing
}  // namespace bayon
