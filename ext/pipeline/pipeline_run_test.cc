// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/pipeline_run.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// Three stages a, b, c, each writing its own output file, run by a fake
// command runner that records what it ran.
struct FakePipeline {
  explicit FakePipeline(const std::string& name) {
    c.workspace = testing::TempDir(name);
    c.image_path = c.workspace + "/images";
    fs::create_directories(c.workspace + "/pipeline");
    for (const char* stage : {"a", "b", "c"}) {
      const std::string output = c.workspace + "/" + stage + ".out";
      stages.push_back({stage,
                        "bayon",
                        stage,
                        {{"output_path", output}},
                        true,
                        {output},
                        {}});
    }
  }

  // Runs the stages first..last; `exit_code` for stage `failing`.
  bool Run(StageSelection selection = {0, 2, false, false},
           const std::string& failing = "",
           int exit_code = 0) {
    ran.clear();
    PipelineRun run(
        c,
        "test.ini",
        stages,
        selection,
        [&](const std::string& command, const std::vector<std::string>& words) {
          EXPECT_EQ(words[0], "bayon");
          ran.push_back(command);
          if (command == failing) {
            if (exit_code == 2) ThrowInputError("bad ", command);
            return exit_code;
          }
          std::ofstream(c.workspace + "/" + command + ".out") << "done";
          return 0;
        });
    const bool ok = run.Run();
    statuses.clear();
    for (const StageRun& stage : run.runs()) statuses.push_back(stage.status);
    return ok;
  }

  nlohmann::json RunJson() const {
    std::ifstream file(c.workspace + "/pipeline.json");
    return nlohmann::json::parse(file);
  }

  PipelineContext c;
  std::vector<Stage> stages;
  std::vector<std::string> ran, statuses;
};

using Strings = std::vector<std::string>;

TEST(PipelineRun, RunsEveryStageThenSkipsThemAll) {
  FakePipeline p("run_twice");
  EXPECT_TRUE(p.Run());
  EXPECT_EQ(p.ran, Strings({"a", "b", "c"}));
  EXPECT_EQ(p.statuses, Strings({"ran", "ran", "ran"}));
  EXPECT_TRUE(fs::exists(StampPath(p.c.workspace, "c")));
  EXPECT_EQ(p.RunJson()["stages"].size(), 3u);
  EXPECT_TRUE(p.Run());
  EXPECT_TRUE(p.ran.empty());
  EXPECT_EQ(p.statuses, Strings({"skipped", "skipped", "skipped"}));
}

TEST(PipelineRun, ChangedOptionsRunTheStageAndEverythingAfterIt) {
  FakePipeline p("run_options");
  ASSERT_TRUE(p.Run());
  SetStageOption(&p.stages[1].options, "max_error", "2");
  EXPECT_TRUE(p.Run());
  EXPECT_EQ(p.ran, Strings({"b", "c"}));
  EXPECT_EQ(p.statuses, Strings({"skipped", "ran", "ran"}));
}

TEST(PipelineRun, SelectionForceAndFromStage) {
  FakePipeline p("run_selection");
  ASSERT_TRUE(p.Run());
  // Only b, again though up to date; c then runs since an earlier stage ran.
  EXPECT_TRUE(p.Run({1, 2, false, true}));
  EXPECT_EQ(p.ran, Strings({"b", "c"}));
  EXPECT_EQ(p.statuses, Strings({"not selected", "ran", "ran"}));
  EXPECT_TRUE(p.Run({0, 0, true, false}));
  EXPECT_EQ(p.ran, Strings({"a"}));
  EXPECT_EQ(p.statuses, Strings({"ran", "not selected", "not selected"}));
}

TEST(PipelineRun, StagesSelectedByName) {
  FakePipeline p("run_select_names");
  const StageSelection all = SelectStages(p.stages, "", "", false);
  EXPECT_EQ(all.first, 0);
  EXPECT_EQ(all.last, 2);
  EXPECT_FALSE(all.from_stage);
  const StageSelection b = SelectStages(p.stages, "b", "b", true);
  EXPECT_EQ(b.first, 1);
  EXPECT_EQ(b.last, 1);
  EXPECT_TRUE(b.force);
  EXPECT_TRUE(b.from_stage);
  EXPECT_THROW(SelectStages(p.stages, "x", "", false), InputError);
  EXPECT_THROW(SelectStages(p.stages, "c", "a", false), InputError);
}

TEST(PipelineRun, TableAndSummaryLineOfARun) {
  FakePipeline p("run_table");
  ASSERT_TRUE(p.Run());
  PipelineRun run(
      p.c,
      "test.ini",
      p.stages,
      {1, 2, false, false},
      [](const std::string&, const std::vector<std::string>&) { return 0; });
  ASSERT_TRUE(run.Run());
  const std::string table = StageTable(run.runs());
  EXPECT_EQ(table.find("  a "), std::string::npos) << table;  // not selected
  EXPECT_NE(table.find("  b                bayon    skipped"),
            std::string::npos)
      << table;
  const std::string line = PipelineSummaryLine(run, p.c.workspace);
  EXPECT_EQ(line.rfind("0 stages ran, 2 up to date, in ", 0), 0u) << line;
  EXPECT_NE(line.find(" -> " + p.c.workspace), std::string::npos) << line;
}

TEST(PipelineRun, AStageThatProducesNothingStopsTheRunWithoutAStamp) {
  FakePipeline p("run_nothing");
  EXPECT_FALSE(p.Run({0, 2, false, false}, "b", 1));
  EXPECT_EQ(p.ran, Strings({"a", "b"}));
  EXPECT_FALSE(fs::exists(StampPath(p.c.workspace, "b")));
  const nlohmann::json json = p.RunJson();
  ASSERT_EQ(json["stages"].size(), 2u);
  EXPECT_EQ(json["stages"][1]["status"], "failed");
  EXPECT_EQ(json["stages"][1]["reason"], "produced nothing usable (exit 1)");
  // The next run resumes at b.
  EXPECT_TRUE(p.Run());
  EXPECT_EQ(p.ran, Strings({"b", "c"}));
}

TEST(PipelineRun, BadInputNamesTheStageAndIsRecorded) {
  FakePipeline p("run_bad_input");
  try {
    p.Run({0, 2, false, false}, "c", 2);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), "stage c: bad c");
  }
  EXPECT_EQ(p.RunJson()["stages"][2]["status"], "failed");
  EXPECT_FALSE(fs::exists(StampPath(p.c.workspace, "c")));
}

TEST(PipelineRun, FormatsSecondsAsTheSummaryPrintsThem) {
  EXPECT_EQ(FormatRunSeconds(12.34), "12.3 s");
  EXPECT_EQ(FormatRunSeconds(125), "2 min 05 s");
}

}  // namespace
}  // namespace bayon
