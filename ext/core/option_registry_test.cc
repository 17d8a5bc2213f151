// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/option_registry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

namespace bayon {
namespace {

// Keeps every option as text, under its full name, as a config would.
class TextRegistry : public OptionRegistry {
 public:
  void Add(const std::string& name, bool* value, const std::string&) override {
    Keep(name, value);
  }
  void Add(const std::string& name, int* value, const std::string&) override {
    Keep(name, value);
  }
  void Add(const std::string& name,
           double* value,
           const std::string&) override {
    Keep(name, value);
  }
  void Add(const std::string& name,
           std::string* value,
           const std::string&) override {
    Text text;
    text.get = [value] { return *value; };
    text.set = [value](const std::string& given) { *value = given; };
    texts_[name] = text;
  }
  void Add(const std::string& name,
           std::vector<std::string>*,
           const std::string&) override {
    texts_[name] = Text();
  }
  using OptionRegistry::Add;

  std::string Get(const std::string& name) { return texts_.at(name).get(); }
  void Set(const std::string& name, const std::string& text) {
    const Text& option = texts_.at(name);
    if (!option.choices.empty()) {
      bool allowed = false;
      for (const std::string& choice : option.choices) {
        allowed |= choice == text;
      }
      if (!allowed) ThrowInputError(name, ": not a choice");
    }
    option.set(text);
  }
  bool Has(const std::string& name) const { return texts_.count(name) > 0; }

 protected:
  void AddText(const std::string& name,
               const Text& text,
               const std::string&) override {
    texts_[name] = text;
  }

 private:
  template <typename T>
  void Keep(const std::string& name, T* value) {
    Text text;
    text.get = [value] { return std::to_string(*value); };
    text.set = [value](const std::string& given) {
      *value = static_cast<T>(std::stod(given));
    };
    texts_[name] = text;
  }
  std::map<std::string, Text> texts_;
};

enum class Shape { kRound, kSquare };

struct Axis {
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d point =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  void Register(OptionRegistry* r) {
    r->Add("direction", &direction, "Direction");
    r->Add("point", &point, "Point, empty: the centroid");
  }
  void Check() const {
    CheckOption(direction.norm() > 0, "direction", "not zero", "0,0,0");
  }
};

struct Part {
  int count = 2;
  std::vector<double> levels = {0.5, 1};
  Shape shape = Shape::kRound;
  Axis axis;
  void Register(OptionRegistry* r) {
    r->Add("count", &count, "Count");
    r->Add("levels", &levels, "Levels");
    r->AddChoice("shape",
                 &shape,
                 {{"round", Shape::kRound}, {"square", Shape::kSquare}},
                 "Shape");
    r->AddNested("axis", &axis);
  }
};

TEST(OptionRegistry, NestedFieldsAreNamedUnderTheirStruct) {
  Part part;
  TextRegistry registry;
  part.Register(&registry);
  EXPECT_TRUE(registry.Has("count"));
  EXPECT_TRUE(registry.Has("axis.direction"));
  EXPECT_TRUE(registry.Has("axis.point"));
  EXPECT_FALSE(registry.Has("direction"));
  registry.Set("shape", "square");
  EXPECT_EQ(part.shape, Shape::kSquare);
  EXPECT_EQ(registry.Get("shape"), "square");
  EXPECT_THROW(registry.Set("shape", "oval"), InputError);
}

TEST(OptionRegistry, PointsAndNumberListsReadBackAsWritten) {
  Part part;
  TextRegistry registry;
  part.Register(&registry);
  EXPECT_EQ(registry.Get("axis.direction"), "0,0,1");
  EXPECT_EQ(registry.Get("axis.point"), "");  // NaN: not given
  EXPECT_EQ(registry.Get("levels"), "0.5,1");

  registry.Set("axis.direction", " 0.1, -2,3e2 ");
  EXPECT_EQ(part.axis.direction, Eigen::Vector3d(0.1, -2, 300));
  EXPECT_EQ(registry.Get("axis.direction"), "0.1,-2,300");
  registry.Set("axis.point", "1,2,3");
  EXPECT_EQ(part.axis.point, Eigen::Vector3d(1, 2, 3));
  registry.Set("axis.point", "");
  EXPECT_TRUE(part.axis.point.array().isNaN().all());

  part.levels = {1.0 / 3, 2};
  EXPECT_EQ(ParseNumbers(registry.Get("levels")), part.levels);
  registry.Set("levels", "");
  EXPECT_TRUE(part.levels.empty());
}

TEST(OptionRegistry, TextThatIsNotNumbersIsRefused) {
  Part part;
  TextRegistry registry;
  part.Register(&registry);
  EXPECT_THROW(registry.Set("axis.direction", "1,2"), InputError);
  EXPECT_THROW(registry.Set("axis.direction", "1,2,3,4"), InputError);
  EXPECT_THROW(registry.Set("axis.direction", "1,x,3"), InputError);
  EXPECT_THROW(registry.Set("levels", "1,,2"), InputError);
  EXPECT_THROW(registry.Set("levels", "nan"), InputError);
  EXPECT_THROW(ParseNumbers("1e999"), InputError);
  unsigned int seed = 7;
  TextRegistry seeds;
  static_cast<OptionRegistry&>(seeds).Add("seed", &seed, "Seed");
  seeds.Set("seed", "4294967295");
  EXPECT_EQ(seed, 4294967295u);
  EXPECT_THROW(seeds.Set("seed", "-1"), InputError);
  EXPECT_THROW(seeds.Set("seed", "4294967296"), InputError);
  EXPECT_THROW(seeds.Set("seed", "1.5"), InputError);
  EXPECT_EQ(seeds.Get("seed"), "4294967295");
  uint64_t big_seed = 1;
  static_cast<OptionRegistry&>(seeds).Add("big_seed", &big_seed, "Seed");
  seeds.Set("big_seed", "18446744073709551615");
  EXPECT_EQ(big_seed, std::numeric_limits<uint64_t>::max());
  EXPECT_THROW(seeds.Set("big_seed", "18446744073709551616"), InputError);
  EXPECT_EQ(part.axis.direction, Eigen::Vector3d::UnitZ());  // untouched
}

TEST(OptionRegistry, ListsOfChoicesAndSwitches) {
  std::vector<Shape> shapes = {Shape::kRound};
  bool left = false, right = true;
  std::string mode = "auto";
  TextRegistry registry;
  OptionRegistry& r = registry;
  r.AddChoices("shapes",
               &shapes,
               {{"round", Shape::kRound}, {"square", Shape::kSquare}},
               "Shapes");
  r.AddSwitches("sides", {{"left", &left}, {"right", &right}}, "Sides");
  r.AddParsed(
      "mode",
      [&mode] { return mode; },
      [&mode](const std::string& text) {
        if (text.empty()) ThrowInputError("no mode");
        mode = text;
      },
      "Mode");
  EXPECT_EQ(registry.Get("shapes"), "round");
  EXPECT_EQ(registry.Get("sides"), "right");
  registry.Set("shapes", "square, round");
  EXPECT_EQ(shapes, (std::vector<Shape>{Shape::kSquare, Shape::kRound}));
  registry.Set("sides", "left");
  EXPECT_TRUE(left);
  EXPECT_FALSE(right);  // a list names every switch that is on
  EXPECT_THROW(registry.Set("shapes", "round,oval"), InputError);
  EXPECT_THROW(registry.Set("sides", "up"), InputError);
  EXPECT_EQ(shapes.size(), 2u);  // a refused list changes nothing
  EXPECT_TRUE(left);
  registry.Set("mode", "dc,dx0");
  EXPECT_EQ(registry.Get("mode"), "dc,dx0");
  EXPECT_THROW(registry.Set("mode", ""), InputError);
}

TEST(OptionRegistry, CheckNestedNamesTheFieldAsRegistered) {
  Part part;
  part.axis.direction.setZero();
  try {
    CheckNested("axis", part.axis);
    FAIL() << "a zero direction passed";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("axis.direction must be", 0), 0u)
        << error.what();
  }
}

}  // namespace
}  // namespace bayon
