// Splitting and merging tagged entities with the cells (entities.hpp).
#include "engine/entities.hpp"

#include <algorithm>

namespace bisect {

EntitySplitter::EntitySplitter(Mesh &mesh) : m_(mesh) {
  std::size_t total = 0;
  for (const Entities &b : m_.entities)
    total += b.size();
  index_.reserve(total);
  for (std::size_t bi = 0; bi < m_.entities.size(); ++bi) {
    const Entities &b = m_.entities[bi];
    if (b.dim < 1 || b.size() == 0)
      continue;
    dims_ |= 1u << b.dim;
    for (std::size_t i = 0; i < b.size(); ++i)
      add(face_key(b.entity(i), b.dim + 1), {std::uint32_t(bi), std::uint32_t(i)});
    on_entity_.resize(m_.num_vertices(), 0);
    for (VertexId v : b.vertices)
      on_entity_[v] = 1;
  }
}

void EntitySplitter::split(const VertexId *x, int n, VertexId a, VertexId b, VertexId m) {
  if (!on_entity(a) || !on_entity(b))
    return; // no entity holds the edge (a, b)
  // The faces of x holding a and b: {a, b} plus d - 1 of the other vertices.
  VertexId others[4];
  int k = 0;
  for (int i = 0; i < n; ++i)
    if (x[i] != a && x[i] != b)
      others[k++] = x[i];
  for (int d = 1; d < n - 1; ++d) {
    if (!(dims_ >> d & 1u))
      continue;
    for_each_face(others, k, d - 2, [&](const VertexId *rest, int count) {
      VertexId face[4] = {a, b};
      std::copy(rest, rest + count, face + 2);
      const FaceKey key = face_key(face, d + 1);
      const auto [first, last] = index_.equal_range(key);
      if (first == last)
        return;
      hits_.clear();
      for (auto it = first; it != last; ++it)
        hits_.push_back(it->second);
      index_.erase(first, last);
      for (const Ref r : hits_) {
        Entities &block = m_.entities[r.block];
        const std::size_t nvs = std::size_t(block.dim + 1);
        const std::size_t added = block.size();
        VertexId *v = block.vertices.data() + r.index * nvs;
        VertexId half[4];
        std::copy(v, v + nvs, half);
        std::replace(v, v + nvs, b, m);       // (.., a, .., m, ..) in place
        std::replace(half, half + nvs, a, m); // (.., m, .., b, ..) appended
        block.vertices.insert(block.vertices.end(), half, half + nvs);
        for (DataArray &arr : block.data) {
          const std::size_t c = std::size_t(arr.components);
          for (std::size_t j = 0; j < c; ++j)
            arr.values.push_back(arr.values[r.index * c + j]);
        }
        add(face_key(block.entity(r.index), int(nvs)), r);
        add(face_key(half, int(nvs)), {r.block, std::uint32_t(added)});
        if (m >= on_entity_.size())
          on_entity_.resize(std::max<std::size_t>(m + 1, 2 * on_entity_.size()), 0);
        on_entity_[m] = 1;
      }
    });
  }
}

void merge_entities(Mesh &mesh, const std::vector<char> &removed) {
  if (mesh.entities.empty())
    return;
  const std::size_t nv = mesh.num_vertices();
  std::vector<VertexId> id(nv, kNoVertex);
  VertexId next = 0;
  for (std::size_t v = 0; v < nv; ++v)
    if (!removed[v])
      id[v] = next++;
  for (Entities &block : mesh.entities) {
    const int nvs = block.dim + 1;
    const std::size_t n = block.size();
    // Merged key -> the kept entities with that key, each able to take in
    // one sibling (two halves make one; a face tagged twice, e.g. in two
    // physical groups, has two pairs of halves that make two).
    struct Kept {
      std::size_t index;
      bool has_sibling;
    };
    std::unordered_multimap<FaceKey, Kept, FaceKeyHash> merged;
    std::vector<char> keep(n, 1);
    auto same_data = [&](std::size_t p, std::size_t q) {
      for (const DataArray &arr : block.data) {
        const std::size_t c = std::size_t(arr.components);
        if (!std::equal(arr.values.begin() + std::ptrdiff_t(p * c),
                        arr.values.begin() + std::ptrdiff_t((p + 1) * c),
                        arr.values.begin() + std::ptrdiff_t(q * c)))
          return false;
      }
      return true;
    };
    for (std::size_t i = 0; i < n; ++i) {
      VertexId *v = block.vertices.data() + i * std::size_t(nvs);
      const auto gone = std::find_if(v, v + nvs, [&](VertexId u) { return removed[u]; });
      if (gone == v + nvs)
        continue;
      const VertexId z = *gone;
      const VertexId a = mesh.parent_edge[2 * std::size_t(z)],
                     b = mesh.parent_edge[2 * std::size_t(z) + 1];
      const bool has_a = std::find(v, v + nvs, a) != v + nvs,
                 has_b = std::find(v, v + nvs, b) != v + nvs;
      if (has_a == has_b) { // neither: nothing coarse to become
        keep[i] = 0;
        continue;
      }
      *gone = has_a ? b : a;
      const FaceKey key = face_key(v, nvs);
      auto [first, last] = merged.equal_range(key);
      auto sibling = std::find_if(first, last, [&](const auto &e) {
        return !e.second.has_sibling && same_data(e.second.index, i);
      });
      if (sibling != last) {
        sibling->second.has_sibling = true;
        keep[i] = 0;
      } else {
        merged.emplace(key, Kept{i, false});
      }
    }
    // Compact the dropped entities out and renumber the vertices.
    std::size_t w = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!keep[i])
        continue;
      for (int k = 0; k < nvs; ++k)
        block.vertices[w * std::size_t(nvs) + std::size_t(k)] =
            id[block.vertices[i * std::size_t(nvs) + std::size_t(k)]];
      for (DataArray &arr : block.data) {
        const std::size_t c = std::size_t(arr.components);
        std::copy_n(arr.values.begin() + std::ptrdiff_t(i * c), c,
                    arr.values.begin() + std::ptrdiff_t(w * c));
      }
      ++w;
    }
    block.vertices.resize(w * std::size_t(nvs));
    for (DataArray &arr : block.data)
      arr.values.resize(w * std::size_t(arr.components));
  }
}

} // namespace bisect
