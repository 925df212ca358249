// The iteration driver (driver.hpp): run_iterations and its final check.
#include "bisect/driver.hpp"
#include "bisect/error.hpp"
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"

#include <catch2/catch.hpp>

#include <vector>

using namespace bisect;

namespace {

// The cells whose first vertex lies in the corner x < 0.3 (of [0,1]^dim).
std::vector<CellId> corner(const Mesh &m) {
  std::vector<CellId> out;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    if (m.point(m.cell(CellId(c))[0])[0] < 0.3)
      out.push_back(CellId(c));
  return out;
}

// A Kuhn mesh of [0,1]^dim, marked.
Mesh marked_kuhn(int dim) {
  Mesh m = generate_kuhn(dim, dim == 4 ? 3 : 6);
  mark_mesh(m, Marking::Index);
  return m;
}

} // namespace

TEST_CASE("driver: a read-only callback lets the last quality pass take the final check's cell "
          "facts; the mesh, quality and verdict are those of the separate passes",
          "[driver][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    INFO("dim " << dim);
    const Mesh start = marked_kuhn(dim);
    DriverOptions options;
    options.iterations = dim == 4 ? 4 : 6;
    std::vector<Mesh> meshes;
    std::vector<DriverResult> results;
    for (int way : {0, 1, 2}) {
      Mesh m = start;
      int calls = 0;
      auto reads = [&](const IterationReport &, Mesh &) { ++calls; };
      options.on_iteration_changes_mesh = way != 2;
      results.push_back(way == 0 ? run_iterations(m, corner, options)
                                 : run_iterations(m, corner, options, reads));
      CHECK(calls == (way == 0 ? 0 : options.iterations));
      meshes.push_back(std::move(m));
    }
    for (std::size_t i = 1; i < meshes.size(); ++i) {
      CHECK(meshes[i].cells == meshes[0].cells);
      CHECK(meshes[i].coords == meshes[0].coords);
      CHECK(results[i].quality.min == results[0].quality.min);
      CHECK(results[i].quality.mean == results[0].quality.mean);
      CHECK(results[i].iterations == options.iterations);
    }
  }
}

TEST_CASE("driver: a callback that may change the mesh is checked after it: a cell flattened "
          "in place in the last iteration's callback is found",
          "[driver][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    INFO("dim " << dim);
    Mesh m = marked_kuhn(dim);
    DriverOptions options;
    options.iterations = 3;
    // One cell's second vertex moved onto its first, in place (the arrays
    // keep their addresses and sizes): only the cell pass sees it, so cell
    // facts taken before the callback would miss it.
    auto flattens = [&](const IterationReport &r, Mesh &mesh) {
      if (r.iteration != 3)
        return;
      const VertexId *c = mesh.cell(CellId(mesh.num_cells() / 2));
      for (int d = 0; d < dim; ++d)
        mesh.coords[std::size_t(dim) * c[1] + std::size_t(d)] = mesh.point(c[0])[d];
    };
    CHECK_THROWS_AS(run_iterations(m, corner, options, flattens), CheckError);
  }
}
