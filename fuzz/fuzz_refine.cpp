// libFuzzer target: the bytes describe a tiny mesh, a marking, a region and
// an iteration count. The mesh is one simplex or a Kuhn mesh (dim 2..4), or
// the part of it in a subset of its cubes, its vertices perturbed a little, renumbered, its cells
// shuffled and some of them turned inside out; then prepare_input (inputs it rejects are skipped),
// mark_mesh and a few iterations of select_cells + refine. After every
// iteration the mesh must pass check_conformity against the input's volume,
// boundary measure and Euler characteristic: abort() otherwise.
//
// Layout: the first bytes choose everything that shapes the run (dimension,
// mesh, marking, region, iterations), so a short input already refines; the
// bulk (per-vertex perturbations, permutations) comes from the bytes that
// follow and, once they run out, from a generator seeded by a hash of the
// whole input, so a short input still gets a fully scrambled mesh.
//
// Sizes are capped so that one run stays around a millisecond: at most 384
// input cells, at most 2000 cells (4D: 1000) after any iteration (refine
// undoes an iteration that would pass the cap), at most 6 iterations (4D: 4).
#include "bisect/generate.hpp"
#include "fuzz_common.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <sstream>
#include <utility>
#include <vector>

namespace {

// Reads the fuzzer's bytes; a splitmix64 stream once they run out.
struct Bytes {
  const std::uint8_t *p;
  std::size_t n;
  std::uint64_t state;
  Bytes(const std::uint8_t *data, std::size_t size) : p(data), n(size), state(0x243f6a8885a308d3) {
    for (std::size_t i = 0; i < size; ++i) // FNV-1a of the whole input
      state = (state ^ data[i]) * 0x100000001b3;
  }
  std::uint8_t u8() {
    if (n) {
      --n;
      return *p++;
    }
    std::uint64_t z = (state += 0x9e3779b97f4a7c15);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9;
    z = (z ^ (z >> 27)) * 0x94d049bb133111eb;
    return std::uint8_t((z ^ (z >> 31)) >> 56);
  }
  unsigned below(unsigned m) {
    if (m <= 256)
      return m ? u8() % m : 0;
    return ((unsigned(u8()) << 8) | u8()) % m;
  }
  // A number in [lo, hi] in 256 steps.
  double real(double lo, double hi) { return lo + (hi - lo) * u8() / 255.0; }
};

std::string vec(const std::vector<double> &v) {
  std::ostringstream s;
  s.precision(17);
  s << "[";
  for (std::size_t i = 0; i < v.size(); ++i)
    s << (i ? "," : "") << v[i];
  return s.str() + "]";
}

// Kuhn meshes and single simplices are made once per process (k = 0: the
// cartesian simplex).
const bisect::Mesh &base_mesh(int dim, int k) {
  static std::map<std::pair<int, int>, bisect::Mesh> cache;
  auto it = cache.find({dim, k});
  if (it == cache.end())
    it = cache
             .emplace(std::make_pair(dim, k),
                      k ? bisect::generate_kuhn(dim, k)
                        : bisect::generate_simplex(dim, bisect::SimplexShape::Cartesian))
             .first;
  return it->second;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  using namespace bisect;
  Bytes in(data, size);
  // Header: what shapes the run.
  const int dim = 2 + int(in.below(3));
  const int k = int(in.below(dim == 2 ? 5 : dim == 3 ? 4 : 3)); // 0: one simplex
  const unsigned marking = in.below(4);                         // index, longest, sorted, explicit
  const unsigned amount = in.below(4); // perturbation: 0 none .. 3 up to 0.3 step
  const int iterations = 1 + int(in.below(dim == 4 ? 4 : 6));
  const unsigned region_type = in.below(4);
  std::vector<double> a(dim), b(dim);
  for (int d = 0; d < dim; ++d)
    a[d] = in.real(-0.2, 1.2);
  for (int d = 0; d < dim; ++d)
    b[d] = in.real(0.0, 1.0);
  const double radius = in.real(0.01, 1.0);
  const unsigned flips = in.below(4); // how many cells to turn inside out: none .. all
  const int roundtrip_after = int(in.below(unsigned(iterations) + 1));

  Mesh mesh = base_mesh(dim, k);
  const int n = mesh.cell_size();

  // Keep the cells of a subset of the Kuhn cubes, one bit each (none: all),
  // which makes non-convex and pinched domains; then drop unused vertices.
  if (k > 1) {
    int cubes = 1;
    for (int d = 0; d < dim; ++d)
      cubes *= k;
    std::vector<bool> keep(cubes);
    bool any = false;
    for (int q = 0; q < cubes; q += 8) {
      const std::uint8_t bits = in.u8();
      for (int i = 0; i < 8 && q + i < cubes; ++i)
        any |= (keep[q + i] = bits >> i & 1);
    }
    if (any) {
      std::vector<VertexId> kept;
      for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
        int cube = 0;
        for (int d = dim - 1; d >= 0; --d) {
          double centroid = 0;
          for (int i = 0; i < n; ++i)
            centroid += mesh.point(mesh.cell(CellId(c))[i])[d] / n;
          cube = cube * k + int(centroid * k);
        }
        if (keep[cube])
          kept.insert(kept.end(), mesh.cell(CellId(c)), mesh.cell(CellId(c)) + n);
      }
      std::vector<VertexId> renumber(mesh.num_vertices(), kNoVertex);
      std::vector<double> coords;
      for (VertexId &v : kept) {
        if (renumber[v] == kNoVertex) {
          renumber[v] = VertexId(coords.size() / dim);
          coords.insert(coords.end(), mesh.point(v), mesh.point(v) + dim);
        }
        v = renumber[v];
      }
      mesh.cells = std::move(kept);
      mesh.coords = std::move(coords);
    }
  }
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();

  // Perturb every vertex by up to 0.1 * amount of the grid step along each
  // axis (may tangle the mesh: prepare_input must then say so).
  const double step = k ? 1.0 / k : 1.0;
  if (amount)
    for (double &x : mesh.coords)
      x += in.real(-0.1, 0.1) * amount * step;

  // Renumber the vertices by a permutation.
  std::vector<VertexId> perm(nv);
  std::iota(perm.begin(), perm.end(), 0);
  for (std::size_t i = nv; i > 1; --i)
    std::swap(perm[i - 1], perm[in.below(unsigned(i))]);
  std::vector<double> coords(mesh.coords.size());
  for (std::size_t v = 0; v < nv; ++v)
    std::copy_n(mesh.point(VertexId(v)), dim, coords.begin() + std::ptrdiff_t(perm[v]) * dim);
  mesh.coords = std::move(coords);
  for (VertexId &v : mesh.cells)
    v = perm[v];

  // Shuffle the cells and reverse the orientation of some.
  std::vector<std::size_t> order(nc);
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = nc; i > 1; --i)
    std::swap(order[i - 1], order[in.below(unsigned(i))]);
  std::vector<VertexId> cells(mesh.cells.size());
  for (std::size_t c = 0; c < nc; ++c) {
    std::copy_n(mesh.cell(CellId(order[c])), n, cells.begin() + std::ptrdiff_t(c) * n);
    if (in.below(3) < flips)
      std::swap(cells[c * n], cells[c * n + 1 + in.below(unsigned(dim))]);
  }
  mesh.cells = std::move(cells);

  try {
    prepare_input(mesh, "fuzz");
  } catch (const InputError &) {
    return 0;
  }
  if (marking == 3) {
    // Explicit: a random rank for a random subset of the edges (the rest come
    // after, by index). Any strict total order of the edges must work.
    std::vector<std::uint64_t> edges;
    for (std::size_t c = 0; c < nc; ++c)
      for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
          edges.push_back(edge_key(mesh.cell(CellId(c))[i], mesh.cell(CellId(c))[j]));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (std::size_t i = edges.size(); i > 1; --i)
      std::swap(edges[i - 1], edges[in.below(unsigned(i))]);
    const std::size_t ranked = in.below(unsigned(edges.size()) + 1);
    for (std::size_t r = 0; r < ranked; ++r)
      mesh.edge_rank[edges[r]] = std::uint32_t(r);
  }
  mark_mesh(mesh, Marking(marking));

  // A sphere surface or solid ball (centre a), a box [a, a + 0.8 b] or a
  // halfspace (normal b - 0.5, through a), inside or around [0,1]^dim.
  std::string spec;
  if (region_type < 2) {
    spec = "{\"type\":\"sphere\",\"center\":" + vec(a) + ",\"radius\":" + std::to_string(radius) +
           (region_type ? ",\"solid\":true}" : "}");
  } else if (region_type == 2) {
    for (int d = 0; d < dim; ++d)
      b[d] = a[d] + 0.8 * b[d];
    spec = "{\"type\":\"box\",\"min\":" + vec(a) + ",\"max\":" + vec(b) + "}";
  } else {
    double offset = 0;
    bool zero = true;
    for (int d = 0; d < dim; ++d) {
      b[d] -= 0.5;
      offset += a[d] * b[d];
      zero = zero && b[d] == 0;
    }
    if (zero)
      b[0] = 1, offset = a[0];
    std::ostringstream o;
    o.precision(17);
    o << offset;
    spec = "{\"type\":\"halfspace\",\"normal\":" + vec(b) + ",\"offset\":" + o.str() + "}";
  }
  const auto region = parse_region(spec, dim, "fuzz");

  bisect_fuzz::RefineCheck how;
  how.iterations = iterations;
  how.max_input_cells = 384;
  how.max_cells = dim == 4 ? 1000 : 2000;
  how.roundtrip_after = roundtrip_after;
  bisect_fuzz::refine_and_check(mesh, *region, how);
  return 0;
}
