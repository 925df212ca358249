// Marking (ALGORITHMS.md §2-4; seeds 002 and 000). Every mark is the
// consistent edge of some old sub-simplex in one global edge order, so
// neighbours always agree on the marks of a shared face.
#include "bisect/mark.hpp"

#include "bisect/check.hpp"
#include "bisect/measure.hpp"
#include "bisect/threads.hpp"
#include "core/dimension.hpp"
#include "core/geometry.hpp"
#include "core/names.hpp"
#include "core/numbering.hpp"
#include "engine/mark_testing.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string_view>

namespace bisect {

namespace {

double squared_length(const EdgeOrder &o, VertexId a, VertexId b) {
  if (a > b)
    std::swap(a, b);
  return geometry::squared_distance(o.coords->data() + std::size_t(a) * o.dim,
                                    o.coords->data() + std::size_t(b) * o.dim, o.dim);
}

} // namespace

bool EdgeOrder::before(VertexId a, VertexId b, VertexId c, VertexId d) const {
  if (a > b)
    std::swap(a, b);
  if (c > d)
    std::swap(c, d);
  if (marking == Marking::Longest) {
    double lab = squared_length(*this, a, b), lcd = squared_length(*this, c, d);
    if (lab != lcd)
      return lab > lcd;
  } else if (marking == Marking::Explicit) {
    auto find = [&](VertexId p, VertexId q) {
      auto it = rank->find(edge_key(p, q));
      return it == rank->end() ? std::uint64_t(1) << 32 : std::uint64_t(it->second);
    };
    std::uint64_t rab = find(a, b), rcd = find(c, d);
    if (rab != rcd)
      return rab < rcd;
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
      if ((i || j != 1) && order.before(ids[i], ids[j], ids[best.first], ids[best.second]))
        best = EdgePick{i, j};
  return best;
}

void triangle_tuple(const EdgeOrder &order, const VertexId *t, VertexId *out) {
  EdgePick e = consistent_edge(order, t, 3);
  int gamma = 3 - e.first - e.second;
  VertexId a = t[e.first], g = t[gamma], b = t[e.second];
  out[0] = a, out[1] = g, out[2] = b;
}

EdgePick opposite_edge(const EdgeOrder &order, const VertexId *x, int n, int t) {
  EdgePick e = consistent_edge(order, x + t, n + 1 - t);
  return EdgePick{t + e.first, t + e.second};
}

void opposite_children(const EdgeOrder &order, const VertexId *x, int n, int t, EdgePick edge,
                       VertexId z, VertexId *c1, VertexId *c2, Stage &child_stage, int &child_tag) {
  const int nv = n + 1;
  child_stage = Stage::Opposite;
  child_tag = t + 1;
  for (int which = 0; which < 2; ++which) {
    VertexId *out = which == 0 ? c1 : c2;
    const int drop = which == 0 ? edge.first : edge.second;
    VertexId old[5];
    int n_old = 0;
    for (int i = t; i < nv; ++i)
      if (i != drop)
        old[n_old++] = x[i];
    if (n_old == 3) { // the old part is a triangle: enter Maubach
      triangle_tuple(order, old, out);
      out[3] = z;
      for (int i = 0; i < t && 4 + i < nv; ++i)
        out[4 + i] = x[i];
      child_stage = Stage::Maubach;
      child_tag = 2;
    } else {
      out[0] = z;
      for (int i = 0; i < t && 1 + i < nv; ++i)
        out[1 + i] = x[i];
      std::copy(old, old + n_old, out + 1 + t);
    }
  }
}

namespace {

// For a tet with refinement edge (a, b) = ids[ea], ids[eb]: the marks of the
// faces opposite a and b, as vertex pairs.
struct TetMarks {
  VertexId a, b;         // refinement edge
  VertexId m1[2], m2[2]; // marks of the faces opposite a and opposite b
  VertexId c, d;         // the two other vertices
};

TetMarks tet_marks(const EdgeOrder &order, const VertexId *ids) {
  EdgePick e = consistent_edge(order, ids, 4);
  TetMarks m{};
  m.a = ids[e.first];
  m.b = ids[e.second];
  int rest[2], r = 0;
  for (int i = 0; i < 4; ++i)
    if (i != e.first && i != e.second)
      rest[r++] = i;
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

bool contains(const VertexId *e, VertexId v) {
  return e[0] == v || e[1] == v;
}
VertexId other(const VertexId *e, VertexId v) {
  return e[0] == v ? e[1] : e[0];
}

} // namespace

TetType classify_tet(const EdgeOrder &order, const VertexId *ids) {
  TetMarks m = tet_marks(order, ids);
  bool t1 = contains(m.m1, m.b), t2 = contains(m.m2, m.a); // mark touches the refinement edge
  if (t1 && t2)
    return other(m.m1, m.b) == other(m.m2, m.a) ? TetType::Planar : TetType::Adjacent;
  if (t1 || t2)
    return TetType::Mixed;
  return TetType::Opposite;
}

namespace {

char type_letter(TetType t) {
  switch (t) {
  case TetType::Planar:
    return 'P';
  case TetType::Adjacent:
    return 'A';
  case TetType::Opposite:
    return 'O';
  case TetType::Mixed:
    return 'M';
  }
  return '?';
}

int letter_rank(char c) {
  return int(std::string_view("PAOM").find(c));
}

} // namespace

std::string simplex_type(const EdgeOrder &order, const VertexId *ids, int dim) {
  if (dim == 3)
    return std::string(1, type_letter(classify_tet(order, ids)));
  if (dim != 4)
    return "";
  // Level 0 (a, b); level 1: the consistent edges of the tets opposite a and b.
  EdgePick e = consistent_edge(order, ids, 5);
  VertexId a = ids[e.first], b = ids[e.second];
  VertexId ta[4], tb[4];
  for (int i = 0, ka = 0, kb = 0; i < 5; ++i) {
    if (ids[i] != a)
      ta[ka++] = ids[i];
    if (ids[i] != b)
      tb[kb++] = ids[i];
  }
  EdgePick pa = consistent_edge(order, ta, 4), pb = consistent_edge(order, tb, 4);
  VertexId ma[2] = {ta[pa.first], ta[pa.second]}, mb[2] = {tb[pb.first], tb[pb.second]};
  bool t1 = contains(ma, b), t2 = contains(mb, a);
  TetType alpha = t1 && t2   ? (other(ma, b) == other(mb, a) ? TetType::Planar : TetType::Adjacent)
                  : t1 || t2 ? TetType::Mixed
                             : TetType::Opposite;
  // Level 2 relative to level 1 is the tet classification of each face.
  char beta = type_letter(classify_tet(order, ta)), gamma = type_letter(classify_tet(order, tb));
  if (letter_rank(gamma) < letter_rank(beta))
    std::swap(beta, gamma);
  return std::string{type_letter(alpha), '_', beta, gamma};
}

void force_type(Mesh &mesh, const std::string &type) {
  const int n = mesh.dim, nv = n + 1;
  if (mesh.num_cells() != 1 || (n != 3 && n != 4))
    throw UsageError("forced types exist for one tetrahedron or one pentatope only");
  const VertexId *x = mesh.cell(0);
  std::vector<std::uint64_t> edges;
  for (int i = 0; i < nv; ++i)
    for (int j = i + 1; j < nv; ++j)
      edges.push_back(edge_key(x[i], x[j]));
  // Every ranking of the edges is a global edge order; try them in a fixed
  // pseudo-random sequence (deterministic output) and keep the first whose
  // marks have the type asked for.
  std::vector<std::uint32_t> perm(edges.size());
  for (std::size_t i = 0; i < perm.size(); ++i)
    perm[i] = std::uint32_t(i);
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
    for (std::size_t i = 0; i < edges.size(); ++i)
      rank[edges[i]] = perm[i];
    std::string t = simplex_type(order, x, n);
    if (t == type) {
      mesh.edge_rank = rank;
      mark_mesh(mesh, Marking::Explicit);
      return;
    }
    if (std::find(seen.begin(), seen.end(), t) == seen.end())
      seen.push_back(t);
  }
  std::sort(seen.begin(), seen.end());
  std::string list;
  for (const std::string &t : seen)
    list += (list.empty() ? "" : ", ") + t;
  throw UsageError("type " + type + " does not arise from any edge order of a " +
                   (n == 3 ? std::string("tetrahedron") : std::string("pentatope")) +
                   "; the types that do: " + list);
}

bool ensure_marked(Mesh &mesh, Marking marking) {
  if (mesh.marked())
    return false;
  mark_mesh(mesh, marking);
  return true;
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
      bool planar =
          contains(m.m1, m.b) && contains(m.m2, m.a) && other(m.m1, m.b) == other(m.m2, m.a);
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

// The refinement one cell would make of one of its facets, found by bisecting
// the cell symbolically (tuples only; new vertices get labels above every
// mesh id, one label per split edge, shared by the two sides of the facet so
// that the same edge gets the same label). The facet's piece tree is walked
// depth first, state_check_levels(Dim) levels deep; each piece records the edge it
// is split by, and its two halves follow in a fixed order (the half keeping
// the smaller-labelled end first). A cell bisection whose edge is not in the
// piece moves the piece into the child that holds it, unsplit.
template <int Dim> class FacetWalk {
  static constexpr int N = Dim + 1;

public:
  FacetWalk(const EdgeOrder &order, VertexId first_label) : order_(order), first_(first_label) {}

  // Side one: records the piece tree of facet `opposite` (local index of the
  // vertex not in it) of the cell x. Side two: compares with what was recorded.
  void record(const VertexId *x, Stage s, int t, int opposite) {
    mids_.clear();
    seq_.clear();
    comparing_ = false;
    differs_ = false; // a walk that found a difference may be used again
    start(x, s, t, opposite);
  }
  bool same(const VertexId *x, Stage s, int t, int opposite) {
    comparing_ = true;
    pos_ = 0;
    differs_ = false;
    start(x, s, t, opposite);
    return !differs_ && pos_ == seq_.size();
  }

private:
  void start(const VertexId *x, Stage s, int t, int opposite) {
    VertexId piece[Dim];
    for (int i = 0, k = 0; i < N; ++i)
      if (i != opposite)
        piece[k++] = x[i];
    walk(x, s, t, piece, 0);
  }

  VertexId label(VertexId a, VertexId b) {
    const std::uint64_t key = edge_key(a, b);
    for (const auto &[k, v] : mids_)
      if (k == key)
        return v;
    const VertexId z = first_ + VertexId(mids_.size());
    mids_.emplace_back(key, z);
    return z;
  }

  void note(std::uint64_t key) {
    if (!comparing_) {
      seq_.push_back(key);
    } else if (pos_ >= seq_.size() || seq_[pos_++] != key) {
      differs_ = true;
    }
  }

  static bool holds(const VertexId *ids, int count, VertexId v) {
    return std::find(ids, ids + count, v) != ids + count;
  }

  void walk(const VertexId *x0, Stage s, int t, const VertexId *piece, int level) {
    VertexId x[N], c1[N], c2[N];
    std::copy(x0, x0 + N, x);
    // A bisection that misses the piece replaces the vertex opposite it, so
    // a few steps always reach one that splits it; the bound is a guard.
    for (int step = 0; step < 4 * N && !differs_; ++step) {
      VertexId a, b, z;
      Stage s1 = Stage::Maubach;
      int t1 = 0;
      if (s == Stage::Maubach) {
        a = x[0];
        b = x[t];
        z = label(a, b);
        maubach_children<Dim>(x, t, z, c1, c2);
        t1 = maubach_child_tag(t, Dim);
      } else if constexpr (Dim >= 3) {
        const EdgePick e = opposite_edge(order_, x, Dim, t);
        a = x[e.first];
        b = x[e.second];
        z = label(a, b);
        opposite_children(order_, x, Dim, t, e, z, c1, c2, s1, t1);
      } else {
        break; // no Stage 1 in 2D (decode_state rejects it)
      }
      const bool has_a = holds(piece, Dim, a), has_b = holds(piece, Dim, b);
      // The child holding a (and not b), and the one holding b.
      const VertexId *with_a = holds(c1, N, a) ? c1 : c2, *with_b = with_a == c1 ? c2 : c1;
      if (has_a && has_b) {
        note(edge_key(a, b));
        if (level + 1 == state_check_levels(Dim) || differs_)
          return;
        VertexId keep_a[Dim], keep_b[Dim];
        for (int i = 0; i < Dim; ++i) {
          keep_a[i] = piece[i] == b ? z : piece[i];
          keep_b[i] = piece[i] == a ? z : piece[i];
        }
        if (a < b) {
          walk(with_a, s1, t1, keep_a, level + 1);
          walk(with_b, s1, t1, keep_b, level + 1);
        } else {
          walk(with_b, s1, t1, keep_b, level + 1);
          walk(with_a, s1, t1, keep_a, level + 1);
        }
        return;
      }
      std::copy(has_a ? with_a : with_b, (has_a ? with_a : with_b) + N, x);
      s = s1;
      t = t1;
    }
    note(~std::uint64_t(0)); // no split within the guard: cannot match a valid side
  }

  const EdgeOrder &order_;
  VertexId first_;
  std::vector<std::pair<std::uint64_t, VertexId>> mids_;
  std::vector<std::uint64_t> seq_;
  std::size_t pos_ = 0;
  bool comparing_ = false, differs_ = false;
};

// The walks of a pair of Maubach cells depend on little: each side's tag,
// the position of the vertex opposite the facet and the order of the
// facet's ids in its tuple. A walk compares ids of the facet with each other
// (which half comes first) and tests ids for equality, and its labels lie
// above every id. So the pair's result is the result for the same pair
// renamed: the facet's ids by their rank among themselves (0 to Dim - 1),
// the two opposite vertices Dim and Dim + 1 (distinct, as in a valid mesh;
// equal ones take the walk). The table keeps each renamed pair's result,
// found by one walk the first time it is met.
std::atomic<bool> g_pair_table{true}; // testing::set_state_pair_table

template <int Dim> class MaubachPairs {
  static constexpr int N = Dim + 1;
  static constexpr int kOrders = Dim == 2 ? 2 : Dim == 3 ? 6 : 24; // Dim!
  static constexpr int kSides = N * N * kOrders;                   // tag (0..Dim), opposite, order

public:
  // calloc: a large table is mapped zeroed, and only the pages of the pairs
  // met are touched (4D: 352 KiB).
  MaubachPairs() : known_(static_cast<std::uint8_t *>(std::calloc(kSides * kSides, 1))) {
    if (!known_)
      throw std::bad_alloc();
  }

  // Whether the table applies: tags in range and two opposite vertices.
  static bool applies(const VertexId *x, int s, int i, const VertexId *y, int t, int j) {
    return s >= 0 && s <= Dim && t >= 0 && t <= Dim && x[i] != y[j];
  }
  // Whether Maubach cells x (tag s, facet opposite i) and y (tag t, facet
  // opposite j) bisect their shared facet alike; `walk` is the calling
  // thread's, made with first label Dim + 2. Safe from several threads: two
  // that meet a new pair at once both walk it and store the same result.
  bool same(const VertexId *x, int s, int i, const VertexId *y, int t, int j,
            FacetWalk<Dim> &walk) const {
    VertexId rx[N], ry[N];
    const int a = side(x, s, i, x, i, Dim, rx), b = side(y, t, j, x, i, Dim + 1, ry);
    std::atomic_ref<std::uint8_t> known(known_.get()[std::size_t(a) * kSides + std::size_t(b)]);
    std::uint8_t k = known.load(std::memory_order_relaxed);
    if (k == 0) {
      walk.record(rx, Stage::Maubach, s, i);
      k = walk.same(ry, Stage::Maubach, t, j) ? 1 : 2;
      known.store(k, std::memory_order_relaxed);
    }
    return k == 1;
  }

private:
  // The side's index in the table, and its renamed tuple in r: each id of
  // the facet (the ids of f but f[fi]) by its rank, `opposite` at i.
  static int side(const VertexId *x, int tag, int i, const VertexId *f, int fi, VertexId opposite,
                  VertexId *r) {
    int rank[Dim], m = 0;
    for (int k = 0; k < N; ++k) {
      if (k == i) {
        r[k] = opposite;
        continue;
      }
      int below = 0;
      for (int q = 0; q < N; ++q)
        below += q != fi && f[q] < x[k];
      r[k] = VertexId(below);
      rank[m++] = below;
    }
    int order = 0; // the ranks' Lehmer code
    for (int k = 0; k < Dim; ++k) {
      int smaller = 0;
      for (int q = k + 1; q < Dim; ++q)
        smaller += rank[q] < rank[k];
      order = order * (Dim - k) + smaller;
    }
    return (tag * N + i) * kOrders + order;
  }

  struct Free {
    void operator()(std::uint8_t *p) const { std::free(p); }
  };
  std::unique_ptr<std::uint8_t, Free> known_; // per pair 0: not met yet, 1: same, 2: different
};

} // namespace

std::string check_state_consistency(const Mesh &mesh, const InteriorFacets *interior) {
  if (mesh.dim < 3 || !mesh.marked() || mesh.num_cells() < 2)
    return {};
  const EdgeOrder order = edge_order(mesh);
  const VertexId first_label = VertexId(mesh.num_vertices());
  if (std::size_t(first_label) + 4096 >= std::size_t(kNoVertex))
    return {}; // no room for labels
  std::string failure;
  dispatch(mesh.dim, [&]<int D>() {
    // Stevenson's reflected neighbours: two Maubach cells with one tag whose
    // tuples (or one tuple and the other's reflection) differ only in the
    // vertex opposite the facet have the same descendants on it.
    auto reflected = [&](CellId a, int i, CellId b, int j) {
      if (mesh.stage[a] != Stage::Maubach || mesh.stage[b] != Stage::Maubach ||
          mesh.tag[a] != mesh.tag[b])
        return false;
      const int d = mesh.tag[a];
      const VertexId *x = mesh.cell(a), *y = mesh.cell(b);
      for (int flip = 0; flip < 2; ++flip) {
        const int ja = flip && i <= d ? d - i : i; // position of a's opposite vertex
        if (ja != j)
          continue;
        bool same = true;
        for (int k = 0; k <= D && same; ++k) {
          const int from = flip && k <= d ? d - k : k;
          same = k == j || x[from] == y[k];
        }
        if (same)
          return true;
      }
      return false;
    };
    // Stops at the first facet the two cells would bisect differently, with
    // its message in `found`.
    const MaubachPairs<D> pairs;
    const bool table = g_pair_table.load();
    auto visitor = [&](FacetWalk<D> &walk, FacetWalk<D> &renamed, std::string &found) {
      return [&](CellId a, int i, CellId b, int j) {
        if (reflected(a, i, b, j))
          return true;
        const VertexId *x = mesh.cell(a), *y = mesh.cell(b);
        if (table && mesh.stage[a] == Stage::Maubach && mesh.stage[b] == Stage::Maubach &&
            MaubachPairs<D>::applies(x, mesh.tag[a], i, y, mesh.tag[b], j)) {
          if (pairs.same(x, mesh.tag[a], i, y, mesh.tag[b], j, renamed))
            return true;
        } else {
          walk.record(x, mesh.stage[a], mesh.tag[a], i);
          if (walk.same(y, mesh.stage[b], mesh.tag[b], j))
            return true;
        }
        VertexId facet[4];
        for (int k = 0, m = 0; k <= D; ++k)
          if (k != i)
            facet[m++] = mesh.cell(a)[k];
        std::sort(facet, facet + D);
        found = cell_pair_name(mesh, a, b) + " would bisect their shared facet " +
                face_ids(mesh, facet, D) + " differently";
        return false;
      };
    };
    if (!interior) {
      FacetWalk<D> walk(order, first_label), renamed(order, VertexId(D + 2));
      for_each_interior_facet(mesh, visitor(walk, renamed, failure));
      return;
    }
    // The recorded pieces by all threads; the first finding in piece order,
    // which is the serial walk's.
    std::vector<std::string> found(interior->size());
    const int workers = int(std::clamp<std::size_t>(interior->size(), 1, std::size_t(threads())));
#pragma omp parallel num_threads(workers)
    {
      FacetWalk<D> walk(order, first_label), renamed(order, VertexId(D + 2));
#pragma omp for schedule(dynamic, 1)
      for (std::size_t p = 0; p < interior->size(); ++p)
        for_each_interior_facet(mesh, (*interior)[p], visitor(walk, renamed, found[p]));
    }
    for (std::string &s : found)
      if (!s.empty()) {
        failure = std::move(s);
        return;
      }
  });
  return failure;
}

std::optional<Marking> parse_marking(const std::string &name) {
  if (name == "index")
    return Marking::Index;
  if (name == "longest")
    return Marking::Longest;
  if (name == "sorted")
    return Marking::Sorted;
  if (name == "explicit")
    return Marking::Explicit;
  return std::nullopt;
}

const char *marking_name(Marking marking) {
  switch (marking) {
  case Marking::Index:
    return "index";
  case Marking::Longest:
    return "longest";
  case Marking::Sorted:
    return "sorted";
  case Marking::Explicit:
    return "explicit";
  }
  return "?";
}

} // namespace bisect

namespace bisect::testing {
void set_state_pair_table(bool on) {
  g_pair_table = on;
}

std::vector<bool> state_pair_verdicts(int dim, const std::vector<VertexId> &cells,
                                      const std::vector<std::uint8_t> &tags, bool table) {
  const int n = dim + 1;
  const std::size_t count = tags.size() / 2;
  std::vector<bool> alike(count);
  if (cells.empty())
    return alike;
  Mesh m; // only for the edge order, which Maubach walks never ask
  m.dim = dim;
  m.marking = Marking::Sorted;
  const EdgeOrder order = edge_order(m);
  const VertexId first = *std::max_element(cells.begin(), cells.end()) + 1;
  dispatch(dim, [&]<int D>() {
    const MaubachPairs<D> pairs;
    FacetWalk<D> walk(order, first), renamed(order, VertexId(D + 2));
    for (std::size_t k = 0; k < count; ++k) {
      const VertexId *x = cells.data() + 2 * k * n, *y = x + n;
      auto opposite = [&](const VertexId *u, const VertexId *v) {
        for (int q = 0; q < n; ++q)
          if (std::find(v, v + n, u[q]) == v + n)
            return q;
        throw std::invalid_argument("state_pair_verdicts: the two cells share no facet");
      };
      const int i = opposite(x, y), j = opposite(y, x), s = tags[2 * k], t = tags[2 * k + 1];
      if (table) {
        alike[k] = pairs.same(x, s, i, y, t, j, renamed);
      } else {
        walk.record(x, Stage::Maubach, s, i);
        alike[k] = walk.same(y, Stage::Maubach, t, j);
      }
    }
  });
  return alike;
}
} // namespace bisect::testing
