// SPDX-License-Identifier: BSD-3-Clause
#include "ext/pipeline/stages.h"

#include "ext/core/errors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

std::string WriteConfig(const std::string& name, const std::string& text) {
  const std::string path = testing::TempDir("stages_" + name) + "/c.ini";
  std::ofstream(path) << text;
  return path;
}

PipelineContext Workspace(const std::string& name) {
  PipelineContext c;
  c.workspace = testing::TempDir("stages_" + name);
  c.image_path = c.workspace + "/images";
  c.database = c.workspace + "/database.db";
  return c;
}

std::vector<std::string> Names(const std::vector<Stage>& stages) {
  std::vector<std::string> names;
  for (const Stage& stage : stages) names.push_back(stage.name);
  return names;
}

const Stage& Find(const std::vector<Stage>& stages, const std::string& name) {
  return *std::find_if(stages.begin(), stages.end(), [&](const Stage& s) {
    return s.name == name;
  });
}

std::string Option(const Stage& stage, const std::string& key) {
  for (const auto& [k, v] : stage.options) {
    if (k == key) return v;
  }
  return "(none)";
}

TEST(PipelineStages, DefaultsRunBayonsChainInOrder) {
  const std::vector<Stage> stages =
      MakeStages(Workspace("defaults"), PipelineConfig());
  EXPECT_EQ(Names(stages),
            std::vector<std::string>({"import",
                                      "targets",
                                      "features",
                                      "match",
                                      "relative",
                                      "disparity",
                                      "tiepoints",
                                      "strip",
                                      "adjust",
                                      "dense",
                                      "edit",
                                      "mesh",
                                      "texture",
                                      "render",
                                      "viewer",
                                      "report"}));
  for (const Stage& stage : stages) EXPECT_EQ(stage.program, "bayon");
}

TEST(PipelineStages, ConfigSectionsReplaceThePipelinesValues) {
  const PipelineContext c = Workspace("sections");
  const PipelineConfig config = ReadPipelineConfigs(
      {WriteConfig("sections_a",
                   "[dense]\nnum_masters = 5\n[strip]\nnum_threads = 1\n"),
       WriteConfig("sections_b", "[dense]\nnum_masters = 7\n")});
  const std::vector<Stage> stages = MakeStages(c, config);
  // Later configs win; a key the pipeline sets is replaced in its place.
  EXPECT_EQ(Option(Find(stages, "dense"), "num_masters"), "7");
  EXPECT_EQ(Option(Find(stages, "strip"), "num_threads"), "1");
  EXPECT_EQ(Option(Find(stages, "strip"), "output_path"),
            c.workspace + "/sparse/initial");
  const std::vector<std::string> words =
      CommandWords(Find(stages, "strip"), true);
  EXPECT_EQ(words.front(), "bayon");
  EXPECT_EQ(words[1], "strip");
  EXPECT_EQ(words.back(), "1");
  EXPECT_EQ(words[words.size() - 2], "--overwrite");
}

TEST(PipelineStages, InteriorRunsOnlyWithItsSection) {
  const PipelineConfig config = ReadPipelineConfigs(
      {WriteConfig("interior", "[interior]\nfilm_scan = 1\n")});
  const std::vector<std::string> names =
      Names(MakeStages(Workspace("interior"), config));
  EXPECT_EQ(names[1], "interior");
}

TEST(PipelineStages, ColmapSiftReplacesTheFrontEnd) {
  const PipelineConfig config = ReadPipelineConfigs(
      {WriteConfig("colmap",
                   "[pipeline]\nfeatures = colmap_sift\nsparse = "
                   "colmap_mapper\n[mapper]\nMapper.min_num_matches = 20\n")});
  const std::vector<Stage> stages = MakeStages(Workspace("colmap"), config);
  const std::vector<std::string> names = Names(stages);
  for (const char* left_out : {"targets", "relative", "disparity", "tiepoints"})
    EXPECT_EQ(std::count(names.begin(), names.end(), left_out), 0) << left_out;
  EXPECT_EQ(Find(stages, "features").command, "feature_extractor");
  EXPECT_EQ(Find(stages, "match").command, "exhaustive_matcher");
  EXPECT_EQ(Find(stages, "strip").program, "colmap");
  EXPECT_EQ(Option(Find(stages, "strip"), "Mapper.min_num_matches"), "20");
}

TEST(PipelineStages, ControlIsAnInputOfStripAndAdjust) {
  PipelineContext c = Workspace("control");
  c.control = c.workspace + "/control";
  const std::vector<Stage> stages = MakeStages(c, PipelineConfig());
  for (const char* name : {"strip", "adjust"}) {
    EXPECT_EQ(Option(Find(stages, name), "control_path"), c.control);
    EXPECT_EQ(Find(stages, name).inputs, std::vector<std::string>({c.control}));
  }
}

TEST(PipelineStages, ACalibratedCameraIsGivenToColmapToo) {
  const PipelineConfig config = ReadPipelineConfigs({WriteConfig(
      "compare",
      "[pipeline]\ncompare_colmap = 1\n[import]\ncamera_model = PINHOLE\n"
      "camera_params = 1520.4,1525.9,302.3,246.9\n")});
  const std::vector<Stage> stages = MakeStages(Workspace("compare"), config);
  const Stage& compare = Find(stages, "compare_colmap");
  EXPECT_EQ(Option(compare, "camera_model"), "PINHOLE");
  EXPECT_EQ(Option(compare, "camera_params"), "1520.4,1525.9,302.3,246.9");
}

TEST(PipelineStages, BadConfigsAreRefusedNamingTheFile) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"loose", "num_masters = 5\n"},
      {"section", "[densify]\nnum_masters = 5\n"},
      {"key", "[pipeline]\nfeaturez = bayon\n"},
      {"value", "[pipeline]\nfeatures = orb\n"}};
  for (const auto& [name, text] : cases) {
    const std::string path = WriteConfig("bad_" + name, text);
    try {
      ReadPipelineConfigs({path});
      ADD_FAILURE() << name << ": accepted";
    } catch (const InputError& error) {
      EXPECT_EQ(std::string(error.what()).rfind(path, 0), 0u) << error.what();
    }
  }
  EXPECT_TRUE(IsStageName("dense"));
  EXPECT_FALSE(IsStageName("densify"));
}

}  // namespace
}  // namespace bayon
