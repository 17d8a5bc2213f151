// SPDX-License-Identifier: BSD-3-Clause
//
// Which image pairs to match. Ring and sequential take the images in the
// order of their names (as COLMAP's sequential_matcher does), for a
// sequence shot around an object and named in that order. Auto, the
// default, does not trust the names: every pair while that is affordable,
// and above that each image with those that look most like it (retrieval,
// image_retrieval.h), as COLMAP's vocabulary-tree matcher does.
#pragma once

#include "ext/colmap/database.h"
#include "ext/core/option_registry.h"

#include <Eigen/Core>

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
  kRetrieval,   // each image with its most similar ones
  kAuto,        // exhaustive up to max_exhaustive_images, else retrieval
};

// "ring", "sequential", "exhaustive", "list", "retrieval", "auto".
const char* PairingModeName(PairingMode mode);

struct PairingOptions {
  PairingMode mode = PairingMode::kAuto;
  // Ring and sequential: neighbours on each side (k). 2 links every image to
  // the next and the one after, so that a pair too convergent to match is
  // bridged.
  int num_neighbors = 2;
  // List: one pair per line, "name1 name2" (COLMAP's matches_importer
  // `pairs` format); blank lines and lines starting with # are skipped.
  std::string pair_list_path;
  // Auto: every pair of up to this many images (1,225 pairs at 50: about
  // 10 min of correlation matching for 6-MP photographs on 2 cores).
  int max_exhaustive_images = 50;
  // Retrieval: each image with this many most similar ones (the pairs are
  // the union, so an image may have more).
  int retrieval_neighbors = 10;
  void Register(OptionRegistry* registry);
  void Check() const;
};

// Whether the pairs of `num_images` images are chosen by similarity.
bool UsesRetrieval(const PairingOptions& options, int num_images);

// The pairs, as (image_id1, image_id2) with image_id1 < image_id2 (COLMAP's
// canonical order), without repeats, in the order of the first image's
// name. `similarity` (image_retrieval.h; rows and columns in the order of
// `images`) is needed where UsesRetrieval; ties go to the earlier name.
// Throws InputError for a list that names unknown images, pairs an image
// with itself, or has a malformed line (with its line number).
std::vector<std::pair<image_t, image_t>> SelectImagePairs(
    const std::vector<DatabaseImage>& images,
    const PairingOptions& options,
    const Eigen::MatrixXd* similarity = nullptr);

}  // namespace bayon
