// The bisection state in files: cell arrays bisect:* (README, "Files").
#include "bisect/state.hpp"
#include "state_arrays.hpp"

#include "core/dimension.hpp"
#include "core/geometry.hpp"
#include "core/names.hpp"

#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <string>

namespace bisect {

namespace {

int find_array(const std::vector<DataArray> &arrays, const char *name) {
  for (std::size_t i = 0; i < arrays.size(); ++i)
    if (arrays[i].name == name)
      return int(i);
  return -1;
}

void set_array(std::vector<DataArray> &arrays, DataArray a) {
  int i = find_array(arrays, a.name.c_str());
  if (i >= 0)
    arrays[i] = std::move(a);
  else
    arrays.push_back(std::move(a));
}

} // namespace

// The lexicographic rank of a permutation p of 0..k-1 among the k!
// permutations, and back.
int permutation_rank(const int *p, int k) {
  int rank = 0;
  for (int i = 0; i < k; ++i) {
    int smaller = 0;
    for (int j = i + 1; j < k; ++j)
      smaller += p[j] < p[i];
    int f = 1;
    for (int m = 2; m < k - i; ++m)
      f *= m;
    rank += smaller * f;
  }
  return rank;
}

bool permutation_of_rank(int rank, int k, int *p) {
  int f = 1;
  for (int m = 2; m <= k; ++m)
    f *= m;
  if (rank < 0 || rank >= f)
    return false;
  bool used[5] = {};
  for (int i = 0; i < k; ++i) {
    f /= (k - i);
    const int pick = rank / f;
    rank %= f;
    for (int v = 0, seen = 0; v < k; ++v)
      if (!used[v] && seen++ == pick) {
        p[i] = v;
        used[v] = true;
        break;
      }
  }
  return true;
}

// Per cell, 1 where orient_positively would swap the first two ids (the
// signed volume is not >= 0), found without changing the mesh: in parallel,
// with each cell's points asked for a few cells ahead (a refined mesh's
// vertices are scattered, and this pass was serial, 0.1 s of a 5.2 M
// pentatope write).
static std::vector<std::uint8_t> negative_cells(const Mesh &mesh) {
  const std::size_t nc = mesh.num_cells();
  std::vector<std::uint8_t> out(nc);
  dispatch(mesh.dim, [&]<int D>() {
    constexpr std::size_t kBlock = std::size_t(1) << 14, kAhead = 8;
    const std::size_t blocks = (nc + kBlock - 1) / kBlock;
    const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
    for (std::size_t k = 0; k < blocks; ++k) {
      double pts[(D + 1) * D];
      const std::size_t end = std::min(nc, (k + 1) * kBlock);
      for (std::size_t c = k * kBlock; c < end; ++c) {
        if (c + kAhead < end)
          geometry::prefetch_points<D>(mesh, CellId(c + kAhead));
        const VertexId *ids = mesh.cell(CellId(c));
        for (int i = 0; i <= D; ++i)
          std::copy(mesh.point(ids[i]), mesh.point(ids[i]) + D, pts + i * D);
        out[c] = std::uint8_t(!(geometry::signed_volume<D>(pts) >= 0));
      }
    }
  });
  return out;
}

// The state's two cell arrays (bisect:state, bisect:marking) as sources, for
// the cells oriented positively as `flipped` says (1: the first two ids
// swapped).
static void state_sources(const Mesh &mesh, const std::vector<std::uint8_t> &flipped,
                          std::vector<ArraySource> &cells) {
  int swapped[5] = {1, 0, 2, 3, 4};
  const int swapped_rank = permutation_rank(swapped, mesh.dim + 1);
  const Mesh *m = &mesh;
  const std::vector<std::uint8_t> *flips = &flipped;
  // 16 r + 8 stage + tag stays below 128 in 2D (r at most 2, the rank of
  // (1, 0, 2)) and 3D (6, of (1, 0, 2, 3)): Int8, half the bytes of Int16,
  // which 4D needs (24, of (1, 0, 2, 3, 4)). The type depends on the
  // dimension alone, so the pieces of a .pvtu agree. (The 14-iteration 3D
  // file: 774 MB, not 779, and no faster to write: deflate's time goes with
  // the information, not the bytes.)
  const ValueType type =
      16 * swapped_rank + 8 + mesh.dim <= 127 ? ValueType::Int8 : ValueType::Int16;
  cells.push_back({kStateArray, 1, type,
                   [=](std::size_t c) {
                     return double(
                         pack_state((*flips)[c] ? swapped_rank : 0, m->stage[c], m->tag[c]));
                   },
                   [=](std::size_t first, std::size_t n, double *out) {
                     const std::uint8_t *flip = flips->data() + first;
                     const Stage *stage = m->stage.data() + first;
                     const std::uint8_t *tag = m->tag.data() + first;
                     for (std::size_t i = 0; i < n; ++i)
                       out[i] = double(pack_state(flip[i] ? swapped_rank : 0, stage[i], tag[i]));
                   }});
  const double marking = double(int(mesh.marking));
  cells.push_back({kMarkingArray, 1, ValueType::Int8, [=](std::size_t) { return marking; },
                   [=](std::size_t, std::size_t n, double *out) { std::fill_n(out, n, marking); }});
}

void encode_state(Mesh &mesh) {
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  const std::vector<std::uint8_t> flipped = negative_cells(mesh);
  for (std::size_t c = 0; c < nc; ++c)
    if (flipped[c])
      std::swap(mesh.cell(CellId(c))[0], mesh.cell(CellId(c))[1]);
  std::vector<ArraySource> sources;
  state_sources(mesh, flipped, sources);
  if (mesh.marked()) {
    for (const ArraySource &a : sources)
      set_array(mesh.cell_data, materialize(a, nc));
    if (mesh.marking == Marking::Explicit) {
      const int ne = nv * n / 2;
      DataArray rank{kEdgeRankArray, ne, std::vector<double>(nc * ne, -1.0)};
      for (std::size_t c = 0; c < nc; ++c) {
        const VertexId *x = mesh.cell(CellId(c));
        for (int i = 0, k = 0; i < nv; ++i)
          for (int j = i + 1; j < nv; ++j, ++k) {
            auto it = mesh.edge_rank.find(edge_key(x[i], x[j]));
            if (it != mesh.edge_rank.end())
              rank.values[c * ne + k] = it->second;
          }
      }
      set_array(mesh.cell_data, std::move(rank));
    }
    encode_tree(mesh);
  }
}

bool StateArrays::hides(const std::string &name) const {
  for (const char *n : {kStateArray, kMarkingArray, kGenerationArray, kParentAArray, kParentBArray,
                        kLevelArray, kParentRankArray})
    if (name == n)
      return true;
  return false;
}

bool can_stream_state(const Mesh &mesh) {
  return mesh.marked() && mesh.marking != Marking::Explicit;
}

StateArrays stream_state(const Mesh &mesh, const std::vector<std::int8_t> *orientation) {
  StateArrays out;
  if (orientation && orientation->size() == mesh.num_cells()) {
    out.flipped.resize(mesh.num_cells());
    std::transform(orientation->begin(), orientation->end(), out.flipped.begin(),
                   [](std::int8_t s) { return std::uint8_t(s <= 0); });
  } else {
    out.flipped = negative_cells(mesh);
  }
  state_sources(mesh, out.flipped, out.cells);
  if (mesh.has_tree())
    tree_sources(mesh, out.cells, out.points);
  return out;
}

void strip_state(Mesh &mesh) {
  const int state = find_array(mesh.cell_data, kStateArray);
  if (state >= 0) {
    const DataArray &a = mesh.cell_data[std::size_t(state)];
    for (std::size_t c = 0; c < mesh.num_cells(); ++c)
      if (int(a.values[c]) >> 4 != 0)
        std::swap(mesh.cell(CellId(c))[0], mesh.cell(CellId(c))[1]);
  }
  std::erase_if(mesh.cell_data, [](const DataArray &a) {
    return a.name == kStateArray || a.name == kOrderArray || a.name == kStageArray ||
           a.name == kTagArray || a.name == kMarkingArray || a.name == kEdgeRankArray;
  });
  strip_tree(mesh);
}

bool decode_state(Mesh &mesh, const std::string &path,
                  const std::vector<std::vector<std::array<CellId, 2>>> *interior,
                  StoredState *stored) {
  StoredState none;
  if (!stored)
    stored = &none;
  // bisect:state and bisect:marking may be stored apart (StoredState); the
  // older form's arrays and the edge ranks are always DataArrays.
  const StateColumn marking = StateColumn::find(mesh.cell_data, &stored->cells, kMarkingArray),
                    packed_column = StateColumn::find(mesh.cell_data, &stored->cells, kStateArray);
  int io = find_array(mesh.cell_data, kOrderArray), is = find_array(mesh.cell_data, kStageArray),
      it = find_array(mesh.cell_data, kTagArray), im = marking ? 0 : -1,
      ip = packed_column ? 0 : -1;
  // Two forms: bisect:state + bisect:marking (written since 0.2), or the
  // older bisect:order + bisect:stage + bisect:tag + bisect:marking.
  if (ip >= 0) {
    if (im < 0)
      throw InputError(path, std::string("bisection state is incomplete: ") + kStateArray +
                                 " without " + kMarkingArray);
    for (int i : {io, is, it})
      if (i >= 0)
        throw InputError(path, std::string("bisection state given twice: ") + kStateArray +
                                   " and " + mesh.cell_data[std::size_t(i)].name);
  }
  int present = (io >= 0) + (is >= 0) + (it >= 0) + (im >= 0);
  if (present == 0 && ip < 0) {
    strip_tree(mesh); // a tree without the state it belongs to means nothing
    *stored = {};
    return false;
  }
  if (ip < 0 && present != 4)
    throw InputError(path, std::string("bisection state is incomplete: expected cell arrays ") +
                               kStateArray + " and " + kMarkingArray + " (or " + kOrderArray +
                               ", " + kStageArray + ", " + kTagArray + ", " + kMarkingArray + ")");
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  const DataArray *order = io >= 0 ? &mesh.cell_data[std::size_t(io)] : nullptr;
  const DataArray *stage = is >= 0 ? &mesh.cell_data[std::size_t(is)] : nullptr;
  const DataArray *tag = it >= 0 ? &mesh.cell_data[std::size_t(it)] : nullptr;
  const StateColumn *packed = ip >= 0 ? &packed_column : nullptr;
  if ((order && order->components != nv) || (stage && stage->components != 1) ||
      (tag && tag->components != 1) || (packed && packed->components() != 1) ||
      marking.components() != 1)
    throw InputError(path, "bisection state arrays have the wrong number of components");
  // (Files give one tuple per cell; arrays made in memory, or a
  // StoredState filled by hand, might not.)
  if ((order && order->values.size() != nc * std::size_t(nv)) ||
      (stage && stage->values.size() != nc) || (tag && tag->values.size() != nc) ||
      (packed && packed->size() != nc) || marking.size() != nc)
    throw InputError(path, "bisection state arrays do not have one tuple per cell");
  double m0 = nc ? marking[0] : 0;
  if (!(m0 == 0 || m0 == 1 || m0 == 2 || m0 == 3))
    throw InputError(path, std::string(kMarkingArray) + " must be 0, 1, 2 or 3");
  mesh.marking = Marking(int(m0));
  int ir = find_array(mesh.cell_data, kEdgeRankArray);
  mesh.edge_rank.clear();
  if (mesh.marking == Marking::Explicit) {
    const int ne = nv * n / 2;
    if (ir < 0 || mesh.cell_data[ir].components != ne)
      throw InputError(path, std::string("explicit marking needs the cell array ") +
                                 kEdgeRankArray + " with " + std::to_string(ne) + " components");
    const DataArray &rank = mesh.cell_data[ir];
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = mesh.cell(CellId(c)); // stored connectivity, as encoded
      for (int i = 0, k = 0; i < nv; ++i)
        for (int j = i + 1; j < nv; ++j, ++k) {
          double r = rank.values[c * ne + k];
          if (r == -1)
            continue;
          if (!(r >= 0 && r < 4294967295.0 && r == std::floor(r)))
            throw InputError(path, cell_name(mesh, CellId(c)) + ": " + kEdgeRankArray + " holds " +
                                       std::to_string(r) + ", not a rank");
          auto [it, fresh] = mesh.edge_rank.emplace(edge_key(x[i], x[j]), std::uint32_t(r));
          if (!fresh && it->second != std::uint32_t(r))
            throw InputError(path, cell_name(mesh, CellId(c)) + ": " + kEdgeRankArray +
                                       " gives edge " + vertex_number(mesh, x[i]) + "-" +
                                       vertex_number(mesh, x[j]) + " two different ranks");
        }
    }
  }
  mesh.stage.resize(nc);
  mesh.tag.resize(nc);
  // One cell's state: its stage, tag and vertex order.
  auto decode_cell = [&](std::size_t c) {
    auto bad = [&](const std::string &what) {
      return InputError(path,
                        cell_name(mesh, CellId(c)) + ": invalid bisection state (" + what + ")");
    };
    if (marking[c] != m0)
      throw bad("mixed " + std::string(kMarkingArray));
    double s, t;
    int perm[5];
    if (packed) {
      const double v = (*packed)[c];
      if (!(v >= 0 && v < 4096 && v == std::floor(v)))
        throw bad(std::string(kStateArray) + " out of range");
      const int w = int(v);
      s = (w >> 3) & 1;
      t = w & 7;
      if (!permutation_of_rank(w >> 4, nv, perm))
        throw bad(std::string(kStateArray) + ": no such vertex order");
    } else {
      s = stage->values[c];
      t = tag->values[c];
      unsigned seen = 0;
      for (int i = 0; i < nv; ++i) {
        const double p = order->values[c * std::size_t(nv) + std::size_t(i)];
        if (!(p >= 0 && p < nv && p == std::floor(p)) || (seen >> int(p) & 1u))
          throw bad(std::string(kOrderArray) + " is not a permutation");
        seen |= 1u << int(p);
        perm[i] = int(p);
      }
    }
    if (s == 1) {
      if (!(t >= 1 && t <= n && t == std::floor(t)))
        throw bad("Maubach tag out of range");
      mesh.stage[c] = Stage::Maubach;
    } else if (s == 0) {
      if (!(t >= 0 && t <= n - 3 && t == std::floor(t)))
        throw bad("Stage 1 tag (generation) out of range");
      mesh.stage[c] = Stage::Opposite;
    } else {
      throw bad("stage must be 0 or 1");
    }
    mesh.tag[c] = std::uint8_t(t);
    VertexId conn[5], *x = mesh.cell(CellId(c));
    std::copy(x, x + nv, conn);
    for (int i = 0; i < nv; ++i)
      x[i] = conn[perm[i]];
  };
  // Blocks of cells by all threads; the first invalid cell in cell order is
  // reported, as by one thread.
  constexpr std::size_t kBlock = std::size_t(1) << 12;
  const std::size_t blocks = (nc + kBlock - 1) / kBlock;
  std::vector<std::exception_ptr> errors(blocks);
  const int workers = int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
  for (std::size_t k = 0; k < blocks; ++k)
    try {
      for (std::size_t c = k * kBlock; c < std::min(nc, (k + 1) * kBlock); ++c)
        decode_cell(c);
    } catch (...) {
      errors[k] = std::current_exception();
    }
  for (const std::exception_ptr &e : errors)
    if (e)
      std::rethrow_exception(e);
  if (std::string why = check_state_consistency(mesh, interior); !why.empty())
    throw InputError(path, "the bisection state is inconsistent (" + why +
                               "): the file was not written by bisect as it is, or was altered "
                               "(cell order, connectivity or bisect:* arrays)");
  for (int i : {io, is, it, ir})
    if (i >= 0)
      mesh.cell_data[i].name.clear();
  std::erase_if(mesh.cell_data, [](const DataArray &a) {
    return a.name.empty() || a.name == kStateArray || a.name == kMarkingArray;
  });
  std::erase_if(stored->cells, [](const StoredArray &a) {
    return a.name == kStateArray || a.name == kMarkingArray;
  });
  decode_tree(mesh, path, stored);
  return true;
}

} // namespace bisect
