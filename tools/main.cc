// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon <command> [options]`: dispatch, logging set-up, and the exit codes
// every command shares: 0 success, 1 ran but produced nothing usable,
// 2 bad input (one line naming what is wrong).
#include "ext/core/errors.h"
#include "tools/commands.h"

#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include <algorithm>
#include <cstring>
#include <iostream>
#include <string>

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* description;
};

// In the order of the processing chain (architecture.md).
constexpr Command kCommands[] = {
    {"import",
     bayon::RunImport,
     "create camera and image rows for a folder of images"},
    {"import_bal",
     bayon::RunImportBal,
     "a Bundle Adjustment in the Large problem as a workspace"},
    {"import_ground_truth",
     bayon::RunImportGroundTruth,
     "benchmark cameras (Middlebury, Strecha) as a COLMAP model"},
    {"synth", bayon::RunSynth, "make a synthetic workspace with known truth"},
    {"synth_cloud",
     bayon::RunSynthCloud,
     "make a synthetic dense cloud with known surface and blunders"},
    {"interior",
     bayon::RunInterior,
     "image frames: pixel pitch, or virtual fiducials of film scans"},
    {"features",
     bayon::RunFeatures,
     "Moravec interest points for every image of a database"},
    {"match",
     bayon::RunMatch,
     "conjugate points by correlation and relaxation"},
    {"relative",
     bayon::RunRelative,
     "relative orientation of matched pairs (DRT, LMedS, coplanarity)"},
    {"disparity",
     bayon::RunDisparity,
     "disparity surfaces: where to search along the epipolar lines"},
    {"tiepoints",
     bayon::RunTiePoints,
     "multi-image tie points by least-squares matching"},
    {"targets",
     bayon::RunTargets,
     "find and measure coded targets; print a sheet of them"},
    {"import_control",
     bayon::RunImportControl,
     "ground control from OpenDroneMap, Metashape or CSV, through PROJ"},
    {"refine_keypoints",
     bayon::RunRefineKeypoints,
     "least-squares refinement of a COLMAP database's matched keypoints"},
    {"dense",
     bayon::RunDense,
     "dense surface points by MPGC, with their precision (CPU)"},
    {"edit",
     bayon::RunEdit,
     "remove blunders from a dense cloud (local surface fitting)"},
    {"strip",
     bayon::RunStripCommand,
     "approximations: chained models, strip adjustment, similarity"},
    {"adjust",
     bayon::RunAdjust,
     "self-calibrating bundle adjustment with statistics"},
    {"mesh",
     bayon::RunMesh,
     "triangulate a dense cloud (cylinder 2.5D Delaunay, PCL, CGAL)"},
    {"texture",
     bayon::RunTexture,
     "view-dependent texture mapping; OBJ, PLY, VRML2 and glTF models"},
    {"viewer",
     bayon::RunViewer,
     "a textured model (.glb) as a self-contained web page (three.js)"},
    {"render",
     bayon::RunRender,
     "wireframe, shaded, textured and stereo images of a model"},
    {"pipeline",
     bayon::RunPipeline,
     "every stage in order, from photographs to the textured model"},
    {"compare_colmap",
     bayon::RunCompareColmap,
     "stock COLMAP on the same images, side by side with bayon"},
    {"report",
     bayon::RunReport,
     "a workspace's results as one self-contained report.html"},
    {"model_converter",
     bayon::RunModelConverter,
     "convert a sparse model between BIN, TXT and PLY"},
    {"evaluate", bayon::RunEvaluate, "compare a result with the ground truth"},
};

void PrintUsage() {
  std::cout << "bayon: photogrammetric reconstruction on COLMAP's data\n\n"
               "Usage: bayon <command> [options]   (bayon <command> -h for "
               "its options)\n\nCommands:\n";
  for (const Command& command : kCommands) {
    std::cout << "  " << command.name
              << std::string(
                     22 - std::min<size_t>(20, std::strlen(command.name)), ' ')
              << command.description << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  FLAGS_log_prefix = false;
  FLAGS_colorlogtostderr = false;

  if (argc < 2 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "--help") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  for (const Command& command : kCommands) {
    if (name != command.name) continue;
    try {
      return command.run(argc - 1, argv + 1);
    } catch (const CLI::ParseError& error) {
      std::cerr << "bayon " << name << ": error: " << error.what()
                << " (see bayon " << name << " -h)" << std::endl;
      return 2;
    } catch (const bayon::InputError& error) {
      std::cerr << "bayon " << name << ": error: " << error.what() << std::endl;
      return 2;
    } catch (const bayon::RunFailure& error) {
      std::cerr << "bayon " << name << ": failed: " << error.what()
                << std::endl;
      return 1;
    } catch (const std::exception& error) {
      std::cerr << "bayon " << name << ": internal error: " << error.what()
                << std::endl;
      return 1;
    }
  }
  std::cerr << "bayon: unknown command '" << name
            << "' (bayon -h lists the commands)" << std::endl;
  return 2;
}
