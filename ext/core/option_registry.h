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

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

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

  // An enumeration given by name; `names` holds every value's.
  template <typename Enum>
  void AddChoice(const std::string& name,
                 Enum* value,
                 const std::vector<std::pair<std::string, Enum>>& names,
                 const std::string& help) {
    Choice choice;
    for (const auto& [text, e] : names) choice.names.push_back(text);
    choice.get = [value, names] {
      for (const auto& [text, e] : names) {
        if (e == *value) return text;
      }
      return std::string();
    };
    choice.set = [value, names](const std::string& text) {
      for (const auto& [t, e] : names) {
        if (t == text) *value = e;
      }
    };
    AddChoice(name, choice, help);
  }

  // The fields of a nested options struct, as `name.field`.
  template <typename Options>
  void AddNested(const std::string& name, Options* options);

 protected:
  struct Choice {
    std::vector<std::string> names;
    std::function<std::string()> get;
    std::function<void(const std::string&)> set;
  };
  virtual void AddChoice(const std::string& name,
                         const Choice& choice,
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
  void AddChoice(const std::string& name,
                 const Choice& choice,
                 const std::string& help) override {
    parent_->AddChoice(Name(name), choice, help);
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
