#pragma once
/// @file UnionFind.h
/// Disjoint sets of consecutive numbers whose root is always the set's least member: numbering
/// sets in the order of their members' first appearance needs no other table.

#include <algorithm>
#include <cstdint>
#include <vector>

namespace tetrapage {

class UnionFind {
 public:
  /// A new set of one; returns its number (the count so far).
  std::uint32_t add() {
    parent_.push_back(std::uint32_t(parent_.size()));
    return parent_.back();
  }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }
  std::size_t size() const { return parent_.size(); }
  /// The bytes held (the parents' capacity).
  std::uint64_t bytes() const { return parent_.capacity() * sizeof(std::uint32_t); }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace tetrapage
