// SPDX-License-Identifier: BSD-3-Clause
//
// `bayon evaluate`: every product of a run against the truth
// (ext/eval/evaluation.h).
#include "ext/core/file_util.h"
#include "ext/eval/evaluation.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <cstdio>

namespace bayon {

int RunEvaluate(int argc, char** argv) {
  EvaluationOptions o;
  std::string output_path;
  CommandLine command(
      "evaluate",
      "Compare results with the ground truth: a sparse model (registered "
      "images, camera centre and rotation errors after a 7-parameter "
      "similarity, calibration per parameter, 3D points against the true "
      "surface), a dense cloud and a mesh (accuracy, completeness over the "
      "visible true surface, topology) and a textured model (PSNR and SSIM "
      "of renders from held-out viewpoints), and a database's pair "
      "orientations (rotation and base direction errors). Prints tables, "
      "writes JSON.");
  CLI::App& app = command.app();
  app.add_option("--ground_truth_path",
                 o.ground_truth_path,
                 "True model folder, or a synthetic workspace's gt/ folder "
                 "(required but for silhouettes)");
  app.add_option("--input_path", o.input_path, "Sparse model to evaluate");
  app.add_option("--calibration_path",
                 o.calibration_path,
                 "calibration.json of the model (default: the one beside it)");
  app.add_option("--database_path",
                 o.database_path,
                 "Database whose pair orientations (`bayon relative`) to "
                 "evaluate");
  app.add_option("--adjacent_pairs",
                 o.adjacent_pairs,
                 "With --database_path, 1: only neighbouring images in the "
                 "database's order, the last with the first (a ring)");
  app.add_option("--cloud_path", o.cloud_path, "Dense cloud (PLY) to evaluate");
  app.add_option("--cloud_errors_path",
                 o.cloud_errors_path,
                 "Write the cloud, in the truth's frame, with each point's "
                 "distance to the true surface (PLY attribute distance_m)");
  app.add_option("--edit_input_path",
                 o.edit_input_path,
                 "The cloud before `bayon edit`, with blunders flagged "
                 "(`bayon synth_cloud`); --cloud_path is the edited one: "
                 "blunders and good points removed, and the RMS of the "
                 "kept points against the blunder-free input's");
  app.add_option("--off_surface_m",
                 o.off_surface_m,
                 "With --edit_input_path: unflagged points farther than this "
                 "from the truth (the input's own blunders) are also counted "
                 "apart");
  app.add_option("--mesh_path", o.mesh_path, "Mesh (PLY) to evaluate");
  app.add_option("--textured_mesh_path",
                 o.textured_mesh_path,
                 "Textured model (PLY with texcoord and a TextureFile "
                 "comment, or per-vertex colours)");
  app.add_option("--texture_path",
                 o.texture_path,
                 "Its texture atlas (default: the PLY's TextureFile)");
  app.add_option("--surface_path",
                 o.surface_path,
                 "True surface (default: <ground truth>/surface.ply)");
  app.add_option("--heldout_path",
                 o.heldout_path,
                 "Held-out viewpoints (default: <ground truth>/heldout)");
  app.add_option("--gsd_m",
                 o.gsd_m,
                 "Ground sampling distance (default: from synth.json)");
  app.add_option("--completeness_threshold_m",
                 o.completeness_threshold_m,
                 "Distance within which the truth counts as reached; 0: "
                 "--completeness_threshold_gsd GSDs");
  app.add_option("--completeness_threshold_gsd",
                 o.completeness_threshold_gsd,
                 "The same in GSDs");
  app.add_option("--num_samples",
                 o.num_samples,
                 "Samples of the true surface and of meshes");
  app.add_option("--render_path",
                 o.render_path,
                 "Write the renders of the texture evaluation here");
  app.add_option("--silhouette_image_path",
                 o.silhouette_image_path,
                 "Photographs of an object on a dark background: --mesh_path "
                 "carried into them through --input_path's cameras, its "
                 "silhouette's IoU with the object (no ground truth needed)");
  app.add_option("--silhouette_threshold",
                 o.silhouette.grey_threshold,
                 "Silhouettes: grey value above which a pixel is the object's");
  app.add_option("--silhouette_mask_path",
                 o.silhouette.mask_dir,
                 "Silhouettes: write the masks here (white both, red model "
                 "only, blue photograph only)");
  app.add_option("--image_path",
                 o.image_path,
                 "Photographs the textured model (--textured_mesh_path) was "
                 "not made from (leave one out): it is rendered through "
                 "their cameras (--input_path) and compared with them");
  app.add_option("--image_names", o.image_names, "Those photographs' names")
      ->delimiter(',');
  app.add_option("--output_path", output_path, "Write the report as JSON here");
  app.add_option(
      "--align", o.align, "1: fit a similarity first; 0: both share a datum");
  app.add_option("--label", o.label, "Name of the model in the tables");
  app.add_option("--num_threads", o.num_threads, "Threads (-1: all cores)");
  if (!command.Parse(argc, argv)) return 0;

  const nlohmann::ordered_json report = RunEvaluation(o, stdout);
  if (!output_path.empty()) {
    WriteFileAtomically(output_path, report.dump(2) + "\n");
  }
  return 0;
}

}  // namespace bayon
