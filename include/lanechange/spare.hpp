#pragma once
// Workspaces that are sized once (HPIPM's habit) must keep their memory when
// a problem shrinks and grows again: a vector of vectors that drops elements
// frees their memory, and takes it anew when they come back. These keep the
// dropped elements aside instead.
#include <cstddef>
#include <utility>
#include <vector>

namespace lanechange {

/// Elements set aside with their memory. A copy starts empty: the memory
/// belongs to the object that grew it, not to its copies.
template <class T>
struct Spare {
  std::vector<T> items;
  Spare() = default;
  Spare(const Spare& /*other*/) {}
  Spare(Spare&&) noexcept = default;
  Spare& operator=(const Spare& /*other*/) { return *this; }
  Spare& operator=(Spare&&) noexcept = default;
  ~Spare() = default;
};

/// Resizes `v` to `n` elements as std::vector::resize does, but the elements
/// it drops go to `spare`, and new ones come from there first (their content
/// is left as it was: the caller fills them). Once `v` and `spare` have held
/// as many elements as the largest size, no call allocates.
template <class T>
void resize_keeping(std::vector<T>& v, std::size_t n, Spare<T>& spare) {
  while (v.size() > n) {
    spare.items.push_back(std::move(v.back()));
    v.pop_back();
  }
  // Room for every element `v` may set aside later, made while it grows.
  if (n > spare.items.capacity()) spare.items.reserve(n);
  while (v.size() < n) {
    if (spare.items.empty()) {
      v.emplace_back();
    } else {
      v.push_back(std::move(spare.items.back()));
      spare.items.pop_back();
    }
  }
}

/// `to = from` element by element, with resize_keeping: the elements keep
/// their memory where they can.
template <class T>
void assign_keeping(std::vector<T>& to, const std::vector<T>& from, Spare<T>& spare) {
  resize_keeping(to, from.size(), spare);
  for (std::size_t i = 0; i < from.size(); ++i) to[i] = from[i];
}

}  // namespace lanechange
