// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <algorithm>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

namespace bayon {

// A map that iterates in insertion order. COLMAP writes model records in the
// order of its hash maps; keeping the order we read lets a model go through
// bayon byte for byte unchanged.
template <typename Key, typename Value>
class OrderedMap {
 public:
  using value_type = std::pair<Key, Value>;
  using iterator = typename std::vector<value_type>::iterator;
  using const_iterator = typename std::vector<value_type>::const_iterator;

  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  bool contains(const Key& key) const { return index_.count(key) > 0; }

  // Inserts or replaces; a new key goes to the end.
  Value& Set(const Key& key, Value value) {
    auto it = index_.find(key);
    if (it != index_.end()) {
      entries_[it->second].second = std::move(value);
      return entries_[it->second].second;
    }
    index_.emplace(key, entries_.size());
    entries_.emplace_back(key, std::move(value));
    return entries_.back().second;
  }

  Value& at(const Key& key) {
    auto it = index_.find(key);
    if (it == index_.end()) throw std::out_of_range("OrderedMap::at");
    return entries_[it->second].second;
  }
  const Value& at(const Key& key) const {
    auto it = index_.find(key);
    if (it == index_.end()) throw std::out_of_range("OrderedMap::at");
    return entries_[it->second].second;
  }
  Value* Find(const Key& key) {
    auto it = index_.find(key);
    return it == index_.end() ? nullptr : &entries_[it->second].second;
  }
  const Value* Find(const Key& key) const {
    auto it = index_.find(key);
    return it == index_.end() ? nullptr : &entries_[it->second].second;
  }

  bool Erase(const Key& key) {
    auto it = index_.find(key);
    if (it == index_.end()) return false;
    entries_.erase(entries_.begin() + it->second);
    Reindex();
    return true;
  }

  void clear() {
    entries_.clear();
    index_.clear();
  }

  void reserve(size_t n) {
    entries_.reserve(n);
    index_.reserve(n);
  }

  void SortByKey() {
    std::sort(entries_.begin(),
              entries_.end(),
              [](const value_type& a, const value_type& b) {
                return a.first < b.first;
              });
    Reindex();
  }

  iterator begin() { return entries_.begin(); }
  iterator end() { return entries_.end(); }
  const_iterator begin() const { return entries_.begin(); }
  const_iterator end() const { return entries_.end(); }

 private:
  void Reindex() {
    index_.clear();
    for (size_t i = 0; i < entries_.size(); ++i) index_[entries_[i].first] = i;
  }

  std::vector<value_type> entries_;
  std::unordered_map<Key, size_t> index_;
};

}  // namespace bayon
