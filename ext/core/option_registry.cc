// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/option_registry.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace bayon {
namespace {

std::string Trimmed(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return std::string();
  return text.substr(begin, text.find_last_not_of(" \t") - begin + 1);
}

// 15 significant digits where they read back exactly, else 17.
std::string FormatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.15g", value);
  if (std::strtod(text, nullptr) != value) {
    std::snprintf(text, sizeof(text), "%.17g", value);
  }
  return text;
}

}  // namespace

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  size_t begin = 0;
  while (begin <= text.size()) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    const std::string item = Trimmed(text.substr(begin, end - begin));
    if (!item.empty()) items.push_back(item);
    begin = end + 1;
  }
  return items;
}

size_t IndexOfName(const std::string& name,
                   const std::vector<std::string>& names) {
  for (size_t k = 0; k < names.size(); ++k) {
    if (names[k] == name) return k;
  }
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  ThrowInputError("'", name, "' is not one of ", list);
}

std::vector<double> ParseNumbers(const std::string& text) {
  std::vector<double> values;
  if (Trimmed(text).empty()) return values;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(',', begin);
    const std::string item = Trimmed(text.substr(begin, end - begin));
    char* rest = nullptr;
    errno = 0;
    const double value = std::strtod(item.c_str(), &rest);
    if (item.empty() || *rest != '\0' || errno == ERANGE ||
        !std::isfinite(value)) {
      ThrowInputError("'", item, "' is not a number (in '", text, "')");
    }
    values.push_back(value);
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return values;
}

std::string FormatNumbers(const std::vector<double>& values) {
  std::string text;
  for (size_t k = 0; k < values.size(); ++k) {
    if (k > 0) text += ",";
    text += FormatNumber(values[k]);
  }
  return text;
}

void OptionRegistry::Add(const std::string& name,
                         Eigen::Vector3d* value,
                         const std::string& help) {
  Text text;
  text.get = [value] {
    if (value->hasNaN()) return std::string();
    return FormatNumbers({value->x(), value->y(), value->z()});
  };
  text.set = [value](const std::string& given) {
    if (Trimmed(given).empty()) {
      value->setConstant(std::nan(""));
      return;
    }
    const std::vector<double> numbers = ParseNumbers(given);
    if (numbers.size() != 3) {
      ThrowInputError("'", given, "' is not three numbers x,y,z");
    }
    *value = Eigen::Vector3d(numbers[0], numbers[1], numbers[2]);
  };
  AddText(name, text, help);
}

namespace {

// A whole number >= 0 that fits into Unsigned, read and written as text.
template <typename Unsigned>
void AddUnsigned(OptionRegistry* registry,
                 const std::string& name,
                 Unsigned* value,
                 const std::string& help) {
  const auto set = [value](const std::string& given) {
    const std::string item = Trimmed(given);
    char* rest = nullptr;
    errno = 0;
    const unsigned long long number = std::strtoull(item.c_str(), &rest, 10);
    if (item.empty() || item[0] == '-' || *rest != '\0' || errno == ERANGE ||
        number > std::numeric_limits<Unsigned>::max()) {
      ThrowInputError("'", given, "' is not a whole number >= 0");
    }
    *value = static_cast<Unsigned>(number);
  };
  registry->AddParsed(
      name, [value] { return std::to_string(*value); }, set, help);
}

}  // namespace

void OptionRegistry::Add(const std::string& name,
                         unsigned int* value,
                         const std::string& help) {
  AddUnsigned(this, name, value, help);
}

void OptionRegistry::Add(const std::string& name,
                         uint64_t* value,
                         const std::string& help) {
  AddUnsigned(this, name, value, help);
}

void OptionRegistry::AddSwitches(
    const std::string& name,
    const std::vector<std::pair<std::string, bool*>>& switches,
    const std::string& help) {
  Text text;
  text.get = [switches] {
    std::string on;
    for (const auto& [n, value] : switches) {
      if (*value) on += (on.empty() ? "" : ",") + n;
    }
    return on;
  };
  text.set = [switches](const std::string& given) {
    std::vector<bool> on(switches.size(), false);
    for (const std::string& item : SplitList(given)) {
      on[IndexOfName(item, ChoiceNames(switches))] = true;
    }
    for (size_t k = 0; k < switches.size(); ++k) *switches[k].second = on[k];
  };
  AddText(name, text, help);
}

void OptionRegistry::Add(const std::string& name,
                         std::vector<double>* value,
                         const std::string& help) {
  Text text;
  text.get = [value] { return FormatNumbers(*value); };
  text.set = [value](const std::string& given) {
    *value = ParseNumbers(given);
  };
  AddText(name, text, help);
}

}  // namespace bayon
