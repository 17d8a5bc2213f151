// SPDX-License-Identifier: BSD-3-Clause
#include "ext/adjustment/adjustment.h"
#include "ext/adjustment/adjustment_input.h"
#include "ext/adjustment/adjustment_output.h"
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/georef/crs.h"
#include "tools/command.h"
#include "tools/commands.h"

#include <filesystem>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace bayon {

int RunAdjust(int argc, char** argv) {
  std::string database_path, input_path, output_path, control_path, log_path;
  std::string datum = "auto", self_calibration = "significant";
  std::string camera_model = "brown_beyer", blunders = "robust";
  std::string tie_points = "auto";
  bool overwrite = false;
  AdjustmentInputOptions input_options;
  AdjustmentOptions options;
  CommandLine command(
      "adjust",
      "Self-calibrating bundle adjustment of a sparse model (bayon strip's or "
      "stock colmap mapper's, hosted in its database) with control points, "
      "the minimum datum or a free network; Brown/Beyer additional "
      "parameters selected by significance, blunders by data snooping, the "
      "precision of every point and orientation. Writes a COLMAP model, "
      "calibration.json, adjustment.json and adjustment.txt.");
  CLI::App& app = command.app();
  app.add_option("--database_path",
                 database_path,
                 "COLMAP database with the model's keypoints (read only)")
      ->required();
  app.add_option("--input_path", input_path, "Input sparse model folder")
      ->required();
  app.add_option("--output_path",
                 output_path,
                 "Output model folder (e.g. sparse/adjusted)")
      ->required();
  app.add_option("--control_path",
                 control_path,
                 "control/ folder: points.txt, observations.txt, "
                 "distances.txt");
  app.add_option("--overwrite", overwrite, "Replace an existing output folder");
  app.add_option("--datum",
                 datum,
                 "auto (control with 3+ control points, else minimum with a "
                 "vertical bar, else free), control, minimum or free")
      ->transform(CLI::IsMember({"auto", "control", "minimum", "free"}));
  app.add_option("--upright",
                 input_options.datum.upright,
                 "Free network: 1 = z along the photographs' up direction, "
                 "origin at the object's centre (0 = the relative "
                 "orientation's coordinates)");
  app.add_option("--datum_point",
                 input_options.datum.datum_point,
                 "Minimum datum: the point that fixes the rotation about the "
                 "vertical (default: the control point farthest from the "
                 "bar)");
  app.add_option("--self_calibration",
                 self_calibration,
                 "none, all, significant (t-test, stepwise), or a list of "
                 "parameters, e.g. dc,dx0,dy0,K1");
  app.add_option("--camera_model",
                 camera_model,
                 "brown_beyer (the ten additional parameters) or colmap "
                 "(the model's own COLMAP cameras)")
      ->transform(CLI::IsMember({"brown_beyer", "colmap"}));
  app.add_option("--image_sigma_px",
                 input_options.image_sigma_px,
                 "A priori standard deviation of an image coordinate, px");
  app.add_option("--tie_points",
                 tie_points,
                 "Tie observations: model (the model's tracks), alsm (bayon "
                 "tiepoints' least-squares tie points), both; auto: both "
                 "where the database has tie points, else model")
      ->transform(CLI::IsMember({"auto", "alsm", "model", "both"}));
  app.add_option("--min_tie_sigma_px",
                 input_options.min_tie_sigma_px,
                 "Tie points: floor of the least-squares standard deviations, "
                 "px");
  app.add_option("--variance_components",
                 options.variance_components,
                 "1: estimate the precision of each observation group "
                 "(keypoint tracks, tie points, manual measurements) by "
                 "variance component estimation before data snooping");
  app.add_option("--blunder_detection",
                 blunders,
                 "robust (Huber, then data snooping), snooping, or none")
      ->transform(CLI::IsMember({"robust", "snooping", "none"}));
  app.add_option("--critical_value",
                 options.snooping_critical_value,
                 "Data snooping: critical normalised residual (Baarda)");
  app.add_option("--significance_t",
                 options.significance_t,
                 "Self-calibration: t-value below which a parameter is "
                 "removed");
  app.add_option("--max_correlation",
                 options.max_correlation,
                 "Correlations above this are flagged");
  app.add_option("--max_exterior_correlation",
                 options.max_exterior_correlation,
                 "Self-calibration (significant): a parameter correlated "
                 "above this with an exterior orientation is not "
                 "determinable and removed (the interior orientation only "
                 "when also imprecise, --max_interior_sigma)");
  app.add_option("--max_interior_sigma",
                 options.max_interior_sigma,
                 "Self-calibration (significant): the interior orientation "
                 "is removed for such a correlation only with a standard "
                 "deviation above this share of the image diagonal");
  app.add_option("--two_steps",
                 options.two_steps,
                 "1: adjust without self-calibration first (the paper's "
                 "first step)");
  app.add_option("--max_num_iterations",
                 options.solver.max_num_iterations,
                 "Iterations per solution");
  app.add_option("--num_threads", options.solver.num_threads, "-1: all cores");
  app.add_option("--log_path",
                 log_path,
                 "Log file (default <output_path>/../../logs/adjust.log)");
  if (!command.Parse(argc, argv)) return 0;

  input_options.datum.datum = datum == "control"   ? DatumType::kControl
                              : datum == "minimum" ? DatumType::kMinimum
                              : datum == "free"    ? DatumType::kFree
                                                   : DatumType::kAuto;
  input_options.tie_points = TiePointSourceFromName(tie_points);
  input_options.camera_model = camera_model == "colmap"
                                   ? CameraModelChoice::kColmap
                                   : CameraModelChoice::kBrownBeyer;
  if (self_calibration == "none") {
    options.self_calibration = SelfCalibration::kNone;
  } else if (self_calibration == "all") {
    options.self_calibration = SelfCalibration::kAll;
  } else if (self_calibration == "significant") {
    options.self_calibration = SelfCalibration::kSignificant;
  } else {
    options.self_calibration = SelfCalibration::kList;
    options.parameter_list = SplitList(self_calibration);
  }
  options.blunder_detection = blunders == "none" ? BlunderDetection::kNone
                              : blunders == "snooping"
                                  ? BlunderDetection::kSnooping
                                  : BlunderDetection::kRobust;
  options.Check();
  input_options.Check();
  CheckOutputPath(output_path, overwrite);
  // The control's frame (import_control) goes with the model: read before
  // the work, not after it.
  const std::optional<GeoFrame> frame =
      control_path.empty() ? std::nullopt : ReadModelGeoFrame(control_path);
  if (log_path.empty()) {
    // sparse/<name> sits two levels below the workspace.
    const fs::path workspace =
        fs::path(output_path).parent_path().parent_path();
    log_path = WorkspaceLogPath(workspace.empty() ? "." : workspace.string(),
                                "adjust");
  }

  AdjustmentInput input = LoadAdjustmentInput(
      database_path, input_path, control_path, input_options);
  command.StartLog(log_path);
  const AdjustmentResult result = RunAdjustment(options, &input.block);
  AdjustmentRunInfo info;
  info.database_path = database_path;
  info.input_path = input_path;
  info.control_path = control_path;
  if (frame) info.georeference_json = GeoFrameJson(*frame);
  info.self_calibration = self_calibration;
  info.blunder_detection = blunders;
  const AdjustmentOutputs outputs =
      MakeAdjustmentOutputs(input, result, options, info);
  WriteAdjustmentOutputs(outputs, output_path, overwrite);

  const AdjustmentPrecision& p = result.precision;
  // Parameter names once each, however many cameras share them.
  std::string parameters;
  std::set<std::string> seen;
  for (const ParameterEstimate& e : result.final_parameters) {
    if (!seen.insert(e.name).second) continue;
    parameters += (parameters.empty() ? "" : ",") + e.name;
  }
  command.PrintSummary(StrCat(
      DatumTypeName(input.datum.type),
      " datum, ",
      input.block.images.size(),
      " images; n = ",
      p.num_observations,
      ", u = ",
      p.num_unknowns,
      ", r = ",
      p.redundancy,
      ", r/n = ",
      static_cast<double>(p.redundancy) / p.num_observations,
      ", sigma0 = ",
      p.sigma0,
      " px; parameters ",
      parameters.empty() ? "none" : parameters,
      " (",
      input.block.cameras.size(),
      input.block.cameras.size() == 1 ? " camera); " : " cameras); ",
      result.rejected.size(),
      " observations rejected",
      outputs.check_rms_m > 0
          ? StrCat("; check points RMS ", 1000 * outputs.check_rms_m, " mm")
          : std::string(),
      "; ",
      result.total_time_s,
      " s -> ",
      output_path));
  return 0;
}

}  // namespace bayon
