// The bisection tree in files: the cell array bisect:generation and the point
// arrays bisect:parent_a, bisect:parent_b (state.hpp, ALGORITHMS.md §10).
// One component each, so that every converter keeps them.
#include "bisect/state.hpp"
#include "state_arrays.hpp"

#include "core/names.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace bisect {

namespace {

DataArray *find(std::vector<DataArray> &arrays, const char *name) {
  for (DataArray &a : arrays)
    if (a.name == name)
      return &a;
  return nullptr;
}

void put(std::vector<DataArray> &arrays, DataArray a) {
  if (DataArray *old = find(arrays, a.name.c_str()))
    *old = std::move(a);
  else
    arrays.push_back(std::move(a));
}

bool is_tree_array(const DataArray &a) {
  return a.name == kGenerationArray || a.name == kParentAArray || a.name == kParentBArray ||
         a.name == kLevelArray || a.name == kParentRankArray;
}

// The array's values as integers in [lo, hi]; InputError naming the entity.
void check_integers(const Mesh &mesh, const StateColumn &a, std::size_t count, double lo, double hi,
                    const char *entity, const std::string &path) {
  if (a.components() != 1)
    throw InputError(path, a.name() + " has " + std::to_string(a.components()) +
                               " components; expected 1");
  if (a.size() != count)
    throw InputError(path, a.name() + " has " + std::to_string(a.size()) + " values for " +
                               std::to_string(count) + " " + entity + "s");
  for (std::size_t i = 0; i < count; ++i) {
    const double v = a[i];
    if (!(v >= lo && v <= hi && v == std::floor(v)))
      throw InputError(path, (entity == std::string("cell") ? cell_name(mesh, CellId(i))
                                                            : vertex_name(mesh, VertexId(i))) +
                                 ": " + a.name() + " holds " + std::to_string(v) +
                                 ", not an integer in " +
                                 std::to_string(static_cast<long long>(lo)) + ".." +
                                 std::to_string(static_cast<long long>(hi)));
  }
}

} // namespace

void tree_sources(const Mesh &mesh, std::vector<ArraySource> &cells,
                  std::vector<ArraySource> &points) {
  const Mesh *m = &mesh;
  cells.push_back({kGenerationArray, 1, ValueType::UInt16,
                   [=](std::size_t c) { return double(m->generation[c]); },
                   [=](std::size_t first, std::size_t n, double *out) {
                     std::copy_n(m->generation.data() + first, n, out);
                   }});
  auto parent = [=](int end) {
    return [=](std::size_t v) {
      const VertexId p = m->parent_edge[2 * v + std::size_t(end)];
      return p == kNoVertex ? -1.0 : double(p);
    };
  };
  auto parents = [=](int end) {
    return [=](std::size_t first, std::size_t n, double *out) {
      const VertexId *p = m->parent_edge.data() + 2 * first + std::size_t(end);
      for (std::size_t i = 0; i < n; ++i)
        out[i] = p[2 * i] == kNoVertex ? -1.0 : double(p[2 * i]);
    };
  };
  points.push_back({kParentAArray, 1, ValueType::Int32, parent(0), parents(0)});
  points.push_back({kParentBArray, 1, ValueType::Int32, parent(1), parents(1)});
  if (mesh.level.size() == mesh.num_vertices())
    points.push_back({kLevelArray, 1, ValueType::UInt16,
                      [=](std::size_t v) { return double(m->level[v]); },
                      [=](std::size_t first, std::size_t n, double *out) {
                        std::copy_n(m->level.data() + first, n, out);
                      }});
  // Explicit marking: the ranks of the split edges, which no cell holds (so
  // bisect:edge_rank does not carry them) and coarsening needs.
  if (mesh.marking == Marking::Explicit) {
    auto rank = [=](std::size_t v) {
      const VertexId a = m->parent_edge[2 * v], b = m->parent_edge[2 * v + 1];
      if (a == kNoVertex)
        return -1.0;
      const auto it = m->edge_rank.find(edge_key(a, b));
      return it == m->edge_rank.end() ? -1.0 : double(it->second);
    };
    points.push_back({kParentRankArray, 1, ValueType::Int32, rank,
                      [=](std::size_t first, std::size_t n, double *out) {
                        for (std::size_t i = 0; i < n; ++i)
                          out[i] = rank(first + i);
                      }});
  }
}

DataArray materialize(const ArraySource &source, std::size_t rows) {
  DataArray a{source.name, source.components,
              std::vector<double>(rows * std::size_t(source.components)), source.type};
  for (std::size_t i = 0; i < a.values.size(); ++i)
    a.values[i] = source.value(i);
  return a;
}

void encode_tree(Mesh &mesh) {
  if (!mesh.has_tree()) {
    strip_tree(mesh); // arrays a tool copied from another mesh are not this one's tree
    return;
  }
  std::vector<ArraySource> cells, points;
  tree_sources(mesh, cells, points);
  for (const ArraySource &a : cells)
    put(mesh.cell_data, materialize(a, mesh.num_cells()));
  for (const ArraySource &a : points)
    put(mesh.point_data, materialize(a, mesh.num_vertices()));
  if (mesh.level.size() != mesh.num_vertices())
    std::erase_if(mesh.point_data, [](const DataArray &x) { return x.name == kLevelArray; });
  if (mesh.marking != Marking::Explicit)
    std::erase_if(mesh.point_data, [](const DataArray &x) { return x.name == kParentRankArray; });
}

void strip_tree(Mesh &mesh) {
  std::erase_if(mesh.cell_data, is_tree_array);
  std::erase_if(mesh.point_data, is_tree_array);
}

bool decode_tree(Mesh &mesh, const std::string &path, StoredState *stored) {
  StoredState none;
  if (!stored)
    stored = &none;
  // Each array among the mesh's DataArrays or in `stored`; either way
  // removed on return (also when refused: the exception ends the read).
  struct Drop {
    Mesh &mesh;
    StoredState &stored;
    ~Drop() {
      strip_tree(mesh);
      const auto tree = [](const StoredArray &a) {
        return a.name == kGenerationArray || a.name == kParentAArray || a.name == kParentBArray ||
               a.name == kLevelArray || a.name == kParentRankArray;
      };
      std::erase_if(stored.cells, tree);
      std::erase_if(stored.points, tree);
    }
  } drop{mesh, *stored};
  const StateColumn generation =
      StateColumn::find(mesh.cell_data, &stored->cells, kGenerationArray);
  const StateColumn pa = StateColumn::find(mesh.point_data, &stored->points, kParentAArray),
                    pb = StateColumn::find(mesh.point_data, &stored->points, kParentBArray),
                    level = StateColumn::find(mesh.point_data, &stored->points, kLevelArray),
                    rank = StateColumn::find(mesh.point_data, &stored->points, kParentRankArray);
  mesh.clear_tree();
  if (!generation && !pa && !pb)
    return false; // a lone bisect:level means nothing
  if (!pa != !pb)
    throw InputError(path, std::string("point arrays ") + kParentAArray + " and " + kParentBArray +
                               " come together; only " + (pa ? kParentAArray : kParentBArray) +
                               " is present");
  const std::size_t nc = mesh.num_cells(), nv = mesh.num_vertices();
  std::vector<std::uint16_t> gen(nc, 0);
  if (generation) {
    // No bisection sequence doubles resolve is deeper than kMaxGeneration
    // (the precision limit stops any edge after about 1,100 halvings, dim
    // generations each); a deeper value is not bisect's and would overflow.
    check_integers(mesh, generation, nc, 0, kMaxGeneration, "cell", path);
    for (std::size_t c = 0; c < nc; ++c)
      gen[c] = std::uint16_t(generation[c]);
  }
  std::vector<VertexId> parents(2 * nv, kNoVertex);
  if (pa) {
    const double top = double(nv) - 1;
    check_integers(mesh, pa, nv, -1, top, "vertex", path);
    check_integers(mesh, pb, nv, -1, top, "vertex", path);
    for (std::size_t v = 0; v < nv; ++v) {
      const double a = pa[v], b = pb[v];
      auto bad = [&](const std::string &what) {
        return InputError(path, vertex_name(mesh, VertexId(v)) + ": " + kParentAArray + " " +
                                    std::to_string(static_cast<long long>(a)) + ", " +
                                    kParentBArray + " " +
                                    std::to_string(static_cast<long long>(b)) + ": " + what);
      };
      if (a == -1 && b == -1)
        continue;
      if (a == -1 || b == -1)
        throw bad("either both are -1 (an original vertex) or neither");
      if (a == b)
        throw bad("the two ends of an edge must differ");
      if (!(a < double(v) && b < double(v)))
        throw bad("a vertex made by bisection has a larger id than both ends of its edge");
      const double *p = mesh.point(VertexId(a)), *q = mesh.point(VertexId(b)),
                   *z = mesh.point(VertexId(v));
      double extent = 0, off = 0;
      for (int k = 0; k < mesh.dim; ++k) {
        extent = std::max(extent, std::abs(p[k] - q[k]));
        off = std::max(off, std::abs(z[k] - 0.5 * (p[k] + q[k])));
      }
      if (!(off <= 1e-6 * extent))
        throw bad("the vertex is not the midpoint of that edge");
      parents[2 * v] = VertexId(a);
      parents[2 * v + 1] = VertexId(b);
    }
  }
  // Levels: 0 exactly for original vertices (else the array is ignored:
  // it is only a hint for coarsening, whose merges are all checked).
  std::vector<std::uint16_t> levels;
  if (level) {
    check_integers(mesh, level, nv, 0, std::numeric_limits<std::uint16_t>::max(), "vertex", path);
    levels.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) {
      levels[v] = std::uint16_t(level[v]);
      if ((levels[v] == 0) != (parents[2 * v] == kNoVertex))
        throw InputError(path,
                         vertex_name(mesh, VertexId(v)) + ": " + kLevelArray + " " +
                             std::to_string(levels[v]) +
                             (levels[v] == 0 ? " (original) but it is a midpoint"
                                             : " (made by bisection) but it has no parent edge"));
    }
  }
  // Explicit marking: the ranks of the split edges (ignored otherwise, as
  // the marking's other arrays are).
  if (rank && mesh.marking == Marking::Explicit) {
    check_integers(mesh, rank, nv, -1, 4294967294.0, "vertex", path);
    for (std::size_t v = 0; v < nv; ++v) {
      if (rank[v] == -1)
        continue;
      if (parents[2 * v] == kNoVertex)
        throw InputError(path, vertex_name(mesh, VertexId(v)) + ": " + kParentRankArray +
                                   " gives a rank to an original vertex (it has no parent edge)");
      const VertexId a = parents[2 * v], b = parents[2 * v + 1];
      const auto r = std::uint32_t(rank[v]);
      const auto [it, fresh] = mesh.edge_rank.emplace(edge_key(a, b), r);
      if (!fresh && it->second != r)
        throw InputError(path, vertex_name(mesh, VertexId(v)) + ": " + kParentRankArray +
                                   " gives edge " + vertex_number(mesh, a) + "-" +
                                   vertex_number(mesh, b) + " two different ranks");
    }
  }
  mesh.generation = std::move(gen);
  mesh.level = std::move(levels);
  mesh.parent_edge = std::move(parents);
  return true;
}

} // namespace bisect
