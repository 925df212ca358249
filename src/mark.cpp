// Marking (ALGORITHMS.md §2-4; seeds 002 and 000). Every mark is the
// consistent edge of some old sub-simplex in one global edge order, so
// neighbours always agree on the marks of a shared face.
#include "mark.hpp"

#include "measure.hpp"
#include "numbering.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string_view>

namespace bisect {

namespace {

double squared_length(const EdgeOrder &o, VertexId a, VertexId b) {
  if (a > b) std::swap(a, b);
  const double *p = o.coords->data() + std::size_t(a) * o.dim;
  const double *q = o.coords->data() + std::size_t(b) * o.dim;
  double s = 0;
  for (int k = 0; k < o.dim; ++k) {
    double d = q[k] - p[k];
    s += d * d;
  }
  return s;
}

} // namespace

bool EdgeOrder::before(VertexId a, VertexId b, VertexId c, VertexId d) const {
  if (a > b) std::swap(a, b);
  if (c > d) std::swap(c, d);
  if (marking == Marking::Longest) {
    double lab = squared_length(*this, a, b), lcd = squared_length(*this, c, d);
    if (lab != lcd) return lab > lcd;
  } else if (marking == Marking::Explicit) {
    auto find = [&](VertexId p, VertexId q) {
      auto it = rank->find(edge_key(p, q));
      return it == rank->end() ? std::uint64_t(1) << 32 : std::uint64_t(it->second);
    };
    std::uint64_t rab = find(a, b), rcd = find(c, d);
    if (rab != rcd) return rab < rcd;
  }
  return a != c ? a < c : b < d;
}

EdgeOrder edge_order(const Mesh &mesh) {
  return EdgeOrder{mesh.marking, &mesh.coords, mesh.dim, &mesh.edge_rank};
}

EdgePick consistent_edge(const EdgeOrder &order, const VertexId *ids, int count) {
  EdgePick best{0, 1};
  for (int i = 0; i < count; ++i)
    for (int j = i + 1; j < count; ++j)
      if ((i || j != 1) &&
          order.before(ids[i], ids[j], ids[best.first], ids[best.second]))
        best = EdgePick{i, j};
  return best;
}

void triangle_tuple(const EdgeOrder &order, const VertexId *t, VertexId *out) {
  EdgePick e = consistent_edge(order, t, 3);
  int gamma = 3 - e.first - e.second;
  VertexId a = t[e.first], g = t[gamma], b = t[e.second];
  out[0] = a, out[1] = g, out[2] = b;
}

namespace {

// For a tet with refinement edge (a, b) = ids[ea], ids[eb]: the marks of the
// faces opposite a and b, as vertex pairs.
struct TetMarks {
  VertexId a, b;          // refinement edge
  VertexId m1[2], m2[2];  // marks of the faces opposite a and opposite b
  VertexId c, d;          // the two other vertices
};

TetMarks tet_marks(const EdgeOrder &order, const VertexId *ids) {
  EdgePick e = consistent_edge(order, ids, 4);
  TetMarks m{};
  m.a = ids[e.first];
  m.b = ids[e.second];
  int rest[2], r = 0;
  for (int i = 0; i < 4; ++i)
    if (i != e.first && i != e.second) rest[r++] = i;
  m.c = ids[rest[0]];
  m.d = ids[rest[1]];
  VertexId fa[3] = {m.b, m.c, m.d}, fb[3] = {m.a, m.c, m.d};
  EdgePick p = consistent_edge(order, fa, 3), q = consistent_edge(order, fb, 3);
  m.m1[0] = fa[p.first];
  m.m1[1] = fa[p.second];
  m.m2[0] = fb[q.first];
  m.m2[1] = fb[q.second];
  return m;
}

bool contains(const VertexId *e, VertexId v) { return e[0] == v || e[1] == v; }
VertexId other(const VertexId *e, VertexId v) { return e[0] == v ? e[1] : e[0]; }

} // namespace

TetType classify_tet(const EdgeOrder &order, const VertexId *ids) {
  TetMarks m = tet_marks(order, ids);
  bool t1 = contains(m.m1, m.b), t2 = contains(m.m2, m.a); // mark touches the refinement edge
  if (t1 && t2) return other(m.m1, m.b) == other(m.m2, m.a) ? TetType::Planar : TetType::Adjacent;
  if (t1 || t2) return TetType::Mixed;
  return TetType::Opposite;
}

namespace {

char type_letter(TetType t) {
  switch (t) {
  case TetType::Planar: return 'P';
  case TetType::Adjacent: return 'A';
  case TetType::Opposite: return 'O';
  case TetType::Mixed: return 'M';
  }
  return '?';
}

int letter_rank(char c) { return int(std::string_view("PAOM").find(c)); }

} // namespace

std::string simplex_type(const EdgeOrder &order, const VertexId *ids, int dim) {
  if (dim == 3) return std::string(1, type_letter(classify_tet(order, ids)));
  if (dim != 4) return "";
  // Level 0 (a, b); level 1: the consistent edges of the tets opposite a and b.
  EdgePick e = consistent_edge(order, ids, 5);
  VertexId a = ids[e.first], b = ids[e.second];
  VertexId ta[4], tb[4];
  for (int i = 0, ka = 0, kb = 0; i < 5; ++i) {
    if (ids[i] != a) ta[ka++] = ids[i];
    if (ids[i] != b) tb[kb++] = ids[i];
  }
  EdgePick pa = consistent_edge(order, ta, 4), pb = consistent_edge(order, tb, 4);
  VertexId ma[2] = {ta[pa.first], ta[pa.second]}, mb[2] = {tb[pb.first], tb[pb.second]};
  bool t1 = contains(ma, b), t2 = contains(mb, a);
  TetType alpha = t1 && t2 ? (other(ma, b) == other(mb, a) ? TetType::Planar : TetType::Adjacent)
                  : t1 || t2 ? TetType::Mixed
                             : TetType::Opposite;
  // Level 2 relative to level 1 is the tet classification of each face.
  char beta = type_letter(classify_tet(order, ta)), gamma = type_letter(classify_tet(order, tb));
  if (letter_rank(gamma) < letter_rank(beta)) std::swap(beta, gamma);
  return std::string{type_letter(alpha), '_', beta, gamma};
}

void force_type(Mesh &mesh, const std::string &type) {
  const int n = mesh.dim, nv = n + 1;
  if (mesh.num_cells() != 1 || (n != 3 && n != 4))
    throw std::invalid_argument("forced types exist for one tetrahedron or one pentatope only");
  const VertexId *x = mesh.cell(0);
  std::vector<std::uint64_t> edges;
  for (int i = 0; i < nv; ++i)
    for (int j = i + 1; j < nv; ++j) edges.push_back(edge_key(x[i], x[j]));
  // Every ranking of the edges is a global edge order; try them in a fixed
  // pseudo-random sequence (deterministic output) and keep the first whose
  // marks have the type asked for.
  std::vector<std::uint32_t> perm(edges.size());
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = std::uint32_t(i);
  std::unordered_map<std::uint64_t, std::uint32_t> rank;
  EdgeOrder order{Marking::Explicit, &mesh.coords, n, &rank};
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
  std::vector<std::string> seen;
  for (int attempt = 0; attempt < 200000; ++attempt) {
    for (std::size_t i = perm.size() - 1; i > 0; --i) { // Fisher-Yates, splitmix64
      state += 0x9e3779b97f4a7c15ull;
      std::uint64_t z = state;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
      z ^= z >> 31;
      std::swap(perm[i], perm[z % (i + 1)]);
    }
    rank.clear();
    for (std::size_t i = 0; i < edges.size(); ++i) rank[edges[i]] = perm[i];
    std::string t = simplex_type(order, x, n);
    if (t == type) {
      mesh.edge_rank = rank;
      mark_mesh(mesh, Marking::Explicit);
      return;
    }
    if (std::find(seen.begin(), seen.end(), t) == seen.end()) seen.push_back(t);
  }
  std::sort(seen.begin(), seen.end());
  std::string list;
  for (const std::string &t : seen) list += (list.empty() ? "" : ", ") + t;
  throw std::invalid_argument("type " + type + " does not arise from any edge order of a " +
                              (n == 3 ? std::string("tetrahedron") : std::string("pentatope")) +
                              "; the types that do: " + list);
}

void mark_mesh(Mesh &mesh, Marking marking) {
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  mesh.marking = marking;
  mesh.stage.assign(nc, Stage::Maubach);
  mesh.tag.assign(nc, std::uint8_t(2));
  EdgeOrder order = edge_order(mesh);
  for (std::size_t c = 0; c < nc; ++c) {
    VertexId *x = mesh.cell(CellId(c));
    if (marking == Marking::Sorted) {
      std::sort(x, x + nv);
      mesh.tag[c] = std::uint8_t(n);
    } else if (n == 2) {
      VertexId t[3] = {x[0], x[1], x[2]};
      triangle_tuple(order, t, x);
    } else if (n == 3) {
      TetMarks m = tet_marks(order, x);
      bool planar = contains(m.m1, m.b) && contains(m.m2, m.a) &&
                    other(m.m1, m.b) == other(m.m2, m.a);
      if (planar) { // Pu: refinement (a, b), marks (b, c), (a, c) -> (a, c, b, d)_2
        VertexId c3 = other(m.m1, m.b), d3 = (c3 == m.c) ? m.d : m.c;
        x[0] = m.a, x[1] = c3, x[2] = m.b, x[3] = d3;
      } else {
        mesh.stage[c] = Stage::Opposite;
        mesh.tag[c] = 0;
      }
    } else {
      mesh.stage[c] = Stage::Opposite;
      mesh.tag[c] = 0;
    }
  }
}

namespace {

int find_array(const std::vector<DataArray> &arrays, const char *name) {
  for (std::size_t i = 0; i < arrays.size(); ++i)
    if (arrays[i].name == name) return int(i);
  return -1;
}

void set_array(std::vector<DataArray> &arrays, DataArray a) {
  int i = find_array(arrays, a.name.c_str());
  if (i >= 0) arrays[i] = std::move(a);
  else arrays.push_back(std::move(a));
}

} // namespace

void encode_state(Mesh &mesh) {
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  DataArray order{kOrderArray, nv, std::vector<double>(nc * nv)};
  DataArray stage{kStageArray, 1, std::vector<double>(nc)};
  DataArray tag{kTagArray, 1, std::vector<double>(nc)};
  DataArray marking{kMarkingArray, 1, std::vector<double>(nc, double(int(mesh.marking)))};
  double pts[5 * 4];
  for (std::size_t c = 0; c < nc; ++c) {
    cell_points(mesh, CellId(c), pts);
    VertexId *x = mesh.cell(CellId(c));
    bool flip = signed_volume(pts, n) < 0;
    for (int i = 0; i < nv; ++i) order.values[c * nv + i] = i;
    if (flip) {
      std::swap(x[0], x[1]);
      order.values[c * nv + 0] = 1;
      order.values[c * nv + 1] = 0;
    }
    stage.values[c] = mesh.stage.empty() ? 0 : double(int(mesh.stage[c]));
    tag.values[c] = mesh.tag.empty() ? 0 : double(mesh.tag[c]);
  }
  if (mesh.marked()) {
    set_array(mesh.cell_data, std::move(order));
    set_array(mesh.cell_data, std::move(stage));
    set_array(mesh.cell_data, std::move(tag));
    set_array(mesh.cell_data, std::move(marking));
    if (mesh.marking == Marking::Explicit) {
      const int ne = nv * n / 2;
      DataArray rank{kEdgeRankArray, ne, std::vector<double>(nc * ne, -1.0)};
      for (std::size_t c = 0; c < nc; ++c) {
        const VertexId *x = mesh.cell(CellId(c));
        for (int i = 0, k = 0; i < nv; ++i)
          for (int j = i + 1; j < nv; ++j, ++k) {
            auto it = mesh.edge_rank.find(edge_key(x[i], x[j]));
            if (it != mesh.edge_rank.end()) rank.values[c * ne + k] = it->second;
          }
      }
      set_array(mesh.cell_data, std::move(rank));
    }
  }
}

bool decode_state(Mesh &mesh, const std::string &path) {
  int io = find_array(mesh.cell_data, kOrderArray), is = find_array(mesh.cell_data, kStageArray),
      it = find_array(mesh.cell_data, kTagArray), im = find_array(mesh.cell_data, kMarkingArray);
  int present = (io >= 0) + (is >= 0) + (it >= 0) + (im >= 0);
  if (present == 0) return false;
  if (present != 4)
    throw InputError(path, std::string("bisection state is incomplete: expected cell arrays ") +
                               kOrderArray + ", " + kStageArray + ", " + kTagArray + ", " +
                               kMarkingArray);
  const int n = mesh.dim, nv = n + 1;
  const std::size_t nc = mesh.num_cells();
  const DataArray &order = mesh.cell_data[io], &stage = mesh.cell_data[is],
                  &tag = mesh.cell_data[it], &marking = mesh.cell_data[im];
  if (order.components != nv || stage.components != 1 || tag.components != 1 ||
      marking.components != 1)
    throw InputError(path, "bisection state arrays have the wrong number of components");
  double m0 = nc ? marking.values[0] : 0;
  if (!(m0 == 0 || m0 == 1 || m0 == 2 || m0 == 3))
    throw InputError(path, std::string(kMarkingArray) + " must be 0, 1, 2 or 3");
  mesh.marking = Marking(int(m0));
  int ir = find_array(mesh.cell_data, kEdgeRankArray);
  mesh.edge_rank.clear();
  if (mesh.marking == Marking::Explicit) {
    const int ne = nv * n / 2;
    if (ir < 0 || mesh.cell_data[ir].components != ne)
      throw InputError(path, std::string("explicit marking needs the cell array ") + kEdgeRankArray +
                                 " with " + std::to_string(ne) + " components");
    const DataArray &rank = mesh.cell_data[ir];
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = mesh.cell(CellId(c)); // stored connectivity, as encoded
      for (int i = 0, k = 0; i < nv; ++i)
        for (int j = i + 1; j < nv; ++j, ++k) {
          double r = rank.values[c * ne + k];
          if (r == -1) continue;
          if (!(r >= 0 && r < 4294967295.0 && r == std::floor(r)))
            throw InputError(path, "cell " + std::to_string(c) + ": " + kEdgeRankArray +
                                       " holds " + std::to_string(r) + ", not a rank");
          auto [it, fresh] = mesh.edge_rank.emplace(edge_key(x[i], x[j]), std::uint32_t(r));
          if (!fresh && it->second != std::uint32_t(r))
            throw InputError(path, "cell " + std::to_string(c) + ": " + kEdgeRankArray +
                                       " gives edge " + std::to_string(x[i]) + "-" +
                                       std::to_string(x[j]) + " two different ranks");
        }
    }
  }
  mesh.stage.resize(nc);
  mesh.tag.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    auto bad = [&](const std::string &what) {
      return InputError(path, "cell " + std::to_string(c) + ": invalid bisection state (" +
                                  what + ")");
    };
    if (marking.values[c] != m0) throw bad("mixed " + std::string(kMarkingArray));
    double s = stage.values[c], t = tag.values[c];
    if (s == 1) {
      if (!(t >= 1 && t <= n && t == std::floor(t))) throw bad("Maubach tag out of range");
      mesh.stage[c] = Stage::Maubach;
    } else if (s == 0) {
      if (!(t >= 0 && t <= n - 3 && t == std::floor(t))) throw bad("Stage 1 generation out of range");
      mesh.stage[c] = Stage::Opposite;
    } else {
      throw bad("stage must be 0 or 1");
    }
    mesh.tag[c] = std::uint8_t(t);
    VertexId conn[5], *x = mesh.cell(CellId(c));
    std::copy(x, x + nv, conn);
    unsigned seen = 0;
    for (int i = 0; i < nv; ++i) {
      double p = order.values[c * nv + i];
      if (!(p >= 0 && p < nv && p == std::floor(p)) || (seen >> int(p) & 1u))
        throw bad(std::string(kOrderArray) + " is not a permutation");
      seen |= 1u << int(p);
      x[i] = conn[int(p)];
    }
  }
  for (int i : {io, is, it, im, ir})
    if (i >= 0) mesh.cell_data[i].name.clear();
  std::erase_if(mesh.cell_data, [](const DataArray &a) { return a.name.empty(); });
  return true;
}

std::optional<Marking> parse_marking(const std::string &name) {
  if (name == "index") return Marking::Index;
  if (name == "longest") return Marking::Longest;
  if (name == "sorted") return Marking::Sorted;
  if (name == "explicit") return Marking::Explicit;
  return std::nullopt;
}

const char *marking_name(Marking marking) {
  switch (marking) {
  case Marking::Index: return "index";
  case Marking::Longest: return "longest";
  case Marking::Sorted: return "sorted";
  case Marking::Explicit: return "explicit";
  }
  return "?";
}

} // namespace bisect
