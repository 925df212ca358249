// Refine to conformity (ALGORITHMS.md §6) and the papers' properties.
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "bisect/threads.hpp"
#include "engine/refine_testing.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

using namespace bisect;

namespace {

Mesh load(const std::string &name) {
  Mesh m = read_mesh(testing::data_path(name));
  prepare_input(m, name);
  return m;
}

// Refines `iterations` times around the region and checks every iteration.
void refine_and_check(Mesh m, Marking marking, const std::string &region_json, int iterations) {
  mark_mesh(m, marking);
  Invariants inv = measure_invariants(m);
  auto region = parse_region(region_json, m.dim, "test");
  std::size_t cells = m.num_cells();
  for (int it = 1; it <= iterations; ++it) {
    auto sel = select_cells(m, *region);
    RefineResult r = refine(m, sel);
    INFO("iteration " << it << ", marking " << marking_name(marking));
    REQUIRE(!r.limit_reached);
    REQUIRE(m.num_cells() >= cells + sel.size());
    cells = m.num_cells();
    REQUIRE_CONFORMING(m, inv);
  }
  // Closure: a pass over an empty selection changes nothing.
  std::size_t before = m.num_cells();
  refine(m, {});
  REQUIRE(m.num_cells() == before);
}

// Every array refinement writes, entities included, bit for bit.
void require_same_mesh(const Mesh &a, const Mesh &b) {
  REQUIRE(a.cells == b.cells);
  REQUIRE(a.coords == b.coords);
  REQUIRE(a.parent_edge == b.parent_edge);
  REQUIRE(a.level == b.level);
  REQUIRE(a.stage == b.stage);
  REQUIRE(a.tag == b.tag);
  REQUIRE(a.generation == b.generation);
  REQUIRE(a.cell_data.size() == b.cell_data.size());
  for (std::size_t k = 0; k < a.cell_data.size(); ++k)
    REQUIRE(a.cell_data[k].values == b.cell_data[k].values);
  REQUIRE(a.entities.size() == b.entities.size());
  for (std::size_t k = 0; k < a.entities.size(); ++k) {
    REQUIRE(a.entities[k].vertices == b.entities[k].vertices);
    REQUIRE(a.entities[k].data.size() == b.entities[k].data.size());
    for (std::size_t j = 0; j < a.entities[k].data.size(); ++j)
      REQUIRE(a.entities[k].data[j].values == b.entities[k].data[j].values);
  }
}

const Marking kMarkings[] = {Marking::Index, Marking::Longest, Marking::Sorted};

} // namespace

TEST_CASE("closure: the bundled 2D mesh stays conforming over 10 local iterations",
          "[refine][2d]") {
  Mesh m = load("square.msh");
  for (Marking mk : kMarkings)
    refine_and_check(m, mk, R"({"type":"sphere","center":[0.5,0.5],"radius":0.3})", 10);
}

TEST_CASE("closure: the bundled ball stays conforming over 10 iterations around the hemisphere",
          "[refine][3d]") {
  Mesh m = load("ball.msh");
  for (Marking mk : kMarkings)
    refine_and_check(
        m, mk,
        R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,"normal":[1,0,0],"offset":0.5})",
        10);
}

TEST_CASE("closure: perturbed and renumbered meshes stay conforming", "[refine][2d][3d]") {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    for (int dim : {2, 3}) {
      Mesh m = testing::renumbered(testing::perturbed_inside_box(generate_kuhn(dim, 4), 0.06, seed),
                                   seed);
      prepare_input(m, "perturbed");
      std::string region = dim == 2 ? R"({"type":"sphere","center":[0.3,0.4],"radius":0.35})"
                                    : R"({"type":"sphere","center":[0.3,0.4,0.5],"radius":0.35})";
      for (Marking mk : kMarkings)
        refine_and_check(m, mk, region, 8);
    }
    Mesh ball = testing::renumbered(load("ball.msh"), seed);
    refine_and_check(ball, seed % 2 ? Marking::Longest : Marking::Index,
                     R"({"type":"sphere","center":[0.2,-0.3,0.1],"radius":1.2})", 6);
  }
}

TEST_CASE("closure: a box region touching the boundary keeps boundary measure", "[refine][3d]") {
  Mesh m = load("ball.msh");
  refine_and_check(m, Marking::Longest, R"({"type":"box","min":[1.5,-2,-2],"max":[3,2,2]})", 6);
}

TEST_CASE("refinement is deterministic: two runs through a saved file equal one run",
          "[refine][io]") {
  const std::string region_json =
      R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,"normal":[1,0,0],"offset":0.5})";
  for (Marking mk : {Marking::Index, Marking::Longest}) {
    for (const char *ext : {".vtu", ".msh"}) {
      Mesh one = load("ball.msh");
      mark_mesh(one, mk);
      auto region = parse_region(region_json, 3, "test");
      for (int it = 0; it < 5; ++it)
        refine(one, select_cells(one, *region));

      Mesh two = load("ball.msh");
      mark_mesh(two, mk);
      for (int it = 0; it < 3; ++it)
        refine(two, select_cells(two, *region));
      std::string path =
          (std::filesystem::temp_directory_path() / (std::string("bisect-two-runs") + ext))
              .string();
      encode_state(two);
      write_mesh(path, two);
      Mesh back = read_mesh(path);
      prepare_input(back, path);
      REQUIRE(decode_state(back, path));
      REQUIRE(back.marking == mk);
      for (int it = 0; it < 2; ++it)
        refine(back, select_cells(back, *region));
      std::filesystem::remove(path);

      REQUIRE(back.num_cells() == one.num_cells());
      REQUIRE(back.coords == one.coords);
      REQUIRE(back.cells == one.cells);
      REQUIRE(back.tag == one.tag);
    }
  }
}

TEST_CASE("cell data is inherited and point data interpolated at midpoints", "[refine][3d]") {
  Mesh m = generate_kuhn(3, 2);
  DataArray cd{"material", 1, {}}, pd{"f", 1, {}};
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    cd.values.push_back(double(c % 3));
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const double *p = m.point(VertexId(v));
    pd.values.push_back(2 * p[0] - p[1] + 3 * p[2]); // linear: interpolation is exact
  }
  m.cell_data.push_back(cd);
  m.point_data.push_back(pd);
  mark_mesh(m, Marking::Index);
  Mesh original = m;
  auto region = parse_region(R"({"type":"sphere","center":[0.5,0.5,0.5],"radius":0.4})", 3, "t");
  for (int it = 0; it < 4; ++it)
    refine(m, select_cells(m, *region));
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const double *p = m.point(VertexId(v));
    REQUIRE(m.point_data[0].values[v] == Approx(2 * p[0] - p[1] + 3 * p[2]).margin(1e-12));
  }
  REQUIRE(m.cell_data[0].values.size() == m.num_cells());
  // Every child's material equals the material of the original cell holding its centroid.
  double pts[4 * 3], opts[4 * 3];
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    cell_points(m, CellId(c), pts);
    double g[3] = {0, 0, 0};
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k)
        g[k] += pts[i * 3 + k] / 4;
    bool found = false;
    for (std::size_t o = 0; o < original.num_cells() && !found; ++o) {
      cell_points(original, CellId(o), opts);
      // inside test: the four sub-volumes with g have the signs of the cell
      double vol = signed_volume(opts, 3), sum = 0;
      bool inside = true;
      for (int i = 0; i < 4; ++i) {
        double q[12];
        std::copy(opts, opts + 12, q);
        std::copy(g, g + 3, q + 3 * i);
        double s = signed_volume(q, 3) / vol;
        inside &= s > 1e-12;
        sum += s;
      }
      if (inside) {
        found = true;
        REQUIRE(m.cell_data[0].values[c] == original.cell_data[0].values[o]);
      }
    }
    REQUIRE(found);
  }
}

TEST_CASE("max cells: an iteration that would pass the limit is undone exactly", "[refine][3d]") {
  Mesh m = load("ball.msh");
  mark_mesh(m, Marking::Index);
  auto region = parse_region(R"({"type":"sphere","center":[0,0,0],"radius":1})", 3, "t");
  refine(m, select_cells(m, *region));
  Mesh before = m;
  RefineLimits limits;
  limits.max_cells = m.num_cells() + 10;
  RefineResult r = refine(m, select_cells(m, *region), limits);
  REQUIRE(r.limit_reached);
  REQUIRE(m.cells == before.cells);
  REQUIRE(m.coords == before.coords);
  REQUIRE(m.tag == before.tag);
  REQUIRE(m.stage == before.stage);
  Invariants inv = measure_invariants(before);
  REQUIRE_CONFORMING(m, inv);
}

TEST_CASE("max cells: a limit tripped on the last closure pass undoes cells bisected several "
          "times",
          "[refine][2d][3d][4d]") {
  // The undo log keeps an input cell's first state only; a late trip has
  // input cells bisected more than once, and appended cells bisected again.
  for (int dim : {2, 3, 4}) {
    INFO("dim " << dim);
    Mesh m = generate_kuhn(dim, dim == 4 ? 2 : 4);
    mark_mesh(m, Marking::Index);
    m.cell_data.push_back(DataArray{"id", 1, std::vector<double>(m.num_cells())});
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      m.cell_data[0].values[c] = double(c);
    std::string centre = "0.3";
    for (int d = 1; d < dim; ++d)
      centre += ",0.3";
    auto region =
        parse_region(R"({"type":"sphere","center":[)" + centre + R"(],"radius":0.05})", dim, "t");
    refine(m, select_cells(m, *region)); // a tree to restore, too
    // Iterations until one needs at least two closure passes.
    Mesh free_run;
    std::vector<CellId> selected;
    for (int it = 0; it < 12; ++it) {
      free_run = m;
      selected = select_cells(m, *region);
      if (refine(free_run, selected).closure_passes >= 2)
        break;
      m = free_run;
    }
    const Mesh before = m;
    REQUIRE(free_run.num_cells() > m.num_cells() + selected.size() + 1);
    RefineLimits limits;
    limits.max_cells = free_run.num_cells() - 1;
    const RefineResult r = refine(m, selected, limits);
    REQUIRE(r.limit_reached);
    REQUIRE(r.bisections > 0);
    REQUIRE(m.cell_data.size() == 1);
    require_same_mesh(m, before);
    const Invariants inv = measure_invariants(before);
    REQUIRE_CONFORMING(m, inv);
  }
}

TEST_CASE("32-bit ids: running out of vertex ids stops cleanly", "[refine][2d]") {
  Mesh m = generate_kuhn(2, 4);
  mark_mesh(m, Marking::Index);
  Mesh before = m;
  RefineLimits limits;
  limits.max_vertices = m.num_vertices() + 5;
  std::vector<CellId> all(m.num_cells());
  for (std::size_t c = 0; c < all.size(); ++c)
    all[c] = CellId(c);
  RefineResult r = refine(m, all, limits);
  REQUIRE(r.limit_reached);
  REQUIRE(m.cells == before.cells);
}

// ---- seed 002 §5.1: uniform refinement of one tet ----

namespace {

struct UniformRun {
  std::vector<double> qmin; // per iteration 0..k
  std::size_t classes = 0;  // over every generated cell
};

UniformRun uniform(Mesh m, Marking marking, int iterations) {
  mark_mesh(m, marking);
  UniformRun run;
  run.qmin.push_back(quality_summary(m).min);
  Mesh all_generated = m; // accumulates every generation's cells for the class count
  for (int it = 1; it <= iterations; ++it) {
    refine_uniform(m);
    run.qmin.push_back(quality_summary(m).min);
    if (it <= 12) {
      all_generated.coords = m.coords;
      all_generated.cells.insert(all_generated.cells.end(), m.cells.begin(), m.cells.end());
    }
  }
  all_generated.stage.clear();
  run.classes = count_similarity_classes(all_generated);
  return run;
}

} // namespace

TEST_CASE("uniform tet: at most 36 classes with index, 72 with longest; min quality period 3",
          "[refine][3d][quality]") {
  for (SimplexShape shape :
       {SimplexShape::Equilateral, SimplexShape::Cartesian, SimplexShape::Random}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      if (shape != SimplexShape::Random && seed > 1)
        continue;
      Mesh tet = generate_simplex(3, shape, seed);
      for (Marking mk : {Marking::Index, Marking::Longest, Marking::Sorted}) {
        UniformRun run = uniform(tet, mk, 12);
        INFO("shape " << int(shape) << " seed " << seed << " marking " << marking_name(mk)
                      << " classes " << run.classes);
        REQUIRE(run.classes <= (mk == Marking::Longest ? 72u : 36u));
        for (int k = 6; k + 3 <= 12; ++k)
          REQUIRE(run.qmin[k] == Approx(run.qmin[k + 3]).epsilon(1e-9));
        // The quality never drops below its cycle's minimum.
        double floor = *std::min_element(run.qmin.begin() + 6, run.qmin.end());
        for (double q : run.qmin)
          REQUIRE(q >= floor * (1 - 1e-9));
      }
    }
  }
}

TEST_CASE("uniform triangle: newest vertex bisection has at most 4 classes, period 2",
          "[refine][2d][quality]") {
  for (SimplexShape shape : {SimplexShape::Equilateral, SimplexShape::Random}) {
    Mesh tri = generate_simplex(2, shape, 4);
    UniformRun run = uniform(tri, Marking::Index, 10);
    INFO("classes " << run.classes);
    REQUIRE(run.classes <= 4u);
    for (int k = 2; k + 2 <= 10; ++k)
      REQUIRE(run.qmin[k] == Approx(run.qmin[k + 2]).epsilon(1e-9));
  }
}

TEST_CASE("precision limit: refining around a point stops before an edge too fine for doubles, "
          "undoing the iteration exactly",
          "[refine][2d][3d]") {
  for (int dim : {2, 3}) {
    for (double offset : {0.0, 1e6}) {
      Mesh m = generate_kuhn(dim, 2, offset, offset + 1);
      mark_mesh(m, Marking::Index);
      const Invariants inv = measure_invariants(m);
      std::string spec = R"({"type": "sphere", "solid": true, "radius": 1e-300, "center": [)";
      for (int k = 0; k < dim; ++k)
        spec += (k ? ", " : "") + std::to_string(offset + 0.3 + 0.05 * k);
      auto region = parse_region(spec + "]}", dim, "test");
      int it = 0;
      RefineResult r;
      for (; it < 300; ++it) {
        const Mesh before = m;
        r = refine(m, select_cells(m, *region));
        if (r.precision_reached) {
          REQUIRE(r.limit_reached);
          REQUIRE(m.cells == before.cells);
          REQUIRE(m.coords == before.coords);
          REQUIRE(m.tag == before.tag);
          break;
        }
      }
      INFO(dim << "D at offset " << offset << ": stopped after " << it << " iterations");
      REQUIRE(r.precision_reached);
      REQUIRE(it > 20);
      REQUIRE_CONFORMING(m, inv);
      // Every edge of the mesh is still resolved.
      for (std::size_t c = 0; c < m.num_cells(); ++c)
        for (int i = 0; i <= dim; ++i)
          for (int j = i + 1; j <= dim; ++j) {
            const double *p = m.point(m.cell(CellId(c))[i]), *q = m.point(m.cell(CellId(c))[j]);
            double ext = 0, mag = 0;
            for (int k = 0; k < dim; ++k) {
              ext = std::max(ext, std::abs(p[k] - q[k]));
              mag = std::max({mag, std::abs(p[k]), std::abs(q[k])});
            }
            REQUIRE(ext >= kRelativeResolution * mag / 4);
          }
    }
  }
}

TEST_CASE("pinched meshes: cells meeting only at a vertex or an edge are accepted, refined and "
          "checked like any other",
          "[refine][check][2d][3d]") {
  struct Case {
    const char *name;
    int dim;
    std::vector<double> coords;
    std::vector<VertexId> cells;
  };
  const Case cases[] = {
      {"2D: two triangles sharing a vertex",
       2,
       {0, 0, 1, 0, 0, 1, -1, 0, 0, -1},
       {0, 1, 2, 0, 3, 4}},
      {"3D: two tets sharing a vertex",
       3,
       {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1},
       {0, 1, 2, 3, 0, 4, 5, 6}},
      {"3D: two tets sharing an edge",
       3,
       {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 1, 0, -1, 0, 0.5, 0, -1, 0.5},
       {0, 1, 2, 3, 0, 1, 4, 5}},
  };
  for (const Case &k : cases)
    for (Marking marking : {Marking::Index, Marking::Longest, Marking::Sorted}) {
      INFO(k.name << ", marking " << marking_name(marking));
      Mesh m;
      m.dim = k.dim;
      m.coords = k.coords;
      m.cells = k.cells;
      REQUIRE_NOTHROW(prepare_input(m, "pinched.vtu"));
      mark_mesh(m, marking);
      const Invariants inv = measure_invariants(m);
      REQUIRE(inv.euler == 1); // a wedge of two balls is contractible
      REQUIRE_CONFORMING(m, inv);
      refine_uniform(m);
      REQUIRE_CONFORMING(m, inv);
      // Around the pinch point, then elsewhere: the closure crosses the pinch.
      for (const char *centre : {"0", "0.3"}) {
        std::string spec = R"({"type": "sphere", "radius": 0.2, "center": [)";
        for (int d = 0; d < k.dim; ++d)
          spec += std::string(d ? ", " : "") + centre;
        auto region = parse_region(spec + "]}", k.dim, "test");
        for (int it = 0; it < 4; ++it) {
          refine(m, select_cells(m, *region));
          REQUIRE_CONFORMING(m, inv);
          REQUIRE(check_refined(m, inv).ok);
        }
      }
      // Written state reads back as consistent.
      Mesh copy = m;
      encode_state(copy);
      prepare_input(copy, "pinched.vtu");
      REQUIRE(decode_state(copy, "pinched.vtu"));
    }
}

namespace {

// The cells of m as sorted tuples of their vertices' coordinates.
std::vector<std::vector<double>> cells_by_coordinates(const Mesh &m) {
  std::vector<std::vector<double>> cells;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    std::vector<std::vector<double>> pts;
    for (int i = 0; i <= m.dim; ++i)
      pts.emplace_back(m.point(m.cell(CellId(c))[i]), m.point(m.cell(CellId(c))[i]) + m.dim);
    std::sort(pts.begin(), pts.end());
    std::vector<double> key;
    for (const auto &p : pts)
      key.insert(key.end(), p.begin(), p.end());
    cells.push_back(key);
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

} // namespace

TEST_CASE("refine with edges to split: bisecting the edges a selection bisected gives its mesh",
          "[refine][split]") {
  // What distributed refinement relies on (distributed.hpp): the smallest
  // conforming refinement that bisects given edges. Splitting exactly the
  // edges a serial refinement bisected gives the serial mesh.
  for (const char *name : {"square.msh", "ball.msh"}) {
    for (Marking mk : kMarkings) {
      INFO(name << ", marking " << marking_name(mk));
      Mesh m0 = load(name);
      mark_mesh(m0, mk);
      m0.entities.clear();
      const Invariants inv = measure_invariants(m0);
      Mesh serial = m0;
      const std::size_t nv0 = serial.num_vertices();
      const std::vector<CellId> sel{0, CellId(serial.num_cells() / 2)};
      refine(serial, sel);
      std::vector<std::array<VertexId, 2>> edges;
      for (std::size_t v = nv0; v < serial.num_vertices(); ++v)
        if (serial.parent_edge[2 * v] < nv0 && serial.parent_edge[2 * v + 1] < nv0)
          edges.push_back({serial.parent_edge[2 * v], serial.parent_edge[2 * v + 1]});
      REQUIRE(edges.size() >= 2);
      Mesh split = m0;
      const RefineResult r = refine(split, {}, edges);
      REQUIRE(!r.limit_reached);
      REQUIRE_CONFORMING(split, inv);
      REQUIRE(cells_by_coordinates(split) == cells_by_coordinates(serial));
      // The same mesh when the closure walks around the split edges' cells
      // in every pass instead of scanning.
      testing::set_walk_around(1);
      Mesh walked = m0;
      refine(walked, {}, edges);
      testing::set_walk_around(0);
      require_same_mesh(walked, split);
      // The split edges are gone: no cell holds both ends of one.
      bool held = false;
      for (std::size_t c = 0; c < split.num_cells(); ++c)
        for (const auto &e : edges) {
          const VertexId *x = split.cell(CellId(c));
          const bool a = std::find(x, x + split.dim + 1, e[0]) != x + split.dim + 1;
          const bool b = std::find(x, x + split.dim + 1, e[1]) != x + split.dim + 1;
          held |= a && b;
        }
      REQUIRE(!held);
      // An edge no cell holds (two far apart vertices) changes nothing.
      Mesh none = m0;
      VertexId far = 0;
      double best = 0;
      for (std::size_t v = 1; v < none.num_vertices(); ++v) {
        double d2 = 0;
        for (int k = 0; k < none.dim; ++k)
          d2 += std::pow(none.point(VertexId(v))[k] - none.point(0)[k], 2);
        if (d2 > best) {
          best = d2;
          far = VertexId(v);
        }
      }
      refine(none, {}, {{0, far}});
      REQUIRE(none.num_cells() == m0.num_cells());
      REQUIRE(none.num_vertices() == m0.num_vertices());
    }
  }
}

// ---- the parallel kernel (refine.cpp, Refiner::bisect_all) ----

namespace {

// Runs `iterations` rounds (a region's selection, or every cell when the
// region is empty) with the kernel in `mode` (testing::set_parallel_bisection)
// on `threads` threads.
Mesh run_kernel(Mesh m, const std::string &region_json, int iterations, int mode, int threads) {
  testing::set_parallel_bisection(mode);
  set_threads(threads);
  std::unique_ptr<Region> region;
  if (!region_json.empty())
    region = parse_region(region_json, m.dim, "test");
  for (int it = 0; it < iterations; ++it) {
    std::vector<CellId> sel;
    if (region)
      sel = select_cells(m, *region);
    else
      for (std::size_t c = 0; c < m.num_cells(); ++c)
        sel.push_back(CellId(c));
    refine(m, sel);
  }
  testing::set_parallel_bisection(0);
  set_threads(0);
  return m;
}

struct KernelCase {
  const char *name;
  Mesh mesh;
  std::string region; // empty: every cell
  int iterations;
};

// Local refinement in 2D, 3D (passes of several thousand cells: several of
// the parallel kernel's blocks) and 4D, and with `uniform` every cell too.
std::vector<KernelCase> kernel_cases(bool uniform) {
  std::vector<KernelCase> cases;
  cases.push_back({"square, sphere", load("square.msh"),
                   R"({"type":"sphere","center":[0.5,0.5],"radius":0.3})", 8});
  if (uniform)
    cases.push_back({"square, uniform", load("square.msh"), "", 3});
  cases.push_back(
      {"ball, hemisphere", load("ball.msh"),
       R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,"normal":[1,0,0],"offset":0.5})",
       4});
  if (uniform)
    cases.push_back({"ball, uniform", load("ball.msh"), "", 2});
  cases.push_back({"4D cube, sphere", generate_kuhn(4, 2),
                   R"({"type":"sphere","center":[0.3,0.3,0.3,0.3],"radius":0.4})", 10});
  if (uniform)
    cases.push_back({"4D cube, uniform", generate_kuhn(4, 3), "", 2});
  return cases;
}

// f(case, marked mesh, its invariants) for every case and marking.
template <class F> void for_each_marked(const std::vector<KernelCase> &cases, F &&f) {
  for (const KernelCase &c : cases)
    for (Marking mk : kMarkings) {
      INFO(c.name << ", marking " << marking_name(mk));
      Mesh m = c.mesh;
      mark_mesh(m, mk);
      f(c, m, measure_invariants(m));
    }
}

} // namespace

TEST_CASE("parallel kernel: bisecting a pass's cells on all threads gives the serial loop's mesh "
          "bit for bit",
          "[refine][threads][2d][3d][4d]") {
  const std::vector<KernelCase> cases = kernel_cases(true);
  // The Gmsh meshes carry tagged boundary facets, which split with the cells.
  REQUIRE(!cases[0].mesh.entities.empty());
  REQUIRE(!cases[2].mesh.entities.empty());
  std::size_t retries = 0;
  for_each_marked(cases, [&](const KernelCase &c, const Mesh &m, const Invariants &inv) {
    const Mesh serial = run_kernel(m, c.region, c.iterations, -1, 1);
    REQUIRE(serial.num_cells() > 2 * m.num_cells());
    for (int threads : {1, 2, 3}) {
      INFO(threads << " threads");
      const Mesh parallel = run_kernel(m, c.region, c.iterations, 1, threads);
      require_same_mesh(parallel, serial);
    }
    // Passes that overflow the midpoint table claim their edges again.
    testing::set_midpoint_room(64);
    const Mesh retried = run_kernel(m, c.region, c.iterations, 1, 2);
    retries += testing::midpoint_retries();
    testing::set_midpoint_room(0);
    require_same_mesh(retried, serial);
    REQUIRE_CONFORMING(serial, inv);
  });
  REQUIRE(retries > 0);
}

TEST_CASE("vector scan: the closure's scan eight cells at a time gives the one-at-a-time scan's "
          "mesh bit for bit",
          "[refine][2d][3d][4d]") {
  if (!testing::set_vector_scan(true))
    WARN("this processor has no AVX2: only the one-at-a-time scan ran");
  for_each_marked(kernel_cases(false),
                  [&](const KernelCase &c, const Mesh &m, const Invariants &inv) {
                    testing::set_vector_scan(false);
                    const Mesh one = run_kernel(m, c.region, c.iterations, -1, 1);
                    testing::set_vector_scan(true);
                    for (int threads : {1, 2}) {
                      INFO(threads << " threads");
                      const Mesh eight = run_kernel(m, c.region, c.iterations, 0, threads);
                      require_same_mesh(eight, one);
                    }
                    REQUIRE(one.num_cells() > 4 * m.num_cells());
                    REQUIRE_CONFORMING(one, inv);
                  });
  testing::set_vector_scan(true);
}

TEST_CASE("walk around: finding the next pass's cells around each bisected edge gives the "
          "scan's mesh bit for bit",
          "[refine][2d][3d][4d]") {
  std::size_t walks = testing::walks();
  for_each_marked(kernel_cases(true),
                  [&](const KernelCase &c, const Mesh &m, const Invariants &inv) {
                    testing::set_walk_around(-1);
                    const Mesh scanned = run_kernel(m, c.region, c.iterations, -1, 1);
                    REQUIRE(testing::walks() == walks);
                    testing::set_walk_around(1);
                    for (int threads : {1, 2}) {
                      INFO(threads << " threads");
                      const Mesh walked = run_kernel(m, c.region, c.iterations, 0, threads);
                      require_same_mesh(walked, scanned);
                      REQUIRE(testing::walks() >= walks + std::size_t(c.iterations));
                      walks = testing::walks();
                    }
                    REQUIRE(scanned.num_cells() > 2 * m.num_cells());
                    REQUIRE_CONFORMING(scanned, inv);
                  });
  testing::set_walk_around(0);
}

TEST_CASE("parallel kernel: a cell past 65535 generations is refused as in the serial loop",
          "[refine][threads][2d]") {
  Mesh m = generate_kuhn(2, 8);
  mark_mesh(m, Marking::Index);
  refine(m, {}); // starts the tree
  m.generation[77] = std::numeric_limits<std::uint16_t>::max();
  for (int mode : {-1, 1}) {
    INFO("mode " << mode);
    testing::set_parallel_bisection(mode);
    Mesh copy = m;
    std::vector<CellId> all(copy.num_cells());
    for (std::size_t c = 0; c < all.size(); ++c)
      all[c] = CellId(c);
    REQUIRE_THROWS_WITH(refine(copy, all), "a cell would pass 65535 generations of bisection");
  }
  testing::set_parallel_bisection(0);
}
