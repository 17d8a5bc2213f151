// SPDX-License-Identifier: BSD-3-Clause
#include "ext/report/workspace_report.h"

#include "ext/core/errors.h"
#include "ext/report/html.h"
#include "ext/report/report_page.h"
#include "ext/report/report_sections.h"
#include "ext/report/report_workspace.h"

#include <glog/logging.h>

#include <ctime>
#include <filesystem>
#include <functional>

namespace bayon {
namespace {

namespace fs = std::filesystem;
using report::Child;
using report::CountOf;
using report::DatumUnits;
using report::Json;
using report::Number;
using report::Page;
using report::Section;
using report::String;
using report::Triple;
using report::Workspace;

// ---------------------------------------------------------------------------
// The summary at the top and the page around the sections.

std::string Card(const std::string& value, const std::string& label) {
  return "<div class=\"card\"><div class=\"value\">" + value +
         "</div><div class=\"label\">" + label + "</div></div>";
}

std::string SummaryCards(const Workspace& ws) {
  std::string cards;
  std::string images = FormatCount(ws.model.images.size());
  if (ws.num_database_images >= 0) {
    images += " / " + FormatCount(ws.num_database_images);
  }
  cards += Card(images, "images oriented");
  cards += Card(FormatCount(ws.model.points3D.size()), "tie points");
  const Json& s = Child(ws.adjustment.json, "statistics");
  if (std::isfinite(Number(s, "sigma0_px"))) {
    cards += Card(FormatFixed(Number(s, "sigma0_px"), 3) + " px",
                  "&sigma;<sub>0</sub> a posteriori");
    cards += Card(FormatFixed(Number(s, "r_over_n"), 2), "r/n");
  }
  const Json& precision = Child(s, "point_precision_rms_mm");
  if (precision.is_array() && precision.size() == 3) {
    cards += Card(Triple(precision, 2),
                  "s<sub>x</sub> / s<sub>y</sub> / s<sub>z</sub> [" +
                      DatumUnits(ws).precision + "]");
  }
  if (ws.dense.ok()) {
    cards += Card(CountOf(ws.dense.json, "num_points"), "dense points");
  }
  if (ws.mesh.ok()) {
    cards += Card(CountOf(ws.mesh.json, "num_faces"), "mesh faces");
  }
  if (ws.pipeline.ok() &&
      std::isfinite(Number(ws.pipeline.json, "total_seconds"))) {
    cards += Card(FormatSeconds(Number(ws.pipeline.json, "total_seconds")),
                  "pipeline time");
  }
  return "<div class=\"cards\">" + cards + "</div>\n";
}

constexpr char kStyle[] = R"css(
:root { --fg: #1f2328; --muted: #656d76; --line: #d8dee4; --accent: #4c78a8; }
* { box-sizing: border-box; }
body { margin: 0; background: #f3f4f6; color: var(--fg); font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1120px; margin: 0 auto; padding: 0 28px 40px; background: #fff; min-height: 100vh; }
header { padding: 26px 0 14px; border-bottom: 3px solid var(--accent); }
h1 { font-size: 26px; margin: 0 0 6px; }
h2 { font-size: 20px; margin: 8px 0 10px; }
h3 { font-size: 15px; margin: 18px 0 6px; }
.meta { color: var(--muted); font-size: 13px; margin: 2px 0; }
code { font: 12.5px ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; background: #f2f4f7; padding: 1px 4px; border-radius: 3px; word-break: break-all; }
nav#toc { margin: 16px 0 6px; font-size: 14px; }
nav#toc ol { columns: 3; margin: 4px 0; padding-left: 22px; }
nav#toc li.not-run a { color: #9aa1a9; }
nav#toc li.not-run::after { content: " (not run)"; color: #9aa1a9; font-size: 12px; }
a { color: #2f6db3; }
section { padding: 14px 0 10px; border-top: 1px solid var(--line); }
.cards { display: flex; flex-wrap: wrap; gap: 10px; margin: 14px 0 6px; }
.card { border: 1px solid var(--line); border-radius: 6px; padding: 8px 14px; min-width: 120px; background: #fafbfc; }
.card .value { font-size: 19px; font-weight: 600; white-space: nowrap; }
.card .label { font-size: 12px; color: var(--muted); }
table { border-collapse: collapse; font-size: 13px; margin: 6px 0 12px; }
th, td { padding: 3px 10px; border-bottom: 1px solid #e8ebef; text-align: left; vertical-align: top; }
thead th { border-bottom: 2px solid #c3c9d0; background: #f5f7f9; font-weight: 600; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.kv th { font-weight: normal; color: #3d444d; }
table.kv td { text-align: right; }
tr.key td { font-weight: 600; }
tr.significant td { font-weight: 600; background: #eef7ec; }
tr.group td { background: #f5f7f9; padding-top: 6px; }
table.precision td:first-child { min-width: 240px; }
.wide { overflow-x: auto; }
.row { display: flex; flex-wrap: wrap; gap: 18px; align-items: flex-start; }
figure { margin: 6px 0 10px; display: table; }
figcaption { display: table-caption; caption-side: bottom; font-size: 12px; color: var(--muted); margin-top: 2px; }
svg.chart { max-width: 100%; height: auto; display: block; }
.frames { display: grid; grid-template-columns: repeat(auto-fill, 160px); gap: 8px 12px; }
.nowrap { white-space: nowrap; }
.grow { flex: 1 1 360px; }
.renders { display: grid; grid-template-columns: repeat(auto-fill, minmax(320px, 1fr)); gap: 12px; }
img.render { width: 100%; height: auto; border: 1px solid var(--line); }
img.atlas { max-width: 360px; border: 1px solid var(--line); }
.badge { display: inline-block; padding: 0 7px; border-radius: 3px; font-size: 12px; color: #fff; background: #8a8f96; }
.badge.ran { background: #3f8f3a; } .badge.skipped { background: #9aa1a9; } .badge.failed { background: #d1403d; }
.not-run { color: #8a8f96; font-style: italic; }
section.absent h2 { color: #8a8f96; }
.problem { color: #b3261e; }
.viewer a { font-weight: 600; }
details { margin: 6px 0 10px; font-size: 13px; }
summary { cursor: pointer; color: #2f6db3; }
pre { font-size: 12px; white-space: pre-wrap; word-break: break-all; background: #f6f8fa; padding: 8px; }
footer { color: var(--muted); font-size: 12px; padding-top: 14px; border-top: 1px solid var(--line); }
@media print { body { background: #fff; } main { max-width: none; } details { display: none; } }
)css";

std::string Now() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char buffer[64];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M %Z", &local);
  return buffer;
}

std::string Header(const Workspace& ws, const std::string& title) {
  std::string html = "<header><h1>" + HtmlEscape(title) + "</h1>\n";
  html += "<p class=\"meta\">Workspace <code>" +
          HtmlEscape(fs::absolute(ws.root).lexically_normal().string()) +
          "</code></p>\n";
  if (ws.pipeline.ok() && !String(ws.pipeline.json, "image_path").empty()) {
    html += "<p class=\"meta\">Photographs <code>" +
            HtmlEscape(String(ws.pipeline.json, "image_path")) +
            "</code></p>\n";
  }
  html += "<p class=\"meta\">Generated " + HtmlEscape(Now()) +
          " by <code>bayon report</code></p>\n</header>\n";
  return html;
}

std::string TableOfContents(const std::vector<Section>& sections) {
  std::string html = "<nav id=\"toc\"><b>Contents</b><ol>";
  for (const Section& section : sections) {
    html += std::string(section.ran ? "<li>" : "<li class=\"not-run\">") +
            "<a href=\"#" + section.id + "\">" + HtmlEscape(section.title) +
            "</a></li>";
  }
  return html + "</ol></nav>\n";
}

}  // namespace

void WorkspaceReportOptions::Register(OptionRegistry* r) {
  r->Add(
      "title", &title, "Page title (default: bayon report: <workspace name>)");
  r->Add("max_render_size_px",
         &max_render_size_px,
         "Longest side of the embedded renders, pixels");
  r->Add("max_renders", &max_renders, "Renders embedded");
  r->Add("max_plot_points",
         &max_plot_points,
         "Sparse points drawn in the plan and side views");
}

void WorkspaceReportOptions::Check() const {
  CheckOption(max_render_size_px >= 64,
              "max_render_size_px",
              ">= 64",
              max_render_size_px);
  CheckOption(jpeg_quality >= 10 && jpeg_quality <= 100,
              "jpeg_quality",
              "in [10, 100]",
              jpeg_quality);
  CheckOption(max_renders >= 0, "max_renders", ">= 0", max_renders);
  CheckOption(max_plot_points >= 1, "max_plot_points", ">= 1", max_plot_points);
  CheckOption(
      max_frame_points >= 1, "max_frame_points", ">= 1", max_frame_points);
  CheckOption(max_frames >= 1, "max_frames", ">= 1", max_frames);
  CheckOption(residual_grid_cells >= 2 && residual_grid_cells <= 50,
              "residual_grid_cells",
              "in [2, 50]",
              residual_grid_cells);
}

WorkspaceReport BuildWorkspaceReport(const std::string& workspace_path,
                                     const WorkspaceReportOptions& options) {
  options.Check();
  const Workspace ws = report::LoadWorkspace(workspace_path);
  Page page(options);
  using SectionBuilder = std::function<Section(const Workspace&, Page*)>;
  const std::vector<std::pair<std::string, SectionBuilder>> builders = {
      {"Pipeline run", report::PipelineSection},
      {"Image network", report::NetworkSection},
      {"Tie-point distribution", report::TiePointSection},
      {"Image residuals", report::ResidualSection},
      {"Additional parameters", report::CalibrationSection},
      {"Precision of the bundle adjustment", report::PrecisionSection},
      {"Dense points", report::DenseSection},
      {"Point cloud editing", report::EditSection},
      {"Surface mesh", report::MeshSection},
      {"Texture", report::TextureSection},
      {"Renders and viewer", report::RendersSection},
      {"Comparison with stock COLMAP", report::ComparisonSection},
      {"Accuracy against the truth", report::EvaluationSection}};
  std::vector<Section> sections;
  for (const auto& [title, build] : builders) {
    // One odd file spoils its own section, not the page.
    try {
      sections.push_back(build(ws, &page));
    } catch (const std::exception& error) {
      LOG(WARNING) << "report section '" << title
                   << "' could not be made: " << error.what();
      page.Problem(title + ": " + error.what());
      Section section;
      section.title = title;
      section.id = "section" + std::to_string(sections.size() + 1);
      section.ran = false;
      section.html = "<p class=\"problem\">Could not be shown: " +
                     HtmlEscape(error.what()) + "</p>\n";
      sections.push_back(section);
    }
  }

  const std::string title =
      options.title.empty()
          ? "bayon report: " +
                fs::absolute(ws.root).lexically_normal().filename().string()
          : options.title;
  WorkspaceReport report;
  std::string& html = report.html;
  html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, "
      "initial-scale=1\">\n<meta name=\"generator\" content=\"bayon "
      "report\">\n<title>" +
      HtmlEscape(title) + "</title>\n<style>" + kStyle +
      "</style>\n</head>\n<body>\n<main>\n";
  html += Header(ws, title);
  html += SummaryCards(ws);
  html += TableOfContents(sections);
  int number = 0;
  for (const Section& section : sections) {
    html += "<section id=\"" + section.id + "\"" +
            (section.ran ? "" : " class=\"absent\"") + "><h2>" +
            std::to_string(++number) + ". " + HtmlEscape(section.title) +
            "</h2>\n" + section.html + "</section>\n";
    report.section_ids.push_back(section.id);
    if (!section.ran) report.not_run.push_back(section.title);
  }
  html +=
      "<footer>bayon, after Gruen, Zhang and Visnovcova, <i>Automatic "
      "Reconstruction and Visualization of a Complex Buddha Tower of Bayon, "
      "Angkor, Cambodia</i>. Image residuals in pixels; object coordinates "
      "in the datum's units.</footer>\n</main>\n</body>\n</html>\n";
  report.problems = page.problems();
  report.num_images = static_cast<int>(ws.model.images.size());
  report.num_points3D = static_cast<int>(ws.model.points3D.size());
  report.num_observations = static_cast<int>(ws.observations.size());
  report.num_charts = page.num_charts();
  report.num_pictures = page.num_pictures();
  return report;
}

}  // namespace bayon
