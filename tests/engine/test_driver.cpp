// The iteration driver (driver.hpp): run_iterations and its final check.
#include "bisect/driver.hpp"
#include "bisect/error.hpp"
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/region.hpp"

#include <catch2/catch.hpp>

#include <bit>
#include <initializer_list>
#include <stdexcept>
#include <string>
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

TEST_CASE("driver: the input's invariants and quality given by the caller replace its own "
          "passes: the same mesh and result, and the final check compares with them",
          "[driver][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    INFO("dim " << dim);
    const Mesh start = marked_kuhn(dim);
    DriverOptions options;
    options.iterations = 3;
    Mesh measured = start;
    const DriverResult a = run_iterations(measured, corner, options);
    const Invariants inv = measure_invariants(start, true);
    const QualitySummary q0 = quality_summary(start);
    options.input_invariants = &inv;
    options.input_quality = &q0;
    Mesh given = start;
    const DriverResult b = run_iterations(given, corner, options);
    CHECK(given.cells == measured.cells);
    CHECK(given.coords == measured.coords);
    CHECK(b.quality.mean == a.quality.mean);
    CHECK(b.iterations == a.iterations);
    // The quality given is the result's when no iteration runs.
    QualitySummary made_up = q0;
    made_up.mean = 0.125;
    options.input_quality = &made_up;
    options.iterations = 0;
    Mesh unchanged = start;
    CHECK(run_iterations(unchanged, corner, options).quality.mean == 0.125);
    options.iterations = 3;
    // Invariants that are not the mesh's fail the final check.
    Invariants wrong = inv;
    wrong.volume *= 2;
    options.input_invariants = &wrong;
    Mesh m = start;
    CHECK_THROWS_AS(run_iterations(m, corner, options), CheckError);
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

TEST_CASE("driver: a monotone region's selection among the previous one's descendants is the "
          "full selection, and looks at fewer cells",
          "[driver][region][2d][3d][4d]") {
  // Every region type that says it is monotone, in every dimension it
  // exists in: at each iteration after the first, select_among gets the
  // candidates; the test compares its selection with a full select_cells of
  // the same mesh, and the final meshes with and without narrowing.
  for (int dim : {2, 3, 4}) {
    // The first `n` of four coordinates, as a JSON list.
    auto first = [](std::initializer_list<double> values, int n) {
      std::string out = "[";
      for (int k = 0; k < n; ++k) {
        if (k)
          out += ',';
        out += std::to_string(values.begin()[k]);
      }
      return out + "]";
    };
    std::vector<std::string> specs = {
        R"({"type": "sphere", "center": )" + first({0.4, 0.45, 0.5, 0.55}, dim) +
            R"(, "radius": 0.3})",
        R"({"type": "sphere", "center": )" + first({0.4, 0.45, 0.5, 0.55}, dim) +
            R"(, "radius": 0.2, "solid": true})",
        R"({"type": "hemisphere", "center": )" + first({0.5, 0.5, 0.5, 0.5}, dim) +
            R"(, "radius": 0.35, "normal": )" + first({1, 0.5, 0, 0}, dim) + R"(, "offset": 0.6})",
        R"({"type": "box", "min": )" + first({0.1, 0.2, 0.3, 0.1}, dim) + R"(, "max": )" +
            first({0.3, 0.5, 0.45, 0.6}, dim) + "}",
        // cuts a corner off the unit cube
        R"({"type": "halfspace", "normal": )" + first({1, 1, 1, 1}, dim) + R"(, "offset": )" +
            std::to_string(0.7 * dim) + "}",
        R"({"type": "union", "regions": [{"type": "sphere", "center": )" +
            first({0.2, 0.2, 0.2, 0.2}, dim) +
            R"(, "radius": 0.1}, {"type": "intersection", "regions": [{"type": "box", "min": )" +
            first({0.4, 0.4, 0.4, 0.4}, dim) + R"(, "max": )" + first({0.9, 0.9, 0.9, 0.9}, dim) +
            R"(}, {"type": "halfspace", "normal": )" + first({1, -1, 0, 0}, dim) +
            R"(, "offset": 0.05}]}]})",
    };
    if (dim > 2) // space-time: one coordinate fewer than the mesh
      specs.push_back(R"({"type": "moving_sphere", "center": )" + first({0.2, 0.3, 0.2}, dim - 1) +
                      R"(, "velocity": )" + first({0.5, 0.1, 0.2}, dim - 1) +
                      R"(, "radius": 0.15})");
    for (const std::string &text : specs) {
      INFO("dim " << dim << ", region " << text);
      const std::unique_ptr<Region> region = parse_region(text, dim, "test");
      REQUIRE(region->monotone());
      const Mesh start = marked_kuhn(dim);
      DriverOptions options;
      options.iterations = dim == 4 ? 4 : 7;
      Mesh full = start;
      run_iterations(full, region_selector(*region), options);
      Mesh narrowed = start;
      int narrowed_calls = 0;
      std::size_t looked = 0, cells = 0;
      options.select_among = [&](const Mesh &m, const std::vector<std::uint64_t> &candidates) {
        ++narrowed_calls;
        std::vector<CellId> among = select_cells(m, *region, candidates);
        const bool same = among == select_cells(m, *region);
        CHECK(same);
        for (std::uint64_t w : candidates)
          looked += std::size_t(std::popcount(w));
        cells += m.num_cells();
        return among;
      };
      const DriverResult r = run_iterations(narrowed, region_selector(*region), options);
      CHECK(r.iterations == options.iterations);
      CHECK(narrowed_calls == options.iterations - 1);
      CHECK(looked < cells);
      const bool same_mesh = narrowed.cells == full.cells && narrowed.coords == full.coords;
      CHECK(same_mesh);
    }
  }
  // The level-set region samples its function: not monotone.
  const std::unique_ptr<Region> levelset = parse_region(
      R"({"type": "levelset", "variables": ["x", "y"], "expression": "x*x + y*y", "value": 0.2})",
      2, "test");
  CHECK_FALSE(levelset->monotone());
}

TEST_CASE("driver: cell arrays carried by each cell's input cell come back as refine() would have "
          "made them, also after a cell limit stops the run and after a selector throws",
          "[driver][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    INFO("dim " << dim);
    Mesh start = marked_kuhn(dim);
    const std::size_t n = start.num_cells();
    DataArray id{"id", 1, std::vector<double>(n), ValueType::Int32};
    DataArray vec{"vec", 3, std::vector<double>(3 * n), ValueType::Float64};
    for (std::size_t c = 0; c < n; ++c) {
      id.values[c] = double(c);
      vec.values[3 * c] = 0.5 * double(c);
      vec.values[3 * c + 1] = double(c) + 0.25;
      vec.values[3 * c + 2] = -double(c);
    }
    start.cell_data = {id, vec};
    const int iterations = dim == 4 ? 4 : 6;
    // 0: a plain run; 1: a cell limit stops it before the last iteration;
    // 2: the selector throws at the third iteration.
    for (int run : {0, 1, 2}) {
      INFO("run " << run);
      std::vector<Mesh> meshes;
      for (bool by_origin : {false, true}) {
        Mesh m = start;
        DriverOptions options;
        options.iterations = iterations;
        options.cell_data_by_origin = by_origin;
        int calls = 0;
        Selector select = [&](const Mesh &mesh) {
          if (run == 2 && ++calls == 3)
            throw std::runtime_error("selector");
          if (by_origin)
            CHECK(mesh.cell_data.empty()); // away while the iterations run
          return corner(mesh);
        };
        if (run == 1) {
          Mesh probe = start;
          DriverOptions o;
          o.iterations = iterations - 1;
          run_iterations(probe, corner, o);
          options.max_cells = probe.num_cells() + 1;
        }
        if (run == 2) {
          CHECK_THROWS_AS(run_iterations(m, select, options), std::runtime_error);
        } else {
          const DriverResult r = run_iterations(m, select, options);
          CHECK(r.iterations == (run == 1 ? iterations - 1 : iterations));
        }
        meshes.push_back(std::move(m));
      }
      const Mesh &plain = meshes[0], &carried = meshes[1];
      CHECK(plain.num_cells() > n);
      CHECK(carried.cells == plain.cells);
      REQUIRE(carried.cell_data.size() == 2);
      for (std::size_t a = 0; a < 2; ++a) {
        CHECK(carried.cell_data[a].name == plain.cell_data[a].name);
        CHECK(carried.cell_data[a].components == plain.cell_data[a].components);
        CHECK(carried.cell_data[a].type == plain.cell_data[a].type);
        const bool same = carried.cell_data[a].values == plain.cell_data[a].values;
        CHECK(same);
      }
    }
  }
}

TEST_CASE("driver: a cell array without one tuple per cell stays in the mesh with "
          "cell_data_by_origin, and the run is the one without it",
          "[driver][2d]") {
  Mesh start = marked_kuhn(2);
  // Short by one tuple: refine() grows it as before; it is not carried by origin.
  start.cell_data = {{"short", 1, std::vector<double>(start.num_cells() - 1, 7.0)}};
  std::vector<Mesh> meshes;
  for (bool by_origin : {false, true}) {
    Mesh m = start;
    DriverOptions options;
    options.iterations = 3;
    options.cell_data_by_origin = by_origin;
    bool seen = true;
    run_iterations(
        m,
        [&](const Mesh &mesh) {
          seen = seen && mesh.cell_data.size() == 1;
          return corner(mesh);
        },
        options);
    CHECK(seen);
    meshes.push_back(std::move(m));
  }
  CHECK(meshes[1].cells == meshes[0].cells);
  REQUIRE(meshes[1].cell_data.size() == 1);
  CHECK(meshes[1].cell_data[0].values == meshes[0].cell_data[0].values);
}

TEST_CASE("driver: --max-memory's estimate counts cell arrays carried by input cell as if they "
          "were in the mesh: for every budget the run stops at the same iteration",
          "[driver][3d]") {
  Mesh start = marked_kuhn(3);
  start.cell_data = {{"a", 2, std::vector<double>(2 * start.num_cells(), 1.0)}};
  // Budgets from far too small to enough, 20% apart: the estimate without
  // the arrays is 0.6 of the one with them, so a budget between the two
  // lets an iteration through that it should not.
  int stopped = 0;
  for (double gib = 1e-6; gib < 1e-2; gib *= 1.2) {
    INFO("budget " << gib << " GiB");
    std::vector<DriverResult> runs;
    for (bool by_origin : {false, true}) {
      Mesh m = start;
      DriverOptions options;
      options.iterations = 6;
      options.max_memory_gib = gib;
      options.cell_data_by_origin = by_origin;
      runs.push_back(run_iterations(m, corner, options));
      CHECK(m.cell_data.size() == 1);
    }
    CHECK(runs[1].stop == runs[0].stop);
    CHECK(runs[1].iterations == runs[0].iterations);
    stopped += runs[0].stop == StopReason::MemoryLimit && runs[0].iterations >= 1;
  }
  CHECK(stopped >= 5); // budgets that stop a run after some iterations were tried
}
