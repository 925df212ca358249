// Helpers shared by the tests.
#pragma once

#include "bisect/check.hpp"
#include "bisect/mesh.hpp"
#include "bisect/state.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace bisect::testing {

// "" when a and b hold the same mesh (dimension, coordinates, cells, and the
// same arrays in the same order), else what differs first.
inline std::string mesh_difference(const Mesh &a, const Mesh &b) {
  if (a.dim != b.dim)
    return "dimension";
  if (a.coords != b.coords)
    return "coordinates";
  if (a.cells != b.cells)
    return "cells";
  auto arrays = [](const std::vector<DataArray> &x, const std::vector<DataArray> &y,
                   const char *kind) -> std::string {
    if (x.size() != y.size())
      return std::string(kind) + " array count";
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].name != y[i].name || x[i].components != y[i].components ||
          x[i].values != y[i].values)
        return std::string(kind) + " array '" + x[i].name + "'";
    return {};
  };
  if (std::string d = arrays(a.point_data, b.point_data, "point"); !d.empty())
    return d;
  return arrays(a.cell_data, b.cell_data, "cell");
}

inline std::string data_path(const std::string &name) {
  return std::string(BISECT_DATA_DIR) + "/" + name;
}

// Renumbers vertices by a random permutation (cells keep their shape).
inline Mesh renumbered(const Mesh &in, std::uint64_t seed) {
  Mesh m = in;
  const std::size_t nv = in.num_vertices();
  std::vector<VertexId> perm(nv);
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(perm.begin(), perm.end(), rng);
  for (std::size_t v = 0; v < nv; ++v)
    std::copy(in.point(VertexId(v)), in.point(VertexId(v)) + in.dim,
              m.coords.begin() + perm[v] * in.dim);
  for (VertexId &x : m.cells)
    x = perm[x];
  for (DataArray &a : m.point_data)
    for (std::size_t v = 0; v < nv; ++v)
      for (int k = 0; k < a.components; ++k)
        a.values[perm[v] * a.components + k] =
            in.point_data[&a - m.point_data.data()].values[v * a.components + k];
  return m;
}

// Moves every vertex by up to `amount` in each coordinate, except vertices
// on the bounding box (so the domain and its volume stay the same).
inline Mesh perturbed_inside_box(const Mesh &in, double amount, std::uint64_t seed) {
  Mesh m = in;
  const int d = in.dim;
  std::vector<double> lo(d, 1e300), hi(d, -1e300);
  for (std::size_t v = 0; v < in.num_vertices(); ++v)
    for (int k = 0; k < d; ++k) {
      lo[k] = std::min(lo[k], in.point(VertexId(v))[k]);
      hi[k] = std::max(hi[k], in.point(VertexId(v))[k]);
    }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (std::size_t v = 0; v < in.num_vertices(); ++v) {
    bool on_box = false;
    for (int k = 0; k < d; ++k)
      on_box |= in.point(VertexId(v))[k] == lo[k] || in.point(VertexId(v))[k] == hi[k];
    if (on_box)
      continue;
    for (int k = 0; k < d; ++k)
      m.coords[v * d + k] += u(rng);
  }
  return m;
}

// Rewrites an encoded mesh's bisect:state as the older arrays bisect:order,
// bisect:stage and bisect:tag, which files written before 0.2 carry (still
// read): the tests of that path tamper with them.
inline void to_legacy_state(Mesh &m) {
  auto it = std::find_if(m.cell_data.begin(), m.cell_data.end(),
                         [](const DataArray &a) { return a.name == kStateArray; });
  if (it == m.cell_data.end())
    return;
  const int nv = m.dim + 1;
  DataArray order{kOrderArray, nv, {}}, stage{kStageArray, 1, {}}, tag{kTagArray, 1, {}};
  for (double v : it->values) {
    const int w = int(v);
    int p[5];
    permutation_of_rank(w >> 4, nv, p);
    for (int i = 0; i < nv; ++i)
      order.values.push_back(p[i]);
    stage.values.push_back((w >> 3) & 1);
    tag.values.push_back(w & 7);
  }
  m.cell_data.erase(it);
  m.cell_data.push_back(std::move(order));
  m.cell_data.push_back(std::move(stage));
  m.cell_data.push_back(std::move(tag));
}

} // namespace bisect::testing

// Asserts the mesh passes every conformity check against `inv`, printing the
// first failure.
#define REQUIRE_CONFORMING(mesh, inv)                                                              \
  do {                                                                                             \
    const ::bisect::CheckResult check_result_ = ::bisect::check_conformity((mesh), &(inv));        \
    INFO(check_result_.failure);                                                                   \
    REQUIRE(check_result_.ok);                                                                     \
  } while (0)
