// SPDX-License-Identifier: BSD-3-Clause
//
// Options registered once (ext/core/option_registry.h) on a command line
// (tools/command.h): dotted names for nested structs, earlier flag names
// still accepted but not listed, choices by name, config keys with dots, and
// Check() naming the field as the command line does.
#include "ext/core/errors.h"
#include "ext/core/option_registry.h"
#include "ext/dense/dense.h"
#include "ext/mesh/meshing.h"
#include "tools/command.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "tests/testing.h"

namespace bayon {
namespace {

enum class Colour { kRed, kGreen };

struct Inner {
  int count = 1;
  void Register(OptionRegistry* r) { r->Add("count", &count, "How many"); }
};

struct Outer {
  double scale = 1.5;
  bool verbose = false;
  std::string label = "a";
  std::vector<std::string> names;
  Colour colour = Colour::kRed;
  Inner inner;
  void Register(OptionRegistry* r) {
    r->Add("scale", &scale, "Scale");
    r->Add("verbose", &verbose, "Verbose");
    r->Add("label", &label, "Label");
    r->Add("names", &names, "Names");
    r->AddChoice("colour",
                 &colour,
                 {{"red", Colour::kRed}, {"green", Colour::kGreen}},
                 "Colour");
    r->AddNested("inner", &inner);
  }
};

// Parses `args` (after the command's name) into a fresh Outer.
Outer Parse(std::vector<std::string> args) {
  Outer outer;
  CommandLine command("test", "test");
  command.AddOptions(&outer, {{"count", "inner.count"}});
  args.insert(args.begin(), "test");
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  EXPECT_TRUE(command.Parse(static_cast<int>(argv.size()), argv.data()));
  return outer;
}

TEST(CommandOptions, NestedFieldsTakeDottedNames) {
  const Outer outer = Parse({"--scale",
                             "2.5",
                             "--verbose",
                             "1",
                             "--label",
                             "b",
                             "--names",
                             "x,y",
                             "--colour",
                             "green",
                             "--inner.count",
                             "4"});
  EXPECT_EQ(outer.scale, 2.5);
  EXPECT_TRUE(outer.verbose);
  EXPECT_EQ(outer.label, "b");
  EXPECT_EQ(outer.names, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(outer.colour, Colour::kGreen);
  EXPECT_EQ(outer.inner.count, 4);
  const Outer defaults = Parse({});
  EXPECT_EQ(defaults.colour, Colour::kRed);
  EXPECT_EQ(defaults.inner.count, 1);
}

TEST(CommandOptions, EarlierNamesStayAcceptedButUnlisted) {
  EXPECT_EQ(Parse({"--count", "7"}).inner.count, 7);
  Outer outer;
  CommandLine command("test", "test");
  command.AddOptions(&outer, {{"count", "inner.count"}});
  const std::string help = command.app().help();
  EXPECT_NE(help.find("--inner.count"), std::string::npos) << help;
  EXPECT_EQ(help.find("--count"), std::string::npos) << help;
}

TEST(CommandOptions, TheEffectiveOptionsNameEachFieldOnce) {
  // What --config reads back: the field under its name, not again under an
  // earlier name (whose default would undo the value given).
  Outer outer;
  CommandLine command("test", "test");
  command.AddOptions(&outer, {{"count", "inner.count"}});
  std::vector<std::string> args = {"test", "--inner.count", "4"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  ASSERT_TRUE(command.Parse(3, argv.data()));
  const std::string options = "\n" + command.EffectiveOptions();
  EXPECT_NE(options.find("\ninner.count=4"), std::string::npos) << options;
  EXPECT_EQ(options.find("\ncount="), std::string::npos) << options;
}

TEST(CommandOptions, ConfigKeysAreTheDottedNames) {
  const std::string dir = testing::TempDir("command_options_config");
  std::ofstream(dir + "/a.ini") << "inner.count = 5\ncolour = green\n";
  const Outer outer = Parse({"--config", dir + "/a.ini"});
  EXPECT_EQ(outer.inner.count, 5);
  EXPECT_EQ(outer.colour, Colour::kGreen);
  std::ofstream(dir + "/b.ini") << "count = 6\n";
  EXPECT_EQ(Parse({"--config", dir + "/b.ini"}).inner.count, 6);
}

TEST(CommandOptions, AChoiceOutsideItsNamesIsRefused) {
  Outer outer;
  CommandLine command("test", "test");
  command.AddOptions(&outer);
  std::vector<std::string> args = {"test", "--colour", "blue"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  EXPECT_THROW(command.Parse(3, argv.data()), CLI::ParseError);
}

// The names every field of an options struct registers, each once.
class NameRecorder : public OptionRegistry {
 public:
  void Add(const std::string& name, bool*, const std::string&) override {
    Record(name);
  }
  void Add(const std::string& name, int*, const std::string&) override {
    Record(name);
  }
  void Add(const std::string& name, double*, const std::string&) override {
    Record(name);
  }
  void Add(const std::string& name, std::string*, const std::string&) override {
    Record(name);
  }
  void Add(const std::string& name,
           std::vector<std::string>*,
           const std::string&) override {
    Record(name);
  }
  std::set<std::string> names;
  int duplicates = 0;

 protected:
  void AddText(const std::string& name,
               const Text&,
               const std::string&) override {
    Record(name);
  }

 private:
  void Record(const std::string& name) {
    duplicates += !names.insert(name).second;
  }
};

// Expects each of `names` registered by Options once, and no name twice.
template <typename Options>
void ExpectRegisteredOnce(const std::vector<std::string>& names) {
  Options options;
  NameRecorder recorder;
  options.Register(&recorder);
  EXPECT_EQ(recorder.duplicates, 0);
  for (const std::string& name : names) {
    EXPECT_EQ(recorder.names.count(name), 1u) << name;
  }
}

TEST(CommandOptions, DenseRegistersItsNestedOptionsUnderTheirNames) {
  ExpectRegisteredOnce<DenseOptions>({"mode",
                                      "patch_match.window_radius",
                                      "fusion.min_consistent_views",
                                      "search.min_ncc",
                                      "mpgc.max_iterations",
                                      "mpgc.lsm.patch_radius",
                                      "mpgc.lsm.interpolation"});
}

TEST(CommandOptions, MeshRegistersEachMethodsOptionsUnderItsName) {
  ExpectRegisteredOnce<MeshOptions>({"method",
                                     "cylinder.axis_direction",
                                     "cylinder.metric",
                                     "poisson.depth",
                                     "colmap_poisson.depth",
                                     "delaunay_graph_cut.max_edge_factor",
                                     "normals.orientation",
                                     "cleanup.max_hole_edges"});
}

TEST(CommandOptions, TextThatIsNotTheValueIsRefusedNamingTheFlag) {
  struct Axis {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    void Register(OptionRegistry* r) { r->Add("direction", &direction, ""); }
  };
  struct WithAxis {
    Axis axis;
    void Register(OptionRegistry* r) { r->AddNested("axis", &axis); }
  };
  for (const char* flag : {"--axis.direction", "--direction"}) {
    WithAxis options;
    CommandLine command("test", "test");
    command.AddOptions(&options, {{"direction", "axis.direction"}});
    std::vector<std::string> args = {"test", flag, "1,2"};
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    try {
      command.Parse(3, argv.data());
      ADD_FAILURE() << "two numbers passed as x,y,z";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string(flag) + ": '1,2' is not three numbers x,y,z");
    }
  }
}

TEST(CommandOptions, CheckNamesTheFieldAsTheCommandLineDoes) {
  DenseOptions options;
  options.mpgc.lsm.patch_radius = 1;
  try {
    options.Check();
    ADD_FAILURE() << "a patch radius of 1 passed";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("mpgc.lsm.patch_radius must be", 0),
              0u)
        << e.what();
  }
  options = DenseOptions();
  options.fusion.max_cost = 5;
  try {
    options.Check();
    ADD_FAILURE() << "a cost of 5 passed";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("fusion.max_cost", 0), 0u)
        << e.what();
  }
}

}  // namespace
}  // namespace bayon
