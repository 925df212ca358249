// The bisection tree in files: the cell array bisect:generation and the point
// arrays bisect:parent_a, bisect:parent_b (state.hpp, ALGORITHMS.md §10).
// One component each, so that every converter keeps them.
#include "bisect/state.hpp"

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
         a.name == kLevelArray;
}

// The array's values as integers in [lo, hi]; InputError naming the entity.
void check_integers(const Mesh &mesh, const DataArray &a, std::size_t count, double lo, double hi,
                    const char *entity, const std::string &path) {
  if (a.components != 1)
    throw InputError(path,
                     a.name + " has " + std::to_string(a.components) + " components; expected 1");
  if (a.values.size() != count)
    throw InputError(path, a.name + " has " + std::to_string(a.values.size()) + " values for " +
                               std::to_string(count) + " " + entity + "s");
  for (std::size_t i = 0; i < count; ++i) {
    const double v = a.values[i];
    if (!(v >= lo && v <= hi && v == std::floor(v)))
      throw InputError(path, (entity == std::string("cell") ? cell_name(mesh, CellId(i))
                                                            : vertex_name(mesh, VertexId(i))) +
                                 ": " + a.name + " holds " + std::to_string(v) +
                                 ", not an integer in " +
                                 std::to_string(static_cast<long long>(lo)) + ".." +
                                 std::to_string(static_cast<long long>(hi)));
  }
}

} // namespace

void encode_tree(Mesh &mesh) {
  if (!mesh.has_tree()) {
    strip_tree(mesh); // arrays a tool copied from another mesh are not this one's tree
    return;
  }
  const std::size_t nc = mesh.num_cells(), nv = mesh.num_vertices();
  DataArray generation{kGenerationArray, 1, std::vector<double>(nc)};
  for (std::size_t c = 0; c < nc; ++c)
    generation.values[c] = mesh.generation[c];
  DataArray a{kParentAArray, 1, std::vector<double>(nv)},
      b{kParentBArray, 1, std::vector<double>(nv)};
  for (std::size_t v = 0; v < nv; ++v) {
    const VertexId p = mesh.parent_edge[2 * v], q = mesh.parent_edge[2 * v + 1];
    a.values[v] = p == kNoVertex ? -1.0 : double(p);
    b.values[v] = q == kNoVertex ? -1.0 : double(q);
  }
  generation.type = ValueType::UInt16;
  a.type = b.type = ValueType::Int32;
  put(mesh.cell_data, std::move(generation));
  put(mesh.point_data, std::move(a));
  put(mesh.point_data, std::move(b));
  if (mesh.level.size() == nv) {
    DataArray level{kLevelArray, 1, std::vector<double>(mesh.level.begin(), mesh.level.end()),
                    ValueType::UInt16};
    put(mesh.point_data, std::move(level));
  } else {
    std::erase_if(mesh.point_data, [](const DataArray &x) { return x.name == kLevelArray; });
  }
}

void strip_tree(Mesh &mesh) {
  std::erase_if(mesh.cell_data, is_tree_array);
  std::erase_if(mesh.point_data, is_tree_array);
}

bool decode_tree(Mesh &mesh, const std::string &path) {
  const DataArray *generation = find(mesh.cell_data, kGenerationArray);
  const DataArray *pa = find(mesh.point_data, kParentAArray),
                  *pb = find(mesh.point_data, kParentBArray),
                  *level = find(mesh.point_data, kLevelArray);
  mesh.clear_tree();
  if (!generation && !pa && !pb) {
    strip_tree(mesh); // a lone bisect:level means nothing
    return false;
  }
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
    check_integers(mesh, *generation, nc, 0, kMaxGeneration, "cell", path);
    for (std::size_t c = 0; c < nc; ++c)
      gen[c] = std::uint16_t(generation->values[c]);
  }
  std::vector<VertexId> parents(2 * nv, kNoVertex);
  if (pa) {
    const double top = double(nv) - 1;
    check_integers(mesh, *pa, nv, -1, top, "vertex", path);
    check_integers(mesh, *pb, nv, -1, top, "vertex", path);
    for (std::size_t v = 0; v < nv; ++v) {
      const double a = pa->values[v], b = pb->values[v];
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
    check_integers(mesh, *level, nv, 0, std::numeric_limits<std::uint16_t>::max(), "vertex", path);
    levels.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) {
      levels[v] = std::uint16_t(level->values[v]);
      if ((levels[v] == 0) != (parents[2 * v] == kNoVertex))
        throw InputError(path,
                         vertex_name(mesh, VertexId(v)) + ": " + kLevelArray + " " +
                             std::to_string(levels[v]) +
                             (levels[v] == 0 ? " (original) but it is a midpoint"
                                             : " (made by bisection) but it has no parent edge"));
    }
  }
  strip_tree(mesh);
  mesh.generation = std::move(gen);
  mesh.level = std::move(levels);
  mesh.parent_edge = std::move(parents);
  return true;
}

} // namespace bisect
