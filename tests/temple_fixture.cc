// SPDX-License-Identifier: BSD-3-Clause
#include "tests/temple_fixture.h"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "tests/testing.h"

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

}  // namespace

TempleSetup TempleConfigFixture() {
  TempleSetup setup;
  setup.images = DataPath("temple-ring");
  const std::string dir =
      SharedFixture("temple_config", [&](const std::string& d) {
        RunOrThrow({"import_ground_truth",
                    "--format",
                    "middlebury",
                    "--input_path",
                    setup.images + "/templeSR_par.txt",
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
               "[mesh]\nmethod = poisson\n"
               "[render]\nnum_views = 2\nsupersampling = 2\nwidth = 480\n"
               "height = 360\nstereo = anaglyph\n";
      });
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

}  // namespace testing
}  // namespace bayon
