// Coarsening along the bisection tree (coarsen.cpp, ALGORITHMS.md §10): refine
// locally N times, coarsen N passes, get the input back exactly; partial
// coarsening conforms; refining again gives what refining the input gives;
// the tree survives files.
#include "bisect/coarsen.hpp"
#include "bisect/colour.hpp"
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/state.hpp"
#include "bisect/threads.hpp"
#include "engine/coarsen_pass.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

using namespace bisect;

namespace {

using Point = std::vector<double>;
using CellShape = std::vector<Point>; // a cell as the sorted coordinates of its vertices

std::vector<CellShape> cell_shapes(const Mesh &m) {
  std::vector<CellShape> out(m.num_cells());
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const VertexId *x = m.cell(CellId(c));
    for (int i = 0; i < m.cell_size(); ++i)
      out[c].emplace_back(m.point(x[i]), m.point(x[i]) + m.dim);
    std::sort(out[c].begin(), out[c].end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Point> vertex_set(const Mesh &m) {
  std::vector<Point> out;
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    out.emplace_back(m.point(VertexId(v)), m.point(VertexId(v)) + m.dim);
  std::sort(out.begin(), out.end());
  return out;
}

// Delaunay mesh of the unit cube's corners and `extra` random inner points.
Mesh random_delaunay(int dim, int extra, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  std::vector<double> pts;
  for (int c = 0; c < (1 << dim); ++c)
    for (int k = 0; k < dim; ++k)
      pts.push_back((c >> k) & 1);
  for (int i = 0; i < extra; ++i)
    for (int k = 0; k < dim; ++k)
      pts.push_back(u(rng));
  double spacing = 1;
  const std::size_t n = pts.size() / std::size_t(dim);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      double s = 0;
      for (int k = 0; k < dim; ++k)
        s += std::pow(pts[dim * a + k] - pts[dim * b + k], 2);
      spacing = std::min(spacing, std::sqrt(s));
    }
  Mesh m = delaunay(dim, pts, spacing);
  prepare_input(m, "delaunay");
  return m;
}

// Shuffles the cell order (with the state, when marked).
Mesh shuffled_cells(const Mesh &in, std::uint64_t seed) {
  Mesh m = in;
  std::vector<std::size_t> perm(in.num_cells());
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(perm.begin(), perm.end(), rng);
  const int n = in.cell_size();
  for (std::size_t c = 0; c < perm.size(); ++c) {
    std::copy(in.cell(CellId(perm[c])), in.cell(CellId(perm[c])) + n, m.cell(CellId(c)));
    if (in.marked()) {
      m.stage[c] = in.stage[perm[c]];
      m.tag[c] = in.tag[perm[c]];
    }
  }
  m.cell_data.clear();
  return m;
}

// The input: an unstructured mesh, renumbered and shuffled, marked.
Mesh input_mesh(int dim, Marking marking, std::uint64_t seed) {
  Mesh m = random_delaunay(dim, dim == 4 ? 8 : dim == 3 ? 30 : 40, seed);
  m = shuffled_cells(testing::renumbered(m, seed * 31 + 7), seed * 17 + 3);
  mark_mesh(m, marking);
  return m;
}

// 4D by colour extrusion (what `bisect extrude` makes): a barycentric
// subdivision of a small 3D Delaunay mesh, coloured, times 2 slabs.
Mesh extruded_input(std::uint64_t seed) {
  Mesh m3 = random_delaunay(3, 2, seed);
  std::vector<std::uint8_t> colour;
  Mesh b = barycentric_subdivision(m3, &colour);
  // Marked as made (Maubach tuples): prepare_input would reorient, i.e.
  // change, the tuples.
  Mesh m = extrude_coloured(b, colour, {0.0, 0.5, 1.0});
  return shuffled_cells(testing::renumbered(m, seed + 5), seed + 9);
}

// Cells whose centroid lies within `radius` of (0.3, 0.3, ...).
std::vector<CellId> near_corner(const Mesh &m, double radius) {
  std::vector<CellId> out;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const VertexId *x = m.cell(CellId(c));
    double d2 = 0;
    for (int k = 0; k < m.dim; ++k) {
      double s = 0;
      for (int i = 0; i < m.cell_size(); ++i)
        s += m.point(x[i])[k];
      d2 += std::pow(s / m.cell_size() - 0.3, 2);
    }
    if (d2 < radius * radius)
      out.push_back(CellId(c));
  }
  return out;
}

void refine_locally(Mesh &m, int iterations) {
  for (int it = 0; it < iterations; ++it) {
    RefineResult r = refine(m, near_corner(m, m.dim == 4 ? 0.25 : 0.3));
    REQUIRE_FALSE(r.limit_reached);
  }
}

// passes 0: until a pass removes nothing.
CoarsenResult coarsen_all(Mesh &m, int passes) {
  CoarsenOptions o;
  o.passes = passes;
  return coarsen(m, std::vector<char>(m.num_cells(), 1), o);
}

struct Case {
  std::string name;
  Mesh mesh;
  int iterations;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (Marking mk : {Marking::Index, Marking::Longest, Marking::Sorted})
    for (int dim : {2, 3, 4})
      for (std::uint64_t seed : {1, 2}) {
        const int n = dim == 4 ? 3 : dim == 3 ? int(3 + seed) : int(4 + seed); // 3..6
        out.push_back(
            {std::to_string(dim) + "D " + marking_name(mk) + " seed " + std::to_string(seed),
             input_mesh(dim, mk, seed), n});
      }
  out.push_back({"4D extruded", extruded_input(3), 3});
  return out;
}

} // namespace

TEST_CASE("coarsen: N passes after N local refinements give the input's cells and vertices back",
          "[coarsen][2d][3d][4d]") {
  for (Case &k : cases()) {
    INFO(k.name << ", " << k.iterations << " iterations");
    const Mesh input = k.mesh;
    Mesh m = input;
    refine_locally(m, k.iterations);
    REQUIRE(m.num_cells() > input.num_cells());
    const std::size_t fine_cells = m.num_cells(), fine_vertices = m.num_vertices();
    const CoarsenResult r = coarsen_all(m, k.iterations);
    // A pass undoes at least the newest refinement iteration (more where a
    // bisection of it reused an older midpoint: that vertex goes whole).
    REQUIRE(r.passes <= k.iterations);
    REQUIRE(r.passes >= 1);
    REQUIRE(r.removed_vertices == fine_vertices - input.num_vertices());
    REQUIRE(r.merged_pairs == fine_cells - input.num_cells());
    REQUIRE(m.num_cells() == input.num_cells());
    REQUIRE(m.num_vertices() == input.num_vertices());
    REQUIRE(cell_shapes(m) == cell_shapes(input));
    REQUIRE(vertex_set(m) == vertex_set(input));
    // Survivors keep their relative order, so the ids are the input's.
    REQUIRE(m.coords == input.coords);
    REQUIRE(std::all_of(m.generation.begin(), m.generation.end(), [](auto g) { return g == 0; }));
    REQUIRE(std::all_of(m.parent_edge.begin(), m.parent_edge.end(),
                        [](VertexId v) { return v == kNoVertex; }));
    REQUIRE(check_state_consistency(m).empty());
    // Generation 0 cells and original vertices are never removed.
    REQUIRE(coarsen_all(m, 1).removed_vertices == 0);
  }
}

TEST_CASE("coarsen: one pass after N local refinements removes the newest iteration",
          "[coarsen][2d][3d][4d]") {
  // A pass removes every vertex of the newest level and, where an older
  // level is the newest around a vertex (the last iteration did not reach
  // it), that one too: mostly exactly the mesh of iteration N - 1.
  std::size_t exact = 0, total = 0;
  for (Case &k : cases()) {
    INFO(k.name << ", " << k.iterations << " iterations");
    const Invariants inv = measure_invariants(k.mesh);
    Mesh before = k.mesh;
    refine_locally(before, k.iterations - 1);
    Mesh m = before;
    refine_locally(m, 1);
    if (m.num_vertices() == before.num_vertices())
      continue; // the region selected nothing new in the last iteration
    const std::uint16_t newest = *std::max_element(m.level.begin(), m.level.end());
    REQUIRE(std::count(m.level.begin(), m.level.end(), newest) ==
            std::ptrdiff_t(m.num_vertices() - before.num_vertices()));
    REQUIRE(coarsen_all(m, 1).passes == 1);
    REQUIRE_CONFORMING(m, inv);
    REQUIRE(check_state_consistency(m).empty());
    REQUIRE(m.level.size() == m.num_vertices());
    REQUIRE(*std::max_element(m.level.begin(), m.level.end()) < newest);
    REQUIRE(m.num_cells() <= before.num_cells());
    ++total;
    exact += cell_shapes(m) == cell_shapes(before) && vertex_set(m) == vertex_set(before);
  }
  INFO(exact << " of " << total << " exactly the mesh of iteration N - 1");
  REQUIRE(exact * 4 >= total * 3);
}

TEST_CASE("coarsen: a pass run among some of its vertices, then again among the rest, is the "
          "whole pass",
          "[coarsen][2d][3d][4d]") {
  // What the distributed coarsen relies on (distributed.cpp): each part runs
  // the pass among the vertices no other part holds, then again once the
  // cells around the others are gathered. Here the pass's vertices (made,
  // no newer vertex in their star) are split in two by a plane; the first
  // run takes one side, later runs all that is left, until a run removes
  // nothing. The cells are those of one whole pass.
  for (Case &k : cases()) {
    INFO(k.name << ", " << k.iterations << " iterations");
    const Invariants inv = measure_invariants(k.mesh);
    Mesh m = k.mesh;
    refine_locally(m, k.iterations);
    Mesh whole = m;
    coarsen_all(whole, 1);
    const std::size_t nv = m.num_vertices();
    std::vector<std::uint16_t> around(nv, 0);
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      std::uint16_t top = 0;
      for (int i = 0; i < m.cell_size(); ++i)
        top = std::max(top, m.level[m.cell(CellId(c))[i]]);
      for (int i = 0; i < m.cell_size(); ++i)
        around[m.cell(CellId(c))[i]] = std::max(around[m.cell(CellId(c))[i]], top);
    }
    std::vector<char> eligible(nv), among(nv), removed;
    std::size_t first_side = 0;
    for (std::size_t v = 0; v < nv; ++v) {
      eligible[v] = m.parent_edge[2 * v] != kNoVertex && m.level[v] >= around[v];
      among[v] = eligible[v] && m.point(VertexId(v))[0] < 0.3;
      first_side += among[v];
    }
    std::vector<char> marks(m.num_cells(), 1);
    std::size_t runs = 0, gone = coarsen_pass_among(m, marks, among, {}, removed).removed_vertices;
    for (std::size_t v = 0; v < nv; ++v)
      if (removed[v])
        REQUIRE(among[v]); // only the first side's vertices went
    for (;;) {
      std::vector<char> rest;
      for (std::size_t v = 0; v < removed.size(); ++v)
        if (!removed[v])
          rest.push_back(eligible[v]);
      eligible = rest;
      const std::size_t more = coarsen_pass_among(m, marks, eligible, {}, removed).removed_vertices;
      ++runs;
      if (more == 0)
        break;
      gone += more;
    }
    INFO(first_side << " vertices on the first side, " << runs << " later runs");
    REQUIRE(first_side > 0);
    REQUIRE(gone > first_side / 2);
    REQUIRE_CONFORMING(m, inv);
    REQUIRE(check_state_consistency(m).empty());
    REQUIRE(cell_shapes(m) == cell_shapes(whole));
    REQUIRE(vertex_set(m) == vertex_set(whole));
  }
}

TEST_CASE("coarsen: a cycle of reused midpoints goes together", "[coarsen][3d]") {
  // 3D longest marking, seed 1, 3 iterations: around one vertex seven
  // midpoints each wait for the next (a cell of one's star was bisected at
  // the next, a midpoint made earlier in the same iteration), so none can be
  // removed alone; they are removed as a group.
  Mesh input = input_mesh(3, Marking::Longest, 1);
  const Invariants inv = measure_invariants(input);
  Mesh m = input;
  refine_locally(m, 3);
  CoarsenOptions o;
  o.passes = 3;
  Mesh partial = m;
  coarsen(m, std::vector<char>(m.num_cells(), 1), o);
  REQUIRE(cell_shapes(m) == cell_shapes(input));
  REQUIRE(vertex_set(m) == vertex_set(input));
  REQUIRE_CONFORMING(m, inv);
  // Partly marked around the cycle: whatever goes, the mesh conforms.
  std::vector<char> marks(partial.num_cells(), 0);
  for (std::size_t c = 0; c < marks.size(); c += 2)
    marks[c] = 1;
  coarsen(partial, marks, o);
  REQUIRE_CONFORMING(partial, inv);
  REQUIRE(check_state_consistency(partial).empty());
  refine_locally(partial, 1);
  REQUIRE_CONFORMING(partial, inv);
}

TEST_CASE("coarsen: partial coarsening of a region conforms", "[coarsen][2d][3d][4d]") {
  std::size_t partial = 0; // cases where the region removed some but not all
  for (Case &k : cases()) {
    INFO(k.name);
    const Invariants inv = measure_invariants(k.mesh);
    Mesh m = k.mesh;
    refine_locally(m, k.iterations);
    const std::size_t fine = m.num_cells();
    // Part of the refined zone: cells whose centroid has x < 0.4.
    std::vector<char> marks(m.num_cells(), 0);
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      double x = 0;
      for (int i = 0; i < m.cell_size(); ++i)
        x += m.point(m.cell(CellId(c))[i])[0];
      marks[c] = x / m.cell_size() < 0.4;
    }
    CoarsenOptions o;
    o.passes = 0;
    const CoarsenResult r = coarsen(m, marks, o);
    REQUIRE(m.num_cells() == fine - r.merged_pairs);
    partial += r.merged_pairs > 0 && m.num_cells() > k.mesh.num_cells();
    REQUIRE_CONFORMING(m, inv);
    REQUIRE(check_state_consistency(m).empty());
    // Refining it again conforms; coarsening the rest gives the input.
    Mesh again = m;
    refine_locally(again, 1);
    REQUIRE_CONFORMING(again, inv);
    coarsen_all(m, 0);
    REQUIRE(cell_shapes(m) == cell_shapes(k.mesh));
  }
  REQUIRE(partial >= 10);
}

TEST_CASE("coarsen: refining after coarsening gives the cells refining the input gives",
          "[coarsen][2d][3d][4d]") {
  for (Case &k : cases()) {
    INFO(k.name);
    const Invariants inv = measure_invariants(k.mesh);
    Mesh direct = k.mesh;
    refine_locally(direct, k.iterations);
    // One pass back, one iteration forward: the same cells again.
    Mesh one = direct;
    coarsen_all(one, 1);
    REQUIRE(one.num_cells() < direct.num_cells());
    REQUIRE_CONFORMING(one, inv);
    Mesh m = direct;
    coarsen_all(m, 0);
    refine_locally(m, k.iterations);
    REQUIRE(cell_shapes(m) == cell_shapes(direct));
  }
}

TEST_CASE("coarsen: the tree survives a .vtu and a .msh file", "[coarsen][io]") {
  const auto dir = std::filesystem::temp_directory_path() / "bisect_test_coarsen";
  std::filesystem::create_directories(dir);
  for (Case &k : cases()) {
    INFO(k.name);
    Mesh m = k.mesh;
    refine_locally(m, k.iterations);
    for (const char *ext : {".vtu", ".msh"}) {
      if (m.dim == 4 && std::string(ext) == ".msh")
        continue;
      const std::string path = (dir / (std::string("refined") + ext)).string();
      save_mesh(path, m);
      Mesh back = load_mesh(path);
      REQUIRE(back.generation == m.generation);
      REQUIRE(back.parent_edge == m.parent_edge);
      REQUIRE(back.point_data.size() == m.point_data.size());
      coarsen_all(back, 0);
      REQUIRE(cell_shapes(back) == cell_shapes(k.mesh));
    }
    // Generations and levels past 255 come back as they were.
    for (std::uint16_t &g : m.generation)
      g = std::uint16_t(g + 300);
    for (std::uint16_t &l : m.level)
      l = l == 0 ? l : std::uint16_t(l + 300); // made vertices

    const std::string path = (dir / "high.vtu").string();
    save_mesh(path, m);
    Mesh back = load_mesh(path);
    CHECK(back.generation == m.generation);
    CHECK(back.level == m.level);
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("coarsen: a simplex of a forced type comes back after N refinements through files",
          "[coarsen][3d][4d][io]") {
  // `generate simplex --type T`, `refine -n N` everywhere, `coarsen --all -n
  // N`, each through a file as the CLI goes: the explicit edge order must
  // survive the refined file, whose cells no longer hold the split edges
  // (their ranks decide the Stage 1 parents coarsening rebuilds).
  const auto dir = std::filesystem::temp_directory_path() / "bisect_test_coarsen_forced";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "mesh.vtu").string();
  // One thread: these meshes are tiny, and waking a team for each of the
  // writers' and checks' loops costs most of the time on a busy machine
  // (results do not depend on the count, threads.hpp).
  set_threads(1);
  auto through_file = [&](Mesh &m) {
    save_mesh(path, m);
    m = load_mesh(path);
  };
  const std::vector<std::string> tets = {"P", "A", "O", "M"};
  const std::vector<std::string> pentatopes = {
      "A_AA", "A_AM", "A_AO", "A_MM", "A_OM", "A_PA", "A_PM", "A_PO", "A_PP", "M_AA",
      "M_AM", "M_AO", "M_MM", "M_OM", "M_OO", "M_PA", "M_PM", "M_PO", "M_PP", "O_AA",
      "O_AM", "O_AO", "O_MM", "O_OM", "O_OO", "O_PA", "O_PM", "O_PO", "O_PP", "P_AA",
      "P_AM", "P_MM", "P_OM", "P_OO", "P_PA", "P_PM", "P_PP"};
  for (const int dim : {3, 4})
    for (const SimplexShape shape :
         {SimplexShape::Equilateral, SimplexShape::Cartesian, SimplexShape::Random})
      for (const std::string &type : dim == 3 ? tets : pentatopes) {
        Mesh input = generate_simplex(dim, shape);
        force_type(input, type);
        through_file(input);
        const Invariants inv = measure_invariants(input);
        Mesh once = input;
        refine_uniform(once);
        Mesh m = input;
        // (Without the split edges' ranks in the file, N = 1 already
        // failed; the 111 pentatopes are kept to a few iterations.)
        const int iterations = dim == 3 ? 6 : shape == SimplexShape::Random ? 4 : 2;
        for (int n = 1; n <= iterations; ++n) {
          INFO(dim << "D " << type << " shape " << int(shape) << ", " << n << " iterations");
          refine_uniform(m);
          Mesh c = m;
          through_file(c);
          REQUIRE_CONFORMING(c, inv);
          // In memory and from the file alike.
          for (Mesh *k : {&m, &c}) {
            Mesh back = *k;
            const CoarsenResult r = coarsen_all(back, n);
            REQUIRE(r.removed_vertices == k->num_vertices() - input.num_vertices());
            REQUIRE(back.num_cells() == 1);
            REQUIRE(back.num_vertices() == input.num_vertices());
            REQUIRE(back.coords == input.coords);
            REQUIRE(cell_shapes(back) == cell_shapes(input));
            REQUIRE_CONFORMING(back, inv);
            // The forced order came back whole: refining again gives what
            // refining the input gives.
            through_file(back);
            REQUIRE(back.edge_rank == input.edge_rank);
            refine_uniform(back);
            REQUIRE(cell_shapes(back) == cell_shapes(once));
          }
        }
      }
  set_threads(0);
  std::filesystem::remove_all(dir);
}

TEST_CASE("coarsen: cell arrays take the common value, the mean, or the sum", "[coarsen]") {
  Mesh m = input_mesh(3, Marking::Longest, 4);
  const std::size_t nc = m.num_cells();
  DataArray id{"id", 1, {}}, count{"count", 1, std::vector<double>(nc, 1.0)};
  for (std::size_t c = 0; c < nc; ++c)
    id.values.push_back(double(c));
  m.cell_data = {id, count};
  Mesh fine = m;
  refine_locally(fine, 4);
  // Make the children of the first pass differ: the mean of 0 and 2 is 1.
  DataArray odd{"odd", 1, std::vector<double>(fine.num_cells(), 0.0)};
  fine.cell_data.push_back(odd);
  CoarsenOptions o;
  o.passes = 0;
  o.sum_arrays = {"count"};
  coarsen(fine, std::vector<char>(fine.num_cells(), 1), o);
  REQUIRE(fine.num_cells() == nc);
  // Parents come back in their slots: cell order and the inherited ids agree.
  REQUIRE(fine.cell_data[0].values == id.values);
  // count: summed over the 2^g descendants of each input cell.
  double total = 0;
  for (double v : fine.cell_data[1].values)
    total += v;
  Mesh counted = m;
  refine_locally(counted, 4);
  REQUIRE(total == double(counted.num_cells()));
  REQUIRE(std::all_of(fine.cell_data[2].values.begin(), fine.cell_data[2].values.end(),
                      [](double v) { return v == 0; }));
  // A name the mesh lacks is an error, not an array left to the default rule.
  Mesh again = m;
  refine_locally(again, 2);
  const Mesh before = again;
  for (bool sum : {true, false}) {
    CoarsenOptions bad;
    (sum ? bad.sum_arrays : bad.min_arrays) = {"cuont"};
    REQUIRE_THROWS_WITH(coarsen(again, std::vector<char>(again.num_cells(), 1), bad),
                        Catch::Contains("no cell array 'cuont'") &&
                            Catch::Contains("'id', 'count'"));
    REQUIRE(again.cells == before.cells);
  }
}

TEST_CASE("coarsen: unmarked cells and a file without the tree stop it", "[coarsen][io]") {
  Mesh m = input_mesh(2, Marking::Index, 5);
  Mesh fine = m;
  refine_locally(fine, 3);
  Mesh none = fine;
  REQUIRE(coarsen(none, std::vector<char>(none.num_cells(), 0)).removed_vertices == 0);
  REQUIRE(none.cells == fine.cells);
  // A file without the tree arrays: generation 0, original vertices.
  encode_state(fine);
  strip_tree(fine);
  Mesh back = fine;
  REQUIRE(decode_state(back, "f.vtu"));
  REQUIRE_FALSE(back.has_tree());
  REQUIRE(coarsen_all(back, 3).removed_vertices == 0);
}

TEST_CASE("coarsen: bad tree arrays are input errors naming the file and the array",
          "[coarsen][io]") {
  Mesh m = input_mesh(2, Marking::Sorted, 6);
  refine_locally(m, 2);
  const std::size_t nv = m.num_vertices();
  auto expect_error = [&](const char *array, double value, std::size_t v, const char *what) {
    Mesh e = m;
    encode_state(e);
    for (auto *arrays : {&e.cell_data, &e.point_data})
      for (DataArray &a : *arrays)
        if (a.name == array)
          a.values[v] = value;
    try {
      decode_state(e, "bad.vtu");
      FAIL("no error for " << array << " = " << value);
    } catch (const InputError &err) {
      const std::string msg = err.what();
      INFO(msg);
      CHECK(msg.find("bad.vtu") != std::string::npos);
      CHECK(msg.find(array) != std::string::npos);
      CHECK(msg.find(what) != std::string::npos);
    }
  };
  expect_error(kParentAArray, double(nv), nv - 1, "not an integer in");
  expect_error(kParentAArray, 0.5, nv - 1, "not an integer in");
  expect_error(kParentBArray, -1, nv - 1, "both");
  expect_error(kParentAArray, double(nv - 1), nv - 1, "larger id");
  expect_error(kParentAArray, 0, 0, "both");
  expect_error(kGenerationArray, -2, 0, "not an integer in");
  expect_error(kGenerationArray, 70000, 0, "not an integer in");
  // A vertex that is not the midpoint of the edge it claims.
  Mesh e = m;
  encode_state(e);
  for (DataArray &a : e.point_data)
    if (a.name == kParentBArray) {
      for (std::size_t v = nv - 1;; --v)
        if (a.values[v] >= 0) {
          const double old = a.values[v];
          a.values[v] = old == 0 ? 1 : 0;
          break;
        }
    }
  REQUIRE_THROWS_AS(decode_state(e, "bad.vtu"), InputError);
  // bisect:parent_rank (explicit marking): a rank for an original vertex,
  // not an integer in -1..2^32-2.
  Mesh forced = generate_simplex(3, SimplexShape::Cartesian);
  force_type(forced, "O");
  refine_uniform(forced);
  auto expect_rank_error = [&](std::size_t v, double value, const char *what) {
    Mesh f = forced;
    encode_state(f);
    for (DataArray &a : f.point_data)
      if (a.name == kParentRankArray)
        a.values[v] = value;
    try {
      decode_state(f, "bad.vtu");
      FAIL("no error for " << kParentRankArray << " = " << value << " at " << v);
    } catch (const InputError &err) {
      const std::string msg = err.what();
      INFO(msg);
      CHECK(msg.find("bad.vtu") != std::string::npos);
      CHECK(msg.find(kParentRankArray) != std::string::npos);
      CHECK(msg.find(what) != std::string::npos);
    }
  };
  REQUIRE(forced.num_vertices() == 5);
  expect_rank_error(0, 0, "original vertex");
  expect_rank_error(4, 0.5, "not an integer in");
  expect_rank_error(4, -2, "not an integer in");
}
