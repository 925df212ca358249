// Test support, linked only into the bisect_hooked binary (never shipped):
// the hook tests/cli/paranoid.sh uses to watch --check and the final check
// catch a non-conforming mesh end to end.
#include "bisect/bisect.hpp"

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <map>
#include <vector>

namespace bisect::cli {
extern void (*g_after_iteration_hook)(int iteration, Mesh &mesh, std::size_t first_new_vertex);
}

namespace {

using namespace bisect;

// BISECT_TEST_CORRUPT_ITERATION=k makes `refine`
// undo one bisection made in iteration k, so that tests/cli/paranoid.sh can
// watch --check catch a non-conforming mesh end to end. Of the vertices made
// in that iteration (ids from `first_new`), the newest whose edge (a, b) was
// bisected in at least two cells gets one pair of siblings (z, a, rest) and
// (z, b, rest) merged back into (b, a, rest): z then hangs on the edge of
// that cell. Cell arrays follow (the second sibling's slot takes the last
// cell). Returns the vertex left hanging, or kNoVertex if none fitted.
VertexId corrupt_one_bisection(Mesh &mesh, std::size_t first_new) {
  const int n = mesh.cell_size(), dim = mesh.dim;
  std::vector<std::vector<CellId>> around(mesh.num_vertices() - first_new);
  for (std::size_t c = 0; c < mesh.num_cells(); ++c)
    for (int i = 0; i < n; ++i)
      if (mesh.cell(CellId(c))[i] >= first_new)
        around[mesh.cell(CellId(c))[i] - first_new].push_back(CellId(c));
  for (std::size_t z = mesh.num_vertices(); z-- > first_new;) {
    const std::vector<CellId> &cells = around[z - first_new];
    // Sibling pairs (cell with a, cell with b), keyed by the edge (a, b).
    std::map<std::pair<VertexId, VertexId>, std::vector<std::pair<CellId, CellId>>> pairs;
    for (std::size_t i = 0; i < cells.size(); ++i)
      for (std::size_t j = 0; j < cells.size(); ++j) {
        if (i == j)
          continue;
        const VertexId *x = mesh.cell(cells[i]), *y = mesh.cell(cells[j]);
        int only_x = -1, missing = 0;
        for (int p = 0; p < n; ++p)
          if (std::find(y, y + n, x[p]) == y + n)
            only_x = p, ++missing;
        if (missing != 1)
          continue;
        VertexId b = kNoVertex;
        for (int p = 0; p < n; ++p)
          if (std::find(x, x + n, y[p]) == x + n)
            b = y[p];
        const VertexId va = x[only_x];
        bool midpoint = true;
        for (int d = 0; d < dim; ++d)
          midpoint &= mesh.point(VertexId(z))[d] == 0.5 * (mesh.point(va)[d] + mesh.point(b)[d]);
        if (midpoint && va < b)
          pairs[{va, b}].push_back({cells[i], cells[j]});
      }
    for (const auto &[edge, list] : pairs) {
      if (list.size() < 2)
        continue; // one parent only: merging would leave no hanging node
      const auto [keep, drop] = list.front();
      VertexId *x = mesh.cell(CellId(keep));
      std::replace(x, x + n, VertexId(z), edge.second); // (z, a, rest) -> (b, a, rest)
      const std::size_t last = mesh.num_cells() - 1;
      std::copy_n(mesh.cell(CellId(last)), n, mesh.cell(CellId(drop)));
      mesh.cells.resize(last * n);
      if (mesh.stage.size() > last) {
        mesh.stage[drop] = mesh.stage[last];
        mesh.tag[drop] = mesh.tag[last];
        mesh.stage.resize(last);
        mesh.tag.resize(last);
      }
      for (DataArray &arr : mesh.cell_data) {
        const std::size_t k = std::size_t(arr.components);
        std::copy_n(arr.values.begin() + std::ptrdiff_t(last * k), k,
                    arr.values.begin() + std::ptrdiff_t(drop * k));
        arr.values.resize(last * k);
      }
      return VertexId(z);
    }
  }
  return kNoVertex;
}

void corrupt_hook(int iteration, Mesh &mesh, std::size_t first_new_vertex) {
  static const int corrupt_after = [] {
    const char *e = std::getenv("BISECT_TEST_CORRUPT_ITERATION");
    return e ? std::atoi(e) : 0;
  }();
  if (iteration == corrupt_after && corrupt_one_bisection(mesh, first_new_vertex) == kNoVertex)
    std::cerr << "bisect: BISECT_TEST_CORRUPT_ITERATION=" << iteration
              << ": no bisection to undo\n";
}

const bool installed = (bisect::cli::g_after_iteration_hook = corrupt_hook, true);

} // namespace
