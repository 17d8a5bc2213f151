// SPDX-License-Identifier: BSD-3-Clause
//
// Disjoint sets over 0..n-1 (union-find with path halving): connected
// components of faces, corners or photographs, and strip's tracks (elements
// added as they are met).
#pragma once

#include <cstddef>
#include <numeric>
#include <vector>

namespace bayon {

class UnionFind {
 public:
  explicit UnionFind(size_t n = 0) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), size_t{0});
  }
  // A new element in a set of its own; its index.
  size_t Add() {
    parent_.push_back(parent_.size());
    return parent_.back();
  }
  size_t Find(size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void Union(size_t a, size_t b) { parent_[Find(a)] = Find(b); }

 private:
  std::vector<size_t> parent_;
};

}  // namespace bayon
