// libFuzzer target: the bytes describe a tiny mesh, a region and a marking.
// A Kuhn mesh (dim 2..4, k 1..3) gets its vertices perturbed a little,
// renumbered, its cells shuffled and some of them turned inside out; then
// prepare_input (inputs it rejects are skipped), mark_mesh and a few
// iterations of select_cells + refine. After every iteration the mesh must
// be conforming with volume, boundary measure and Euler characteristic
// unchanged: abort() otherwise.
#include "fuzz_common.hpp"
#include "generate.hpp"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <vector>

namespace {

// Reads the fuzzer's bytes; zeros once they run out.
struct Bytes {
  const std::uint8_t *p;
  std::size_t n;
  std::uint8_t u8() {
    if (!n)
      return 0;
    --n;
    return *p++;
  }
  unsigned below(unsigned m) { return m ? u8() % m : 0; }
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

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  using namespace bisect;
  Bytes in{data, size};
  const int dim = 2 + int(in.below(3));
  const int k = 1 + int(in.below(dim == 4 ? 2 : 3));
  Mesh mesh = generate_kuhn(dim, k);
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  const int n = mesh.cell_size();

  // Perturb interior and boundary vertices by up to 0.3 of the grid step
  // along each axis (may tangle the mesh: prepare_input must then say so).
  const double step = 1.0 / k;
  const unsigned amount = in.below(4); // 0: none .. 3: up to 0.3 step
  for (double &x : mesh.coords)
    if (amount)
      x += in.real(-0.1, 0.1) * amount * step;

  // Renumber the vertices by a permutation taken from the bytes.
  std::vector<VertexId> perm(nv);
  std::iota(perm.begin(), perm.end(), 0);
  for (std::size_t i = nv; i > 1; --i)
    std::swap(perm[i - 1], perm[in.below(unsigned(i))]);
  std::vector<double> coords(mesh.coords.size());
  for (std::size_t v = 0; v < nv; ++v)
    std::copy_n(mesh.point(VertexId(v)), dim, coords.begin() + std::ptrdiff_t(perm[v]) * dim);
  mesh.coords = coords;
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
    if (in.u8() & 1)
      std::swap(cells[c * n], cells[c * n + 1 + in.below(unsigned(dim))]);
  }
  mesh.cells = cells;

  try {
    prepare_input(mesh, "fuzz");
  } catch (const InputError &) {
    return 0;
  }
  mark_mesh(mesh, Marking(in.below(3)));

  // A sphere (surface or solid) or a box, inside or around [0,1]^dim.
  std::string spec;
  if (in.u8() & 1) {
    std::vector<double> c(dim);
    for (double &x : c)
      x = in.real(-0.2, 1.2);
    spec = "{\"type\":\"sphere\",\"center\":" + vec(c) + ",\"radius\":" +
           std::to_string(in.real(0.01, 1.0)) + ((in.u8() & 1) ? ",\"solid\":true}" : "}");
  } else {
    std::vector<double> lo(dim), hi(dim);
    for (int d = 0; d < dim; ++d) {
      lo[d] = in.real(-0.2, 1.2);
      hi[d] = lo[d] + in.real(0.0, 0.8);
    }
    spec = "{\"type\":\"box\",\"min\":" + vec(lo) + ",\"max\":" + vec(hi) + "}";
  }
  const auto region = parse_region(spec, dim, "fuzz");
  const int iterations = 1 + int(in.below(dim == 4 ? 3 : 5));
  bisect_fuzz::refine_and_check(mesh, *region, iterations);
  return 0;
}
