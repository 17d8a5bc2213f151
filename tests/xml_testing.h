// SPDX-License-Identifier: BSD-3-Clause
//
// For tests: a small well-formedness check of XML (the inline SVG charts of
// a report), without an XML library. It checks what a browser's XML parser
// would refuse: tags nested and closed, attributes quoted and not repeated,
// no '<' in text or attribute values, '&' only in the five predefined
// entities or character references, and one root element. It does not read
// DTDs, CDATA or processing instructions beyond skipping them.
#pragma once

#include <cctype>
#include <set>
#include <string>
#include <vector>

namespace bayon {
namespace testing {

// "" when `xml` is well-formed, else what is wrong and where.
inline std::string XmlWellFormednessError(const std::string& xml) {
  const auto is_name_start = [](char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == ':';
  };
  const auto is_name_char = [&](char c) {
    return is_name_start(c) || std::isdigit(static_cast<unsigned char>(c)) ||
           c == '-' || c == '.';
  };
  const auto where = [&](size_t i) {
    return " at offset " + std::to_string(i) + ": '" + xml.substr(i, 40) + "'";
  };
  // An entity or character reference starting at xml[i] == '&'; returns its
  // length, 0 when invalid.
  const auto reference_length = [&](size_t i) -> size_t {
    const size_t end = xml.find(';', i);
    if (end == std::string::npos || end - i > 12) return 0;
    const std::string name = xml.substr(i + 1, end - i - 1);
    static const std::set<std::string> kPredefined = {
        "amp", "lt", "gt", "quot", "apos"};
    if (kPredefined.count(name)) return end - i + 1;
    if (name.size() >= 2 && name[0] == '#') {
      const bool hex = name[1] == 'x';
      if (hex && name.size() < 3) return 0;
      for (size_t k = hex ? 2 : 1; k < name.size(); ++k) {
        if (hex ? !std::isxdigit(static_cast<unsigned char>(name[k]))
                : !std::isdigit(static_cast<unsigned char>(name[k]))) {
          return 0;
        }
      }
      return end - i + 1;
    }
    return 0;
  };
  std::vector<std::string> open;
  int num_roots = 0;
  size_t i = 0;
  while (i < xml.size()) {
    const char c = xml[i];
    if (c == '&') {
      const size_t length = reference_length(i);
      if (length == 0) return "bad entity reference" + where(i);
      i += length;
      continue;
    }
    if (c != '<') {
      if (open.empty() && !std::isspace(static_cast<unsigned char>(c))) {
        return "text outside the root element" + where(i);
      }
      ++i;
      continue;
    }
    if (xml.compare(i, 4, "<!--") == 0) {
      const size_t end = xml.find("-->", i + 4);
      if (end == std::string::npos) return "unclosed comment" + where(i);
      i = end + 3;
      continue;
    }
    if (xml.compare(i, 2, "<?") == 0) {
      const size_t end = xml.find("?>", i + 2);
      if (end == std::string::npos) return "unclosed <?" + where(i);
      i = end + 2;
      continue;
    }
    if (xml.compare(i, 2, "</") == 0) {
      size_t k = i + 2;
      while (k < xml.size() && is_name_char(xml[k])) ++k;
      const std::string name = xml.substr(i + 2, k - i - 2);
      while (k < xml.size() && std::isspace(static_cast<unsigned char>(xml[k])))
        ++k;
      if (k >= xml.size() || xml[k] != '>') return "bad end tag" + where(i);
      if (open.empty() || open.back() != name) {
        return "end tag </" + name + "> does not close <" +
               (open.empty() ? std::string("nothing") : open.back()) + ">" +
               where(i);
      }
      open.pop_back();
      i = k + 1;
      continue;
    }
    // A start tag.
    size_t k = i + 1;
    if (k >= xml.size() || !is_name_start(xml[k])) return "bad '<'" + where(i);
    while (k < xml.size() && is_name_char(xml[k])) ++k;
    const std::string name = xml.substr(i + 1, k - i - 1);
    if (open.empty()) {
      if (++num_roots > 1) return "a second root element" + where(i);
    }
    std::set<std::string> attributes;
    bool self_closing = false;
    while (true) {
      const size_t before = k;
      while (k < xml.size() && std::isspace(static_cast<unsigned char>(xml[k])))
        ++k;
      if (k >= xml.size()) return "unclosed start tag <" + name + ">";
      if (xml[k] == '>') {
        ++k;
        break;
      }
      if (xml.compare(k, 2, "/>") == 0) {
        self_closing = true;
        k += 2;
        break;
      }
      if (k == before) return "attributes need spaces between them" + where(k);
      if (!is_name_start(xml[k])) return "bad attribute name" + where(k);
      const size_t name_start = k;
      while (k < xml.size() && is_name_char(xml[k])) ++k;
      const std::string attribute = xml.substr(name_start, k - name_start);
      if (!attributes.insert(attribute).second) {
        return "repeated attribute " + attribute + where(name_start);
      }
      while (k < xml.size() && std::isspace(static_cast<unsigned char>(xml[k])))
        ++k;
      if (k >= xml.size() || xml[k] != '=') {
        return "attribute " + attribute + " without a value" + where(k);
      }
      ++k;
      while (k < xml.size() && std::isspace(static_cast<unsigned char>(xml[k])))
        ++k;
      if (k >= xml.size() || (xml[k] != '"' && xml[k] != '\'')) {
        return "unquoted attribute " + attribute + where(k);
      }
      const char quote = xml[k];
      const size_t end = xml.find(quote, k + 1);
      if (end == std::string::npos) return "unclosed attribute" + where(k);
      for (size_t v = k + 1; v < end; ++v) {
        if (xml[v] == '<') return "'<' in an attribute value" + where(v);
        if (xml[v] == '&') {
          const size_t length = reference_length(v);
          if (length == 0) return "bad entity in an attribute" + where(v);
          v += length - 1;
        }
      }
      k = end + 1;
    }
    if (!self_closing) open.push_back(name);
    i = k;
  }
  if (!open.empty()) return "unclosed element <" + open.back() + ">";
  if (num_roots != 1) return "no root element";
  return "";
}

}  // namespace testing
}  // namespace bayon
