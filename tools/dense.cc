// SPDX-License-Identifier: BSD-3-Clause
#include "ext/dense/dense.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/georef/crs.h"
#include "ext/image/image_io.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace bayon {
namespace {

// The flags of the nested options before they took their dotted names,
// still accepted (configs, scripts): old name -> name.
const std::map<std::string, std::string> kFlagsBefore = {
    {"patch_match_window_radius", "patch_match.window_radius"},
    {"patch_match_window_step", "patch_match.window_step"},
    {"patch_match_iterations", "patch_match.num_iterations"},
    {"patch_match_levels", "patch_match.num_levels"},
    {"patch_match_candidates", "patch_match.num_propagation_candidates"},
    {"patch_match_best_views", "patch_match.best_views"},
    {"edge_margin_px", "fusion.edge_margin_px"},
    {"min_consistent_views", "fusion.min_consistent_views"},
    {"max_depth_error_px", "fusion.max_depth_error_px"},
    {"max_normal_error_deg", "fusion.max_normal_error_deg"},
    {"max_cost", "fusion.max_cost"},
    {"window_radius", "search.window_radius"},
    {"search_step_px", "search.step_px"},
    {"search_stride", "search.stride"},
    {"min_ncc", "search.min_ncc"},
    {"best_views", "search.best_views"},
    {"patch_radius", "mpgc.lsm.patch_radius"},
    {"min_template_stddev", "mpgc.lsm.min_template_stddev"},
    {"min_correlation", "mpgc.min_correlation"},
    {"min_search_views", "mpgc.min_search_views"},
    {"geometric_sigma_px", "mpgc.geometric_sigma_px"},
    {"convergence_px", "mpgc.convergence_px"},
    {"convergence_sigma", "mpgc.convergence_sigma"},
    {"max_iterations", "mpgc.max_iterations"},
    {"max_shift_px", "mpgc.max_shift_px"}};

}  // namespace

int RunDense(int argc, char** argv) {
  OrientedInput in;
  std::string output_path, fused_path, report_path, log_path;
  bool overwrite = false;
  DenseOptions options;
  CommandLine command(
      "dense",
      "Dense surface points by multi-photo geometrically constrained "
      "matching (MPGC, the Bayon paper's sec. 3.3) on the CPU. multiview "
      "(default): every photograph a master, a depth and a normal for every "
      "pixel by propagating plane hypotheses (PatchMatch), the depth maps "
      "fused where they agree, then MPGC of every fused point against the "
      "views that confirmed it. paper: the paper's sampling, a Moravec "
      "point per cell of a few masters, approximations by correlation along "
      "the master rays, then MPGC. Both give X, Y, Z with their standard "
      "deviations. Writes a PLY (normals, colours, sx sy sz, num_images, "
      "master_id) and COLMAP's fused.ply + fused.ply.vis beside it.");
  CLI::App& app = command.app();
  in.AddOptions(app,
                "Workspace: defaults images/, sparse/adjusted, database.db "
                "and dense/points.ply under it");
  app.add_option("--output_path", output_path, "Dense cloud (PLY)");
  app.add_option("--fused_path",
                 fused_path,
                 "COLMAP fused.ply (default: beside --output_path)");
  app.add_option("--report_path",
                 report_path,
                 "Report as JSON (default: --output_path with .json)");
  command.AddOptions(&options, kFlagsBefore);
  app.add_option("--overwrite", overwrite, "Replace existing output files");
  app.add_option(
      "--log_path", log_path, "Log file (default <workspace>/logs/dense.log)");
  if (!command.Parse(argc, argv)) return 0;
  if (in.ApplyWorkspace() && output_path.empty()) {
    output_path = in.workspace_path + "/dense/points.ply";
  }
  if (in.image_path.empty() || in.input_path.empty() || output_path.empty()) {
    ThrowInputError(
        "give --workspace_path, or --image_path, --input_path and "
        "--output_path");
  }
  options.Check();
  in.Check();
  const fs::path output_folder = fs::absolute(output_path).parent_path();
  if (fused_path.empty()) fused_path = (output_folder / "fused.ply").string();
  if (report_path.empty()) {
    report_path = fs::path(output_path).replace_extension(".json").string();
  }
  for (const std::string& path : {output_path, fused_path, report_path}) {
    CheckOutputPath(path, overwrite);
  }
  CheckOutputPath(fused_path + ".vis", overwrite);
  if (log_path.empty()) {
    log_path = WorkspaceLogPath(WorkspaceOfStageFile(output_path), "dense");
  }
  command.StartLog(log_path);

  const Scene scene = ReadOrientedModel(in.input_path, in.database_path);
  const bool paper = options.mode == DenseMode::kPaper;
  const std::vector<MasterSelection> masters =
      paper ? SelectMasters(scene, options)
            : SelectMultiViewMasters(scene, options);
  for (const MasterSelection& selection : masters) {
    std::string search;
    for (image_t id : selection.search) {
      search += (search.empty() ? "" : ", ") + scene.images.at(id).name;
    }
    LOG(INFO) << "master " << scene.images.at(selection.master).name
              << (paper ? ", search images " : ", source views ") << search;
  }
  // A photograph that cannot be read costs its own part only: the masters
  // match without it, and the summary says so.
  std::map<image_t, std::string> unreadable;
  std::map<image_t, DenseImage> images;
  DenseReport report;
  std::vector<std::vector<image_t>> seen;
  PointCloud cloud;
  if (paper) {
    images = LoadDenseImages(
        scene, masters, in.image_path, options.highpass_sigma_px, &unreadable);
    for (const auto& [id, error] : unreadable) {
      LOG(WARNING) << "left out: " << error;
    }
    cloud = DenseReconstruct(scene, images, masters, options, &report, &seen);
  } else {
    cloud = DenseReconstructMultiView(
        scene, in.image_path, masters, options, &report, &seen, &unreadable);
  }
  if (cloud.empty()) {
    throw RunFailure(StrCat("no dense point was matched in ",
                            masters.size(),
                            " master images:\n",
                            report.Summary()));
  }
  AddUnmodelledSigma(options, &cloud, &report);
  // .vis indices: positions in the model's image list.
  std::map<image_t, uint32_t> index_of;
  for (const auto& [image_id, image] : scene.images) {
    index_of.emplace(image_id, static_cast<uint32_t>(index_of.size()));
  }
  std::vector<std::vector<uint32_t>> visibility;
  visibility.reserve(seen.size());
  for (const std::vector<image_t>& ids : seen) {
    std::vector<uint32_t>& indices = visibility.emplace_back();
    for (image_t id : ids) indices.push_back(index_of.at(id));
  }
  fs::create_directories(output_folder);
  fs::create_directories(fs::absolute(fused_path).parent_path());
  PlyWriteOptions write_options;
  write_options.comment = "bayon dense";
  WritePointCloudPly(cloud, output_path, write_options);
  WriteColmapFusedPly(cloud, fused_path, "bayon dense", &visibility);
  WriteFileAtomically(report_path,
                      DenseReportJson(report, options).dump(2) + "\n");
  CopyGeoFrame(in.input_path, output_folder.string());
  // A picture per master of what became of its cells.
  const fs::path rejects_folder = output_folder / "rejects";
  fs::create_directories(rejects_folder);
  for (const DenseMasterReport& master : report.masters) {
    if (!master.skipped.empty()) continue;
    const cv::Mat color =
        paper ? images.at(master.master).color
              : LoadDenseColor(scene, master.master, in.image_path);
    WriteImage(
        (rejects_folder / fs::path(master.name).stem()).string() + ".png",
        RejectMap(master, color));
  }
  std::string left_out;
  for (const auto& [id, error] : unreadable) {
    left_out += "\n  left out: " + error;
  }
  command.PrintSummary(report.Summary() + left_out + "\n  -> " + output_path +
                       ", " + fused_path + ", " + rejects_folder.string() +
                       "/");
  return 0;
}

}  // namespace bayon
