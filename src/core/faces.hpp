// Faces of cells as hash keys: the sorted vertex ids of a face (1 to 4 of
// them), padded with kNoVertex. Used to find tagged entities (mesh.hpp) among
// the faces of cells: when reading (is every entity a face?), when a cell is
// bisected (which of its faces are entities?) and when coarsening merges them.
#pragma once

#include "bisect/mesh.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace bisect {

struct FaceKey {
  std::array<VertexId, 4> ids{kNoVertex, kNoVertex, kNoVertex, kNoVertex};
  bool operator==(const FaceKey &) const = default;
};

// The key of the face with `count` (1..4) vertices `v`, in any order.
inline FaceKey face_key(const VertexId *v, int count) {
  // Insertion sort: at most 4 ids (std::sort here draws -Warray-bounds
  // false positives from GCC 12).
  FaceKey k;
  for (int i = 0; i < count; ++i) {
    int j = i;
    for (; j > 0 && k.ids[j - 1] > v[i]; --j)
      k.ids[j] = k.ids[j - 1];
    k.ids[j] = v[i];
  }
  return k;
}

struct FaceKeyHash {
  std::size_t operator()(const FaceKey &k) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (VertexId v : k.ids)
      h = (h ^ v) * 0xFF51AFD7ED558CCDull;
    return std::size_t(h ^ (h >> 29));
  }
};

// Calls visit(face, count) for every face with `count` = d + 1 vertices of
// the cell x with n vertices (all subsets of that size, vertices in x's order).
template <class Visit> void for_each_face(const VertexId *x, int n, int d, Visit &&visit) {
  const int count = d + 1;
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    if (__builtin_popcount(mask) != count)
      continue;
    VertexId face[5];
    int k = 0;
    for (int i = 0; i < n; ++i)
      if (mask >> i & 1u)
        face[k++] = x[i];
    visit(face, count);
  }
}

} // namespace bisect
