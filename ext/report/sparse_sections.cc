// SPDX-License-Identifier: BSD-3-Clause
//
// The sections of `bayon report` on the pipeline run and the sparse model:
// the image network, the tie-point distribution, the image residuals, the
// additional parameters and the precision table (report_sections.h).
#include "ext/report/html.h"
#include "ext/report/report_sections.h"
#include "ext/report/svg_plot.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace bayon {
namespace report {

namespace fs = std::filesystem;

namespace {

// The Bayon paper's SGAP figures (sec. 3.2.4), beside ours in the precision
// table.
struct PaperPrecision {
  static constexpr int kTiePoints = 181;
  static constexpr int kObservations = 1250;
  static constexpr double kRedundancyRatio = 0.52;
  static constexpr double kSigma0Um = 20.3;
  static constexpr double kSx = 5.8, kSy = 3.7, kSz = 8.8;  // mm
};

// Every how many of `count` items to show so that at most `max_shown` are
// (at least 1).
size_t Stride(size_t count, int max_shown) {
  return std::max<size_t>(1, (count + max_shown - 1) / std::max(max_shown, 1));
}

// ---------------------------------------------------------------------------
// 1. The pipeline run.

std::string StatusBadge(const std::string& status) {
  const std::string css = status == "ran"       ? "ran"
                          : status == "skipped" ? "skipped"
                          : status == "failed"  ? "failed"
                                                : "other";
  return "<span class=\"badge " + css + "\">" + HtmlEscape(status) + "</span>";
}

}  // namespace

Section PipelineSection(const Workspace& ws, Page* page) {
  Section section{"pipeline", "Pipeline run"};
  const std::string status = FileStatus(
      ws.pipeline, "bayon pipeline; the stages were run one by one", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& json = ws.pipeline.json;
  KeyValueTable facts;
  if (!String(json, "image_path").empty()) {
    facts.Add("Photographs",
              "<code>" + HtmlEscape(String(json, "image_path")) + "</code>");
  }
  const std::string config = String(json, "config");
  facts.Add(
      "Configuration",
      config.empty() ? "defaults" : "<code>" + HtmlEscape(config) + "</code>");
  facts.Add("Total time", FormatSeconds(Number(json, "total_seconds")));

  HtmlTable table({"#", "Stage", "Program", "Status", "Time", "Note"},
                  "rlllrl");
  std::vector<Bar> bars;
  std::string commands;
  int index = 0;
  for (const Json& stage : Child(json, "stages")) {
    const std::string name = String(stage, "name");
    const std::string stage_status = String(stage, "status");
    const double seconds = Number(stage, "seconds");
    table.AddRow({std::to_string(++index),
                  HtmlEscape(name),
                  HtmlEscape(String(stage, "program")),
                  StatusBadge(stage_status),
                  FormatSeconds(seconds),
                  HtmlEscape(String(stage, "reason"))});
    Bar bar;
    bar.label = name;
    bar.values = {std::isfinite(seconds) ? seconds : 0.0};
    bar.color = stage_status == "ran"      ? "#4c78a8"
                : stage_status == "failed" ? "#e45756"
                                           : "#bab0ac";
    bar.tooltip = name + ": " + stage_status;
    bars.push_back(bar);
    std::string line;
    for (const Json& arg : Child(stage, "command")) {
      if (!arg.is_string()) continue;
      const std::string text = arg.get<std::string>();
      const bool quote = text.find_first_of(" \t'\"") != std::string::npos;
      line += (line.empty() ? "" : " ") + (quote ? "'" + text + "'" : text);
    }
    if (!line.empty()) commands += HtmlEscape(line) + "\n";
  }
  BarChartOptions chart;
  chart.horizontal = true;
  chart.chart.width_px = 560;
  chart.chart.height_px = 0;
  chart.chart.title = "Time per stage";
  chart.chart.x_label = "seconds";
  chart.value_decimals = 1;
  chart.value_unit = " s";
  section.html += facts.Html();
  section.html += "<div class=\"row\"><div>" + table.Html() + "</div>" +
                  page->Figure(SvgBarChart(bars, chart),
                               "Blue: ran; grey: skipped (outputs complete "
                               "and newer than their inputs) or not "
                               "selected; red: failed.") +
                  "</div>\n";
  if (!commands.empty()) {
    section.html += "<details><summary>Commands</summary><pre>" + commands +
                    "</pre></details>\n";
  }
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 2. The image network.

struct CameraStation {
  std::string name;
  Eigen::Vector3d center;
  Eigen::Vector3d direction;  // viewing direction (the camera's +z)
  Eigen::Vector3d up;         // the image's up (the camera's -y)
};

std::vector<CameraStation> Stations(const Scene& model) {
  std::vector<CameraStation> stations;
  for (const Image* image : ImagesByName(model)) {
    const Eigen::Matrix3d world_from_cam =
        image->cam_from_world.rotation.toRotationMatrix().transpose();
    stations.push_back({image->name,
                        image->cam_from_world.Center(),
                        world_from_cam.col(2),
                        -world_from_cam.col(1)});
  }
  return stations;
}

// The axes of the two views: the plan view looks down `up` onto (e1, e2),
// the side view along e2 onto (e1, up). A metric datum is z-up, and so is
// an upright free network (datum.vertical). In an older free network the
// stations' own geometry decides: stations spread in two
// dimensions (a ring, a block) are seen onto their plane, so that a ring
// shows as a ring whichever way the photographs were turned; stations along
// a line (a strip along a facade) are seen from the photographs' up
// direction (the axis the images' y axes agree on, upside-down views
// counting alike). e1 is the direction along which the stations spread most.
struct ViewAxes {
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  bool datum_axes = true;
  bool stations_plane = false;  // `up` is the normal of the stations' plane
};

ViewAxes ChooseViewAxes(const std::vector<CameraStation>& stations,
                        bool upright) {
  ViewAxes axes;
  if (upright || stations.size() < 2) return axes;
  axes.datum_axes = false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const CameraStation& s : stations) mean += s.center;
  mean /= static_cast<double>(stations.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero(),
                  up_scatter = Eigen::Matrix3d::Zero();
  for (const CameraStation& s : stations) {
    scatter += (s.center - mean) * (s.center - mean).transpose();
    up_scatter += s.up * s.up.transpose();
  }
  // Eigenvalues in increasing order.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(scatter);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ups(up_scatter);
  Eigen::Vector3d up = ups.eigenvectors().col(2);
  axes.stations_plane = pca.eigenvalues()(1) > 0.1 * pca.eigenvalues()(2);
  if (axes.stations_plane) up = pca.eigenvectors().col(0);
  // The sign most photographs agree with.
  double agreement = 0;
  for (const CameraStation& s : stations) agreement += s.up.dot(up);
  axes.up = (agreement < 0 ? -up : up).normalized();
  const Eigen::Matrix3d across =
      Eigen::Matrix3d::Identity() - axes.up * axes.up.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> horizontal(
      across * scatter * across);
  Eigen::Vector3d e1 = across * horizontal.eigenvectors().col(2);
  if (e1.norm() < 1e-9) e1 = axes.up.unitOrthogonal();
  axes.e1 = e1.normalized();
  axes.e2 = axes.up.cross(axes.e1);
  return axes;
}

std::string StationView(const Workspace& ws,
                        const std::vector<CameraStation>& stations,
                        const Eigen::Vector3d& ex,
                        const Eigen::Vector3d& ey,
                        const std::string& title,
                        const std::string& x_label,
                        const std::string& y_label,
                        bool with_labels,
                        const WorkspaceReportOptions& options) {
  PointSeries points;
  points.color = "#9a9a9a";
  points.radius_px = 1.1;
  points.opacity = 0.6;
  const size_t num_points = ws.model.points3D.size();
  const size_t every = Stride(num_points, options.max_plot_points);
  size_t i = 0;
  for (const auto& [point3D_id, point] : ws.model.points3D) {
    if (i++ % every == 0) {
      points.points.emplace_back(point.xyz.dot(ex), point.xyz.dot(ey));
    }
  }
  std::vector<ViewCamera> cameras;
  for (const CameraStation& s : stations) {
    cameras.push_back(
        {Eigen::Vector2d(s.center.dot(ex), s.center.dot(ey)),
         Eigen::Vector2d(s.direction.dot(ex), s.direction.dot(ey)),
         ImageStem(s.name)});
  }
  StationViewOptions view;
  view.chart.width_px = 520;
  view.chart.height_px = 0;  // from the drawing
  if (!with_labels) view.max_labels = 0;
  view.chart.title = title;
  view.chart.x_label = x_label;
  view.chart.y_label = y_label;
  view.chart.note = FormatCount(static_cast<int64_t>(points.points.size())) +
                    (every > 1 ? " of " + FormatCount(num_points) : "") +
                    " points";
  return SvgStationView(points, cameras, view);
}

// What the strip (strip.json) did not orient from its models: the images
// it could not orient, those it placed by spatial resection, and the pairs
// its view graph left out, each with strip's reason.
std::string StripNotes(const Json& strip) {
  std::string html;
  const Json& unoriented = Child(strip, "unoriented_images");
  if (unoriented.is_array() && !unoriented.empty()) {
    std::string names;
    for (const Json& name : unoriented) {
      names += (names.empty() ? "" : ", ") + HtmlEscape(String(name));
    }
    html += Paragraph(
        "Not oriented by the strip (no model attached them and "
        "too few intersected tie points placed them): " +
        names + ".");
  }
  const Json& resected = Child(strip, "resected_images");
  if (resected.is_array() && !resected.empty()) {
    std::string names;
    for (const Json& image : resected) {
      names += (names.empty() ? "" : ", ") + HtmlEscape(String(image, "name")) +
               " (" + FormatCount(Integer(image, "num_inliers")) + " of " +
               FormatCount(Integer(image, "num_points")) + " points, RMS " +
               FormatFixed(Number(image, "rms_px"), 2) + " px)";
    }
    html += Paragraph(
        "Placed by spatial resection from the tie points: " + names + ".");
  }
  const Json& dropped = Child(strip, "dropped_pairs");
  if (dropped.is_array() && !dropped.empty()) {
    std::string items;
    for (const Json& line : dropped) {
      items += "<li>" + HtmlEscape(String(line)) + "</li>";
    }
    html += Paragraph(FormatCount(dropped.size()) +
                      (dropped.size() == 1 ? " image pair" : " image pairs") +
                      " left out before the strip, the relative rotations "
                      "disagreeing with the loops they lie on:") +
            "<ul>" + items + "</ul>";
  }
  return html;
}

}  // namespace

Section NetworkSection(const Workspace& ws, Page* page) {
  Section section{"network", "Image network"};
  const std::vector<CameraStation> stations = Stations(ws.model);
  const ViewAxes axes = ChooseViewAxes(stations, IsDatumUpright(ws));
  const Units units = DatumUnits(ws);
  const std::string unit = " [" + units.length + "]";
  std::string text = FormatCount(ws.model.images.size()) + " images oriented";
  if (ws.num_database_images >= 0) {
    text += " of " + FormatCount(ws.num_database_images) + " in the database";
  }
  text += ", " + FormatCount(ws.model.points3D.size()) +
          " object points (tie points) with " +
          FormatCount(ws.observations.size()) + " image observations.";
  const Json& strip = ws.strip.json;
  if (ws.strip.ok() && Child(strip, "closed_ring").is_boolean()) {
    if (Child(strip, "closed_ring").get<bool>()) {
      const Json& closure = Child(strip, "closure");
      text += " The strip closed into a ring (closure error " +
              FormatSignificant(Number(closure, "rotation_deg"), 3) +
              "&deg; and " +
              FormatPercent(Number(closure, "position_relative_to_path"), 2) +
              " of the path, distributed).";
    } else {
      text += " The strip is open (not closed into a ring).";
    }
  }
  section.html += Paragraph(text);
  if (ws.strip.ok()) section.html += StripNotes(strip);
  const std::string x = axes.datum_axes ? "X" : "x";
  const std::string y = axes.datum_axes ? "Y" : "y";
  const std::string z = axes.datum_axes ? "Z" : "z";
  const std::string plan_title = axes.stations_plane
                                     ? "Plan view (onto the stations' plane)"
                                     : "Plan view";
  section.html += "<div class=\"row\">";
  section.html += page->Figure(
      StationView(ws,
                  stations,
                  axes.e1,
                  axes.e2,
                  plan_title,
                  x + unit,
                  y + unit,
                  /*with_labels=*/true,
                  page->options()),
      "Camera stations (red: centre and viewing direction) over the sparse "
      "points (grey)" +
          std::string(axes.stations_plane && !axes.datum_axes
                          ? ", seen perpendicular to the plane of the "
                            "stations."
                          : ", seen from above."));
  section.html +=
      page->Figure(StationView(ws,
                               stations,
                               axes.e1,
                               axes.up,
                               "Side view",
                               x + unit,
                               z + unit,
                               /*with_labels=*/false,
                               page->options()),
                   "The same, seen from the side (looking along " + y + ").");
  section.html += "</div>\n";
  if (!axes.datum_axes) {
    section.html += Paragraph(
        "<small>Free network: coordinates in the strip's model units, the "
        "views' axes from the stations: " +
        std::string(axes.stations_plane
                        ? "z is the normal of the plane the stations lie in "
                          "(turned towards the photographs' up)"
                        : "z is the photographs' up direction") +
        ", x the direction of the stations' largest spread.</small>");
  }

  // The stations' precision, collapsed.
  const Json& images = Child(ws.adjustment.json, "images");
  if (images.is_array() && !images.empty()) {
    HtmlTable table({"Image",
                     "X0",
                     "Y0",
                     "Z0",
                     "sX0",
                     "sY0",
                     "sZ0",
                     "s&omega;",
                     "s&phi;",
                     "s&kappa;"},
                    "lrrrrrrrrr");
    for (const Json& image : images) {
      const Json& c = Child(image, "center");
      const Json& sc = Child(image, "center_std_dev_mm");
      const Json& sr = Child(image, "rotation_std_dev_mdeg");
      std::vector<std::string> row = {HtmlEscape(String(image, "name"))};
      for (int k = 0; k < 3; ++k) row.push_back(FormatFixed(NumberAt(c, k), 4));
      for (int k = 0; k < 3; ++k)
        row.push_back(FormatFixed(NumberAt(sc, k), 2));
      for (int k = 0; k < 3; ++k)
        row.push_back(FormatFixed(NumberAt(sr, k), 1));
      table.AddRow(row);
    }
    section.html += "<details><summary>Exterior orientations (centres in " +
                    units.length + ", their standard deviations in " +
                    units.precision +
                    ", rotations' in millidegrees about the camera axes)"
                    "</summary>" +
                    table.Html() + "</details>\n";
  }
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 3. Tie-point distribution.

struct ImageTies {
  const Image* image = nullptr;
  std::vector<Eigen::Vector2d> track_xy, tie_xy;
};

std::vector<ImageTies> TiesPerImage(const Workspace& ws) {
  std::map<image_t, ImageTies> by_id;
  for (const auto& [image_id, image] : ws.model.images) {
    by_id[image_id].image = &image;
  }
  for (const Observation& o : ws.observations) {
    ImageTies& ties = by_id[o.image_id];
    (o.tie ? ties.tie_xy : ties.track_xy).push_back(o.xy);
  }
  std::vector<ImageTies> list;
  for (const Image* image : ImagesByName(ws.model)) {
    list.push_back(by_id[image->image_id]);
  }
  return list;
}

// The cells of a 5 x 5 grid over the frame with at least one point.
int OccupiedCells(const std::vector<Eigen::Vector2d>& a,
                  const std::vector<Eigen::Vector2d>& b,
                  const Eigen::Vector2d& size) {
  std::set<int> cells;
  for (const auto* points : {&a, &b}) {
    for (const Eigen::Vector2d& p : *points) {
      const int cx = std::clamp(static_cast<int>(5 * p.x() / size.x()), 0, 4);
      const int cy = std::clamp(static_cast<int>(5 * p.y() / size.y()), 0, 4);
      cells.insert(cy * 5 + cx);
    }
  }
  return static_cast<int>(cells.size());
}

std::vector<Eigen::Vector2d> Thin(const std::vector<Eigen::Vector2d>& points,
                                  size_t every) {
  std::vector<Eigen::Vector2d> kept;
  for (size_t i = 0; i < points.size(); i += every) kept.push_back(points[i]);
  return kept;
}

std::string RaysChart(const Workspace& ws, Page* page) {
  std::vector<Bar> bars;
  const Json& rays =
      Child(Child(ws.adjustment.json, "statistics"), "tie_points_by_rays");
  if (rays.is_object() && !rays.empty()) {
    for (const auto& [label, count] : rays.items()) {
      bars.push_back({label, {Number(count)}, "", ""});
    }
  } else {
    std::map<int, int> histogram;
    for (const auto& [point3D_id, point] : ws.model.points3D) {
      ++histogram[std::min<int>(point.track.size(), 10)];
    }
    for (const auto& [length, count] : histogram) {
      bars.push_back({length == 10 ? "10+" : std::to_string(length),
                      {static_cast<double>(count)},
                      "",
                      ""});
    }
  }
  BarChartOptions chart;
  chart.chart.width_px = 360;
  chart.chart.height_px = 260;
  chart.chart.title = "Tie points by number of rays";
  chart.chart.x_label = "images per point";
  chart.chart.y_label = "points";
  chart.value_decimals = 0;
  return page->Figure(SvgBarChart(bars, chart),
                      "The paper's 181 tie points connect 2, 3, 4, 5 and 6 "
                      "images 18, 63, 81, 15 and 4 times.");
}

}  // namespace

Section TiePointSection(const Workspace& ws, Page* page) {
  Section section{"tiepoints", "Tie-point distribution"};
  const std::vector<ImageTies> ties = TiesPerImage(ws);
  const bool split = ws.has_tie_observations;
  std::vector<Bar> bars;
  for (const ImageTies& t : ties) {
    Bar bar;
    bar.label = ImageStem(t.image->name);
    bar.values = {static_cast<double>(t.track_xy.size())};
    if (split) bar.values.push_back(static_cast<double>(t.tie_xy.size()));
    bars.push_back(bar);
  }
  BarChartOptions chart;
  chart.chart.width_px =
      std::clamp(120 + 24 * static_cast<int>(bars.size()), 420, 1040);
  chart.chart.height_px = 300;
  chart.chart.title = "Observations per image";
  chart.chart.y_label = "image points";
  if (split) {
    chart.series = {{"keypoint tracks", kTrackColor},
                    {"LSM tie points", kTieColor}};
  }
  std::string caption =
      "Image points of the adjusted model's object points, per photograph";
  caption += split ? " (blue: tracks of matched keypoints; orange: "
                     "multi-image tie points of least-squares matching)."
                   : ".";
  section.html += "<div class=\"row\">" +
                  page->Figure(SvgBarChart(bars, chart), caption) +
                  RaysChart(ws, page) + "</div>\n";

  const Json& tp = ws.tiepoints.json;
  if (ws.tiepoints.ok()) {
    KeyValueTable facts;
    facts.Add("Tie points measured (bayon tiepoints)",
              CountOf(tp, "num_points"));
    facts.Add("Their image observations", CountOf(tp, "num_observations"));
    facts.Add("Mean images per point",
              FormatFixed(Number(tp, "mean_images_per_point"), 2));
    facts.Add("Median precision of an observation",
              FormatFixed(Number(tp, "median_sigma_px"), 3) + " px");
    section.html += facts.Html();
  }

  // Small multiples: where in each frame the points lie.
  const WorkspaceReportOptions& options = page->options();
  const size_t every_image = Stride(ties.size(), options.max_frames);
  std::string frames;
  for (size_t i = 0; i < ties.size(); i += every_image) {
    const ImageTies& t = ties[i];
    const Camera& camera = ws.model.cameras.at(t.image->camera_id);
    const Eigen::Vector2d size(camera.width, camera.height);
    const size_t total = t.track_xy.size() + t.tie_xy.size();
    const size_t every = Stride(total, options.max_frame_points);
    std::vector<PointSeries> series(2);
    series[0].points = Thin(t.track_xy, every);
    series[0].color = kTrackColor;
    series[1].points = Thin(t.tie_xy, every);
    series[1].color = kTieColor;
    for (PointSeries& s : series) s.radius_px = 1.3;
    ImageFrameOptions frame;
    frame.width_px = 160;
    frame.title = ImageStem(t.image->name);
    frame.note = FormatCount(total) + " points, " +
                 std::to_string(OccupiedCells(t.track_xy, t.tie_xy, size)) +
                 "/25 cells";
    frames += page->Chart(SvgImageFrame(size, series, {}, frame));
  }
  section.html += "<h3>Where the points lie in each photograph</h3>\n";
  section.html += "<div class=\"frames\">" + frames + "</div>\n";
  section.html += Paragraph(
      "<small>Each frame is one photograph (x right, y down); cells: of a "
      "5&nbsp;&times;&nbsp;5 grid over the frame, those with at least one "
      "point" +
      std::string(every_image > 1 ? "; every " + std::to_string(every_image) +
                                        "th image shown"
                                  : "") +
      ".</small>");
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 4. Residuals.

// Mean residual vectors over a grid of cells of the frame, for the images of
// the most common image size (one camera in a ring).
std::string ResidualField(const Workspace& ws, Page* page) {
  std::map<std::pair<uint64_t, uint64_t>, int> sizes;
  for (const auto& [image_id, image] : ws.model.images) {
    const Camera& camera = ws.model.cameras.at(image.camera_id);
    ++sizes[{camera.width, camera.height}];
  }
  if (sizes.empty()) return "";
  const auto size_key =
      std::max_element(sizes.begin(), sizes.end(), [](auto& a, auto& b) {
        return a.second < b.second;
      })->first;
  const Eigen::Vector2d size(size_key.first, size_key.second);
  const int nx = std::max(page->options().residual_grid_cells, 2);
  const int ny =
      std::max(1, static_cast<int>(std::lround(nx * size.y() / size.x())));
  std::vector<Eigen::Vector2d> sum(nx * ny, Eigen::Vector2d::Zero());
  std::vector<int> count(nx * ny, 0);
  for (const Observation& o : ws.observations) {
    const Camera& camera =
        ws.model.cameras.at(ws.model.images.at(o.image_id).camera_id);
    if (camera.width != size_key.first || camera.height != size_key.second ||
        !o.residual.allFinite()) {
      continue;
    }
    const int cx =
        std::clamp(static_cast<int>(nx * o.xy.x() / size.x()), 0, nx - 1);
    const int cy =
        std::clamp(static_cast<int>(ny * o.xy.y() / size.y()), 0, ny - 1);
    sum[cy * nx + cx] += o.residual;
    ++count[cy * nx + cx];
  }
  std::vector<double> lengths;
  for (int c = 0; c < nx * ny; ++c) {
    if (count[c] >= 3) lengths.push_back((sum[c] / count[c]).norm());
  }
  if (lengths.empty()) return "";
  std::sort(lengths.begin(), lengths.end());
  const double longest = lengths.back();
  const double typical = lengths[lengths.size() * 9 / 10];
  if (typical <= 0) return "";
  // The 90th percentile of the mean vectors spans 0.6 of a cell: one long
  // arrow does not shrink the others to dots.
  const double cell = size.x() / nx;
  const double scale = 0.6 * cell / typical;
  std::vector<FrameArrow> arrows;
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const int c = cy * nx + cx;
      if (count[c] < 3) continue;
      const Eigen::Vector2d from((cx + 0.5) * size.x() / nx,
                                 (cy + 0.5) * size.y() / ny);
      arrows.push_back({from, from + scale * sum[c] / count[c]});
    }
  }
  ImageFrameOptions frame;
  frame.width_px = 360;
  frame.title = "Mean residual per cell";
  frame.note = "arrows " + FormatFixed(scale, 0) +
               " times the mean residual (longest " + FormatFixed(longest, 3) +
               " px)";
  return page->Figure(
      SvgImageFrame(size, {}, arrows, frame),
      "Mean image residual in " + std::to_string(nx) + " &times; " +
          std::to_string(ny) + " cells of the frame (" +
          FormatCount(size_key.first) + " &times; " +
          FormatCount(size_key.second) +
          " px images), cells with 3 or more observations. A pattern shows "
          "systematic image errors the camera model leaves; noise only shows "
          "random directions.");
}

// One histogram of residuals in x or y.
std::string ResidualHistogram(const std::vector<double>& values,
                              const std::string& group,
                              const std::string& axis,
                              const std::string& color,
                              Page* page) {
  HistogramOptions histogram;
  histogram.chart.width_px = 420;
  histogram.chart.height_px = 240;
  histogram.symmetric = true;
  histogram.show_normal = true;
  histogram.num_bins = 41;
  histogram.color = color;
  histogram.chart.y_label = "observations";
  histogram.chart.title =
      "Residuals in " + axis + (group.empty() ? "" : ", " + group);
  histogram.chart.x_label = "v" + axis + " [px]";
  histogram.chart.note = "n = " + FormatCount(values.size()) + ", RMS " +
                         FormatFixed(Rms(values), 3) + " px";
  return page->Figure(SvgHistogram(values, histogram));
}

}  // namespace

Section ResidualSection(const Workspace& ws, Page* page) {
  Section section{"residuals", "Image residuals"};
  std::vector<double> vx, vy, tie_x, tie_y, track_x, track_y;
  double max_norm = 0;
  for (const Observation& o : ws.observations) {
    if (!o.residual.allFinite()) continue;
    vx.push_back(o.residual.x());
    vy.push_back(o.residual.y());
    (o.tie ? tie_x : track_x).push_back(o.residual.x());
    (o.tie ? tie_y : track_y).push_back(o.residual.y());
    max_norm = std::max(max_norm, o.residual.norm());
  }
  if (vx.empty()) {
    section.ran = false;
    section.html = NotRun("the adjusted model has no observations");
    return section;
  }
  section.html += Paragraph(
      "Residuals of the " + FormatCount(vx.size()) +
      " image observations of the adjusted model: each object point "
      "projected through its photograph's adjusted orientation and full "
      "calibration, minus the measured image point. Red: the normal "
      "distribution with the residuals' mean and standard deviation." +
      std::string(ws.has_tie_observations
                      ? " Keypoint tracks and least-squares tie points are "
                        "shown apart: their precision differs by an order "
                        "of magnitude."
                      : ""));
  if (ws.has_tie_observations) {
    section.html +=
        "<div class=\"row\">" +
        ResidualHistogram(track_x, "keypoint tracks", "x", kTrackColor, page) +
        ResidualHistogram(track_y, "keypoint tracks", "y", kTrackColor, page) +
        "</div>\n<div class=\"row\">" +
        ResidualHistogram(tie_x, "LSM tie points", "x", kTieColor, page) +
        ResidualHistogram(tie_y, "LSM tie points", "y", kTieColor, page) +
        "</div>\n";
  } else {
    section.html += "<div class=\"row\">" +
                    ResidualHistogram(vx, "", "x", kTrackColor, page) +
                    ResidualHistogram(vy, "", "y", kTrackColor, page) +
                    "</div>\n";
  }
  HtmlTable table({"Observations", "n", "RMS vx [px]", "RMS vy [px]"}, "lrrr");
  table.AddRow({"all",
                FormatCount(vx.size()),
                FormatFixed(Rms(vx), 3),
                FormatFixed(Rms(vy), 3)});
  if (ws.has_tie_observations) {
    table.AddRow({"keypoint tracks",
                  FormatCount(track_x.size()),
                  FormatFixed(Rms(track_x), 3),
                  FormatFixed(Rms(track_y), 3)});
    table.AddRow({"LSM tie points",
                  FormatCount(tie_x.size()),
                  FormatFixed(Rms(tie_x), 3),
                  FormatFixed(Rms(tie_y), 3)});
  }
  const Json& s = Child(ws.adjustment.json, "statistics");
  const Json& rms = Child(s, "residual_rms_px");
  if (rms.is_array() && rms.size() == 2) {
    // n counts coordinates; an image point has two.
    const int64_t num_coordinates = Integer(s, "n_image_coordinates");
    table.AddRow({"as bayon adjust reports them",
                  Count(num_coordinates < 0 ? -1 : num_coordinates / 2),
                  FormatFixed(NumberAt(rms, 0), 3),
                  FormatFixed(NumberAt(rms, 1), 3)});
  }
  section.html += "<div class=\"row\">" + ResidualField(ws, page) +
                  "<div class=\"grow\">" + table.Html();
  section.html += Paragraph(
      "Largest residual " + FormatFixed(max_norm, 2) + " px" +
      (std::isfinite(Number(s, "mean_reprojection_error_px"))
           ? "; mean reprojection error (COLMAP's figure) " +
                 FormatFixed(Number(s, "mean_reprojection_error_px"), 3) + " px"
           : "") +
      ".");

  // Normalized residuals exist for the rejected observations only.
  const Json& blunders = Child(ws.adjustment.json, "blunder_detection");
  const Json& rejected = Child(blunders, "rejected");
  if (rejected.is_array()) {
    std::string text =
        "Blunder detection (" + HtmlEscape(String(blunders, "method")) +
        ", data snooping with critical value " +
        FormatFixed(Number(blunders, "critical_value"), 2) +
        "): " + FormatCount(rejected.size()) + " observations rejected";
    const int64_t removed = Integer(blunders, "num_points_removed");
    if (removed > 0) {
      text += ", " + FormatCount(removed) +
              " points left with fewer than two rays removed";
    }
    section.html += Paragraph(text + ".");
    if (!rejected.empty()) {
      HtmlTable list({"Image",
                      "Point",
                      "vx [px]",
                      "vy [px]",
                      "w (normalized)",
                      "r (redundancy)"},
                     "llrrrr");
      int shown = 0;
      for (const Json& o : rejected) {
        if (++shown > 30) break;
        const Json& v = Child(o, "residual_px");
        list.AddRow({HtmlEscape(String(o, "image")),
                     HtmlEscape(String(o, "point")),
                     FormatFixed(NumberAt(v, 0), 2),
                     FormatFixed(NumberAt(v, 1), 2),
                     FormatFixed(Number(o, "w"), 1),
                     FormatFixed(Number(o, "redundancy"), 3)});
      }
      section.html += "<details><summary>Rejected observations" +
                      std::string(rejected.size() > 30 ? " (first 30)" : "") +
                      "</summary>" + list.Html() + "</details>\n";
    }
  }
  section.html += "</div></div>\n";
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 5. Additional parameters.

const char* const kAdditionalParameters[] = {
    "dc", "dx0", "dy0", "K1", "K2", "K3", "P1", "P2", "B1", "B2"};

std::string ParameterMeaning(const std::string& name) {
  static const std::map<std::string, std::string> kMeaning = {
      {"dc", "camera constant correction"},
      {"dx0", "principal point offset x"},
      {"dy0", "principal point offset y"},
      {"K1", "radial distortion r<sup>3</sup>"},
      {"K2", "radial distortion r<sup>5</sup>"},
      {"K3", "radial distortion r<sup>7</sup>"},
      {"P1", "decentring distortion"},
      {"P2", "decentring distortion"},
      {"B1", "affinity (scale of x)"},
      {"B2", "shear"}};
  const auto it = kMeaning.find(name);
  return it == kMeaning.end() ? "" : it->second;
}

std::string ParameterUnit(const std::string& name) {
  if (name == "dc" || name == "dx0" || name == "dy0" || name == "c" ||
      name == "x0" || name == "y0") {
    return "mm";
  }
  if (name == "K1") return "mm<sup>&minus;2</sup>";
  if (name == "K2") return "mm<sup>&minus;4</sup>";
  if (name == "K3") return "mm<sup>&minus;6</sup>";
  if (name == "P1" || name == "P2") return "mm<sup>&minus;1</sup>";
  return "&ndash;";
}

// The ten additional parameters of one Brown/Beyer camera.
std::string AdditionalParameterTable(const CalibrationEntry& entry,
                                     const Json& self_calibration,
                                     Page* page) {
  const std::vector<std::string> names = ParameterNames(entry.camera.model_id);
  const double t_critical =
      std::isfinite(Number(self_calibration, "significance_t"))
          ? Number(self_calibration, "significance_t")
          : 2.0;
  // What the adjustment says per parameter of this camera.
  std::map<std::string, const Json*> estimated, removed;
  for (const Json& p : Child(self_calibration, "parameters")) {
    if (Integer(p, "camera_id") == entry.camera.camera_id) {
      estimated[String(p, "name")] = &p;
    }
  }
  for (const Json& p : Child(self_calibration, "removed")) {
    if (Integer(p, "camera_id") == entry.camera.camera_id) {
      removed[String(p, "name")] = &p;
    }
  }
  HtmlTable table({"Parameter",
                   "Meaning",
                   "Value",
                   "&sigma;",
                   "t = value/&sigma;",
                   "Unit",
                   "Status"},
                  "llrrrll");
  std::vector<Bar> bars;
  for (const char* name : kAdditionalParameters) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) continue;
    const size_t k = it - names.begin();
    if (k >= entry.camera.params.size()) continue;
    double value = entry.camera.params[k];
    double sigma = k < entry.std_devs.size() ? entry.std_devs[k] : kNaN;
    double t = kNaN;
    std::string status;
    std::string row_class;
    if (estimated.count(name)) {
      const Json& p = *estimated[name];
      value = Number(p, "value");
      sigma = Number(p, "std_dev");
      t = Number(p, "t");
      if (!std::isfinite(t) && sigma > 0) t = value / sigma;
      const bool significant = std::abs(t) > t_critical;
      status = significant ? "estimated, significant" : "estimated";
      if (significant) row_class = "significant";
      bars.push_back(
          {name, {std::abs(t)}, significant ? "#54a24b" : "#bab0ac", ""});
    } else if (removed.count(name)) {
      const Json& p = *removed[name];
      value = Number(p, "value");
      sigma = Number(p, "std_dev");
      t = Number(p, "t");
      status = "removed: " + HtmlEscape(String(p, "reason"));
      bars.push_back(
          {name, {std::isfinite(t) ? std::abs(t) : 0.0}, "#e45756", ""});
    } else {
      status = "not estimated";
      sigma = kNaN;
    }
    table.AddRow({std::string("<b>") + name + "</b>",
                  ParameterMeaning(name),
                  FormatSignificant(value, 4),
                  FormatSignificant(sigma, 3),
                  FormatFixed(t, 1),
                  ParameterUnit(name),
                  status},
                 row_class);
  }
  std::string html = table.Html();
  if (!bars.empty()) {
    BarChartOptions chart;
    chart.horizontal = true;
    chart.chart.width_px = 420;
    chart.chart.height_px = 0;
    chart.chart.title = "|t| of the additional parameters";
    chart.chart.x_label = "|t|";
    chart.value_decimals = 1;
    html += page->Figure(
        SvgBarChart(bars, chart),
        "Green: significant (|t| &gt; " + FormatFixed(t_critical, 2) +
            "); grey: estimated, not significant; red: removed (t at "
            "removal).");
  }
  return html;
}

// Every parameter of a camera that is not Brown/Beyer (COLMAP's models).
std::string ColmapParameterTable(const CalibrationEntry& entry) {
  const std::vector<std::string> names = ParameterNames(entry.camera.model_id);
  HtmlTable table({"Parameter", "Value", "&sigma;", "t"}, "lrrr");
  for (size_t k = 0; k < names.size() && k < entry.camera.params.size(); ++k) {
    const double value = entry.camera.params[k];
    const double sigma = k < entry.std_devs.size() ? entry.std_devs[k] : kNaN;
    table.AddRow({HtmlEscape(names[k]),
                  FormatSignificant(value, 6),
                  sigma > 0 ? FormatSignificant(sigma, 3) : "&ndash;",
                  sigma > 0 ? FormatFixed(value / sigma, 1) : "&ndash;"});
  }
  return table.Html();
}

}  // namespace

Section CalibrationSection(const Workspace& ws, Page* page) {
  Section section{"calibration", "Additional parameters"};
  if (!ws.calibration_error.empty()) {
    page->Problem(ws.calibration_error);
    section.html +=
        "<p class=\"problem\">" + HtmlEscape(ws.calibration_error) + "</p>\n";
  }
  const Json& sc = Child(ws.adjustment.json, "self_calibration");
  if (ws.calibration.empty()) {
    section.ran = false;
    section.html += NotRun(
        "no <code>sparse/adjusted/calibration.json</code> (bayon adjust)");
    return section;
  }
  if (sc.is_object()) {
    section.html += Paragraph(
        "Self-calibration <b>" + HtmlEscape(String(sc, "mode")) +
        "</b>: after an adjustment without them, the ten additional "
        "parameters of Brown (1971) and Beyer (1992) are estimated, tested "
        "by t = value / &sigma; against " +
        FormatFixed(Number(sc, "significance_t"), 2) +
        " and removed step by step where not significant or not "
        "determinable (the paper's sec. 3.2.4; there dx0, dc, B1 and K1 "
        "were significant).");
  }
  for (const CalibrationEntry& entry : ws.calibration) {
    const Camera& camera = entry.camera;
    KeyValueTable facts;
    facts.Add("Model", HtmlEscape(camera.ModelName()));
    facts.Add("Image size",
              FormatCount(camera.width) + " &times; " +
                  FormatCount(camera.height) + " px");
    const bool brown = camera.model_id == CameraModelId::kBrownBeyer;
    if (brown) {
      const std::vector<std::string> names = ParameterNames(camera.model_id);
      const auto param = [&](const std::string& name) {
        const auto it = std::find(names.begin(), names.end(), name);
        return it == names.end() ? kNaN : camera.params[it - names.begin()];
      };
      facts.Add(
          "Pixel pitch",
          FormatSignificant(1000 * camera.pixel_pitch_mm, 4) + " &micro;m");
      facts.Add("Camera constant c + dc",
                FormatFixed(param("c") + param("dc"), 4) + " mm (" +
                    FormatFixed(camera.MeanFocalLengthPx(), 1) + " px)");
      facts.Add("Principal point x0 + dx0, y0 + dy0",
                FormatFixed(param("x0") + param("dx0"), 4) + ", " +
                    FormatFixed(param("y0") + param("dy0"), 4) + " mm");
    }
    if (entry.colmap_camera) {
      facts.Add("Written to COLMAP as",
                HtmlEscape(entry.colmap_camera->ModelName()) + " (fit RMS " +
                    FormatFixed(entry.colmap_fit_rms_px, 4) + " px, max " +
                    FormatFixed(entry.colmap_fit_max_px, 4) + " px)");
    }
    section.html += "<h3>Camera " + std::to_string(camera.camera_id) + "</h3>";
    section.html += facts.Html();
    section.html += brown ? AdditionalParameterTable(entry, sc, page)
                          : ColmapParameterTable(entry);
  }
  const Json& flags = Child(sc, "flagged_correlations");
  if (flags.is_array() && !flags.empty()) {
    std::vector<std::string> pairs;
    for (const Json& f : flags) {
      const Json& names = Child(f, "parameters");
      if (!names.is_array() || names.size() != 2 || !names[0].is_string() ||
          !names[1].is_string()) {
        continue;
      }
      pairs.push_back(HtmlEscape(names[0].get<std::string>()) + "&ndash;" +
                      HtmlEscape(names[1].get<std::string>()) + " " +
                      FormatFixed(Number(f, "correlation"), 3));
    }
    std::string text = "Correlations between the parameters above " +
                       FormatFixed(Number(sc, "max_correlation"), 2) + ": ";
    for (size_t i = 0; i < pairs.size(); ++i) {
      text += (i > 0 ? ", " : "") + pairs[i];
    }
    text += ".";
    section.html += Paragraph(text);
  }
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 6. Precision (the paper's table).

// "2: 721, 3: 457, ...": tie points by the number of images they connect.
std::string RaysText(const Json& rays) {
  if (!rays.is_object() || rays.empty()) return "&ndash;";
  std::string text;
  for (const auto& [label, count] : rays.items()) {
    text += (text.empty() ? "" : ", ") + HtmlEscape(label) + ":&nbsp;" +
            CountNumber(Number(count));
  }
  return text;
}

}  // namespace

namespace {

// The variance components of adjustment.json's statistics, as a table;
// empty where none were estimated.
std::string VarianceComponentsHtml(const Json& components) {
  if (!components.is_array() || components.empty()) return std::string();
  HtmlTable vc({"Observation group",
                "Observations",
                "Redundancy",
                "Variance scale",
                "Median &sigma; [px]"},
               "lrrrr");
  for (const Json& c : components) {
    vc.AddRow({HtmlEscape(String(c, "group")),
               CountOf(c, "num_observations"),
               FormatFixed(Number(c, "redundancy"), 1),
               FormatFixed(Number(c, "variance_scale"), 4),
               FormatFixed(Number(c, "median_sigma_px"), 4)});
  }
  return "<h3>Variance components</h3>" + vc.Html();
}

// Each check point's difference and standard deviation, folded away; empty
// without check points.
std::string CheckPointsHtml(const Json& checks) {
  if (Integer(checks, "num") <= 0) return std::string();
  HtmlTable list({"Check point", "dX", "dY", "dZ", "sX", "sY", "sZ", "Rays"},
                 "lrrrrrrr");
  for (const Json& p : Child(checks, "points")) {
    const Json& d = Child(p, "difference_mm");
    const Json& sd = Child(p, "std_dev_mm");
    std::vector<std::string> row = {HtmlEscape(String(p, "name"))};
    for (int k = 0; k < 3; ++k) row.push_back(FormatFixed(NumberAt(d, k), 2));
    for (int k = 0; k < 3; ++k) row.push_back(FormatFixed(NumberAt(sd, k), 2));
    row.push_back(CountOf(p, "rays"));
    list.AddRow(row);
  }
  return "<details><summary>Check points (mm)</summary>" + list.Html() +
         "</details>\n";
}

}  // namespace

Section PrecisionSection(const Workspace& ws, Page* page) {
  Section section{"precision", "Precision of the bundle adjustment"};
  const std::string status =
      FileStatus(ws.adjustment, "bayon adjust wrote no statistics", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& r = ws.adjustment.json;
  const Json& s = Child(r, "statistics");
  const Units units = DatumUnits(ws);
  const Json& datum = Child(r, "datum");
  section.html += Paragraph("Datum: <b>" + HtmlEscape(String(datum, "type")) +
                            "</b> &ndash; " +
                            HtmlEscape(String(datum, "description")) + ".");
  const std::string meaning = String(datum, "precision");
  if (!meaning.empty()) {
    section.html +=
        Paragraph("Standard deviations: " + HtmlEscape(meaning) + ".");
  }

  HtmlTable table(
      {"Quantity", "Symbol", "This workspace", "Bayon tower (paper, SGAP)"},
      "lnrr");
  table.AddRow({"Tie points",
                "",
                CountOf(s, "num_tie_points"),
                FormatCount(PaperPrecision::kTiePoints)});
  table.AddRow({"Tie points by images (rays): count",
                "",
                RaysText(Child(s, "tie_points_by_rays")),
                "2:&nbsp;18, 3:&nbsp;63, 4:&nbsp;81, 5:&nbsp;15, 6:&nbsp;4"});
  table.AddRow({"Control / check points",
                "",
                CountOf(s, "num_control_points") + " / " +
                    CountOf(s, "num_check_points"),
                "7 / &ndash;"});
  table.AddRow({"Observations",
                "n",
                CountOf(s, "n"),
                FormatCount(PaperPrecision::kObservations)});
  table.AddRow({"Unknowns, datum defect",
                "u, d",
                CountOf(s, "u") + ", " + CountOf(s, "d"),
                "&ndash;"});
  table.AddRow({"Redundancy", "r", CountOf(s, "r"), "&ndash;"});
  table.AddRow({"Global internal reliability",
                "r/n",
                FormatFixed(Number(s, "r_over_n"), 3),
                FormatFixed(PaperPrecision::kRedundancyRatio, 2)});
  table.AddRow({"Standard deviation of unit weight, a priori",
                "",
                FormatFixed(Number(s, "sigma0_apriori_px"), 3) + " px",
                "&ndash;"});
  std::string sigma0 = FormatFixed(Number(s, "sigma0_px"), 3) + " px";
  if (std::isfinite(Number(s, "sigma0_image_um"))) {
    sigma0 +=
        " = " + FormatFixed(Number(s, "sigma0_image_um"), 2) + " &micro;m";
  }
  table.AddRow({"Standard deviation of image coordinates a posteriori",
                "s<sub>0</sub>",
                sigma0,
                FormatFixed(PaperPrecision::kSigma0Um, 1) + " &micro;m"});
  table.AddRow(
      {"Theoretical precision of the tie points (RMS)",
       "s<sub>x</sub> / s<sub>y</sub> / s<sub>z</sub>",
       Triple(Child(s, "point_precision_rms_mm"), 2) + " " + units.precision,
       FormatFixed(PaperPrecision::kSx, 1) + " / " +
           FormatFixed(PaperPrecision::kSy, 1) + " / " +
           FormatFixed(PaperPrecision::kSz, 1) + " mm"},
      "key");
  if (Child(s, "num_weak_tie_points").is_number()) {
    table.AddRow(
        {"&hellip; not counted: tie points whose rays meet at less "
         "than " +
             FormatFixed(Number(s, "min_intersection_angle_deg"), 1) + "&deg;",
         "",
         CountOf(s, "num_weak_tie_points"),
         "&ndash;"});
  }
  table.AddRow(
      {"&hellip; largest",
       "",
       Triple(Child(s, "point_precision_max_mm"), 2) + " " + units.precision,
       "&ndash;"});
  table.AddRow(
      {"Precision of the camera stations (RMS)",
       "s<sub>X0</sub> / s<sub>Y0</sub> / s<sub>Z0</sub>",
       Triple(Child(s, "center_precision_rms_mm"), 2) + " " + units.precision,
       "&ndash;"});
  table.AddRow({"&hellip; of their rotations (RMS)",
                "s<sub>&omega;</sub> / s<sub>&phi;</sub> / s<sub>&kappa;</sub>",
                Triple(Child(s, "rotation_precision_rms_mdeg"), 1) + " mdeg",
                "&ndash;"});
  table.AddRow({"Redundancy numbers, mean / min",
                "r<sub>i</sub>",
                FormatFixed(Number(s, "redundancy_number_mean"), 3) + " / " +
                    FormatFixed(Number(s, "redundancy_number_min"), 3),
                "&ndash;"});
  const Json& checks = Child(r, "check_points");
  if (Integer(checks, "num") > 0) {
    table.AddRow({"Check points: RMS of adjusted &minus; given",
                  "&mu;<sub>X</sub> / &mu;<sub>Y</sub> / &mu;<sub>Z</sub>",
                  Triple(Child(checks, "rms_mm"), 2) + " mm (3D " +
                      FormatFixed(Number(checks, "rms_3d_mm"), 2) + " mm, " +
                      CountOf(checks, "num") + " points)",
                  "&ndash;"},
                 "key");
  }
  section.html += table.Html("precision");
  if (!IsDatumMetric(ws)) {
    section.html += Paragraph(
        "<small>A free network keeps the strip's model units: its "
        "precision figures are thousandths of a model unit (adjustment.txt "
        "prints them as mm). The paper's figures are in millimetres on the "
        "object, from 7 control points.</small>");
  }
  section.html += VarianceComponentsHtml(Child(s, "variance_components"));
  section.html += CheckPointsHtml(checks);
  return section;
}

}  // namespace report
}  // namespace bayon
