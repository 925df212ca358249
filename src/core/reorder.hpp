// Renumbering a mesh's vertices (not installed): the .pvtu readers put the
// vertices in an order of their own (pvtu.cpp, distributed.cpp).
#pragma once

#include "bisect/mesh.hpp"

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace bisect {

// Puts vertex order[i] at place i: coordinates, point arrays, cells and
// tagged entities follow (the tree and anything else per vertex is the
// caller's). Returns each old vertex's new id.
inline std::vector<VertexId> reorder_vertices(Mesh &m, const std::vector<VertexId> &order) {
  const std::size_t nv = order.size(), dim = std::size_t(m.dim);
  std::vector<VertexId> id(nv);
  for (std::size_t i = 0; i < nv; ++i)
    id[order[i]] = VertexId(i);
  std::vector<double> coords(m.coords.size());
  for (std::size_t i = 0; i < nv; ++i)
    std::copy_n(m.point(order[i]), dim, coords.data() + i * dim);
  m.coords = std::move(coords);
  for (DataArray &a : m.point_data) {
    const std::size_t k = std::size_t(a.components);
    std::vector<double> values(a.values.size());
    for (std::size_t i = 0; i < nv; ++i)
      std::copy_n(a.values.data() + order[i] * k, k, values.data() + i * k);
    a.values = std::move(values);
  }
  for (VertexId &x : m.cells)
    x = id[x];
  for (Entities &block : m.entities)
    for (VertexId &x : block.vertices)
      x = id[x];
  return id;
}

} // namespace bisect
