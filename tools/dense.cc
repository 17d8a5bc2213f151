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

int RunDense(int argc, char** argv) {
  OrientedInput in;
  std::string output_path, fused_path, report_path, log_path;
  bool overwrite = false;
  DenseOptions options;
  std::string mode = "multiview";
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
  app.add_option("--mode", mode, "multiview (depth maps) or paper")
      ->transform(CLI::IsMember({"multiview", "paper"}));
  app.add_option("--max_image_size",
                 options.max_image_size,
                 "multiview: depth maps of the photographs shrunk by a whole "
                 "factor to this longer side at most, px");
  app.add_option("--num_source_views",
                 options.num_source_views,
                 "multiview: source views per master (smallest angle at "
                 "what it looks at, from --min_triangulation_angle_deg)");
  app.add_option("--min_triangulation_angle_deg",
                 options.min_triangulation_angle_deg,
                 "multiview: smallest angle between master and source rays");
  app.add_option("--patch_match_window_radius",
                 options.patch_match.window_radius,
                 "multiview: correlation window radius, depth-map px");
  app.add_option("--patch_match_window_step",
                 options.patch_match.window_step,
                 "multiview: every n-th pixel of the window");
  app.add_option("--patch_match_iterations",
                 options.patch_match.num_iterations,
                 "multiview: red-black propagation iterations per level");
  app.add_option("--patch_match_levels",
                 options.patch_match.num_levels,
                 "multiview: coarse-to-fine levels of halved size (1: the "
                 "working size alone), each level's planes starting the next");
  app.add_option("--patch_match_candidates",
                 options.patch_match.num_propagation_candidates,
                 "multiview: neighbours' planes scored per pixel (the "
                 "best-matched of 8)");
  app.add_option("--patch_match_best_views",
                 options.patch_match.best_views,
                 "multiview: a plane's cost over its best n views");
  app.add_option("--edge_margin_px",
                 options.fusion.edge_margin_px,
                 "multiview: depth-map pixels this near an area without "
                 "depth are not fused (against edge fattening; 0: off)");
  app.add_option("--min_consistent_views",
                 options.fusion.min_consistent_views,
                 "multiview: other depth maps that must agree with a pixel");
  app.add_option("--max_depth_error_px",
                 options.fusion.max_depth_error_px,
                 "multiview: agreement in depth, pixel footprints (depth / "
                 "focal length) of the depth map compared with");
  app.add_option("--max_normal_error_deg",
                 options.fusion.max_normal_error_deg,
                 "multiview: agreement in normal, degrees");
  app.add_option("--max_cost",
                 options.fusion.max_cost,
                 "multiview: largest matching cost (1 - NCC) fused");
  app.add_option("--add_unmodelled_sigma",
                 options.add_unmodelled_sigma,
                 "Add the errors MPGC's model leaves out, estimated from the "
                 "cloud's scatter about its local surface, to the points' "
                 "sigmas in quadrature");
  app.add_option("--refine",
                 options.refine,
                 "multiview: MPGC for every fused point (0: the fused points, "
                 "without covariance)");
  app.add_option("--max_refine_shift_gsd",
                 options.max_refine_shift_gsd,
                 "multiview: reject points MPGC moves further, depth-map "
                 "GSDs");
  app.add_option("--highpass_sigma_px",
                 options.highpass_sigma_px,
                 "Matching on grey values minus their Gaussian blur of this "
                 "sigma, px (0 = off): different light between photographs");
  app.add_option("--num_masters",
                 options.num_masters,
                 "Master images (0: every one, multiview; 5, paper)");
  app.add_option("--master_names",
                 options.master_names,
                 "Master images by name, comma-separated (overrides "
                 "--num_masters)")
      ->delimiter(',');
  app.add_option("--num_search_images",
                 options.num_search_images,
                 "Search images per master (nearest viewing directions)");
  app.add_option("--max_search_angle_deg",
                 options.max_search_angle_deg,
                 "Largest angle between master and search directions");
  app.add_option("--cell_size",
                 options.cell_size,
                 "Dense pattern: one Moravec point per cell of this side, px");
  app.add_option("--min_interest",
                 options.min_interest,
                 "Smallest Moravec interest of a cell's point");
  app.add_option("--coarse_step",
                 options.coarse_step,
                 "Coarse cells (full depth range): every n-th in x and y");
  app.add_option("--band_tolerance",
                 options.band_tolerance,
                 "Band beyond the coarse points' depths, share of the depth");
  app.add_option("--band_radius_cells",
                 options.band_radius_cells,
                 "Coarse cells around a cell that bound its band");
  app.add_option("--min_depth",
                 options.min_depth,
                 "Depth range when the model has too few sparse points");
  app.add_option("--max_depth", options.max_depth, "(see --min_depth)");
  app.add_option("--depth_margin",
                 options.depth_margin,
                 "Widening of the sparse points' depth range, share");
  app.add_option("--window_radius",
                 options.search.window_radius,
                 "Correlation window along the ray: radius, px");
  app.add_option("--search_step_px",
                 options.search.step_px,
                 "Approximations: largest epipolar step between ray samples");
  app.add_option("--search_stride",
                 options.search.stride,
                 "Approximations: every n-th ray sample first, then around "
                 "the best peaks (1: every sample)");
  app.add_option("--min_ncc",
                 options.search.min_ncc,
                 "Smallest mean correlation of an approximation");
  app.add_option("--min_peak_margin",
                 options.min_peak_margin,
                 "Approximations: best minus second peak along the ray");
  app.add_option("--min_view_ncc",
                 options.min_view_ncc,
                 "Views correlating less at the approximation stay out of "
                 "the point's MPGC");
  app.add_option("--num_ray_views",
                 options.num_ray_views,
                 "Approximations: search in the nearest n search images");
  app.add_option("--best_views",
                 options.search.best_views,
                 "Approximations: score of the best n views (0 = all)");
  app.add_option(
      "--patch_radius", options.mpgc.lsm.patch_radius, "MPGC patch radius, px");
  app.add_option("--min_template_stddev",
                 options.mpgc.lsm.min_template_stddev,
                 "paper: MPGC matches master patches with this contrast at "
                 "least (flat_patch), grey values");
  app.add_option("--refine_min_template_stddev",
                 options.refine_min_template_stddev,
                 "multiview: the same for the refinement of fused points");
  app.add_option("--min_correlation",
                 options.mpgc.min_correlation,
                 "MPGC: search patches correlating less are dropped");
  app.add_option("--min_search_views",
                 options.mpgc.min_search_views,
                 "MPGC: fewest search images a point keeps");
  app.add_option("--geometric_sigma_px",
                 options.mpgc.geometric_sigma_px,
                 "MPGC: a priori sigma of the collinearity conditions, px");
  app.add_option("--convergence_px",
                 options.mpgc.convergence_px,
                 "MPGC: converged when no patch centre moves more, px");
  app.add_option("--convergence_sigma",
                 options.mpgc.convergence_sigma,
                 "MPGC: converged also when a step moves the solution by "
                 "less than this many standard deviations (0: off)");
  app.add_option("--max_iterations",
                 options.mpgc.max_iterations,
                 "MPGC: most iterations per solution");
  app.add_option("--max_shift_px",
                 options.mpgc.max_shift_px,
                 "MPGC: largest move of a patch from its approximation");
  app.add_option("--max_sigma_gsd",
                 options.max_sigma_gsd,
                 "Reject points with a larger sigma along the master ray, "
                 "in ground sampling distances");
  app.add_option("--off_surface_gsd",
                 options.off_surface_gsd,
                 "Reject points off the plane of their neighbours by more "
                 "than this many GSDs");
  app.add_option("--min_neighbors",
                 options.min_neighbors,
                 "Reject points with fewer accepted neighbours (isolated)");
  app.add_option("--surface_radius_cells",
                 options.surface_radius_cells,
                 "Neighbours of the off-surface test: cells around");
  app.add_option("--max_growth_passes",
                 options.max_growth_passes,
                 "Region growing: passes of MPGC from the surface of the "
                 "accepted neighbours (0 = off)");
  app.add_option("--growth_min_search_views",
                 options.growth_min_search_views,
                 "Region growing: search images a grown point needs");
  app.add_option("--num_threads", options.num_threads, "-1 = all cores");
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
  options.mode = mode == "paper" ? DenseMode::kPaper : DenseMode::kMultiView;
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
