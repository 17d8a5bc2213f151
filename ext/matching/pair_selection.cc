// SPDX-License-Identifier: BSD-3-Clause
#include "ext/matching/pair_selection.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/matching/image_retrieval.h"

#include <glog/logging.h>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

namespace bayon {

void PairingOptions::Register(OptionRegistry* r) {
  r->AddChoice(
      "mode",
      &mode,
      ChoicesOf<PairingMode>([](PairingMode m) { return PairingModeName(m); },
                             {PairingMode::kAuto,
                              PairingMode::kRetrieval,
                              PairingMode::kExhaustive,
                              PairingMode::kRing,
                              PairingMode::kSequential,
                              PairingMode::kList}),
      "auto (every pair up to max_exhaustive_images, else "
      "retrieval), retrieval (the most similar photographs), "
      "exhaustive, ring or sequential (in name order), or list");
  r->Add("max_exhaustive_images",
         &max_exhaustive_images,
         "auto: every pair up to this many images");
  r->Add("retrieval_neighbors",
         &retrieval_neighbors,
         "retrieval: each image with this many most similar ones");
  r->Add("num_neighbors",
         &num_neighbors,
         "ring/sequential: successors paired with each image");
  r->Add(
      "pair_list_path", &pair_list_path, "list: file of 'name1 name2' lines");
}

const char* PairingModeName(PairingMode mode) {
  switch (mode) {
    case PairingMode::kRing:
      return "ring";
    case PairingMode::kSequential:
      return "sequential";
    case PairingMode::kExhaustive:
      return "exhaustive";
    case PairingMode::kList:
      return "list";
    case PairingMode::kRetrieval:
      return "retrieval";
    case PairingMode::kAuto:
      return "auto";
  }
  return "?";
}

void PairingOptions::Check() const {
  CheckOption(num_neighbors >= 1, "num_neighbors", ">= 1", num_neighbors);
  CheckOption(max_exhaustive_images >= 2,
              "max_exhaustive_images",
              ">= 2",
              max_exhaustive_images);
  CheckOption(retrieval_neighbors >= 1,
              "retrieval_neighbors",
              ">= 1",
              retrieval_neighbors);
  if (mode == PairingMode::kList && pair_list_path.empty()) {
    ThrowInputError("mode list needs pair_list_path");
  }
}

bool UsesRetrieval(const PairingOptions& options, int num_images) {
  return options.mode == PairingMode::kRetrieval ||
         (options.mode == PairingMode::kAuto &&
          num_images > options.max_exhaustive_images);
}

namespace {

std::vector<std::pair<image_t, image_t>> ReadPairList(
    const std::string& path, const std::vector<DatabaseImage>& images) {
  std::map<std::string, image_t> ids;
  for (const DatabaseImage& image : images) ids[image.name] = image.image_id;
  std::istringstream lines(ReadFileToString(path));
  std::string line;
  std::vector<std::pair<image_t, image_t>> pairs;
  int line_number = 0;
  while (std::getline(lines, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::string name1, name2, extra;
    if (!(fields >> name1 >> name2) || (fields >> extra)) {
      ThrowInputError(path,
                      ":",
                      line_number,
                      ": expected two image names, got '",
                      line,
                      "'");
    }
    for (const std::string& name : {name1, name2}) {
      if (!ids.count(name)) {
        ThrowInputError(path,
                        ":",
                        line_number,
                        ": image '",
                        name,
                        "' is not in the database");
      }
    }
    if (name1 == name2) {
      ThrowInputError(
          path, ":", line_number, ": pairs image '", name1, "' with itself");
    }
    pairs.emplace_back(ids[name1], ids[name2]);
  }
  return pairs;
}

// Each image (in name order) with its k most similar others; ties go to
// the earlier name.
std::vector<std::pair<image_t, image_t>> MostSimilarPairs(
    const std::vector<DatabaseImage>& images,
    const std::vector<DatabaseImage>& sorted,
    const Eigen::MatrixXd& similarity,
    int k) {
  std::map<image_t, int> index;
  for (size_t i = 0; i < images.size(); ++i) {
    index[images[i].image_id] = static_cast<int>(i);
  }
  const int n = static_cast<int>(sorted.size());
  Eigen::MatrixXd by_name(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      by_name(i, j) = similarity(index.at(sorted[i].image_id),
                                 index.at(sorted[j].image_id));
    }
  }
  std::vector<std::pair<image_t, image_t>> pairs;
  for (int i = 0; i < n; ++i) {
    for (int j : MostSimilar(by_name, i, k)) {
      pairs.emplace_back(sorted[i].image_id, sorted[j].image_id);
    }
  }
  return pairs;
}

}  // namespace

std::vector<std::pair<image_t, image_t>> SelectImagePairs(
    const std::vector<DatabaseImage>& images,
    const PairingOptions& options,
    const Eigen::MatrixXd* similarity) {
  options.Check();
  std::vector<DatabaseImage> sorted = images;
  std::sort(sorted.begin(),
            sorted.end(),
            [](const DatabaseImage& a, const DatabaseImage& b) {
              return a.name < b.name;
            });
  const int n = static_cast<int>(sorted.size());
  std::vector<std::pair<image_t, image_t>> raw;
  PairingMode mode = options.mode;
  if (mode == PairingMode::kAuto) {
    mode = UsesRetrieval(options, n) ? PairingMode::kRetrieval
                                     : PairingMode::kExhaustive;
  }
  switch (mode) {
    case PairingMode::kRing:
    case PairingMode::kSequential:
      for (int i = 0; i < n; ++i) {
        for (int d = 1; d <= options.num_neighbors; ++d) {
          int j = i + d;
          if (j >= n) {
            if (mode == PairingMode::kSequential) break;
            j %= n;
          }
          if (j != i) raw.emplace_back(sorted[i].image_id, sorted[j].image_id);
        }
      }
      break;
    case PairingMode::kRetrieval:
      CHECK(similarity != nullptr && similarity->rows() == n &&
            similarity->cols() == n)
          << "retrieval needs the images' similarities";
      raw = MostSimilarPairs(
          images, sorted, *similarity, options.retrieval_neighbors);
      break;
    case PairingMode::kAuto:  // resolved above
    case PairingMode::kExhaustive:
      for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
          raw.emplace_back(sorted[i].image_id, sorted[j].image_id);
        }
      }
      break;
    case PairingMode::kList:
      raw = ReadPairList(options.pair_list_path, sorted);
      break;
  }
  std::set<std::pair<image_t, image_t>> seen;
  std::vector<std::pair<image_t, image_t>> pairs;
  for (auto [a, b] : raw) {
    if (a > b) std::swap(a, b);
    if (seen.insert({a, b}).second) pairs.emplace_back(a, b);
  }
  return pairs;
}

}  // namespace bayon
