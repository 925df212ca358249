// Splitting and merging tagged entities with the cells (entities.hpp).
#include "engine/entities.hpp"

#include <algorithm>
#include <array>
#include <functional>
#include <map>

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
    // A pass may remove several vertices of one entity (a face split at z1,
    // one half split again at z2, where z2 may be the older vertex: a reused
    // midpoint). Ids do not tell the order, the siblings do: a pair merges
    // at z when both halves are there (the same face once z is replaced by
    // the end of z's edge each lacks), so rounds merge what they can until
    // nothing pairs; a half whose sibling was never tagged then becomes the
    // whole face (newest removed vertex first).
    auto parent_at = [&](std::size_t i, VertexId z, FaceKey &key) {
      VertexId v[4];
      std::copy_n(block.vertices.data() + i * std::size_t(nvs), nvs, v);
      const VertexId a = mesh.parent_edge[2 * std::size_t(z)],
                     b = mesh.parent_edge[2 * std::size_t(z) + 1];
      const bool has_a = std::find(v, v + nvs, a) != v + nvs,
                 has_b = std::find(v, v + nvs, b) != v + nvs;
      if (has_a == has_b)
        return VertexId(kNoVertex);
      const VertexId end = has_a ? b : a;
      *std::find(v, v + nvs, z) = end;
      key = face_key(v, nvs);
      return end;
    };
    auto removed_in = [&](std::size_t i, std::vector<VertexId> &out) {
      out.clear();
      const VertexId *v = block.vertices.data() + i * std::size_t(nvs);
      for (int k = 0; k < nvs; ++k)
        if (removed[v[k]])
          out.push_back(v[k]);
    };
    std::vector<VertexId> gone;
    for (bool progress = true; progress;) {
      progress = false;
      // (z, parent face) -> the live halves that would make it.
      std::map<std::pair<VertexId, std::array<VertexId, 4>>, std::vector<std::size_t>> halves;
      for (std::size_t i = 0; i < n; ++i) {
        if (!keep[i])
          continue;
        removed_in(i, gone);
        for (const VertexId z : gone) {
          FaceKey key;
          if (parent_at(i, z, key) != kNoVertex)
            halves[{z, key.ids}].push_back(i);
        }
      }
      std::vector<char> used(n, 0);
      for (const auto &[zk, list] : halves) {
        // Pair halves with the same data (a face in two groups: two pairs).
        for (std::size_t p = 0; p < list.size(); ++p) {
          const std::size_t i = list[p];
          if (used[i] || !keep[i])
            continue;
          for (std::size_t q = p + 1; q < list.size(); ++q) {
            const std::size_t j = list[q];
            if (used[j] || !keep[j] || !same_data(i, j))
              continue;
            FaceKey key;
            const VertexId end = parent_at(i, zk.first, key);
            VertexId *v = block.vertices.data() + i * std::size_t(nvs);
            *std::find(v, v + nvs, zk.first) = end;
            keep[j] = 0;
            used[i] = used[j] = 1;
            progress = true;
            break;
          }
        }
      }
    }
    // Leftovers: a half without a tagged sibling becomes its parent; an
    // entity with no coarse counterpart (no end of z's edge) is dropped.
    for (std::size_t i = 0; i < n; ++i) {
      for (;;) {
        if (!keep[i])
          break;
        removed_in(i, gone);
        if (gone.empty())
          break;
        const VertexId z = *std::max_element(gone.begin(), gone.end());
        FaceKey key;
        const VertexId end = parent_at(i, z, key);
        if (end == kNoVertex) {
          keep[i] = 0;
          break;
        }
        VertexId *v = block.vertices.data() + i * std::size_t(nvs);
        *std::find(v, v + nvs, z) = end;
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
