// Prototype (issue 13, not the library): closure without global scans.
// 3D, Maubach tuples only. A facet-neighbour array (4 cell ids per tet, the
// neighbour across the facet opposite local vertex i) is kept current by
// every bisection; bisecting a cell at its refinement edge e bisects the
// whole ring of cells around e at once (recursive patch bisection), after
// first bisecting, recursively (explicit stack), every ring cell whose own
// refinement edge is not e. No midpoint table, no scans.
//
// Measured against bisect::refine() on the same Kuhn cube, the same
// selection rule, one thread.
//
// Usage: patch_proto ours|proto|check K iterations [radius band]
//        patch_proto ours|proto|check MESH.msh iterations
//   K: the Kuhn cube [0,1]^3 with K^3 cubes (6 K^3 tets), selection: the
//      vertex band around a sphere (Selection below);
//   MESH.msh: read and validated as bisect_bench does, its tagged entities
//      and data arrays dropped (the prototype carries none), selection: the
//      hemisphere region of bisect_bench's 3D run (select_cells).
//   ours:  bisect::refine() alone, timed per iteration, peak RSS
//   proto: the prototype alone, timed per iteration, peak RSS
//   PROTO_THREADS=N in the environment: the library's threads (default 1;
//          the prototype itself is serial).
//   check: both in one process; after every iteration compares cell counts
//          and the cells (by their vertices' coordinates), and checks the
//          prototype's conformity (facets sorted), volume and neighbours.
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
#include <stdexcept>
#include <memory>
#include <string>
#include <vector>

using namespace bisect;
using Clock = std::chrono::steady_clock;

namespace {

long proc_status_kb(const char *field) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(field, 0) == 0)
      return std::atol(line.c_str() + std::string(field).size());
  return -1;
}

double secs(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

[[noreturn]] void fail(const std::string &what) {
  std::fprintf(stderr, "patch_proto: FAILED: %s\n", what.c_str());
  std::fflush(stdout);
  std::exit(2);
}

// The selection rule, the same for both meshes: a cell some vertex of which
// lies within `band` of the sphere |p - c| = R, or whose vertices straddle
// the sphere. c = (0.5, 0.5, 0.5).
struct Selection {
  double radius = 0.3, band = 0.004;
  std::vector<CellId> operator()(const VertexId *cells, std::size_t nc,
                                 const double *coords) const {
    std::vector<CellId> out;
    for (std::size_t c = 0; c < nc; ++c) {
      double lo = 1e300, hi = -1e300, near = 1e300;
      for (int i = 0; i < 4; ++i) {
        const double *p = coords + 3 * std::size_t(cells[4 * c + i]);
        const double dx = p[0] - 0.5, dy = p[1] - 0.5, dz = p[2] - 0.5;
        const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
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

double total_volume(const VertexId *cells, std::size_t nc, const double *coords) {
  double s = 0;
  for (std::size_t c = 0; c < nc; ++c)
    s += tet_volume(coords + 3 * std::size_t(cells[4 * c]), coords + 3 * std::size_t(cells[4 * c + 1]),
                    coords + 3 * std::size_t(cells[4 * c + 2]),
                    coords + 3 * std::size_t(cells[4 * c + 3]));
  return s;
}

// A cell's key independent of vertex numbering: its four points, sorted, hashed.
std::vector<std::uint64_t> cell_hashes(const VertexId *cells, std::size_t nc, const double *coords) {
  std::vector<std::uint64_t> h(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    std::array<std::array<double, 3>, 4> p;
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k)
        p[i][k] = coords[3 * std::size_t(cells[4 * c + i]) + k];
    std::sort(p.begin(), p.end());
    std::uint64_t x = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) {
        std::uint64_t b;
        std::memcpy(&b, &p[i][k], 8);
        x ^= b + 0x9e3779b97f4a7c15ull + (x << 6) + (x >> 2);
        x *= 0xbf58476d1ce4e5b9ull;
        x ^= x >> 31;
      }
    h[c] = x;
  }
  std::sort(h.begin(), h.end());
  return h;
}

// A facet: its sorted ids, and who holds it (cell * 4 + local vertex opposite).
struct Facet {
  std::uint64_t ab;
  std::uint32_t c;
  std::uint32_t who;
  bool operator<(const Facet &o) const { return ab != o.ab ? ab < o.ab : c < o.c; }
  bool same(const Facet &o) const { return ab == o.ab && c == o.c; }
};

std::vector<Facet> sorted_facets(const VertexId *cells, std::size_t nc) {
  std::vector<Facet> f(4 * nc);
  for (std::size_t c = 0; c < nc; ++c)
    for (int i = 0; i < 4; ++i) {
      VertexId v[3];
      int k = 0;
      for (int j = 0; j < 4; ++j)
        if (j != i)
          v[k++] = cells[4 * c + j];
      std::sort(v, v + 3);
      f[4 * c + i] = Facet{std::uint64_t(v[0]) << 32 | v[1], v[2], std::uint32_t(4 * c + i)};
    }
  std::sort(f.begin(), f.end());
  return f;
}

// The prototype: plain arrays, 3D, every cell a Maubach tuple with a tag.
class Patch {
public:
  std::vector<VertexId> cells;       // 4 per tet
  std::vector<std::uint8_t> tag;     // per tet, 1..3
  std::vector<CellId> nb;            // 4 per tet: across the facet opposite local i, or kNoCell
  std::vector<double> coords;        // 3 per vertex
  std::vector<std::uint16_t> gen;    // per tet: bisections since the start (the tree, as ours)
  std::vector<VertexId> parent_edge; // 2 per vertex (the tree, as ours)
  std::size_t bisections = 0, rings = 0, ring_cells = 0, pushes = 0, max_stack = 0;
  std::size_t collects = 0, walked = 0; // ring walks, and the cells they visited

  std::size_t num_cells() const { return tag.size(); }
  std::size_t num_vertices() const { return coords.size() / 3; }

  // The neighbours of the input (sorted facet keys), once.
  void build_neighbours() {
    const std::size_t nc = num_cells();
    nb.assign(4 * nc, kNoCell);
    std::vector<Facet> f = sorted_facets(cells.data(), nc);
    for (std::size_t i = 0; i < f.size();) {
      std::size_t j = i + 1;
      while (j < f.size() && f[j].same(f[i]))
        ++j;
      if (j - i > 2)
        fail("input: a facet held by more than two cells");
      if (j - i == 2) {
        nb[f[i].who] = f[i + 1].who / 4;
        nb[f[i + 1].who] = f[i].who / 4;
      }
      i = j;
    }
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
      cells.reserve(4 * cap);
      nb.reserve(4 * cap);
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
    VertexId x[4];
    CellId n[4];
    int t;
  };
  std::vector<Old> old_;

  bool has_edge(CellId c, VertexId a, VertexId b) const {
    const VertexId *x = &cells[4 * std::size_t(c)];
    const VertexId p = x[0], q = x[tag[c]];
    return (p == a && q == b) || (p == b && q == a);
  }

  // The two local vertices of cell c that are not a or b.
  void others(CellId c, VertexId a, VertexId b, int &k1, int &k2) const {
    const VertexId *x = &cells[4 * std::size_t(c)];
    k1 = k2 = -1;
    for (int i = 0; i < 4; ++i)
      if (x[i] != a && x[i] != b)
        (k1 < 0 ? k1 : k2) = i;
  }

  // ring_ = the cells around edge {a, b}, from c: walk one way through the
  // facets holding the edge until back at c or at the boundary, then the other.
  void collect_ring(CellId c, VertexId a, VertexId b) {
    ring_.clear();
    ring_.push_back(c);
    ++collects;
    int k1, k2;
    others(c, a, b, k1, k2);
    CellId prev = c, cur = nb[4 * std::size_t(c) + k1];
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
    if (cur == kNoCell) { // the boundary: the other way from c
      prev = c;
      cur = nb[4 * std::size_t(c) + k2];
      while (cur != kNoCell) {
        ring_.push_back(cur);
        int j1, j2;
        others(cur, a, b, j1, j2);
        const CellId n1 = nb[4 * std::size_t(cur) + j1], n2 = nb[4 * std::size_t(cur) + j2];
        const CellId next = n1 == prev ? n2 : n1;
        prev = cur;
        cur = next;
        if (cur == c || ring_.size() > 200)
          fail("open ring closed on itself");
      }
    }
  }

  void bisect_cell(CellId c0) {
    stack_.clear();
    stack_.push_back(c0);
    while (!stack_.empty()) {
      const CellId c = stack_.back();
      const VertexId *x = &cells[4 * std::size_t(c)];
      const VertexId a = x[0], b = x[tag[c]];
      collect_ring(c, a, b);
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
        if (stack_.size() > 10000)
          fail("recursion deeper than 10000: a cycle (inconsistent tags?)");
        continue;
      }
      walked += ring_.size();
      bisect_ring(a, b);
      stack_.pop_back();
    }
  }

  // Bisects every cell of ring_ (all refined at edge {a, b}) at one midpoint.
  void bisect_ring(VertexId a, VertexId b) {
    const std::size_t m = ring_.size();
    const VertexId z = VertexId(num_vertices());
    {
      const double *p = &coords[3 * std::size_t(a)], *q = &coords[3 * std::size_t(b)];
      double mid[3];
      for (int k = 0; k < 3; ++k)
        mid[k] = 0.5 * (p[k] + q[k]);
      coords.insert(coords.end(), mid, mid + 3);
      parent_edge.push_back(a);
      parent_edge.push_back(b);
    }
    const CellId base = CellId(num_cells());
    cells.resize(cells.size() + 4 * m);
    nb.resize(nb.size() + 4 * m);
    tag.resize(tag.size() + m);
    gen.resize(gen.size() + m);
    old_.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
      const CellId r = ring_[i];
      std::memcpy(old_[i].x, &cells[4 * std::size_t(r)], sizeof old_[i].x);
      std::memcpy(old_[i].n, &nb[4 * std::size_t(r)], sizeof old_[i].n);
      old_[i].t = tag[r];
    }
    // The child of ring cell j that holds end v: child 1 (its slot) holds its x0.
    auto child_with = [&](CellId n, VertexId v) -> CellId {
      for (std::size_t j = 0; j < m; ++j)
        if (ring_[j] == n)
          return old_[j].x[0] == v ? n : CellId(base + j);
      fail("a neighbour across a facet holding the edge is not in its ring");
    };
    for (std::size_t i = 0; i < m; ++i) {
      const CellId s = ring_[i], s2 = CellId(base + i);
      const Old &o = old_[i];
      const int d = o.t;
      VertexId *c1 = &cells[4 * std::size_t(s)], *c2 = &cells[4 * std::size_t(s2)];
      maubach_children<3>(o.x, d, z, c1, c2);
      const std::uint8_t t = std::uint8_t(maubach_child_tag(d, 3));
      tag[s] = tag[s2] = t;
      gen[s2] = ++gen[s];
      CellId *n1 = &nb[4 * std::size_t(s)], *n2 = &nb[4 * std::size_t(s2)];
      // Child 1 = x with x[d] -> z: facet opposite z is the parent's facet
      // opposite x[d] (same outside neighbour, whose back pointer names slot
      // s already); facet opposite x0 is shared with child 2.
      n1[d] = o.n[d];
      n1[0] = s2;
      // Child 2 = (x1..xd, z, x(d+1)..): x[k] at k-1 for 1 <= k <= d, z at d.
      n2[d] = o.n[0];
      if (o.n[0] != kNoCell) {
        CellId *back = &nb[4 * std::size_t(o.n[0])];
        int k = 0;
        while (k < 4 && back[k] != s)
          ++k;
        if (k == 4)
          fail("outside neighbour does not point back");
        back[k] = s2;
      }
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
};

// Checks of the prototype's mesh after an iteration (fails loudly).
void check_patch(const Patch &p, double volume0, bool cube) {
  const std::size_t nc = p.num_cells();
  std::vector<Facet> f = sorted_facets(p.cells.data(), nc);
  std::size_t boundary = 0, interior = 0;
  for (std::size_t i = 0; i < f.size();) {
    std::size_t j = i + 1;
    while (j < f.size() && f[j].same(f[i]))
      ++j;
    if (j - i > 2)
      fail("not conforming: a facet held by more than two cells");
    if (j - i == 1) {
      ++boundary;
      if (p.nb[f[i].who] != kNoCell)
        fail("neighbour across a boundary facet");
    } else {
      ++interior;
      if (p.nb[f[i].who] != f[i + 1].who / 4 || p.nb[f[i + 1].who] != f[i].who / 4)
        fail("neighbour array wrong: cells " + std::to_string(f[i].who / 4) + " and " +
             std::to_string(f[i + 1].who / 4) + " share a facet");
    }
    i = j;
  }
  // Every facet accounted for: with the two passes above, nb is symmetric
  // and each entry names the cell that really shares that facet.
  if (boundary + 2 * interior != 4 * nc)
    fail("facet count");
  const double v = total_volume(p.cells.data(), nc, p.coords.data());
  if (std::fabs(v - volume0) > 1e-9 * volume0)
    fail("volume changed: " + std::to_string(v));
  // Conformity also means no vertex in the interior of a facet or an edge; a
  // facet held once must lie on the cube's boundary (else: a hanging facet).
  for (std::size_t i = 0; i < f.size();) {
    std::size_t j = i + 1;
    while (j < f.size() && f[j].same(f[i]))
      ++j;
    if (cube && j - i == 1) {
      const VertexId ids[3] = {VertexId(f[i].ab >> 32), VertexId(f[i].ab), f[i].c};
      bool on_face = false;
      for (int k = 0; k < 3 && !on_face; ++k) {
        const double c0 = p.coords[3 * std::size_t(ids[0]) + k];
        on_face = (c0 == 0.0 || c0 == 1.0) && p.coords[3 * std::size_t(ids[1]) + k] == c0 &&
                  p.coords[3 * std::size_t(ids[2]) + k] == c0;
      }
      if (!on_face)
        fail("a facet held by one cell inside the cube (hanging)");
    }
    i = j;
  }
}

Mesh make_input(const std::string &input) {
  Mesh m;
  if (input.find_first_not_of("0123456789") == std::string::npos) {
    m = generate_kuhn(3, std::atoi(input.c_str()));
  } else {
    m = read_mesh(input);
    prepare_input(m, input);
    m.entities.clear();
    m.cell_data.clear();
    m.point_data.clear();
    m.physical_names.clear();
    if (m.dim != 3)
      fail("not a 3D mesh");
  }
  mark_mesh(m, Marking::Index);
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    if (m.stage[c] != Stage::Maubach || m.tag[c] < 1 || m.tag[c] > 3)
      fail("input cell " + std::to_string(c) + " is not a Maubach tuple");
  return m;
}

Patch make_patch(const Mesh &m) {
  Patch p;
  p.cells = m.cells;
  p.tag = m.tag;
  p.coords = m.coords;
  p.gen.assign(m.num_cells(), 0);
  p.parent_edge.assign(2 * m.num_vertices(), kNoVertex);
  return p;
}

} // namespace

int main(int argc, char **argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: patch_proto ours|proto|check K|MESH.msh iterations [radius band]\n");
    return 1;
  }
  const std::string mode = argv[1];
  const std::string input = argv[2];
  const bool cube = input.find_first_not_of("0123456789") == std::string::npos;
  const int iterations = std::atoi(argv[3]);
  Selection select;
  if (argc > 4)
    select.radius = std::atof(argv[4]);
  if (argc > 5)
    select.band = std::atof(argv[5]);
  set_threads(std::getenv("PROTO_THREADS") ? std::atoi(std::getenv("PROTO_THREADS")) : 1);
  const bool ours = mode == "ours" || mode == "check", proto = mode == "proto" || mode == "check";
  if (!ours && !proto)
    fail("mode must be ours, proto or check");

  Mesh mesh = make_input(input);
  // The file's selection: bisect_bench's 3D region (one per implementation).
  const char *hemisphere = R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,)"
                           R"("normal":[1,0,0],"offset":0.5})";
  std::unique_ptr<Region> region_ours, region_proto;
  if (!cube) {
    region_ours = parse_region(hemisphere, 3, "bench");
    region_proto = parse_region(hemisphere, 3, "bench");
  }
  // The selections, outside the timed refinement. The prototype's arrays are
  // lent to a Mesh for select_cells (swapped, not copied: no memory).
  auto select_ours = [&]() {
    return cube ? select(mesh.cells.data(), mesh.num_cells(), mesh.coords.data())
                : select_cells(mesh, *region_ours);
  };
  const std::size_t nc_in = mesh.num_cells();
  const double volume0 = total_volume(mesh.cells.data(), nc_in, mesh.coords.data());
  Patch patch;
  double t_build = 0;
  if (proto) {
    patch = make_patch(mesh);
    const auto t0 = Clock::now();
    patch.build_neighbours();
    t_build = secs(t0, Clock::now());
    if (!ours)
      mesh = Mesh{};
  }
  auto select_proto = [&]() {
    if (cube)
      return select(patch.cells.data(), patch.num_cells(), patch.coords.data());
    Mesh view;
    view.dim = 3;
    view.cells.swap(patch.cells);
    view.coords.swap(patch.coords);
    std::vector<CellId> sel = select_cells(view, *region_proto);
    view.cells.swap(patch.cells);
    view.coords.swap(patch.coords);
    return sel;
  };
  const long rss0 = proc_status_kb("VmRSS:");
  if (cube)
    std::printf("mode %s, Kuhn k=%s: %zu tets, sphere r=%g band=%g, %d iterations, 1 thread\n",
                mode.c_str(), input.c_str(), nc_in, select.radius, select.band, iterations);
  else
    std::printf("mode %s, %s: %zu tets, bisect_bench's hemisphere, %d iterations, 1 thread\n",
                mode.c_str(), input.c_str(), nc_in, iterations);
  if (proto)
    std::printf("neighbour array built in %.4f s (%.1f M tets/s)\n", t_build,
                1e-6 * nc_in / t_build);
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
      std::printf("%4d %10zu %10zu %9zu %9.4f %10.2f %9s  ours (%zu closure passes)\n", it,
                  sel.size(), cells_ours, r.bisections, t, 2e-6 * r.bisections / t, "",
                  r.closure_passes);
    }
    if (proto) {
      const auto sel = select_proto();
      const std::size_t b0 = patch.bisections, rings0 = patch.rings, push0 = patch.pushes;
      const auto t0 = Clock::now();
      patch.refine(sel);
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
        check_patch(patch, volume0, cube);
        if (cell_hashes(mesh.cells.data(), mesh.num_cells(), mesh.coords.data()) !=
            cell_hashes(patch.cells.data(), patch.num_cells(), patch.coords.data()))
          fail("iteration " + std::to_string(it) + ": the two meshes' cells differ");
        verdict = "ok";
      }
      std::printf("%4d %10zu %10zu %9zu %9.4f %10.2f %9s  proto (%zu rings, mean %.2f cells, "
                  "%zu pushes, max stack %zu)\n",
                  it, sel.size(), cells_proto, b, t, 2e-6 * b / t, verdict,
                  patch.rings - rings0, double(b) / double(patch.rings - rings0),
                  patch.pushes - push0, patch.max_stack);
    }
    std::fflush(stdout);
  }
  const long hwm = proc_status_kb("VmHWM:"); // before the rebuild below
  const double cells = double(ours ? mesh.num_cells() : patch.num_cells());
  if (ours)
    std::printf("TOTAL ours:  %.4f s, %zu bisections, %.2f M generated tets/s\n", t_ours, b_ours,
                2e-6 * b_ours / t_ours);
  if (proto) {
    std::printf("TOTAL proto: %.4f s, %zu bisections, %.2f M generated tets/s (+ %.4f s "
                "neighbour build once)\n",
                t_proto, b_proto, 2e-6 * b_proto / t_proto, t_build);
    std::printf("proto: %zu ring walks visiting %zu cells for %zu rings of %zu cells (%zu pushes)\n",
                patch.collects, patch.walked, patch.rings, patch.ring_cells, patch.pushes);
    // What building the array from scratch would cost on the result (a
    // refine() that did not keep it between calls), and a last check: the
    // array kept current equals the one built.
    const std::vector<CellId> kept = patch.nb;
    const auto t0 = Clock::now();
    patch.build_neighbours();
    const double t_rebuild = secs(t0, Clock::now());
    if (patch.nb != kept)
      fail("the neighbour array kept current differs from one built from the result");
    std::printf("neighbour array of the result built from scratch: %.4f s (%.1f M tets/s); equal "
                "to the one kept current\n",
                t_rebuild, 1e-6 * patch.num_cells() / t_rebuild);
    const std::size_t nc = patch.num_cells(), nv = patch.num_vertices();
    std::printf("proto arrays (size): cells %zu B, tag %zu, nb %zu, gen %zu, coords %zu, "
                "parent_edge %zu = %.1f B/tet; capacity %.1f B/tet\n",
                16 * nc, nc, 16 * nc, 2 * nc, 24 * nv, 8 * nv,
                (34.0 * nc + 32.0 * nv) / nc,
                (4.0 * patch.cells.capacity() + patch.tag.capacity() + 4.0 * patch.nb.capacity() +
                 2.0 * patch.gen.capacity() + 8.0 * patch.coords.capacity() +
                 4.0 * patch.parent_edge.capacity()) /
                    nc);
  }
  std::printf("peak RSS (before that rebuild) %.1f MiB = %.1f B/tet; above the pre-refinement RSS %.1f B/tet\n",
              hwm / 1024.0, hwm * 1024.0 / cells, (hwm - rss0) * 1024.0 / cells);
  return 0;
}
