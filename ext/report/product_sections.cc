// SPDX-License-Identifier: BSD-3-Clause
//
// The sections of `bayon report` on the products after the adjustment
// (dense points, editing, mesh, texture, renders) and on the comparisons
// (stock COLMAP, the truth) (report_sections.h).
#include "ext/colmap/ply_io.h"
#include "ext/report/html.h"
#include "ext/report/report_sections.h"
#include "ext/report/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace bayon {
namespace report {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------
// 7. Dense points, 8. editing, 9. mesh, 10. texture.

std::string DenseCloudFigures(const Workspace& ws, Page* page) {
  const fs::path path = ws.root / "dense" / "points.ply";
  if (!fs::is_regular_file(path)) return "";
  PointCloud cloud;
  try {
    cloud = ReadPointCloudPly(path.string());
  } catch (const std::exception& error) {
    page->Problem("dense/points.ply: " + std::string(error.what()));
    return "";
  }
  const PointAttribute* s_normal = cloud.FindAttribute("s_normal");
  const PointAttribute* sx = cloud.FindAttribute("sx");
  const PointAttribute* sy = cloud.FindAttribute("sy");
  const PointAttribute* sz = cloud.FindAttribute("sz");
  const PointAttribute* rays = cloud.FindAttribute("num_images");
  const Units units = DatumUnits(ws);
  std::string html;
  if (sx && sy && sz) {
    html += Paragraph(
        "Median standard deviations of the dense points s<sub>x</sub> / "
        "s<sub>y</sub> / s<sub>z</sub>: " +
        FormatFixed(1000 * Median(sx->values), 2) + " / " +
        FormatFixed(1000 * Median(sy->values), 2) + " / " +
        FormatFixed(1000 * Median(sz->values), 2) + " " + units.precision +
        (s_normal ? "; along the surface normal " +
                        FormatFixed(1000 * Median(s_normal->values), 2) + " " +
                        units.precision
                  : "") +
        ".");
  }
  html += "<div class=\"row\">";
  if (s_normal) {
    std::vector<double> values;
    for (const double v : s_normal->values) values.push_back(1000 * v);
    HistogramOptions histogram;
    histogram.chart.width_px = 420;
    histogram.chart.height_px = 250;
    histogram.chart.title = "Precision along the surface normal";
    histogram.chart.x_label =
        "s_normal [" + std::string(IsDatumMetric(ws) ? "mm" : "1e-3 units") +
        "]";
    histogram.chart.y_label = "points";
    histogram.min = 0;
    std::vector<double> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    histogram.max = sorted.empty() ? 1 : sorted[sorted.size() * 99 / 100];
    histogram.num_bins = 40;
    histogram.color = "#54a24b";
    html += page->Figure(SvgHistogram(values, histogram));
  }
  if (rays) {
    std::map<int, int> counts;
    for (const double v : rays->values) ++counts[static_cast<int>(v)];
    std::vector<Bar> bars;
    for (const auto& [n, count] : counts) {
      bars.push_back({std::to_string(n), {static_cast<double>(count)}, "", ""});
    }
    BarChartOptions chart;
    chart.chart.width_px = 320;
    chart.chart.height_px = 250;
    chart.chart.title = "Images per dense point";
    chart.chart.x_label = "images (master + search)";
    chart.chart.y_label = "points";
    chart.value_decimals = 0;
    html += page->Figure(SvgBarChart(bars, chart));
  }
  return html + "</div>\n";
}

}  // namespace

Section DenseSection(const Workspace& ws, Page* page) {
  Section section{"dense", "Dense points"};
  const std::string status = FileStatus(ws.dense, "bayon dense", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& d = ws.dense.json;
  // The paper's mode tries cells of a Moravec point each; the multiview
  // mode the pixels of the depth maps.
  const bool paper = String(d, "mode") != "multiview";
  const std::string cells = paper ? "cells" : "pixels";
  KeyValueTable facts;
  facts.Add("Points", CountOf(d, "num_points"));
  facts.Add(
      paper ? "Cells tried (one Moravec point each)" : "Depth-map pixels tried",
      CountOf(d, "num_cells"));
  if (Integer(d, "num_cells") > 0) {
    facts.Add(
        "Yield",
        FormatPercent(Number(d, "num_points") / Number(d, "num_cells"), 1));
  }
  if (paper) facts.Add("Cell size", CountOf(d, "cell_size") + " px");
  facts.Add("Time",
            FormatSeconds(Number(d, "seconds")) + " (" +
                FormatFixed(Number(d, "points_per_second"), 0) + " points/s)");
  if (!paper) {
    facts.Add("Time split",
              "depth maps " + FormatSeconds(Number(d, "propagation_seconds")) +
                  ", fusion " + FormatSeconds(Number(d, "fusion_seconds")) +
                  ", MPGC " + FormatSeconds(Number(d, "mpgc_seconds")));
  }
  section.html += facts.Html();

  // Reasons that occur anywhere, in the order of the first master's.
  std::vector<std::string> reasons;
  for (const Json& m : Child(d, "masters")) {
    for (const auto& [reason, count] : Child(m, "rejected").items()) {
      if (Number(count) > 0 &&
          std::find(reasons.begin(), reasons.end(), reason) == reasons.end()) {
        reasons.push_back(reason);
      }
    }
  }
  // Per master: the figures, and the reject reasons as rows of a second
  // table (thirteen reasons do not fit as columns).
  const Json& masters = Child(d, "masters");
  HtmlTable table({"Master",
                   paper ? "Search images" : "Source views",
                   paper ? "Cells" : "Pixels",
                   "Points",
                   "Yield",
                   "Median &sigma; [GSD]",
                   "Time"},
                  "lrrrrrr");
  std::vector<std::string> reason_header = {"Reject reason"};
  std::string reason_align = "l";
  std::vector<Bar> bars;
  for (const Json& m : masters) {
    const double cells = Number(m, "num_cells"),
                 points = Number(m, "num_points");
    table.AddRow({HtmlEscape(String(m, "name")),
                  FormatCount(Child(m, "search_image_ids").size()),
                  CountNumber(cells),
                  CountNumber(points),
                  cells > 0 ? FormatPercent(points / cells, 1) : "&ndash;",
                  FormatFixed(Number(m, "median_sigma_gsd"), 2),
                  FormatSeconds(Number(m, "seconds"))});
    reason_header.push_back(HtmlEscape(ImageStem(String(m, "name"))));
    reason_align += 'r';
    Bar bar;
    bar.label = ImageStem(String(m, "name"));
    bar.values.push_back(std::max(0.0, points));
    for (const std::string& reason : reasons) {
      const double count = Number(Child(m, "rejected"), reason.c_str());
      bar.values.push_back(std::isfinite(count) ? count : 0.0);
    }
    bars.push_back(bar);
  }
  HtmlTable reason_table(reason_header, reason_align);
  for (const std::string& reason : reasons) {
    std::vector<std::string> row = {HtmlEscape(reason)};
    for (const Json& m : masters) {
      row.push_back(CountNumber(Number(Child(m, "rejected"), reason.c_str())));
    }
    reason_table.AddRow(row);
  }
  section.html += table.Html();
  if (!bars.empty()) {
    BarChartOptions chart;
    chart.horizontal = true;
    chart.chart.width_px = 600;
    chart.chart.height_px = 0;
    chart.chart.title = (paper ? "Cells" : "Pixels") +
                        std::string(" per master: points and reject reasons");
    chart.chart.x_label = cells;
    chart.series = {{"points", "#4c78a8"}};
    for (size_t i = 0; i < reasons.size(); ++i) {
      chart.series.push_back({reasons[i], kPalette[(i + 1) % kPaletteSize]});
    }
    section.html +=
        "<div class=\"row\">" + page->Figure(SvgBarChart(bars, chart)) +
        (reason_table.empty() ? "" : "<div>" + reason_table.Html() + "</div>") +
        "</div>\n";
  }
  section.html += DenseCloudFigures(ws, page);
  return section;
}

Section EditSection(const Workspace& ws, Page* page) {
  Section section{"edit", "Point cloud editing"};
  const std::string status = FileStatus(ws.edit, "bayon edit", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& e = ws.edit.json;
  KeyValueTable facts;
  facts.Add("Method", HtmlEscape(String(e, "method")));
  facts.Add("Points in", CountOf(e, "num_input"));
  facts.Add("Kept", CountOf(e, "num_kept"));
  std::string removed = CountOf(e, "num_removed");
  if (Integer(e, "num_input") > 0) {
    removed +=
        " (" +
        FormatPercent(Number(e, "num_removed") / Number(e, "num_input"), 1) +
        ")";
  }
  facts.Add("Removed as blunders", removed);
  for (const auto& [reason, count] : Child(e, "removed_by_reason").items()) {
    facts.Add("&nbsp;&nbsp;" + HtmlEscape(reason), CountNumber(Number(count)));
  }
  const Json& converged = Child(e, "converged");
  if (converged.is_boolean()) {
    facts.Add("Converged", converged.get<bool>() ? "yes" : "no");
  }
  facts.Add("Time", FormatSeconds(Number(e, "seconds")));
  section.html += facts.Html();
  const Json& iterations = Child(e, "iterations");
  if (iterations.is_array() && !iterations.empty()) {
    HtmlTable table({"Iteration",
                     "Tested",
                     "Flagged",
                     "Newly flagged",
                     "Restored",
                     "Median normalized deviation"},
                    "rrrrrr");
    for (const Json& it : iterations) {
      table.AddRow({CountOf(it, "iteration"),
                    CountOf(it, "num_tested"),
                    CountOf(it, "num_flagged"),
                    CountOf(it, "num_newly_flagged"),
                    CountOf(it, "num_restored"),
                    FormatFixed(Number(it, "median_normalized_deviation"), 3)});
    }
    section.html += "<details><summary>Iterations</summary>" + table.Html() +
                    "</details>\n";
  }
  return section;
}

Section MeshSection(const Workspace& ws, Page* page) {
  Section section{"mesh", "Surface mesh"};
  const std::string status = FileStatus(ws.mesh, "bayon mesh", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& m = ws.mesh.json;
  const Units units = DatumUnits(ws);
  KeyValueTable facts;
  facts.Add("Method", HtmlEscape(String(m, "method")));
  facts.Add("Points in", CountOf(m, "num_input_points"));
  facts.Add("Vertices / faces",
            CountOf(m, "num_vertices") + " / " + CountOf(m, "num_faces"));
  facts.Add("Boundary loops", CountOf(m, "num_boundary_loops"));
  facts.Add("Non-manifold edges / vertices",
            CountOf(m, "num_non_manifold_edges") + " / " +
                CountOf(m, "num_non_manifold_vertices"));
  facts.Add("Connected components", CountOf(m, "num_components"));
  facts.Add("Mean / longest edge",
            FormatSignificant(Number(m, "mean_edge"), 3) + " / " +
                FormatSignificant(Number(m, "longest_edge"), 3) + " " +
                units.length);
  facts.Add("Area",
            FormatSignificant(Number(m, "area"), 4) + " " + units.length +
                "<sup>2</sup>");
  const Json& seconds = Child(m, "seconds");
  double total = 0;
  for (const auto& [step, value] : seconds.items()) {
    if (value.is_number()) total += value.get<double>();
  }
  facts.Add("Time", FormatSeconds(total));
  section.html += facts.Html();
  const Json& cleanup = Child(m, "cleanup");
  if (cleanup.is_object()) {
    std::string text;
    for (const auto& [name, value] : cleanup.items()) {
      if (Number(value) > 0) {
        std::string label = name;
        std::replace(label.begin(), label.end(), '_', ' ');
        text += (text.empty() ? "" : ", ") + HtmlEscape(label) + " " +
                CountNumber(Number(value));
      }
    }
    section.html += Paragraph(
        "Cleanup: " + (text.empty() ? "nothing to repair" : text) + ".");
  }
  return section;
}

Section TextureSection(const Workspace& ws, Page* page) {
  Section section{"texture", "Texture"};
  const std::string status = FileStatus(ws.texture, "bayon texture", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& t = ws.texture.json;
  KeyValueTable facts;
  facts.Add("Pre-processing / blending",
            HtmlEscape(String(t, "preprocess")) + " / " +
                HtmlEscape(String(t, "blend")));
  facts.Add("Photographs", CountOf(t, "num_images"));
  std::string unseen = CountOf(t, "num_unseen_faces");
  if (Integer(t, "num_faces") > 0) {
    unseen += " (" +
              FormatPercent(
                  Number(t, "num_unseen_faces") / Number(t, "num_faces"), 1) +
              ")";
  }
  facts.Add("Faces / unseen by any photograph",
            CountOf(t, "num_faces") + " / " + unseen);
  facts.Add("Photographs seeing a face (mean)",
            FormatFixed(Number(t, "mean_views_per_face"), 2));
  facts.Add("Charts", CountOf(t, "num_charts"));
  facts.Add("Atlas",
            CountOf(t, "atlas_width") + " &times; " +
                CountOf(t, "atlas_height") + " texels, " +
                FormatPercent(Number(t, "atlas_fill"), 1) + " filled");
  facts.Add("Texel size",
            FormatSignificant(Number(t, "texel_size"), 3) + " " +
                DatumUnits(ws).length);
  facts.Add("Seam measure (mean colour difference across seams)",
            FormatFixed(Number(t, "seam_difference"), 2) + " grey levels on " +
                CountOf(t, "num_seam_edges") + " edges");
  const Json& balance = Child(t, "balance");
  if (!balance.is_null()) {
    double lowest = 1e300, highest = -1e300;
    for (const auto& [name, image] : Child(balance, "images").items()) {
      for (const Json& gain : Child(image, "gain_bgr")) {
        lowest = std::min(lowest, Number(gain));
        highest = std::max(highest, Number(gain));
      }
    }
    std::string text =
        "differences over " + CountOf(balance, "num_faces") + " shared faces " +
        FormatFixed(Number(balance, "sigma_before"), 2) + " &rarr; " +
        FormatFixed(Number(balance, "sigma_after"), 2) +
        " grey levels (robust sigma)";
    if (lowest <= highest) {
      text += "; gains " + FormatFixed(lowest, 3) + " to " +
              FormatFixed(highest, 3);
    }
    facts.Add("Exposure balance (gain and offset per photograph and channel)",
              text);
  }
  const Json& leveling = Child(t, "seam_leveling_report");
  if (!leveling.is_null() && Integer(leveling, "num_seam_edges") > 0) {
    facts.Add(
        "Seam levelling (the solver's differences at the chart "
        "borders' samples)",
        FormatFixed(Number(leveling, "difference_before"), 2) + " &rarr; " +
            FormatFixed(Number(leveling, "difference_after"), 2) +
            " grey levels");
  }
  double total = 0;
  for (const auto& [step, value] : Child(t, "seconds").items()) {
    if (value.is_number()) total += value.get<double>();
  }
  facts.Add("Time", FormatSeconds(total));
  std::vector<Bar> bars;
  for (const auto& [name, count] : Child(t, "faces_per_image").items()) {
    bars.push_back({ImageStem(name), {Number(count)}, "", ""});
  }
  std::string figures;
  if (!bars.empty()) {
    BarChartOptions chart;
    chart.chart.width_px =
        std::clamp(120 + 24 * static_cast<int>(bars.size()), 420, 760);
    chart.chart.height_px = 280;
    chart.chart.title = "Faces textured from each photograph";
    chart.chart.y_label = "faces";
    figures += page->Figure(SvgBarChart(bars, chart),
                            "Faces whose optimal image (where the face "
                            "projects largest) is the photograph.");
  }
  const fs::path atlas = ws.root / "model" / "model.png";
  if (fs::is_regular_file(atlas)) {
    const std::string picture =
        page->Picture(atlas, "texture atlas", 360, "atlas");
    if (!picture.empty()) {
      figures += "<figure>" + picture +
                 "<figcaption>The texture atlas (model/model.png, "
                 "scaled down).</figcaption></figure>";
    }
  }
  section.html += "<div class=\"row\"><div>" + facts.Html() + "</div>" +
                  figures + "</div>\n";
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 11. Renders and the viewer.

// The renders to show: the first view of each mode, then more textured
// views.
std::vector<fs::path> ChooseRenders(const fs::path& folder, int max_renders) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg")) {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  std::vector<fs::path> chosen;
  const auto add = [&](const fs::path& path) {
    if (static_cast<int>(chosen.size()) < max_renders &&
        std::find(chosen.begin(), chosen.end(), path) == chosen.end()) {
      chosen.push_back(path);
    }
  };
  const auto with_prefix = [&](const std::string& prefix) {
    std::vector<fs::path> matching;
    for (const fs::path& file : files) {
      if (file.filename().string().rfind(prefix, 0) == 0) {
        matching.push_back(file);
      }
    }
    return matching;
  };
  // Row-interleaved and side-by-side stereo pictures do not survive being
  // scaled down; the anaglyph does.
  for (const char* mode : {"textured_", "shaded_", "wireframe_", "anaglyph_"}) {
    const std::vector<fs::path> matching = with_prefix(mode);
    if (!matching.empty()) add(matching.front());
  }
  // Then the other textured views, evenly around the orbit.
  std::vector<fs::path> textured;
  for (const fs::path& file : with_prefix("textured_")) {
    if (std::find(chosen.begin(), chosen.end(), file) == chosen.end()) {
      textured.push_back(file);
    }
  }
  const size_t room = max_renders > static_cast<int>(chosen.size())
                          ? max_renders - chosen.size()
                          : 0;
  for (size_t k = 0; k < std::min(room, textured.size()); ++k) {
    add(textured[k * textured.size() / std::min(room, textured.size())]);
  }
  // An untextured model: more views of whatever there is.
  if (textured.empty()) {
    for (const fs::path& file : files) {
      const std::string name = file.filename().string();
      if (name.rfind("interleaved_", 0) != 0 &&
          name.rfind("side_by_side_", 0) != 0) {
        add(file);
      }
    }
  }
  return chosen;
}

}  // namespace

Section RendersSection(const Workspace& ws, Page* page) {
  Section section{"renders", "Renders and viewer"};
  const fs::path viewer = ws.root / "viewer" / "index.html";
  const WorkspaceReportOptions& options = page->options();
  if (fs::is_regular_file(viewer)) {
    const fs::path report_dir =
        options.report_dir.empty() ? ws.root : fs::path(options.report_dir);
    const fs::path link =
        fs::absolute(viewer).lexically_normal().lexically_relative(
            fs::absolute(report_dir).lexically_normal());
    section.html += "<p class=\"viewer\"><a href=\"" +
                    HtmlEscape(link.generic_string()) +
                    "\">Open the model in the interactive viewer</a> (" +
                    HtmlEscape(link.generic_string()) +
                    ": orbit, pan, zoom; textured, shaded, wireframe, "
                    "anaglyph; works offline).</p>\n";
  } else {
    section.html += NotRun("no <code>viewer/index.html</code> (bayon viewer)");
  }
  const fs::path renders = ws.root / "renders";
  const std::vector<fs::path> chosen =
      fs::is_directory(renders) ? ChooseRenders(renders, options.max_renders)
                                : std::vector<fs::path>();
  if (chosen.empty()) {
    section.html +=
        NotRun("no pictures in <code>renders/</code> (bayon render)");
    if (!fs::is_regular_file(viewer)) section.ran = false;
    return section;
  }
  std::string pictures;
  for (const fs::path& path : chosen) {
    const std::string name = path.filename().string();
    const std::string picture =
        page->Picture(path, name, options.max_render_size_px, "render");
    if (picture.empty()) continue;
    pictures += "<figure>" + picture + "<figcaption>" + HtmlEscape(name) +
                "</figcaption></figure>\n";
  }
  section.html += "<div class=\"renders\">" + pictures + "</div>\n";
  return section;
}

namespace {

// ---------------------------------------------------------------------------
// 12. The comparison with stock COLMAP, 13. the evaluation against a truth.

std::string Cell(const Json& json, const char* key, int decimals) {
  const Json& value = Child(json, key);
  if (value.is_number_integer()) return FormatCount(value.get<int64_t>());
  return FormatFixed(Number(value), decimals);
}

std::string SignificantCell(const Json& json, const char* key) {
  return FormatSignificant(Number(json, key), 4);
}

}  // namespace

Section ComparisonSection(const Workspace& ws, Page* page) {
  Section section{"colmap", "Comparison with stock COLMAP"};
  const std::string status =
      FileStatus(ws.comparison, "bayon compare_colmap", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& c = ws.comparison.json;
  const Json& b = Child(c, "bayon");
  const Json& m = Child(c, "colmap");
  const std::string num_images = CountOf(c, "num_images");
  HtmlTable table({"", "bayon", "COLMAP"}, "lrr");
  table.AddRow({"Model",
                HtmlEscape(String(b, "model_display").empty()
                               ? String(b, "model_path")
                               : String(b, "model_display")),
                HtmlEscape(String(m, "model_display").empty()
                               ? String(m, "model_path")
                               : String(m, "model_display"))});
  table.AddRow({"Images registered",
                Cell(b, "registered", 0) + " / " + num_images,
                Cell(m, "registered", 0) + " / " + num_images},
               "key");
  table.AddRow({"3D points", Cell(b, "points3D", 0), Cell(m, "points3D", 0)});
  table.AddRow(
      {"Observations", Cell(b, "observations", 0), Cell(m, "observations", 0)});
  table.AddRow({"Mean track length",
                Cell(b, "mean_track_length", 2),
                Cell(m, "mean_track_length", 2)});
  table.AddRow({"Mean reprojection error [px]",
                Cell(b, "mean_reprojection_error_px", 3),
                Cell(m, "mean_reprojection_error_px", 3)});
  table.AddRow({"RMS reprojection error [px]",
                Cell(b, "rms_reprojection_error_px", 3),
                Cell(m, "rms_reprojection_error_px", 3)});
  table.AddRow({"&sigma;<sub>0</sub> [px]",
                Cell(b, "sigma0_px", 3),
                Cell(m, "sigma0_px", 3)},
               "key");
  if (Child(b, "adjustment_sigma0").is_number() ||
      Child(m, "adjustment_sigma0").is_number()) {
    table.AddRow({"&sigma;<sub>0</sub> of the adjustment [px]",
                  Cell(b, "adjustment_sigma0", 3),
                  Cell(m, "adjustment_sigma0", 3)});
  }
  if (Child(b, "adjustment_sigma0_apriori_px").is_number() ||
      Child(m, "adjustment_sigma0_apriori_px").is_number()) {
    table.AddRow({"&hellip; a priori [px]",
                  Cell(b, "adjustment_sigma0_apriori_px", 3),
                  Cell(m, "adjustment_sigma0_apriori_px", 3)});
  }
  std::vector<std::string> stages;
  for (const Json* side : {&b, &m}) {
    for (const auto& [name, seconds] : Child(*side, "stage_seconds").items()) {
      if (std::find(stages.begin(), stages.end(), name) == stages.end()) {
        stages.push_back(name);
      }
    }
  }
  for (const std::string& name : stages) {
    const auto time = [&](const Json& side) {
      const double s = Number(Child(side, "stage_seconds"), name.c_str());
      return std::isfinite(s) ? FormatSeconds(s) : "";
    };
    table.AddRow({"Time: " + HtmlEscape(name), time(b), time(m)});
  }
  table.AddRow({"Time: total",
                FormatSeconds(Number(b, "total_seconds")),
                FormatSeconds(Number(m, "total_seconds"))},
               "key");
  const Json& truth = Child(c, "truth");
  if (truth.is_object()) {
    const Json& tb = Child(truth, "bayon");
    const Json& tm = Child(truth, "colmap");
    table.AddRow({"<b>Against the truth</b> <code>" +
                      HtmlEscape(String(truth, "path")) + "</code>",
                  "",
                  ""},
                 "group");
    table.AddRow(
        {"Registered", Cell(tb, "registered", 0), Cell(tm, "registered", 0)});
    table.AddRow({"Camera centres, RMS [truth units]",
                  SignificantCell(tb, "center_rms"),
                  SignificantCell(tm, "center_rms")},
                 "key");
    table.AddRow({"Camera centres, max [truth units]",
                  SignificantCell(tb, "center_max"),
                  SignificantCell(tm, "center_max")});
    table.AddRow({"Camera centres, RMS [% of the camera distance]",
                  Cell(tb, "center_rms_percent", 3),
                  Cell(tm, "center_rms_percent", 3)});
    table.AddRow({"Rotations, RMS [&deg;]",
                  Cell(tb, "rotation_rms_deg", 3),
                  Cell(tm, "rotation_rms_deg", 3)},
                 "key");
  }
  const Json& a = Child(c, "agreement");
  if (a.is_object()) {
    table.AddRow({"<b>Agreement of the cameras</b> (COLMAP's fitted to "
                  "bayon's by a similarity, " +
                      CountOf(a, "num_common") + " common images)",
                  "",
                  ""},
                 "group");
    table.AddRow({"Camera centres, RMS / max [bayon units]",
                  SignificantCell(a, "center_rms") + " / " +
                      SignificantCell(a, "center_max"),
                  ""});
    table.AddRow({"Camera centres, RMS [% of the camera distance]",
                  Cell(a, "center_rms_percent", 3),
                  ""});
    table.AddRow(
        {"Rotations, RMS [&deg;]", Cell(a, "rotation_rms_deg", 3), ""});
  }
  section.html += table.Html("comparison");
  return section;
}

Section EvaluationSection(const Workspace& ws, Page* page) {
  Section section{"evaluation", "Accuracy against the truth"};
  const std::string status = FileStatus(
      ws.evaluation, "bayon evaluate --output_path evaluation.json", page);
  if (!status.empty()) {
    section.ran = false;
    section.html = status;
    return section;
  }
  const Json& e = ws.evaluation.json;
  section.html +=
      Paragraph("Truth: <code>" + HtmlEscape(String(e, "ground_truth_path")) +
                "</code>.");
  const Json& sparse = Child(e, "sparse");
  if (sparse.is_object()) {
    KeyValueTable facts;
    facts.Add("Images registered",
              CountOf(sparse, "num_registered") + " / " +
                  CountOf(sparse, "num_truth_images"));
    facts.Add("Camera centres, RMS / max",
              FormatSignificant(Number(sparse, "center_rms"), 4) + " / " +
                  FormatSignificant(Number(sparse, "center_max"), 4) +
                  " (truth units; " +
                  FormatPercent(Number(sparse, "center_rms_relative"), 3) +
                  " of the camera distance)");
    facts.Add("Rotations, RMS / max",
              FormatFixed(Number(sparse, "rotation_rms_deg"), 4) + " / " +
                  FormatFixed(Number(sparse, "rotation_max_deg"), 4) + "&deg;");
    section.html += "<h3>Orientation</h3>" + facts.Html();
  }
  for (const Json& camera : Child(e, "calibration")) {
    HtmlTable table({"Parameter",
                     "Estimate",
                     "Truth",
                     "Error",
                     "&sigma;",
                     "Error / &sigma;"},
                    "lrrrrr");
    for (const Json& p : Child(camera, "parameters")) {
      table.AddRow({HtmlEscape(String(p, "name")),
                    FormatSignificant(Number(p, "estimate"), 5),
                    FormatSignificant(Number(p, "truth"), 5),
                    FormatSignificant(Number(p, "error"), 3),
                    FormatSignificant(Number(p, "sigma"), 3),
                    FormatFixed(Number(p, "error_over_sigma"), 2)});
    }
    section.html += "<h3>Calibration, camera " + CountOf(camera, "camera_id") +
                    "</h3>" + table.Html();
  }
  HtmlTable surfaces({"Product",
                      "Points / vertices",
                      "Accuracy median",
                      "RMS",
                      "95 %",
                      "Completeness",
                      "walls",
                      "tops"},
                     "lrrrrrrr");
  for (const char* key : {"cloud", "mesh"}) {
    const Json& s = Child(e, key);
    if (!s.is_object()) continue;
    const Json& gsd = Child(s, "accuracy_gsd");
    const Json& metres = Child(s, "accuracy_m");
    const bool in_gsd = gsd.is_object();
    const auto value = [&](const char* stat) {
      return in_gsd ? FormatFixed(Number(gsd, stat), 2) + " GSD"
                    : FormatSignificant(Number(metres, stat), 3);
    };
    // Completeness of the true surface facing sideways and up.
    const auto orientation = [&](const char* part) {
      return FormatPercent(
          Number(Child(Child(s, "completeness_by_orientation"), part),
                 "completeness_fraction"),
          1);
    };
    surfaces.AddRow({key,
                     CountOf(s, "num_points"),
                     value("median"),
                     value("rms"),
                     value("p95"),
                     FormatPercent(Number(s, "completeness_fraction"), 1),
                     orientation("walls"),
                     orientation("tops")});
  }
  if (!surfaces.empty()) {
    section.html += "<h3>Surfaces</h3>" + surfaces.Html();
  }
  const Json& texture = Child(e, "texture");
  if (texture.is_object()) {
    KeyValueTable facts;
    facts.Add("PSNR / SSIM",
              FormatFixed(Number(texture, "mean_psnr_db"), 2) + " dB / " +
                  FormatFixed(Number(texture, "mean_ssim"), 3));
    facts.Add("After a per-channel gain and offset",
              FormatFixed(Number(texture, "mean_normalized_psnr_db"), 2) +
                  " dB / " +
                  FormatFixed(Number(texture, "mean_normalized_ssim"), 3));
    section.html +=
        "<h3>Textured model from the held-out viewpoints</h3>" + facts.Html();
  }
  return section;
}

}  // namespace report
}  // namespace bayon
