// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_workspace.h"

#include "ext/colmap/bayon_tables.h"
#include "ext/colmap/calibration_json.h"
#include "ext/colmap/control_io.h"
#include "ext/colmap/database.h"
#include "ext/colmap/model_io.h"
#include "ext/colmap/ply_io.h"
#include "ext/core/camera_conversion.h"
#include "ext/core/file_util.h"
#include "ext/core/progress.h"
#include "ext/core/random.h"
#include "ext/image/image_io.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <future>
#include <map>
#include <random>
#include <set>

namespace fs = std::filesystem;

namespace bayon {
namespace {

nlohmann::ordered_json Vector(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// The mesh's faces [first, last) with only the vertices they use.
TriangleMesh SubMesh(const TriangleMesh& mesh, size_t first, size_t last) {
  TriangleMesh part;
  std::vector<int> index(mesh.NumVertices(), -1);
  for (size_t f = first; f < last; ++f) {
    Eigen::Vector3i face;
    for (int k = 0; k < 3; ++k) {
      int& i = index[mesh.faces[f][k]];
      if (i < 0) {
        i = static_cast<int>(part.vertices.positions.size());
        part.vertices.positions.push_back(
            mesh.vertices.positions[mesh.faces[f][k]]);
      }
      face[k] = i;
    }
    part.faces.push_back(face);
  }
  return part;
}

nlohmann::ordered_json OptionsToJson(const TowerSceneOptions& o) {
  nlohmann::ordered_json json;
  json["scene"] = "tower";
  json["seed"] = o.seed;
  json["num_views"] = o.num_views;
  json["tower"] = {{"width_m", o.tower.width_m},
                   {"height_m", o.tower.height_m},
                   {"relief_depth_m", o.tower.relief_depth_m},
                   {"num_tiers", o.tower.num_tiers},
                   {"platform_width_m", o.tower.platform_width_m},
                   {"platform_height_m", o.tower.platform_height_m},
                   {"mesh_spacing_m", o.tower.mesh_spacing_m},
                   {"texel_size_m", o.tower.texel_size_m},
                   {"ground_texel_size_m", o.tower.ground_texel_size_m},
                   {"ground_size_m", o.tower.ground_size_m},
                   {"bar_target_distance_m", o.tower.bar_target_distance_m},
                   {"seed", o.tower.seed}};
  json["camera"] = {{"focal_length_mm", o.camera.focal_length_mm},
                    {"pixel_pitch_mm", o.camera.pixel_pitch_mm},
                    {"width", o.camera.width},
                    {"height", o.camera.height},
                    {"distortion", o.camera.distortion}};
  json["stations"] = {{"min_distance_m", o.min_distance_m},
                      {"max_distance_m", o.max_distance_m},
                      {"min_height_m", o.min_height_m},
                      {"max_height_m", o.max_height_m},
                      {"vertical_pair_height_m", o.vertical_pair_height_m}};
  json["rendering"] = {{"supersampling", o.supersampling},
                       {"noise_sigma", o.noise_sigma},
                       {"jpeg_quality", o.jpeg_quality},
                       {"one_light", o.one_light},
                       {"film_scan", o.film_scan},
                       {"film_margin_mm", o.film_margin_mm},
                       {"film_max_rotation_deg", o.film_max_rotation_deg},
                       {"film_max_shift_mm", o.film_max_shift_mm},
                       {"tone_curve", "sRGB(exposure * radiance), 8 bit"},
                       {"targets", "unlit (retro-reflective)"}};
  json["num_heldout_views"] = o.num_heldout_views;
  json["truth_in_database"] = o.truth_in_database;
  json["control_sigma_m"] = o.control_sigma_m;
  json["control_sigma_px"] = o.control_sigma_px;
  return json;
}

// The photographs into images/, each encoded and written while the next one
// renders (encoding is single-threaded and would leave the other cores
// idle); returns where the targets appear in them.
std::vector<ImageMeasurement> RenderPhotographs(
    const TowerScene& scene,
    const MeshRenderer& renderer,
    const TowerSceneOptions& options,
    const OutputDirectory& output,
    std::vector<double>* render_seconds,
    TowerWorkspaceSummary* summary) {
  const int n = static_cast<int>(scene.stations.size());
  fs::create_directories(output.File("images"));
  std::vector<ImageMeasurement> observations;
  render_seconds->assign(n, 0);
  Progress progress("Rendering photographs", n, "images");
  std::vector<int> params;
  if (options.jpeg_quality > 0) {
    params = {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality};
  }
  std::future<void> writing;
  for (int i = 0; i < n; ++i) {
    RenderResult render;
    cv::Mat photo = RenderTowerPhotograph(scene, renderer, i, options, &render);
    (*render_seconds)[i] = render.stats.seconds;
    summary->render_seconds += render.stats.seconds;
    for (const ImageMeasurement& m : VisibleTargets(scene, i, render)) {
      observations.push_back(m);
    }
    if (writing.valid()) writing.get();
    writing = std::async(
        std::launch::async,
        [&params,
         path = output.File("images/" + scene.stations[i].name),
         photo = std::move(photo)] { WriteImage(path, photo, params); });
    progress.Add();
  }
  if (writing.valid()) writing.get();
  progress.Finish();
  return observations;
}

// The true model into gt/sparse (as COLMAP's model) and gt/calibration.json:
// cameras, poses, and the targets as 3D points observed at their exact image
// positions.
void WriteTrueModel(const TowerScene& scene,
                    const std::vector<ImageMeasurement>& observations,
                    const std::string& gt,
                    TowerWorkspaceSummary* summary) {
  const int n = static_cast<int>(scene.stations.size());
  Scene truth;
  truth.cameras.Set(scene.camera.camera_id, scene.camera);
  std::map<std::string, image_t> image_ids;
  for (int i = 0; i < n; ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.name = scene.stations[i].name;
    image.camera_id = scene.camera.camera_id;
    image.cam_from_world = scene.stations[i].cam_from_world;
    image.frame = scene.stations[i].frame;
    truth.images.Set(image.image_id, image);
    image_ids[image.name] = image.image_id;
  }
  for (const ControlTarget& target : scene.model.targets) {
    std::vector<TrackElement> track;
    for (const ImageMeasurement& m : observations) {
      if (m.point_name != target.name) continue;
      Image& image = truth.images.at(image_ids.at(m.image_name));
      Point2D point;
      point.xy = m.xy;
      image.points2D.push_back(point);
      track.push_back(
          {image.image_id, static_cast<point2D_t>(image.points2D.size() - 1)});
    }
    if (track.empty()) continue;
    const point3D_t id = truth.AddPoint3D(target.center, track);
    truth.points3D.at(id).color = Eigen::Matrix<uint8_t, 3, 1>(255, 255, 255);
  }
  truth.UpdateReprojectionErrors();
  const std::vector<SceneCameraConversion> conversions =
      ConvertSceneCamerasToColmap(&truth);
  std::vector<CalibrationEntry> calibration;
  for (const SceneCameraConversion& conversion : conversions) {
    calibration.push_back(CalibrationEntryFromConversion(conversion));
    summary->colmap_fit_rms_px = conversion.conversion.rms_residual_px;
  }
  WriteModel(truth, gt + "/sparse", ModelFormat::kText);
  WriteCalibrationJson(gt + "/calibration.json", calibration);
}

// Control: exact in gt/control, and as a user would have them in control/
// (surveyed with control_sigma_m, measured with control_sigma_px).
void WriteControl(const TowerScene& scene,
                  const TowerSceneOptions& options,
                  const std::vector<ImageMeasurement>& observations,
                  const std::string& gt,
                  const OutputDirectory& output,
                  TowerWorkspaceSummary* summary) {
  std::vector<ControlPoint> points, user_points;
  std::mt19937 rng(options.seed * 31337u + 1u);
  std::normal_distribution<double> gauss(0, 1);
  int number = 0;
  std::set<std::string> coded;
  std::map<std::string, int> num_seen;
  for (const ImageMeasurement& truth : observations) {
    ++num_seen[truth.point_name];
  }
  for (const ControlTarget& target : scene.model.targets) {
    ControlPoint point;
    point.name = target.name;
    point.xyz = target.center;
    points.push_back(point);
    if (target.on_bar) continue;  // the bar gives scale and vertical only
    // Coded targets are found by `bayon targets`, not measured by hand:
    // their image measurements stay in gt/control. A third of them (codes
    // divisible by 3) seen in three photographs or more were surveyed:
    // their coordinates are in control/, so they are control or check
    // points; the others are tie points.
    if (target.code >= 0) {
      coded.insert(target.name);
      if (target.code % 3 != 0 || num_seen[target.name] < 3) continue;
    }
    ControlPoint user = point;
    user.sigma.setConstant(options.control_sigma_m);
    user.xyz += options.control_sigma_m * RandomVector<3>(gauss, rng);
    user.type = ++number % 3 == 0 ? ControlPointType::kCheck
                                  : ControlPointType::kControl;
    user_points.push_back(user);
  }
  std::vector<ImageMeasurement> user_observations;
  for (const ImageMeasurement& truth : observations) {
    if (coded.count(truth.point_name) > 0) continue;
    ImageMeasurement& m = user_observations.emplace_back(truth);
    m.xy += options.control_sigma_px * RandomVector<2>(gauss, rng);
    m.sigma_px = options.control_sigma_px;
  }
  DistanceObservation bar;
  bar.name1 = scene.model.bar_bottom_name;
  bar.name2 = scene.model.bar_top_name;
  bar.distance_m = options.tower.bar_target_distance_m;
  bar.vertical = true;
  fs::create_directories(gt + "/control");
  WriteControlPoints(gt + "/control/points.txt", points);
  WriteImageMeasurements(gt + "/control/observations.txt", observations);
  WriteDistances(gt + "/control/distances.txt", {bar});
  fs::create_directories(output.File("control"));
  bar.sigma_m = 0.0005;
  WriteControlPoints(output.File("control/points.txt"), user_points);
  WriteImageMeasurements(output.File("control/observations.txt"),
                         user_observations);
  WriteDistances(output.File("control/distances.txt"), {bar});
  summary->num_targets = static_cast<int>(points.size());
  summary->num_observations = static_cast<int>(observations.size());
}

// Held-out viewpoints into gt/heldout: the digital camera's COLMAP fit.
void WriteHeldout(const TowerScene& scene,
                  const TowerSceneOptions& options,
                  const std::string& gt) {
  Scene heldout;
  Camera camera = SyntheticCamera(options.camera);
  heldout.cameras.Set(camera.camera_id, camera);
  for (size_t k = 0; k < scene.heldout_cam_from_world.size(); ++k) {
    Image image;
    image.image_id = static_cast<image_t>(k + 1);
    char name[48];
    std::snprintf(name, sizeof(name), "heldout_%02d.png", int(k + 1));
    image.name = name;
    image.camera_id = camera.camera_id;
    image.cam_from_world = scene.heldout_cam_from_world[k];
    heldout.images.Set(image.image_id, image);
  }
  ConvertSceneCamerasToColmap(&heldout);
  fs::create_directories(gt + "/heldout");
  WriteModel(heldout, gt + "/heldout", ModelFormat::kText);
}

// The image frames (the interior orientation in the narrow sense) into
// gt/interior.json; returns the mean ground sampling distance at the tower.
double WriteInteriorTruth(const TowerScene& scene,
                          const TowerSceneOptions& options,
                          const std::string& gt) {
  const int n = static_cast<int>(scene.stations.size());
  nlohmann::ordered_json interior;
  interior["format"] = "bayon-interior-truth";
  interior["film_scan"] = options.film_scan;
  interior["images"] = nlohmann::ordered_json::array();
  double gsd_sum = 0;
  const Eigen::Vector3d tower_center = scene.model.tower_bounds.center();
  for (int i = 0; i < n; ++i) {
    const TowerStation& station = scene.stations[i];
    const ImageFrame frame =
        station.frame ? *station.frame : scene.camera.DefaultFrame();
    nlohmann::ordered_json entry;
    entry["name"] = station.name;
    entry["image_id"] = i + 1;
    entry["pixel_from_frame"] = {{frame.pixel_from_frame(0, 0),
                                  frame.pixel_from_frame(0, 1),
                                  frame.pixel_from_frame(0, 2)},
                                 {frame.pixel_from_frame(1, 0),
                                  frame.pixel_from_frame(1, 1),
                                  frame.pixel_from_frame(1, 2)}};
    if (station.frame) {
      entry["frame_corners_px"] = nlohmann::ordered_json::array();
      for (const Eigen::Vector2d& corner : station.frame_corners_px) {
        entry["frame_corners_px"].push_back({corner.x(), corner.y()});
      }
      entry["rotation_deg"] = std::atan2(-frame.pixel_from_frame(1, 0),
                                         frame.pixel_from_frame(0, 0)) *
                              180 / M_PI;
    }
    interior["images"].push_back(entry);
    gsd_sum += (station.cam_from_world.Center() - tower_center).norm() /
               scene.camera.MeanFocalLengthPx();
  }
  WriteFileAtomically(gt + "/interior.json", interior.dump(2) + "\n");
  return gsd_sum / n;
}

// Everything about the rendering, for evaluation and re-rendering
// (gt/synth.json, less the total time).
nlohmann::ordered_json DescribeRendering(
    const TowerScene& scene,
    const TowerSceneOptions& options,
    const std::vector<double>& render_seconds,
    const TowerWorkspaceSummary& summary) {
  const int n = static_cast<int>(scene.stations.size());
  nlohmann::ordered_json description = OptionsToJson(options);
  Eigen::AlignedBox3d region = scene.model.object_bounds;
  region.min() -= Eigen::Vector3d(0.05, 0.05, 0);
  region.min().z() = 0.01;  // above the ground
  region.max() += Eigen::Vector3d::Constant(0.05);
  description["evaluation_region"] = {{"min", Vector(region.min())},
                                      {"max", Vector(region.max())}};
  description["gsd_m"] = summary.gsd_m;
  description["object_bounds"] = {
      {"min", Vector(scene.model.object_bounds.min())},
      {"max", Vector(scene.model.object_bounds.max())}};
  description["images"] = nlohmann::ordered_json::array();
  for (int i = 0; i < n; ++i) {
    const TowerStation& s = scene.stations[i];
    const TowerStation& next = scene.stations[(i + 1) % n];
    description["images"].push_back(
        {{"name", s.name},
         {"center", Vector(s.cam_from_world.Center())},
         {"azimuth_deg", s.azimuth_deg},
         {"convergence_with_next_deg",
          ConvergenceAngleDeg(s.cam_from_world, next.cam_from_world)},
         {"weather", s.weather},
         {"sun_direction", Vector(s.lighting.sun_direction.normalized())},
         {"sun_intensity", s.lighting.sun_intensity},
         {"ambient_intensity", s.lighting.ambient_intensity},
         {"exposure", s.exposure},
         {"render_seconds", render_seconds[i]}});
  }
  description["converging_pairs"] = nlohmann::ordered_json::array();
  for (int pair : scene.converging_pairs) {
    description["converging_pairs"].push_back(
        {scene.stations[pair].name, scene.stations[(pair + 1) % n].name});
  }
  if (scene.vertical_pair >= 0) {
    const Eigen::Vector3d base =
        scene.stations[(scene.vertical_pair + 1) % n].cam_from_world.Center() -
        scene.stations[scene.vertical_pair].cam_from_world.Center();
    description["vertical_pair"] = {
        {"images",
         {scene.stations[scene.vertical_pair].name,
          scene.stations[(scene.vertical_pair + 1) % n].name}},
        {"base_elevation_deg",
         std::asin(std::abs(base.z()) / base.norm()) * 180 / M_PI}};
  }
  description["render_seconds"] = summary.render_seconds;
  return description;
}

// The database, as `bayon import --single_camera 1` would write it: the
// true camera and frames, or (without truth_in_database) the camera as
// EXIF would give it.
void WriteTowerDatabase(const TowerScene& scene,
                        const TowerSceneOptions& options,
                        const std::string& path) {
  const int n = static_cast<int>(scene.stations.size());
  Database database(path, Database::Mode::kCreate);
  auto transaction = database.BeginTransaction();
  Camera camera = scene.camera;
  if (!options.truth_in_database) {
    camera = Camera::Create(
        CameraModelId::kBrownBeyer,
        options.camera.focal_length_mm / options.camera.pixel_pitch_mm,
        scene.camera.width,
        scene.camera.height,
        options.camera.pixel_pitch_mm);
    camera.has_prior_focal_length = true;
  }
  const camera_t camera_id = WriteCameraWithCalibration(&database, camera);
  for (int i = 0; i < n; ++i) {
    DatabaseImage image;
    image.name = scene.stations[i].name;
    image.camera_id = camera_id;
    const image_t image_id = database.WriteImage(image);
    if (options.truth_in_database) {
      InteriorRecord record;
      record.frame = scene.stations[i].frame ? *scene.stations[i].frame
                                             : scene.camera.DefaultFrame();
      record.method =
          scene.stations[i].frame ? "synthetic_truth" : kDigitalInteriorMethod;
      WriteInterior(&database, image_id, record);
    }
  }
  transaction.Commit();
}

}  // namespace

TowerWorkspaceSummary WriteTowerWorkspace(const TowerSceneOptions& options,
                                          const std::string& workspace,
                                          bool overwrite) {
  options.Check();
  const Timer total_timer;
  OutputDirectory output(workspace, overwrite);
  TowerWorkspaceSummary summary;
  const TowerScene scene = PlanTowerScene(options);
  const MeshRenderer renderer = MakeTowerRenderer(scene);
  const std::string gt = output.File("gt");
  fs::create_directories(gt + "/sparse");
  // The true surface with its texture, and the ground, written while the
  // photographs render (60 MB, single-threaded encoding).
  std::future<size_t> surface_writing = std::async(std::launch::async, [&] {
    PlyWriteOptions ply;
    ply.comment = "TextureFile surface_texture.png";
    const TriangleMesh surface = scene.model.Surface();
    WriteMeshPly(surface, gt + "/surface.ply", ply);
    WriteImage(gt + "/surface_texture.png", scene.model.texture);
    const size_t ground_first =
        scene.model.num_object_faces + scene.model.num_target_faces;
    WriteMeshPly(
        SubMesh(scene.model.mesh, ground_first, scene.model.mesh.NumFaces()),
        gt + "/ground.ply");
    return surface.NumFaces();
  });
  std::vector<double> render_seconds;
  const std::vector<ImageMeasurement> observations = RenderPhotographs(
      scene, renderer, options, output, &render_seconds, &summary);
  WriteTrueModel(scene, observations, gt, &summary);
  summary.num_surface_faces = surface_writing.get();
  WriteControl(scene, options, observations, gt, output, &summary);
  WriteHeldout(scene, options, gt);
  summary.gsd_m = WriteInteriorTruth(scene, options, gt);
  nlohmann::ordered_json description =
      DescribeRendering(scene, options, render_seconds, summary);
  WriteTowerDatabase(scene, options, output.File("database.db"));
  summary.num_images = static_cast<int>(scene.stations.size());
  summary.total_seconds = total_timer.Seconds();
  description["total_seconds"] = summary.total_seconds;
  WriteFileAtomically(gt + "/synth.json", description.dump(2) + "\n");
  output.Commit();
  return summary;
}

}  // namespace bayon
