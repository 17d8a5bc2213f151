// SPDX-License-Identifier: BSD-3-Clause
//
// Inside `bayon report` (workspace_report.h): one function per section of
// the page, in page order. Each returns its section, marked "not run" where
// the workspace lacks the stage's output; none throws for a missing or
// unreadable optional file.
#pragma once

#include "ext/report/report_page.h"
#include "ext/report/report_workspace.h"

namespace bayon {
namespace report {

// sparse_sections.cc: the pipeline and the sparse model.
Section PipelineSection(const Workspace& ws, Page* page);
Section NetworkSection(const Workspace& ws, Page* page);
Section TiePointSection(const Workspace& ws, Page* page);
Section ResidualSection(const Workspace& ws, Page* page);
Section CalibrationSection(const Workspace& ws, Page* page);
Section PrecisionSection(const Workspace& ws, Page* page);

// product_sections.cc: the products after the adjustment, and the
// comparisons.
Section DenseSection(const Workspace& ws, Page* page);
Section EditSection(const Workspace& ws, Page* page);
Section MeshSection(const Workspace& ws, Page* page);
Section TextureSection(const Workspace& ws, Page* page);
Section RendersSection(const Workspace& ws, Page* page);
Section ComparisonSection(const Workspace& ws, Page* page);
Section EvaluationSection(const Workspace& ws, Page* page);

}  // namespace report
}  // namespace bayon
