// SPDX-License-Identifier: BSD-3-Clause
#include "tools/commands.h"

namespace bayon {

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"import",
       RunImport,
       "create camera and image rows for a folder of images"},
      {"import_bal",
       RunImportBal,
       "a Bundle Adjustment in the Large problem as a workspace"},
      {"import_ground_truth",
       RunImportGroundTruth,
       "benchmark cameras (Middlebury, Strecha) as a COLMAP model"},
      {"synth", RunSynth, "make a synthetic workspace with known truth"},
      {"synth_cloud",
       RunSynthCloud,
       "make a synthetic dense cloud with known surface and blunders"},
      {"interior",
       RunInterior,
       "image frames: pixel pitch, or virtual fiducials of film scans"},
      {"features",
       RunFeatures,
       "Moravec interest points for every image of a database"},
      {"match", RunMatch, "conjugate points by correlation and relaxation"},
      {"relative",
       RunRelative,
       "relative orientation of matched pairs (DRT, LMedS, coplanarity)"},
      {"disparity",
       RunDisparity,
       "disparity surfaces: where to search along the epipolar lines"},
      {"tiepoints",
       RunTiePoints,
       "multi-image tie points by least-squares matching"},
      {"targets",
       RunTargets,
       "find and measure coded targets; print a sheet of them"},
      {"import_control",
       RunImportControl,
       "ground control from OpenDroneMap, Metashape or CSV, through PROJ"},
      {"refine_keypoints",
       RunRefineKeypoints,
       "least-squares refinement of a COLMAP database's matched keypoints"},
      {"dense",
       RunDense,
       "dense surface points by MPGC, with their precision (CPU)"},
      {"edit",
       RunEdit,
       "remove blunders from a dense cloud (local surface fitting)"},
      {"strip",
       RunStripCommand,
       "approximations: chained models, strip adjustment, similarity"},
      {"adjust",
       RunAdjust,
       "self-calibrating bundle adjustment with statistics"},
      {"mesh",
       RunMesh,
       "triangulate a dense cloud (cylinder 2.5D Delaunay, PCL, CGAL)"},
      {"texture",
       RunTexture,
       "view-dependent texture mapping; OBJ, PLY, VRML2 and glTF models"},
      {"viewer",
       RunViewer,
       "a textured model (.glb) as a self-contained web page (three.js)"},
      {"render",
       RunRender,
       "wireframe, shaded, textured and stereo images of a model"},
      {"pipeline",
       RunPipeline,
       "every stage in order, from photographs to the textured model"},
      {"compare_colmap",
       RunCompareColmap,
       "stock COLMAP on the same images, side by side with bayon"},
      {"report",
       RunReport,
       "a workspace's results as one self-contained report.html"},
      {"model_converter",
       RunModelConverter,
       "convert a sparse model between BIN, TXT and PLY"},
      {"evaluate", RunEvaluate, "compare a result with the ground truth"},
  };
  return commands;
}

const Command* FindCommand(const std::string& name) {
  for (const Command& command : Commands()) {
    if (name == command.name) return &command;
  }
  return nullptr;
}

}  // namespace bayon
