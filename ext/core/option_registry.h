// SPDX-License-Identifier: BSD-3-Clause
//
// Options registered once, by the struct that holds them, as COLMAP's
// OptionManager has them. Each options struct names its fields and says what
// they are in
//
//   void Register(OptionRegistry* registry);
//
// and a nested struct's fields go under its name (`mpgc.lsm.patch_radius`).
// A command puts them on its command line with those names
// (`--mpgc.lsm.patch_radius`), a config file uses them as keys, and Check()
// names them so too: a struct's Check() names its own fields, and
// CheckNested() puts the nested struct's name in front. ext/ knows nothing
// of the command line; tools/command.h registers into CLI11.
#pragma once

#include "ext/core/errors.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

// "a, b,c" -> {"a", "b", "c"}: items trimmed of spaces, empty ones dropped.
std::vector<std::string> SplitList(const std::string& text);
// The index of `name` in `names`; InputError listing them otherwise.
size_t IndexOfName(const std::string& name,
                   const std::vector<std::string>& names);
template <typename T>
std::vector<std::string> ChoiceNames(
    const std::vector<std::pair<std::string, T>>& pairs) {
  std::vector<std::string> names;
  for (const auto& pair : pairs) names.push_back(pair.first);
  return names;
}

class OptionRegistry {
 public:
  virtual ~OptionRegistry() = default;

  virtual void Add(const std::string& name,
                   bool* value,
                   const std::string& help) = 0;
  virtual void Add(const std::string& name,
                   int* value,
                   const std::string& help) = 0;
  virtual void Add(const std::string& name,
                   double* value,
                   const std::string& help) = 0;
  virtual void Add(const std::string& name,
                   std::string* value,
                   const std::string& help) = 0;
  // A list, comma separated on the command line.
  virtual void Add(const std::string& name,
                   std::vector<std::string>* value,
                   const std::string& help) = 0;

  // A point or a direction, "x,y,z". Empty text stands for every
  // coordinate NaN, which options use for "not given".
  void Add(const std::string& name,
           Eigen::Vector3d* value,
           const std::string& help);
  // Numbers, comma separated.
  void Add(const std::string& name,
           std::vector<double>* value,
           const std::string& help);
  // A seed, a count that cannot be negative.
  void Add(const std::string& name,
           unsigned int* value,
           const std::string& help);
  void Add(const std::string& name, uint64_t* value, const std::string& help);

  // An enumeration given by name; `names` holds every value's.
  template <typename Enum>
  void AddChoice(const std::string& name,
                 Enum* value,
                 const std::vector<std::pair<std::string, Enum>>& names,
                 const std::string& help) {
    Text choice;
    choice.choices = ChoiceNames(names);
    choice.get = [value, names] {
      for (const auto& [text, e] : names) {
        if (e == *value) return text;
      }
      return std::string();
    };
    choice.set = [value, names](const std::string& text) {
      *value = names[IndexOfName(text, ChoiceNames(names))].second;
    };
    AddText(name, choice, help);
  }

  // Several values of an enumeration, comma separated.
  template <typename Enum>
  void AddChoices(const std::string& name,
                  std::vector<Enum>* values,
                  const std::vector<std::pair<std::string, Enum>>& names,
                  const std::string& help) {
    Text choices;
    choices.get = [values, names] {
      std::string text;
      for (Enum value : *values) {
        for (const auto& [t, e] : names) {
          if (e == value) text += (text.empty() ? "" : ",") + t;
        }
      }
      return text;
    };
    choices.set = [values, names](const std::string& text) {
      std::vector<Enum> given;
      for (const std::string& item : SplitList(text)) {
        given.push_back(names[IndexOfName(item, ChoiceNames(names))].second);
      }
      *values = given;
    };
    AddText(name, choices, help);
  }
  // A value an options struct writes and reads itself; `set` throws
  // InputError (without the option's name) for text it cannot read.
  void AddParsed(const std::string& name,
                 std::function<std::string()> get,
                 std::function<void(const std::string&)> set,
                 const std::string& help) {
    AddText(name, Text{{}, std::move(get), std::move(set)}, help);
  }
  // Switches, each turned on by naming it in a comma-separated list.
  void AddSwitches(const std::string& name,
                   const std::vector<std::pair<std::string, bool*>>& switches,
                   const std::string& help);

  // The fields of a nested options struct, as `name.field`.
  template <typename Options>
  void AddNested(const std::string& name, Options* options);

 protected:
  // A value the command line and configs hold as text: `get` writes it,
  // `set` reads it and throws InputError (without the option's name) for
  // text it cannot read. `choices`, where not empty: every text allowed.
  struct Text {
    std::vector<std::string> choices;
    std::function<std::string()> get;
    std::function<void(const std::string&)> set;
  };
  virtual void AddText(const std::string& name,
                       const Text& text,
                       const std::string& help) = 0;

 private:
  // Forwards every field to `parent` with `prefix.` in front of its name.
  class Prefixed;
};

class OptionRegistry::Prefixed : public OptionRegistry {
 public:
  Prefixed(OptionRegistry* parent, std::string prefix)
      : parent_(parent), prefix_(std::move(prefix)) {}
  void Add(const std::string& name,
           bool* value,
           const std::string& help) override {
    parent_->Add(Name(name), value, help);
  }
  void Add(const std::string& name,
           int* value,
           const std::string& help) override {
    parent_->Add(Name(name), value, help);
  }
  void Add(const std::string& name,
           double* value,
           const std::string& help) override {
    parent_->Add(Name(name), value, help);
  }
  void Add(const std::string& name,
           std::string* value,
           const std::string& help) override {
    parent_->Add(Name(name), value, help);
  }
  void Add(const std::string& name,
           std::vector<std::string>* value,
           const std::string& help) override {
    parent_->Add(Name(name), value, help);
  }

 protected:
  void AddText(const std::string& name,
               const Text& text,
               const std::string& help) override {
    parent_->AddText(Name(name), text, help);
  }

 private:
  std::string Name(const std::string& name) const {
    return prefix_ + "." + name;
  }
  OptionRegistry* parent_;
  std::string prefix_;
};

template <typename Options>
void OptionRegistry::AddNested(const std::string& name, Options* options) {
  Prefixed nested(this, name);
  options->Register(&nested);
}

// The (name, value) pairs of AddChoice from an enumeration's name function.
template <typename Enum, typename NameOf>
std::vector<std::pair<std::string, Enum>> ChoicesOf(
    NameOf name_of, const std::vector<Enum>& values) {
  std::vector<std::pair<std::string, Enum>> choices;
  for (Enum value : values) choices.emplace_back(name_of(value), value);
  return choices;
}

// "1.5, 2,3" -> {1.5, 2, 3}; InputError for what is not a number.
std::vector<double> ParseNumbers(const std::string& text);
// The shortest text that reads back as the same numbers, comma separated.
std::string FormatNumbers(const std::vector<double>& values);

// Checks a nested options struct; its complaint names the field as the
// registry does, `name.field`.
template <typename Options>
void CheckNested(const std::string& name, const Options& options) {
  try {
    options.Check();
  } catch (const InputError& error) {
    throw InputError(name + "." + error.what());
  }
}

}  // namespace bayon
