// SPDX-License-Identifier: BSD-3-Clause
//
// Which image pairs to match. Images are taken in the order of their names
// (as COLMAP's sequential_matcher does), so that a sequence shot around an
// object is a ring in name order.
#pragma once

#include "ext/colmap/database.h"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace bayon {

enum class PairingMode {
  kRing,        // each image with its k successors, wrapping around
  kSequential,  // each image with its k successors, no wrap-around
  kExhaustive,  // every pair
  kList,        // pairs from a file
};

// "ring", "sequential", "exhaustive", "list"; nullopt for other names.
std::optional<PairingMode> PairingModeFromName(const std::string& name);
const char* PairingModeName(PairingMode mode);

struct PairingOptions {
  PairingMode mode = PairingMode::kRing;
  // Ring and sequential: neighbours on each side (k). 2 links every image to
  // the next and the one after, so that a pair too convergent to match is
  // bridged.
  int num_neighbors = 2;
  // List: one pair per line, "name1 name2" (COLMAP's matches_importer
  // `pairs` format); blank lines and lines starting with # are skipped.
  std::string pair_list_path;
  void Check() const;
};

// The pairs, as (image_id1, image_id2) with image_id1 < image_id2 (COLMAP's
// canonical order), without repeats, in the order of the first image's
// name. Throws InputError for a list that names unknown images, pairs an
// image with itself, or has a malformed line (with its line number).
std::vector<std::pair<image_t, image_t>> SelectImagePairs(
    const std::vector<DatabaseImage>& images, const PairingOptions& options);

}  // namespace bayon
