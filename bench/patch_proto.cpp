// Prototype (issue 13, not the library): closure without global scans.
// 3D and 4D Maubach tuples, and 3D Stage 1 tets (Stage::Opposite, as the
// longest marking gives). A facet-neighbour array (Dim+1 cell ids
// per cell, the neighbour across the facet opposite local vertex i) is kept
// current by every bisection; bisecting a cell at its refinement edge e
// bisects the whole patch of cells around e at once (recursive patch
// bisection), after first bisecting, recursively (explicit stack), every
// patch cell whose own refinement edge is not e. No midpoint table, no scans.
//
// 3D: the patch is a ring, walked both ways; the children's neighbours come
// from hand-written index formulas for a Maubach tet; a Stage 1 tet is bisected
// by the library's opposite_edge/opposite_children, its children's neighbours
// from where each vertex sits in them (bisect_stage1). Recursive patch
// bisection can meet a cycle: each cell's patch holds the next cell, whose
// refinement edge differs, and the last's holds the first. No cell of it can
// then be bisected with its whole patch; it is detected (runaway) and fails
// loudly. The ball with longest marking meets one (see the results). 4D: the cells around an edge
// are no cycle; the patch is collected by a search through the Dim-1 facets of each cell that hold
// the edge (a visited stamp per cell), and the children's neighbours by generic facet matching
// (sorted ids of every child facet that holds the midpoint, matched within the patch; the facet
// opposite the midpoint takes the parent's outside neighbour, whose back pointer is fixed).
//
// Measured against bisect::refine() on the same Kuhn cube, the same
// selection rule, one thread.
//
// Usage: patch_proto [--dim 4] ours|proto|check K iterations [radius band] [--region FILE]
//        patch_proto ours|proto|check MESH.msh iterations
//   K: the Kuhn cube [0,1]^Dim with K^Dim cubes (Dim! K^Dim cells),
//      selection: the vertex band around a sphere (Selection below), or with
//      --region FILE (a region spec, data/regions/*.json) the cells it touches;
//   MESH.msh (3D only): read and validated as bisect_bench does, its tagged
//      entities and data arrays dropped (the prototype carries none),
//      selection: the hemisphere region of bisect_bench's 3D run (select_cells).
//   --dim 4: the 4D Kuhn hypercube (pentatopes); default 3.
//   ours:  bisect::refine() alone, timed per iteration, peak RSS
//   proto: the prototype alone, timed per iteration, peak RSS
//   PROTO_THREADS=N in the environment: the library's threads (default 1;
//          the prototype itself is serial).
//   PROTO_MARKING=sorted: the sorted marking instead of index (in 4D index
//          marking gives Stage 1 cells, which the 4D prototype cannot bisect).
//   PROTO_MARKING=longest: the longest-edge marking (3D: A/M/O tets, every
//          Kuhn tet among them, start in Stage 1).
//   check: both in one process; after every iteration compares cell counts,
//          the cells (by their vertices' coordinates) and their states (stage,
//          tag, points in tuple order), and checks the prototype's conformity
//          (facets sorted), volume and neighbours.
//   PROTO_STATECHECK=1 (check mode): also check_state_consistency on
//          refine()'s mesh after every iteration.
#include "bench_util.hpp"
#include "bisect/check.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/threads.hpp"
#include "core/numbering.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

using namespace bisect;
using bisect::bench::Clock;
using bisect::bench::proc_status_kb;
using bisect::bench::secs;

namespace {

[[noreturn]] void fail(const std::string &what) {
  std::fprintf(stderr, "patch_proto: FAILED: %s\n", what.c_str());
  std::fflush(stdout);
  std::exit(2);
}

// The selection rule, the same for both meshes: a cell some vertex of which
// lies within `band` of the sphere |p - c| = R, or whose vertices straddle
// the sphere. c = (0.5, ..., 0.5).
template <int Dim> struct Selection {
  double radius = 0.3, band = 0.004;
  std::vector<CellId> operator()(const VertexId *cells, std::size_t nc,
                                 const double *coords) const {
    constexpr int N = Dim + 1;
    std::vector<CellId> out;
    for (std::size_t c = 0; c < nc; ++c) {
      double lo = 1e300, hi = -1e300, near = 1e300;
      for (int i = 0; i < N; ++i) {
        const double *p = coords + Dim * std::size_t(cells[N * c + i]);
        double s = 0;
        for (int k = 0; k < Dim; ++k)
          s += (p[k] - 0.5) * (p[k] - 0.5);
        const double d = std::sqrt(s);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
        near = std::min(near, std::fabs(d - radius));
      }
      if (near < band || (lo < radius && radius < hi))
        out.push_back(CellId(c));
    }
    return out;
  }
};

double tet_volume(const double *a, const double *b, const double *c, const double *d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return std::fabs(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                   u[2] * (v[0] * w[1] - v[1] * w[0])) /
         6.0;
}

// |det(x1 - x0, ..., x4 - x0)| / 4! by elimination with partial pivoting.
double pentatope_volume(const double *const p[5]) {
  double m[4][4];
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      m[r][k] = p[r + 1][k] - p[0][k];
  double det = 1;
  for (int col = 0; col < 4; ++col) {
    int piv = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::fabs(m[r][col]) > std::fabs(m[piv][col]))
        piv = r;
    if (m[piv][col] == 0)
      return 0;
    if (piv != col)
      for (int k = 0; k < 4; ++k)
        std::swap(m[piv][k], m[col][k]);
    det *= m[col][col];
    for (int r = col + 1; r < 4; ++r) {
      const double f = m[r][col] / m[col][col];
      for (int k = col; k < 4; ++k)
        m[r][k] -= f * m[col][k];
    }
  }
  return std::fabs(det) / 24.0;
}

template <int Dim>
double total_volume(const VertexId *cells, std::size_t nc, const double *coords) {
  double s = 0;
  if constexpr (Dim == 3) {
    for (std::size_t c = 0; c < nc; ++c)
      s += tet_volume(
          coords + 3 * std::size_t(cells[4 * c]), coords + 3 * std::size_t(cells[4 * c + 1]),
          coords + 3 * std::size_t(cells[4 * c + 2]), coords + 3 * std::size_t(cells[4 * c + 3]));
  } else {
    static_assert(Dim == 4);
    for (std::size_t c = 0; c < nc; ++c) {
      const double *p[5];
      for (int i = 0; i < 5; ++i)
        p[i] = coords + 4 * std::size_t(cells[5 * c + i]);
      s += pentatope_volume(p);
    }
  }
  return s;
}

// Mixes a coordinate's bits into hash x (the cell hashes below).
inline void mix(std::uint64_t &x, double value) {
  std::uint64_t b;
  std::memcpy(&b, &value, 8);
  x ^= b + 0x9e3779b97f4a7c15ull + (x << 6) + (x >> 2);
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 31;
}

// A cell's key independent of vertex numbering: its points, sorted, hashed.
template <int Dim>
std::vector<std::uint64_t> cell_hashes(const VertexId *cells, std::size_t nc,
                                       const double *coords) {
  constexpr int N = Dim + 1;
  std::vector<std::uint64_t> h(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    std::array<std::array<double, Dim>, N> p;
    for (int i = 0; i < N; ++i)
      for (int k = 0; k < Dim; ++k)
        p[i][k] = coords[Dim * std::size_t(cells[N * c + i]) + k];
    std::sort(p.begin(), p.end());
    std::uint64_t x = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < N; ++i)
      for (int k = 0; k < Dim; ++k)
        mix(x, p[i][k]);
    h[c] = x;
  }
  std::sort(h.begin(), h.end());
  return h;
}

// A cell's state independent of vertex numbering: its stage, tag and its
// points in tuple order, hashed (the tuple order decides all later bisections).
template <int Dim>
std::vector<std::uint64_t> state_hashes(const VertexId *cells, const Stage *stage,
                                        const std::uint8_t *tag, std::size_t nc,
                                        const double *coords) {
  constexpr int N = Dim + 1;
  std::vector<std::uint64_t> h(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    std::uint64_t x = 0x9e3779b97f4a7c15ull ^ (std::uint64_t(stage[c]) << 8 | tag[c]);
    for (int i = 0; i < N; ++i)
      for (int k = 0; k < Dim; ++k)
        mix(x, coords[Dim * std::size_t(cells[N * c + i]) + k]);
    h[c] = x;
  }
  std::sort(h.begin(), h.end());
  return h;
}

// A facet: its sorted ids (3D: v0 v1 | v2; 4D: v0 v1 | v2 v3), and who holds
// it (cell * (Dim+1) + local vertex opposite).
template <int Dim> struct Facet {
  using Low = std::conditional_t<Dim == 3, std::uint32_t, std::uint64_t>;
  std::uint64_t ab;
  Low c;
  std::uint32_t who;
  bool operator<(const Facet &o) const { return ab != o.ab ? ab < o.ab : c < o.c; }
  bool same(const Facet &o) const { return ab == o.ab && c == o.c; }
  void ids(VertexId *v) const {
    v[0] = VertexId(ab >> 32);
    v[1] = VertexId(ab);
    if constexpr (Dim == 3) {
      v[2] = c;
    } else {
      v[2] = VertexId(c >> 32);
      v[3] = VertexId(c);
    }
  }
};

template <int Dim> std::vector<Facet<Dim>> sorted_facets(const VertexId *cells, std::size_t nc) {
  constexpr int N = Dim + 1;
  std::vector<Facet<Dim>> f(N * nc);
  for (std::size_t c = 0; c < nc; ++c)
    for (int i = 0; i < N; ++i) {
      VertexId v[Dim];
      int k = 0;
      for (int j = 0; j < N; ++j)
        if (j != i)
          v[k++] = cells[N * c + j];
      std::sort(v, v + Dim);
      Facet<Dim> &g = f[N * c + i];
      g.ab = std::uint64_t(v[0]) << 32 | v[1];
      if constexpr (Dim == 3)
        g.c = v[2];
      else
        g.c = std::uint64_t(v[2]) << 32 | v[3];
      g.who = std::uint32_t(N * c + i);
    }
  std::sort(f.begin(), f.end());
  return f;
}

// f(i, j) for each run [i, j) of equal facets in sorted f (one facet, held
// by j - i cells).
template <int Dim, class F> void for_each_facet_run(const std::vector<Facet<Dim>> &f, F &&fn) {
  for (std::size_t i = 0; i < f.size();) {
    std::size_t j = i + 1;
    while (j < f.size() && f[j].same(f[i]))
      ++j;
    fn(i, j);
    i = j;
  }
}

// Thrown by a recursion cycle: the cells of the cycle, each as its points.
struct Cycle {
  std::vector<std::vector<double>> cells;
};

// The prototype: plain arrays; a cell is a Maubach tuple with a tag, or (3D)
// a Stage 1 cell (Stage::Opposite, its tag the number of new vertices).
template <int Dim> class Patch {
  static constexpr int N = Dim + 1;

public:
  std::vector<VertexId> cells; // Dim+1 per cell
  // Per cell, its state in one byte (one array: the ring's cells are scattered,
  // and each more per-cell array costs a cache miss per ring cell): a Maubach
  // tuple's tag 1..Dim (refinement edge local (0, tag)), or (3D) a Stage 1
  // cell, whose tag is 0 (no new vertices: its children enter Maubach), as
  // kStage1 | first << 3 | second, its refinement edge's local ids
  // (opposite_edge, cached: refine() recomputes it where it needs it).
  std::vector<std::uint8_t> tag;
  static constexpr std::uint8_t kStage1 = 0x80;
  EdgeOrder order; // the library's, over coords (set_order, once in place)
  std::unordered_map<std::uint64_t, std::uint32_t> rank; // Marking::Explicit's (unused)
  std::vector<CellId> nb;         // Dim+1 per cell: across the facet opposite local i, or kNoCell
  std::vector<double> coords;     // Dim per vertex
  std::vector<std::uint16_t> gen; // per cell: bisections since the start (the tree, as ours)
  std::vector<VertexId> parent_edge; // 2 per vertex (the tree, as ours)
  std::size_t bisections = 0, rings = 0, ring_cells = 0, pushes = 0, max_stack = 0;
  std::size_t collects = 0, walked = 0; // patch collections, and the cells they visited
  std::size_t depth_sum = 0;            // the stack's depth at each patch bisection, summed
  std::size_t stage1 = 0;               // Stage 1 cells bisected

  // The edge order over this object's coords (call once the object is where
  // it stays: the order holds a pointer to the vector), and the input's
  // states (the mesh's stage and tag arrays) encoded in tag.
  void set_order(Marking marking, const std::vector<Stage> &stage) {
    order = EdgeOrder{marking, &coords, Dim, &rank};
    for (std::size_t c = 0; c < num_cells(); ++c)
      tag[c] = encode(&cells[N * c], stage[c], tag[c]);
  }

  // The library's stage and tag of cell c.
  Stage stage_of(std::size_t c) const {
    return tag[c] & kStage1 ? Stage::Opposite : Stage::Maubach;
  }
  std::uint8_t tag_of(std::size_t c) const { return tag[c] & kStage1 ? 0 : tag[c]; }

  std::size_t num_cells() const { return tag.size(); }
  std::size_t num_vertices() const { return coords.size() / Dim; }

  // The neighbours of the input (sorted facet keys), once.
  void build_neighbours() {
    const std::size_t nc = num_cells();
    nb.assign(N * nc, kNoCell);
    const std::vector<Facet<Dim>> f = sorted_facets<Dim>(cells.data(), nc);
    for_each_facet_run<Dim>(f, [&](std::size_t i, std::size_t j) {
      if (j - i > 2)
        fail("input: a facet held by more than two cells");
      if (j - i == 2) {
        nb[f[i].who] = f[i + 1].who / N;
        nb[f[i + 1].who] = f[i].who / N;
      }
    });
  }

  // Each selected cell (input ids, ascending) bisected exactly once, unless
  // an earlier one's closure already bisected it; then closure (recursive).
  void refine(const std::vector<CellId> &selected) {
    nc0_ = num_cells();
    done_.assign(nc0_, 0);
    // Room for the iteration, as refine() makes it (Refiner::reserve): 3 new
    // cells per selected one, and the arrays at least double when they grow.
    // Vertices grow as refine()'s do: by the vectors' own doubling.
    const std::size_t want = nc0_ + 3 * selected.size();
    if (tag.capacity() < want) {
      const std::size_t cap = std::max(want, 2 * nc0_);
      cells.reserve(N * cap);
      nb.reserve(N * cap);
      tag.reserve(cap);
      gen.reserve(cap);
    }
    for (CellId c : selected)
      if (!done_[c])
        bisect_cell(c);
  }

private:
  std::size_t nc0_ = 0;
  std::vector<std::uint8_t> done_; // per input cell: bisected in this call
  std::vector<CellId> stack_, ring_;
  struct Old {
    VertexId x[N];
    CellId n[N];
    int t;         // the encoded tag
    VertexId keep; // the end of the edge its child 1 (in its slot) holds
  };
  std::vector<Old> old_;
  std::vector<std::uint32_t> seen_; // 4D: per cell, the collection that last reached it
  std::uint32_t stamp_ = 0;
  // 4D: a child facet holding the midpoint: its other ids sorted, and who
  // holds it (cell * N + local vertex opposite).
  struct Half {
    std::array<VertexId, Dim - 1> v;
    std::uint32_t who;
    bool operator<(const Half &o) const { return v < o.v; }
  };
  std::vector<Half> halves_;

  // A state in one byte (tag above): the refinement edge's local ids
  // (refinement_pick in refine.cpp) kept for a Stage 1 cell.
  std::uint8_t encode(const VertexId *x, Stage s, int t) const {
    if (s == Stage::Maubach)
      return std::uint8_t(t);
    if (Dim != 3 || t != 0)
      fail("a Stage 1 cell other than a 3D one with tag 0");
    const EdgePick e = opposite_edge(order, x, Dim, t);
    return std::uint8_t(kStage1 | e.first << 3 | e.second);
  }
  // The local ids of the refinement edge of a cell in state b.
  static int first_end(std::uint8_t b) { return b & kStage1 ? (b >> 3) & 7 : 0; }
  static int second_end(std::uint8_t b) { return b & kStage1 ? b & 7 : b; }

  // Outside cell `out`, which named `from` as a neighbour, names `to` instead.
  void repoint(CellId out, CellId from, CellId to) {
    CellId *back = &nb[N * std::size_t(out)];
    int q = 0;
    while (q < N && back[q] != from)
      ++q;
    if (q == N)
      fail("outside neighbour does not point back");
    back[q] = to;
  }

  bool has_edge(CellId c, VertexId a, VertexId b) const {
    const VertexId *x = &cells[N * std::size_t(c)];
    const std::uint8_t t = tag[c];
    const VertexId p = x[first_end(t)], q = x[second_end(t)];
    return (p == a && q == b) || (p == b && q == a);
  }

  // The two local vertices of cell c that are not a or b (3D).
  void others(CellId c, VertexId a, VertexId b, int &k1, int &k2) const {
    const VertexId *x = &cells[4 * std::size_t(c)];
    k1 = k2 = -1;
    for (int i = 0; i < 4; ++i)
      if (x[i] != a && x[i] != b)
        (k1 < 0 ? k1 : k2) = i;
  }

  // 3D: ring_ = the cells around edge {a, b}, from c: walk one way through
  // the facets holding the edge until back at c or at the boundary, then the
  // other.
  void collect_ring(CellId c, VertexId a, VertexId b) {
    ring_.clear();
    ring_.push_back(c);
    ++collects;
    int k1, k2;
    others(c, a, b, k1, k2);
    // From c through its facet opposite local vertex k, around the edge,
    // appending each cell met; returns where the walk ended: back at c (a
    // closed ring) or kNoCell (the boundary).
    auto walk = [&](int k) {
      CellId prev = c, cur = nb[4 * std::size_t(c) + k];
      while (cur != kNoCell && cur != c) {
        ring_.push_back(cur);
        int j1, j2;
        others(cur, a, b, j1, j2);
        const CellId n1 = nb[4 * std::size_t(cur) + j1], n2 = nb[4 * std::size_t(cur) + j2];
        const CellId next = n1 == prev ? n2 : n1;
        prev = cur;
        cur = next;
        if (ring_.size() > 200)
          fail("ring around an edge longer than 200 cells");
      }
      return cur;
    };
    if (walk(k1) == kNoCell && walk(k2) == c) // the boundary: the other way from c
      fail("open ring closed on itself");
  }

  // 4D (any Dim): ring_ = the cells around edge {a, b}, from c: a breadth-
  // first search through the Dim-1 facets of each cell that hold the edge
  // (those opposite a vertex other than a and b); ring_ is its queue.
  void collect_patch(CellId c, VertexId a, VertexId b) {
    ++collects;
    if (seen_.size() < num_cells())
      seen_.resize(std::max(num_cells(), tag.capacity()), 0);
    if (++stamp_ == 0) { // wrapped: forget every stamp
      std::fill(seen_.begin(), seen_.end(), 0);
      stamp_ = 1;
    }
    ring_.clear();
    ring_.push_back(c);
    seen_[c] = stamp_;
    for (std::size_t q = 0; q < ring_.size(); ++q) {
      const CellId r = ring_[q];
      const VertexId *x = &cells[N * std::size_t(r)];
      const CellId *n = &nb[N * std::size_t(r)];
      for (int i = 0; i < N; ++i) {
        if (x[i] == a || x[i] == b)
          continue;
        const CellId o = n[i];
        if (o != kNoCell && seen_[o] != stamp_) {
          seen_[o] = stamp_;
          ring_.push_back(o);
        }
      }
      if (ring_.size() > 2000)
        fail("patch around an edge larger than 2000 cells");
    }
  }

  // Prints the stack from `from` (where the cycle starts) up: each cell's
  // state and refinement edge; throws Cycle (or fails past depth 10000).
  [[noreturn]] void runaway(std::size_t from) {
    std::fprintf(stderr, "runaway stack, depth %zu; from stack[%zu] up:\n", stack_.size(), from);
    for (std::size_t k = from; k < stack_.size(); ++k) {
      const CellId q = stack_[k];
      const VertexId *y = &cells[N * std::size_t(q)];
      std::fprintf(stderr, "  stack[%zu] = cell %u: %s tag %d gen %d, ids", k, unsigned(q),
                   tag[q] & kStage1 ? "Stage 1" : "Maubach", int(tag_of(q)), int(gen[q]));
      for (int i = 0; i < N; ++i)
        std::fprintf(stderr, " %u", unsigned(y[i]));
      // Whether the cell was in the mesh when this call began, or is a child
      // made by this call (the input cells' slots: done_ once bisected).
      const bool input = q < nc0_ && !done_[q];
      std::fprintf(stderr, ", refinement edge (%u, %u), %s\n", unsigned(y[first_end(tag[q])]),
                   unsigned(y[second_end(tag[q])]), input ? "in the input" : "made in this call");
    }
    if (stack_.size() > 10000)
      fail("recursion deeper than 10000");
    std::fprintf(stderr, "recursion cycle: a cell's patch needs a cell below it on the stack "
                         "bisected first\n");
    Cycle cyc;
    for (std::size_t k = from + 1; k < stack_.size(); ++k) {
      const VertexId *y = &cells[N * std::size_t(stack_[k])];
      std::vector<double> pts;
      for (int i = 0; i < N; ++i)
        pts.insert(pts.end(), &coords[Dim * std::size_t(y[i])],
                   &coords[Dim * std::size_t(y[i])] + Dim);
      cyc.cells.push_back(pts);
    }
    throw cyc;
  }

  void bisect_cell(CellId c0) {
    stack_.clear();
    stack_.push_back(c0);
    while (!stack_.empty()) {
      const CellId c = stack_.back();
      const VertexId *x = &cells[N * std::size_t(c)];
      const VertexId a = x[first_end(tag[c])], b = x[second_end(tag[c])];
      if constexpr (Dim == 3)
        collect_ring(c, a, b);
      else
        collect_patch(c, a, b);
      CellId first_other = kNoCell;
      for (CellId r : ring_)
        if (!has_edge(r, a, b)) {
          first_other = r;
          break;
        }
      if (first_other != kNoCell) {
        walked += ring_.size();
        stack_.push_back(first_other);
        ++pushes;
        max_stack = std::max(max_stack, stack_.size());
        // A cycle: first_other already waits lower on the stack, so no cell
        // of the cycle can ever be bisected with its whole patch. Looked for
        // only past depth 64 (the deepest terminating stacks seen: 35 cells,
        // index marking K=30; 43, the ball refined uniformly). The cells on
        // the stack are all whole, each in the ring of the one below it, so
        // a repeat is a cycle of the current mesh.
        if (stack_.size() > 64) {
          std::size_t at = stack_.size() - 1; // its last place below the top
          while (at > 0 && stack_[at - 1] != first_other)
            --at;
          if (at > 0 || stack_.size() > 10000)
            runaway(at > 0 ? at - 1 : stack_.size() - 12);
        }
        continue;
      }
      walked += ring_.size();
      depth_sum += stack_.size();
      if constexpr (Dim == 3)
        bisect_ring(a, b);
      else
        bisect_patch(a, b);
      stack_.pop_back();
    }
  }

  // The new vertex z = midpoint(a, b), and room for ring_.size() new cells;
  // returns z, sets base (the first new cell) and old_ (the ring's cells).
  VertexId open_ring(VertexId a, VertexId b, CellId &base) {
    const std::size_t m = ring_.size();
    const VertexId z = VertexId(num_vertices());
    {
      const double *p = &coords[Dim * std::size_t(a)], *q = &coords[Dim * std::size_t(b)];
      double mid[Dim];
      for (int k = 0; k < Dim; ++k)
        mid[k] = 0.5 * (p[k] + q[k]);
      coords.insert(coords.end(), mid, mid + Dim);
      parent_edge.push_back(a);
      parent_edge.push_back(b);
    }
    base = CellId(num_cells());
    cells.resize(cells.size() + N * m);
    nb.resize(nb.size() + N * m);
    tag.resize(tag.size() + m);
    gen.resize(gen.size() + m);
    old_.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
      const CellId r = ring_[i];
      std::memcpy(old_[i].x, &cells[N * std::size_t(r)], sizeof old_[i].x);
      std::memcpy(old_[i].n, &nb[N * std::size_t(r)], sizeof old_[i].n);
      old_[i].t = tag[r];
      // Maubach: child 1 is x with x[t] -> z, holding x0; Stage 1: child 1
      // drops the edge's first end (opposite_children).
      old_[i].keep = old_[i].x[tag[r] & kStage1 ? tag[r] & 7 : 0];
    }
    return z;
  }

  // 3D: ring cell i, a Stage 1 cell, bisected at z (midpoint of its
  // refinement edge) by the library's opposite_children; the children's
  // neighbours from where each vertex sits in them: in a child lacking end
  // `lacks` and holding `keep`, the facet opposite z is the parent's facet
  // opposite `lacks` (outside the ring; its back pointer fixed for child 2),
  // the facet opposite `keep` is shared with the sibling, and the facet
  // opposite any other vertex v halves the parent's facet opposite v, whose
  // neighbour is in the ring: its child holding `keep` (child_with).
  template <class ChildWith>
  [[gnu::noinline]] void bisect_stage1(std::size_t i, VertexId z, CellId base,
                                       ChildWith &child_with) {
    const CellId s = ring_[i], s2 = CellId(base + i);
    const Old &o = old_[i];
    const EdgePick e{first_end(std::uint8_t(o.t)), second_end(std::uint8_t(o.t))};
    VertexId *c1 = &cells[4 * std::size_t(s)], *c2 = &cells[4 * std::size_t(s2)];
    Stage cs;
    int ct;
    opposite_children(order, o.x, 3, 0, e, z, c1, c2, cs, ct);
    tag[s] = encode(c1, cs, ct);
    tag[s2] = encode(c2, cs, ct);
    ++stage1;
    for (int which = 0; which < 2; ++which) {
      const CellId ch = which == 0 ? s : s2, sib = which == 0 ? s2 : s;
      const VertexId *y = which == 0 ? c1 : c2;
      const VertexId keep = o.x[which == 0 ? e.second : e.first];
      const int lacks = which == 0 ? e.first : e.second; // local in o.x
      CellId *n = &nb[4 * std::size_t(ch)];
      for (int k = 0; k < 4; ++k) {
        const VertexId v = y[k];
        if (v == z) {
          const CellId out = o.n[lacks];
          n[k] = out;
          if (out != kNoCell && ch != s)
            repoint(out, s, ch);
        } else if (v == keep) {
          n[k] = sib;
        } else {
          int p = 0;
          while (p < 4 && o.x[p] != v)
            ++p;
          if (p == 4)
            fail("a Stage 1 child's vertex not in its parent");
          n[k] = o.n[p] == kNoCell ? kNoCell : child_with(o.n[p], keep);
        }
      }
    }
    if (s < nc0_)
      done_[s] = 1;
  }

  // 3D: bisects every cell of ring_ (all refined at edge {a, b}) at one midpoint.
  void bisect_ring(VertexId a, VertexId b) {
    const std::size_t m = ring_.size();
    CellId base;
    const VertexId z = open_ring(a, b, base);
    // The child of ring cell j that holds end v: child 1 (its slot) holds its keep.
    auto child_with = [&](CellId n, VertexId v) -> CellId {
      for (std::size_t j = 0; j < m; ++j)
        if (ring_[j] == n)
          return old_[j].keep == v ? n : CellId(base + j);
      fail("a neighbour across a facet holding the edge is not in its ring");
    };
    for (std::size_t i = 0; i < m; ++i) {
      const CellId s = ring_[i], s2 = CellId(base + i);
      const Old &o = old_[i];
      const int d = o.t;
      VertexId *c1 = &cells[4 * std::size_t(s)], *c2 = &cells[4 * std::size_t(s2)];
      gen[s2] = ++gen[s];
      if (d & kStage1) {
        bisect_stage1(i, z, base, child_with);
        continue;
      }
      maubach_children<3>(o.x, d, z, c1, c2);
      const std::uint8_t t = std::uint8_t(maubach_child_tag(d, 3));
      tag[s] = tag[s2] = t;
      CellId *n1 = &nb[4 * std::size_t(s)], *n2 = &nb[4 * std::size_t(s2)];
      // Child 1 = x with x[d] -> z: facet opposite z is the parent's facet
      // opposite x[d] (same outside neighbour, whose back pointer names slot
      // s already); facet opposite x0 is shared with child 2.
      n1[d] = o.n[d];
      n1[0] = s2;
      // Child 2 = (x1..xd, z, x(d+1)..): x[k] at k-1 for 1 <= k <= d, z at d.
      n2[d] = o.n[0];
      if (o.n[0] != kNoCell)
        repoint(o.n[0], s, s2);
      n2[d - 1] = s;
      for (int k = 1; k < 4; ++k) {
        if (k == d)
          continue;
        const CellId n = o.n[k];
        const int k2 = k < d ? k - 1 : k;
        if (n == kNoCell) {
          n1[k] = n2[k2] = kNoCell;
        } else {
          n1[k] = child_with(n, o.x[0]);
          n2[k2] = child_with(n, o.x[d]);
        }
      }
      if (s < nc0_)
        done_[s] = 1;
    }
    bisections += m;
    ++rings;
    ring_cells += m;
  }

  // 4D (any Dim): bisects every cell of ring_ (all refined at edge {a, b})
  // at one midpoint z; the children's neighbours by facet matching. A
  // child's facet opposite z is the parent's facet opposite the end the child
  // lacks: the parent's outside neighbour there (its back pointer fixed if the
  // child is not in the parent's slot). Every other facet holds z: keyed by
  // its other ids, sorted, matched within the patch; one left unmatched is on
  // the boundary (checked: the parent's facet it halves has no neighbour).
  void bisect_patch(VertexId a, VertexId b) {
    const std::size_t m = ring_.size();
    CellId base;
    const VertexId z = open_ring(a, b, base);
    halves_.clear();
    for (std::size_t i = 0; i < m; ++i) {
      const CellId s = ring_[i], s2 = CellId(base + i);
      const Old &o = old_[i];
      const int d = o.t;
      maubach_children<Dim>(o.x, d, z, &cells[N * std::size_t(s)], &cells[N * std::size_t(s2)]);
      const std::uint8_t t = std::uint8_t(maubach_child_tag(d, Dim));
      tag[s] = tag[s2] = t;
      gen[s2] = ++gen[s];
      for (const CellId ch : {s, s2}) {
        const VertexId *y = &cells[N * std::size_t(ch)];
        CellId *n = &nb[N * std::size_t(ch)];
        for (int k = 0; k < N; ++k) {
          if (y[k] == z) {
            // The end the child lacks, and the parent's facet opposite it.
            bool has_a = false;
            for (int j = 0; j < N; ++j)
              has_a |= y[j] == a;
            const VertexId lacks = has_a ? b : a;
            int j = 0;
            while (o.x[j] != lacks)
              ++j;
            const CellId out = o.n[j];
            n[k] = out;
            if (out != kNoCell && ch != s)
              repoint(out, s, ch);
            continue;
          }
          Half h;
          int w = 0;
          for (int j = 0; j < N; ++j)
            if (j != k && y[j] != z)
              h.v[w++] = y[j];
          std::sort(h.v.begin(), h.v.end());
          h.who = std::uint32_t(N * std::size_t(ch) + k);
          halves_.push_back(h);
        }
      }
      if (s < nc0_)
        done_[s] = 1;
    }
    std::sort(halves_.begin(), halves_.end());
    for (std::size_t i = 0; i < halves_.size();) {
      if (i + 1 < halves_.size() && halves_[i + 1].v == halves_[i].v) {
        if (i + 2 < halves_.size() && halves_[i + 2].v == halves_[i].v)
          fail("a facet held by three children");
        nb[halves_[i].who] = halves_[i + 1].who / N;
        nb[halves_[i + 1].who] = halves_[i].who / N;
        i += 2;
        continue;
      }
      // Unmatched: the parent's facet opposite the same vertex must be on
      // the boundary. The child's cell came from ring_ slot or base + j.
      const std::uint32_t who = halves_[i].who;
      const CellId ch = who / N;
      const VertexId v = cells[who];
      const std::size_t j =
          ch >= base ? std::size_t(ch - base)
                     : std::size_t(std::find(ring_.begin(), ring_.end(), ch) - ring_.begin());
      const Old &o = old_[j];
      int p = 0;
      while (p < N && o.x[p] != v)
        ++p;
      if (p == N || o.n[p] != kNoCell)
        fail("a child facet holding the midpoint is unmatched inside the mesh");
      nb[who] = kNoCell;
      ++i;
    }
    bisections += m;
    ++rings;
    ring_cells += m;
  }
};

// Checks of the prototype's mesh after an iteration (fails loudly).
template <int Dim> void check_patch(const Patch<Dim> &p, double volume0, bool cube) {
  constexpr int N = Dim + 1;
  const std::size_t nc = p.num_cells();
  std::vector<Facet<Dim>> f = sorted_facets<Dim>(p.cells.data(), nc);
  std::size_t boundary = 0, interior = 0;
  for_each_facet_run<Dim>(f, [&](std::size_t i, std::size_t j) {
    if (j - i > 2)
      fail("not conforming: a facet held by more than two cells");
    if (j - i == 1) {
      ++boundary;
      if (p.nb[f[i].who] != kNoCell)
        fail("neighbour across a boundary facet");
    } else {
      ++interior;
      if (p.nb[f[i].who] != f[i + 1].who / N || p.nb[f[i + 1].who] != f[i].who / N)
        fail("neighbour array wrong: cells " + std::to_string(f[i].who / N) + " and " +
             std::to_string(f[i + 1].who / N) + " share a facet");
    }
  });
  // Every facet accounted for: with the two passes above, nb is symmetric
  // and each entry names the cell that really shares that facet.
  if (boundary + 2 * interior != N * nc)
    fail("facet count");
  const double v = total_volume<Dim>(p.cells.data(), nc, p.coords.data());
  if (std::fabs(v - volume0) > 1e-9 * volume0)
    fail("volume changed: " + std::to_string(v));
  // Conformity also means no vertex in the interior of a facet or an edge; a
  // facet held once must lie on the cube's boundary (else: a hanging facet).
  if (!cube)
    return;
  for_each_facet_run<Dim>(f, [&](std::size_t i, std::size_t j) {
    if (j - i != 1)
      return;
    VertexId ids[Dim];
    f[i].ids(ids);
    bool on_face = false;
    for (int k = 0; k < Dim && !on_face; ++k) {
      const double c0 = p.coords[Dim * std::size_t(ids[0]) + k];
      on_face = c0 == 0.0 || c0 == 1.0;
      for (int q = 1; q < Dim && on_face; ++q)
        on_face = p.coords[Dim * std::size_t(ids[q]) + k] == c0;
    }
    if (!on_face)
      fail("a facet held by one cell inside the cube (hanging)");
  });
}

template <int Dim> Mesh make_input(const std::string &input) {
  Mesh m;
  if (input.find_first_not_of("0123456789") == std::string::npos) {
    m = generate_kuhn(Dim, std::atoi(input.c_str()));
  } else {
    if (Dim != 3)
      fail("a mesh file only in 3D");
    m = read_mesh(input);
    prepare_input(m, input);
    m.entities.clear();
    m.cell_data.clear();
    m.point_data.clear();
    m.physical_names.clear();
    if (m.dim != 3)
      fail("not a 3D mesh");
  }
  // Index marking (the brief's). PROTO_MARKING=sorted: the sorted rule
  // ((x0 < ... < xn)_n, ALGORITHMS.md §4), Maubach from the start in 4D too,
  // where index marking puts every pentatope in Stage 1.
  // PROTO_MARKING=longest: longest-edge order; in 3D its A/M/O tets (every
  // Kuhn tet) start in Stage 1, which the 3D prototype bisects with the
  // library's opposite_edge/opposite_children.
  const char *mk = std::getenv("PROTO_MARKING");
  const std::string mks = mk ? mk : "index";
  Marking marking;
  if (mks == "index")
    marking = Marking::Index;
  else if (mks == "sorted")
    marking = Marking::Sorted;
  else if (mks == "longest")
    marking = Marking::Longest;
  else
    fail("PROTO_MARKING must be index, sorted or longest");
  mark_mesh(m, marking);
  std::size_t stage1 = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    if (Dim == 3 && m.stage[c] == Stage::Opposite && m.tag[c] <= 1)
      ++stage1;
    else if (m.stage[c] != Stage::Maubach || m.tag[c] < 1 || m.tag[c] > Dim)
      fail("input cell " + std::to_string(c) + " is not a Maubach tuple (stage " +
           std::to_string(int(m.stage[c])) + ", tag " + std::to_string(int(m.tag[c])) + ")");
  std::printf("marking %s: %zu of %zu input cells in Stage 1\n", mks.c_str(), stage1,
              m.num_cells());
  return m;
}

// Call set_order on the result once it is where it stays.
template <int Dim> Patch<Dim> make_patch(const Mesh &m) {
  Patch<Dim> p;
  p.cells = m.cells;
  p.tag = m.tag;
  p.coords = m.coords;
  p.rank = m.edge_rank;
  p.gen.assign(m.num_cells(), 0);
  p.parent_edge.assign(2 * m.num_vertices(), kNoVertex);
  return p;
}

template <int Dim>
int run(const std::string &mode, const std::string &input, int iterations,
        const Selection<Dim> &select, const std::string &region_file, int threads) {
  constexpr int N = Dim + 1;
  const char *word = Dim == 3 ? "tets" : "pentatopes";
  const bool cube = input.find_first_not_of("0123456789") == std::string::npos;
  const bool ours = mode == "ours" || mode == "check", proto = mode == "proto" || mode == "check";
  if (!ours && !proto)
    fail("mode must be ours, proto or check");

  Mesh mesh = make_input<Dim>(input);
  // The file's selection: bisect_bench's 3D region (one per implementation),
  // or the region file's.
  const char *hemisphere = R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,)"
                           R"("normal":[1,0,0],"offset":0.5})";
  std::unique_ptr<Region> region_ours, region_proto;
  if (!region_file.empty()) {
    region_ours = read_region(region_file, Dim);
    region_proto = read_region(region_file, Dim);
  } else if (!cube) {
    region_ours = parse_region(hemisphere, 3, "bench");
    region_proto = parse_region(hemisphere, 3, "bench");
  }
  // The selections, outside the timed refinement. The prototype's arrays are
  // lent to a Mesh for select_cells (swapped, not copied: no memory).
  auto select_ours = [&]() {
    return !region_ours ? select(mesh.cells.data(), mesh.num_cells(), mesh.coords.data())
                        : select_cells(mesh, *region_ours);
  };
  const std::size_t nc_in = mesh.num_cells();
  const double volume0 = total_volume<Dim>(mesh.cells.data(), nc_in, mesh.coords.data());
  Patch<Dim> patch;
  double t_build = 0;
  if (proto) {
    patch = make_patch<Dim>(mesh);
    patch.set_order(mesh.marking, mesh.stage);
    const auto t0 = Clock::now();
    patch.build_neighbours();
    t_build = secs(t0, Clock::now());
    if (!ours)
      mesh = Mesh{};
  }
  auto select_proto = [&]() {
    if (!region_proto)
      return select(patch.cells.data(), patch.num_cells(), patch.coords.data());
    Mesh view;
    view.dim = Dim;
    view.cells.swap(patch.cells);
    view.coords.swap(patch.coords);
    std::vector<CellId> sel = select_cells(view, *region_proto);
    view.cells.swap(patch.cells);
    view.coords.swap(patch.coords);
    return sel;
  };
  const long rss0 = proc_status_kb("VmRSS:");
  if (!region_file.empty())
    std::printf(
        "mode %s, %dD Kuhn k=%s: %zu %s, region %s, %d iterations, %d thread(s) for refine()\n",
        mode.c_str(), Dim, input.c_str(), nc_in, word, region_file.c_str(), iterations, threads);
  else if (cube)
    std::printf("mode %s, %sKuhn k=%s: %zu %s, sphere r=%g band=%g, %d iterations, %d thread(s) "
                "for refine()\n",
                mode.c_str(), Dim == 3 ? "" : "4D ", input.c_str(), nc_in, word, select.radius,
                select.band, iterations, threads);
  else
    std::printf("mode %s, %s: %zu tets, bisect_bench's hemisphere, %d iterations, %d thread(s) for "
                "refine()\n",
                mode.c_str(), input.c_str(), nc_in, iterations, threads);
  if (proto)
    std::printf("neighbour array built in %.4f s (%.1f M %s/s)\n", t_build, 1e-6 * nc_in / t_build,
                word);
  std::printf("%4s %10s %10s %9s %9s %10s %9s\n", "it", "selected", "cells", "bisect", "secs",
              "Mgen/s", "check");
  double t_ours = 0, t_proto = 0;
  std::size_t b_ours = 0, b_proto = 0;
  for (int it = 1; it <= iterations; ++it) {
    std::size_t cells_ours = 0, cells_proto = 0;
    if (ours) {
      const auto sel = select_ours();
      const auto t0 = Clock::now();
      const RefineResult r = refine(mesh, sel);
      const double t = secs(t0, Clock::now());
      if (r.limit_reached || r.cancelled)
        fail("refine hit a limit");
      t_ours += t;
      b_ours += r.bisections;
      cells_ours = mesh.num_cells();
      if (std::getenv("PROTO_STATECHECK")) { // diagnosis: the library's consistency check
        const std::string why = check_state_consistency(mesh);
        std::printf("     refine()'s states after iteration %d: %s\n", it,
                    why.empty() ? "consistent (check_state_consistency)" : why.c_str());
      }
      std::printf("%4d %10zu %10zu %9zu %9.4f %10.2f %9s  ours (%zu closure passes)\n", it,
                  sel.size(), cells_ours, r.bisections, t, 2e-6 * r.bisections / t, "",
                  r.closure_passes);
    }
    if (proto) {
      const auto sel = select_proto();
      const std::size_t b0 = patch.bisections, rings0 = patch.rings, push0 = patch.pushes,
                        depth0 = patch.depth_sum, s10 = patch.stage1;
      const auto t0 = Clock::now();
      try {
        patch.refine(sel);
      } catch (const Cycle &cyc) {
        // Which of the cycle's cells refine() bisected in this iteration
        // (check mode): a cell of the cycle can be bisected only through a
        // non-conforming intermediate mesh.
        if (ours) {
          std::size_t gone = 0;
          for (const std::vector<double> &pts : cyc.cells) {
            bool present = false;
            for (std::size_t c = 0; c < mesh.num_cells() && !present; ++c) {
              present = true;
              for (int i = 0; i < N && present; ++i) {
                const double *p = mesh.point(mesh.cell(CellId(c))[i]);
                bool found = false;
                for (int j = 0; j < N && !found; ++j)
                  found = std::equal(p, p + Dim, pts.begin() + Dim * j);
                present = found;
              }
            }
            gone += !present;
          }
          std::printf("iteration %d: refine() bisected %zu of the cycle's %zu cells\n", it, gone,
                      cyc.cells.size());
        }
        fail("iteration " + std::to_string(it) + ": recursion cycle (runaway stack)");
      }
      const double t = secs(t0, Clock::now());
      t_proto += t;
      const std::size_t b = patch.bisections - b0;
      b_proto += b;
      cells_proto = patch.num_cells();
      const char *verdict = "";
      if (ours) {
        if (cells_proto != cells_ours)
          fail("iteration " + std::to_string(it) + ": cell counts differ, ours " +
               std::to_string(cells_ours) + ", prototype " + std::to_string(cells_proto));
        check_patch<Dim>(patch, volume0, cube);
        if (cell_hashes<Dim>(mesh.cells.data(), mesh.num_cells(), mesh.coords.data()) !=
            cell_hashes<Dim>(patch.cells.data(), patch.num_cells(), patch.coords.data()))
          fail("iteration " + std::to_string(it) + ": the two meshes' cells differ");
        std::vector<Stage> st(patch.num_cells());
        std::vector<std::uint8_t> tg(patch.num_cells());
        for (std::size_t c = 0; c < st.size(); ++c) {
          st[c] = patch.stage_of(c);
          tg[c] = patch.tag_of(c);
        }
        if (state_hashes<Dim>(mesh.cells.data(), mesh.stage.data(), mesh.tag.data(),
                              mesh.num_cells(), mesh.coords.data()) !=
            state_hashes<Dim>(patch.cells.data(), st.data(), tg.data(), patch.num_cells(),
                              patch.coords.data()))
          fail("iteration " + std::to_string(it) +
               ": the two meshes' cell states (stage, tag, tuple order) differ");
        verdict = "ok";
      }
      const double nr = double(patch.rings - rings0);
      std::printf("%4d %10zu %10zu %9zu %9.4f %10.2f %9s  proto (%zu rings, mean %.2f cells, "
                  "%zu pushes, max stack %zu, mean depth %.2f, %zu Stage 1)\n",
                  it, sel.size(), cells_proto, b, t, 2e-6 * b / t, verdict, patch.rings - rings0,
                  double(b) / nr, patch.pushes - push0, patch.max_stack,
                  double(patch.depth_sum - depth0) / nr, patch.stage1 - s10);
    }
    std::fflush(stdout);
  }
  const long hwm = proc_status_kb("VmHWM:"); // before the rebuild below
  const double cells = double(ours ? mesh.num_cells() : patch.num_cells());
  if (ours)
    std::printf("TOTAL ours:  %.4f s, %zu bisections, %.2f M generated %s/s\n", t_ours, b_ours,
                2e-6 * b_ours / t_ours, word);
  if (proto) {
    std::printf("TOTAL proto: %.4f s, %zu bisections, %.2f M generated %s/s (+ %.4f s "
                "neighbour build once)\n",
                t_proto, b_proto, 2e-6 * b_proto / t_proto, word, t_build);
    std::printf("proto: %zu ring walks visiting %zu cells for %zu rings of %zu cells (%zu pushes); "
                "mean ring %.2f cells, mean stack depth %.2f, max %zu\n",
                patch.collects, patch.walked, patch.rings, patch.ring_cells, patch.pushes,
                double(patch.ring_cells) / double(patch.rings),
                double(patch.depth_sum) / double(patch.rings), patch.max_stack);
    // What building the array from scratch would cost on the result (a
    // refine() that did not keep it between calls), and a last check: the
    // array kept current equals the one built.
    const std::vector<CellId> kept = patch.nb;
    const auto t0 = Clock::now();
    patch.build_neighbours();
    const double t_rebuild = secs(t0, Clock::now());
    if (patch.nb != kept)
      fail("the neighbour array kept current differs from one built from the result");
    std::printf("neighbour array of the result built from scratch: %.4f s (%.1f M %s/s); equal "
                "to the one kept current\n",
                t_rebuild, 1e-6 * patch.num_cells() / t_rebuild, word);
    const std::size_t nc = patch.num_cells(), nv = patch.num_vertices();
    const double per_cell = 4.0 * N + 1 + 4.0 * N + 2, per_vertex = 8.0 * Dim + 8;
    std::printf("proto arrays (size): cells %zu B, tag %zu, nb %zu, gen %zu, coords %zu, "
                "parent_edge %zu = %.1f B/cell; capacity %.1f B/cell\n",
                4 * N * nc, nc, 4 * N * nc, 2 * nc, 8 * Dim * nv, 8 * nv,
                (per_cell * nc + per_vertex * nv) / nc,
                (4.0 * patch.cells.capacity() + patch.tag.capacity() + 4.0 * patch.nb.capacity() +
                 2.0 * patch.gen.capacity() + 8.0 * patch.coords.capacity() +
                 4.0 * patch.parent_edge.capacity()) /
                    nc);
  }
  std::printf("peak RSS (before that rebuild) %.1f MiB = %.1f B/cell; above the pre-refinement RSS "
              "%.1f B/cell\n",
              hwm / 1024.0, hwm * 1024.0 / cells, (hwm - rss0) * 1024.0 / cells);
  return 0;
}

} // namespace

int main(int argc, char **argv) {
  std::vector<std::string> args;
  int dim = 3;
  std::string region_file;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--dim" && i + 1 < argc)
      dim = std::atoi(argv[++i]);
    else if (a == "--region" && i + 1 < argc)
      region_file = argv[++i];
    else
      args.push_back(a);
  }
  if (args.size() < 3 || (dim != 3 && dim != 4)) {
    std::fprintf(stderr, "usage: patch_proto [--dim 4] ours|proto|check K|MESH.msh iterations "
                         "[radius band] [--region FILE]\n");
    return 1;
  }
  const std::string mode = args[0];
  const std::string input = args[1];
  const int iterations = std::atoi(args[2].c_str());
  const int threads = std::getenv("PROTO_THREADS") ? std::atoi(std::getenv("PROTO_THREADS")) : 1;
  set_threads(threads);
  if (dim == 3) {
    Selection<3> select;
    if (args.size() > 3)
      select.radius = std::atof(args[3].c_str());
    if (args.size() > 4)
      select.band = std::atof(args[4].c_str());
    return run<3>(mode, input, iterations, select, region_file, threads);
  }
  Selection<4> select;
  if (args.size() > 3)
    select.radius = std::atof(args[3].c_str());
  if (args.size() > 4)
    select.band = std::atof(args[4].c_str());
  return run<4>(mode, input, iterations, select, region_file, threads);
}
