// SPDX-License-Identifier: BSD-3-Clause
//
// Which photographs look alike, from the photographs alone: a bag of visual
// words (Sivic and Zisserman 2003, "Video Google"; Nister and Stewenius
// 2006, the idea behind COLMAP's vocabulary-tree matcher), so that pairs can
// be chosen for large sets without trusting the order of the file names.
//
// Each photograph, reduced to max_image_size, gives up to max_num_features
// SIFT descriptors (sift.h). A flat vocabulary of vocabulary_size words is
// learnt by k-means from the set's own descriptors (no trained vocabulary
// file to ship), each descriptor votes for its nearest word, the votes are
// weighted by tf-idf (a word seen in every photograph says nothing) and the
// histograms normalised. The cosine of two histograms shortlists, for each
// photograph, the shortlist_size most alike; a flat vocabulary this small
// confuses repeated structure (a facade's windows), so the shortlisted
// pairs are then matched by descriptor (descriptor_matcher.h, at this
// reduced size), and their similarity is the share of descriptors matched,
// as COLMAP re-ranks its vocabulary tree's candidates by spatial
// verification. Pairs off every shortlist have similarity 0.
#pragma once

#include "ext/core/option_registry.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace bayon {

struct RetrievalOptions {
  int max_image_size = 640;     // long side the photographs are reduced to
  int max_num_features = 1000;  // SIFT descriptors per photograph
  int vocabulary_size = 256;    // words (fewer for small sets)
  int shortlist_size = 30;      // candidates matched per photograph
  int num_threads = -1;         // photographs in parallel; -1 = all cores
  void Register(OptionRegistry* registry);
  void Check() const;  // throws InputError naming field, value, rule
};

// The columns j != i of row i of `similarity`, the k largest, largest
// first; ties in column order.
std::vector<int> MostSimilar(const Eigen::MatrixXd& similarity, int i, int k);

// N x N similarities of the photographs (symmetric, in [0, 1], 1 on the
// diagonal), in the order given; with N <= shortlist_size + 1 every pair is
// matched, and the result does not depend on the order. Throws InputError
// for an unreadable photograph.
Eigen::MatrixXd ImageSimilarities(const std::vector<std::string>& image_files,
                                  const RetrievalOptions& options);

}  // namespace bayon
