// Space-time extrusion by colour (seed 001): eq. 5 / eq. 9 tuples, Stevenson's
// bisection equals Maubach's, conformity of local refinement, similarity
// classes, and the closure cost of colour order against plain id order.
#include "bisect/colour.hpp"
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/slice.hpp"
#include "bisect/state.hpp"
#include "core/numbering.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <random>
#include <set>
#include <unistd.h>

using namespace bisect;

namespace {

// ------------------------------------------- Stevenson's rule (test only) ---

// Seed 001 Def. 6, for any n: (x0..xn)_g with refinement edge (x0, xn),
// g' = (g + 1) mod n, children (x0, z, x1, ..., x(n-1))_g' and
// (xn, z, x1, ..., xg, x(n-1), ..., x(g+1))_g'. For n = 4 this is eq. 8.
using MidpointIds = std::map<std::pair<VertexId, VertexId>, VertexId>;

VertexId midpoint_id(MidpointIds &mids, VertexId a, VertexId b) {
  auto key = std::minmax(a, b);
  return mids.emplace(std::pair(key.first, key.second), VertexId(1000 + mids.size())).first->second;
}

struct Tagged {
  std::vector<VertexId> x;
  int tag;
};

std::array<Tagged, 2> stevenson_children(const Tagged &t, MidpointIds &mids) {
  const int n = int(t.x.size()) - 1, g = t.tag;
  const VertexId z = midpoint_id(mids, t.x[0], t.x[n]);
  Tagged c1{{t.x[0], z}, (g + 1) % n}, c2{{t.x[n], z}, (g + 1) % n};
  for (int i = 1; i < n; ++i)
    c1.x.push_back(t.x[i]);
  for (int i = 1; i <= g; ++i)
    c2.x.push_back(t.x[i]);
  for (int i = n - 1; i > g; --i)
    c2.x.push_back(t.x[i]);
  return {c1, c2};
}

template <int Dim> std::array<Tagged, 2> maubach(const Tagged &t, MidpointIds &mids) {
  VertexId c1[Dim + 1], c2[Dim + 1];
  const VertexId z = midpoint_id(mids, t.x[0], t.x[t.tag]);
  maubach_children<Dim>(t.x.data(), t.tag, z, c1, c2);
  const int tag = maubach_child_tag(t.tag, Dim);
  return {Tagged{{c1, c1 + Dim + 1}, tag}, Tagged{{c2, c2 + Dim + 1}, tag}};
}

// The vertex sets of the leaves after each of `generations` uniform bisections.
template <class Rule>
std::vector<std::set<std::vector<VertexId>>> leaf_sets(Tagged root, int generations,
                                                       MidpointIds &mids, Rule rule) {
  std::vector<Tagged> level{root};
  std::vector<std::set<std::vector<VertexId>>> out;
  for (int g = 0; g < generations; ++g) {
    std::vector<Tagged> next;
    for (const Tagged &t : level)
      for (const Tagged &c : rule(t, mids))
        next.push_back(c);
    level = std::move(next);
    std::set<std::vector<VertexId>> sets;
    for (const Tagged &t : level) {
      std::vector<VertexId> s = t.x;
      std::sort(s.begin(), s.end());
      sets.insert(s);
    }
    out.push_back(std::move(sets));
  }
  return out;
}

template <int Dim> void check_stevenson_is_maubach(int generations) {
  Tagged root{{}, 0};
  for (int i = 0; i <= Dim; ++i)
    root.x.push_back(VertexId(i));
  MidpointIds mids; // shared: the same edge gets the same midpoint id in both
  auto stevenson = leaf_sets(root, generations, mids, stevenson_children);
  Tagged root_n = root;
  root_n.tag = Dim;
  auto maubach_sets = leaf_sets(root_n, generations, mids, maubach<Dim>);
  for (int g = 0; g < generations; ++g) {
    INFO("n = " << Dim << ", generation " << g + 1);
    REQUIRE(stevenson[g].size() == std::size_t(2) << g);
    REQUIRE(stevenson[g] == maubach_sets[g]);
  }
  // The pairing matters: Maubach from tag n-1 is a different refinement.
  Tagged root_other = root;
  root_other.tag = Dim - 1;
  auto other = leaf_sets(root_other, generations, mids, maubach<Dim>);
  REQUIRE(other.back() != stevenson.back());
}

// ----------------------------------------------------------------- meshes ---

Mesh extrude_by_propagation(const Mesh &in, const std::vector<double> &slices) {
  Colouring c = colour_mesh(in);
  INFO(c.why);
  REQUIRE(c.ok);
  return extrude_coloured(in, c.colour, slices);
}

// What a prism mesh must measure: volume V T, boundary 2 V + |dOmega| T,
// the Euler characteristic of the input.
Invariants prism_invariants(const Mesh &in, const std::vector<double> &slices) {
  Invariants base = measure_invariants(in), out;
  const double T = slices.back() - slices.front();
  out.volume = base.volume * T;
  out.boundary_measure = 2 * base.volume + base.boundary_measure * T;
  out.euler = base.euler;
  return out;
}

// A small mesh with no colouring: 5 tets around an interior edge (3D) or 5
// triangles around an interior vertex (2D), jittered and renumbered.
Mesh odd_ring(int dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  Mesh m;
  m.dim = dim;
  if (dim == 3)
    m.coords = {u(rng), u(rng), -1 + u(rng), u(rng), u(rng), 1 + u(rng)};
  else
    m.coords = {u(rng), u(rng)};
  const VertexId first = dim == 3 ? 2 : 1;
  for (int i = 0; i < 5; ++i) {
    double a = 2 * M_PI * i / 5 + u(rng), r = 1 + u(rng);
    m.coords.insert(m.coords.end(), {r * std::cos(a), r * std::sin(a)});
    if (dim == 3)
      m.coords.push_back(u(rng));
  }
  for (VertexId i = 0; i < 5; ++i) {
    if (dim == 3)
      m.cells.insert(m.cells.end(), {0, 1});
    else
      m.cells.push_back(0);
    m.cells.insert(m.cells.end(), {first + i, first + (i + 1) % 5});
  }
  return testing::renumbered(m, seed);
}

// The space-time test meshes: a renumbered Kuhn mesh (colourable as it is)
// and the barycentric subdivision of an odd ring (not colourable before),
// over uneven slices.
struct Case {
  std::string name;
  Mesh input;
  std::vector<double> slices;
};

std::vector<Case> cases(int dim, std::uint64_t seed) {
  const std::vector<std::vector<double>> slices = {
      {0, 0.35, 1}, {0, 0.2, 0.5, 1}, {-0.5, 0, 0.1, 0.6, 1}};
  std::vector<Case> out;
  out.push_back(
      {"kuhn", testing::renumbered(generate_kuhn(dim, dim == 3 ? 2 : 4), seed), slices[seed % 3]});
  out.push_back({"barycentric odd ring", barycentric_subdivision(odd_ring(dim, seed)),
                 slices[(seed + 1) % 3]});
  for (Case &k : out)
    prepare_input(k.input, k.name);
  return out;
}

std::unique_ptr<Region> moving_sphere(int dim) {
  return dim == 4
             ? parse_region(
                   R"({"type":"moving_sphere","center":[0.3,0.4,0.2],"velocity":[0.3,0.2,0.5],"radius":0.3})",
                   4, "test")
             : parse_region(
                   R"({"type":"moving_sphere","center":[0.3,0.4],"velocity":[0.3,0.2],"radius":0.3})",
                   3, "test");
}

// Refines around the moving sphere, then randomly chosen cells, checking
// conformity after every iteration.
void refine_and_check(Mesh m, const Invariants &inv, std::uint64_t seed, int sphere_iterations,
                      int random_iterations) {
  auto region = moving_sphere(m.dim);
  for (int it = 1; it <= sphere_iterations; ++it) {
    refine(m, select_cells(m, *region));
    INFO("moving sphere, iteration " << it << ", " << m.num_cells() << " cells");
    REQUIRE_CONFORMING(m, inv);
  }
  std::mt19937_64 rng(seed);
  for (int it = 1; it <= random_iterations; ++it) {
    std::vector<CellId> pick;
    for (std::size_t c = 0; c < m.num_cells(); ++c)
      if (rng() % 16 == 0)
        pick.push_back(CellId(c));
    refine(m, pick);
    INFO("random cells, iteration " << it << ", " << m.num_cells() << " cells");
    REQUIRE_CONFORMING(m, inv);
  }
}

void check_consistency(std::uint64_t seed, int dim) {
  for (const Case &k : cases(dim, seed)) {
    INFO(dim << "D+t, " << k.name << ", seed " << seed << ", " << k.slices.size() << " slices");
    Mesh m = extrude_by_propagation(k.input, k.slices);
    const Invariants inv = prism_invariants(k.input, k.slices);
    REQUIRE_CONFORMING(m, inv);
    refine_and_check(m, inv, seed, 3, 2);
  }
}

} // namespace

TEST_CASE("Stevenson's bisection from (x0..xn)_0 has Maubach's leaves from (x0..xn)_n",
          "[extrude][colour][2d][3d][4d]") {
  check_stevenson_is_maubach<2>(8);
  check_stevenson_is_maubach<3>(8);
  check_stevenson_is_maubach<4>(8);
}

TEST_CASE(
    "extrusion by colour: one tet gives the tuples of eq. 9, one triangle their 2D+t analogue",
    "[extrude][colour][4d][3d]") {
  // Colours: vertex 0 -> C (2), 1 -> A (0), 2 -> D (3), 3 -> B (1).
  Mesh tet = generate_simplex(3, SimplexShape::Random, 4);
  Mesh st = extrude_coloured(tet, {2, 0, 3, 1}, {0.0, 0.5});
  REQUIRE(st.dim == 4);
  REQUIRE(st.num_vertices() == 8);
  REQUIRE(st.marking == Marking::Sorted);
  const VertexId A = 1, B = 3, C = 0, D = 2, A_ = 5, B_ = 7, C_ = 4, D_ = 6; // ' = +4
  const std::vector<std::array<VertexId, 5>> eq9 = {
      {D, C, B, A, D_}, {C, B, A, D_, C_}, {B, A, D_, C_, B_}, {A, D_, C_, B_, A_}};
  REQUIRE(st.num_cells() == 4);
  for (std::size_t c = 0; c < 4; ++c) {
    INFO("pentatope " << c + 1);
    REQUIRE(std::equal(eq9[c].begin(), eq9[c].end(), st.cell(CellId(c))));
    REQUIRE(st.stage[c] == Stage::Maubach);
    REQUIRE(st.tag[c] == 4);
  }
  for (VertexId v = 0; v < 8; ++v) {
    REQUIRE(st.point(v)[3] == (v < 4 ? 0.0 : 0.5));
    REQUIRE(st.point_data.back().values[v] == (v < 4 ? 0.0 : 1.0)); // "slice"
  }
  double pts[12];
  cell_points(tet, 0, pts);
  REQUIRE(measure_invariants(st).volume ==
          Approx(0.5 * std::abs(signed_volume(pts, 3))).epsilon(1e-12));

  Mesh tri = generate_simplex(2, SimplexShape::Random, 4); // 0 -> B, 1 -> C, 2 -> A
  Mesh st3 = extrude_coloured(tri, {1, 2, 0}, {1.0, 2.0, 4.0});
  REQUIRE(st3.dim == 3);
  REQUIRE(st3.num_cells() == 6);
  const VertexId a = 2, b = 0, c = 1;
  for (VertexId s = 0; s < 2; ++s) {
    const VertexId o = 3 * s, p = 3 * (s + 1);
    const std::vector<std::array<VertexId, 4>> rule = {
        {c + o, b + o, a + o, c + p}, {b + o, a + o, c + p, b + p}, {a + o, c + p, b + p, a + p}};
    for (std::size_t k = 0; k < 3; ++k) {
      REQUIRE(std::equal(rule[k].begin(), rule[k].end(), st3.cell(CellId(3 * s + k))));
      REQUIRE(st3.tag[3 * s + k] == 3);
    }
  }
  REQUIRE(st3.point(7)[2] == 4.0);
}

TEST_CASE("extrusion by colour rejects an improper colouring, bad slices and 4D input",
          "[extrude][colour]") {
  Mesh m = generate_kuhn(3, 1);
  Colouring c = colour_mesh(m);
  REQUIRE(c.ok);
  REQUIRE_NOTHROW(extrude_coloured(m, c.colour, {0, 1}));
  std::vector<std::uint8_t> bad = c.colour;
  bad[m.cell(0)[0]] = bad[m.cell(0)[1]];
  REQUIRE_THROWS_WITH(extrude_coloured(m, bad, {0, 1}), Catch::Contains("not proper"));
  REQUIRE_THROWS_AS(extrude_coloured(m, c.colour, {0}), InputError);
  REQUIRE_THROWS_AS(extrude_coloured(m, c.colour, {1, 0}), InputError);
  // The result's point array "slice" would be written twice.
  Mesh with_slice = m;
  with_slice.point_data.push_back({"slice", 1, std::vector<double>(m.num_vertices(), 1.0)});
  REQUIRE_THROWS_WITH(extrude_coloured(with_slice, c.colour, {0, 1}),
                      Catch::Contains("point array 'slice'"));
  Mesh m4 = generate_kuhn(4, 1);
  REQUIRE_THROWS_WITH(extrude_coloured(m4, std::vector<std::uint8_t>(m4.num_vertices(), 0), {0, 1}),
                      Catch::Contains("2D or 3D"));
}

TEST_CASE("extrusion by colour: the state survives a .vtu round trip and refine continues it",
          "[extrude][colour][4d][io]") {
  Mesh in = testing::renumbered(generate_kuhn(3, 2), 5);
  DataArray id{"source", 1, {}};
  for (std::size_t c = 0; c < in.num_cells(); ++c)
    id.values.push_back(double(c));
  in.cell_data.push_back(id);
  Mesh m = extrude_by_propagation(in, {0, 0.25, 1});
  REQUIRE(m.cell_data.size() == 1);
  for (std::size_t c = 0; c < m.num_cells();
       ++c) // prism cells of slab s, tet t: index (s nc + t) 4 + k
    REQUIRE(m.cell_data[0].values[c] == double((c / 4) % in.num_cells()));
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("bisect_extrude_colour_" + std::to_string(::getpid()) + ".vtu"))
                               .string();
  Mesh w = m;
  encode_state(w);
  write_mesh(path, w);
  Mesh r = read_mesh(path);
  std::filesystem::remove(path);
  prepare_input(r, path);
  REQUIRE(decode_state(r, path));
  REQUIRE(r.marking == Marking::Sorted);
  REQUIRE(r.cells == m.cells);
  REQUIRE(r.tag == m.tag);
  REQUIRE(r.stage == m.stage);
  // Refining the reloaded mesh and the original gives the same cells.
  auto region = moving_sphere(4);
  for (int it = 0; it < 2; ++it) {
    refine(m, select_cells(m, *region));
    refine(r, select_cells(r, *region));
  }
  REQUIRE(r.cells == m.cells);
}

TEST_CASE(
    "label arrays (colour, slice) are not averaged: refinement and slicing mark new vertices -1",
    "[extrude][colour][4d][slice]") {
  Mesh in = testing::renumbered(generate_kuhn(3, 2), 9);
  Colouring c = colour_mesh(in);
  REQUIRE(c.ok);
  set_colour_array(in, c.colour);
  DataArray x{"x", 1, {}}; // a field: still interpolated
  for (std::size_t v = 0; v < in.num_vertices(); ++v)
    x.values.push_back(in.point(VertexId(v))[0]);
  in.point_data.push_back(x);
  Mesh m = extrude_coloured(in, c.colour, {0, 0.5, 1});
  const std::size_t nv0 = m.num_vertices();
  auto array = [](const Mesh &mesh, const std::string &name) -> const DataArray & {
    for (const DataArray &a : mesh.point_data)
      if (a.name == name)
        return a;
    FAIL("no point array " << name);
    throw;
  };
  const std::vector<double> colour0 = array(m, "colour").values, slice0 = array(m, "slice").values;
  auto region = moving_sphere(4);
  for (int it = 0; it < 3; ++it)
    refine(m, select_cells(m, *region));
  REQUIRE(m.num_vertices() > nv0);
  for (const char *name : {"colour", "slice"}) {
    const DataArray &a = array(m, name);
    REQUIRE(a.values.size() == m.num_vertices());
    for (std::size_t v = 0; v < m.num_vertices(); ++v)
      REQUIRE(a.values[v] == (v < nv0 ? (name[0] == 'c' ? colour0 : slice0)[v] : kNoLabel));
  }
  const DataArray &fx = array(m, "x");
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    REQUIRE(fx.values[v] == Approx(m.point(VertexId(v))[0]).margin(1e-12));
  // The colouring of a refined mesh is gone, not wrong.
  REQUIRE_FALSE(colour_array(m));
  // A section between slices: cut points inside edges get -1, points at
  // vertices keep their labels.
  Mesh s = slice_mesh(m, 3, 0.3);
  const DataArray &sl = array(s, "slice"), &sx = array(s, "x");
  REQUIRE(std::all_of(sl.values.begin(), sl.values.end(), [](double v) { return v == kNoLabel; }));
  for (std::size_t v = 0; v < s.num_vertices(); ++v)
    REQUIRE(sx.values[v] == Approx(s.point(VertexId(v))[0]).margin(1e-12));
  Mesh s0 = slice_mesh(m, 3, 0.5); // the middle slice: every cut point is a vertex of slice 1
  const DataArray &sl0 = array(s0, "slice");
  REQUIRE(std::count(sl0.values.begin(), sl0.values.end(), 1.0) > 0);
}

TEST_CASE("extrusion by colour: local refinement stays conforming after every iteration (3D+t)",
          "[extrude][colour][4d]") {
  for (std::uint64_t seed = 1; seed <= 2; ++seed)
    check_consistency(seed, 3);
}

TEST_CASE("extrusion by colour: local refinement stays conforming after every iteration (2D+t)",
          "[extrude][colour][3d]") {
  for (std::uint64_t seed = 1; seed <= 4; ++seed)
    check_consistency(seed, 2);
}

TEST_CASE("extrusion by colour: conforming under many seeds", "[extrude][colour][slow]") {
  for (std::uint64_t seed = 3; seed <= 14; ++seed)
    check_consistency(seed, 3);
  for (std::uint64_t seed = 5; seed <= 30; ++seed)
    check_consistency(seed, 2);
}

TEST_CASE("extrusion by colour: the tagging is consistent, uniform refinement needs no closure",
          "[extrude][colour][4d][3d]") {
  for (int dim : {2, 3})
    for (std::uint64_t seed = 1; seed <= 2; ++seed)
      for (const Case &k : cases(dim, seed)) {
        INFO(dim << "D+t, " << k.name << ", seed " << seed);
        Mesh m = extrude_by_propagation(k.input, k.slices);
        const Invariants inv = prism_invariants(k.input, k.slices);
        for (int g = 1; g <= (dim == 3 ? 4 : 6); ++g) {
          const std::size_t before = m.num_cells();
          RefineResult r = refine_uniform(m);
          INFO("generation " << g);
          REQUIRE(r.closure_passes == 0);
          REQUIRE(m.num_cells() == 2 * before);
        }
        REQUIRE_CONFORMING(m, inv);
      }
}

TEST_CASE("extrusion by colour: one prism refined uniformly has at most 384 classes per pentatope, "
          "period 4",
          "[extrude][colour][4d][quality]") {
  // The cartesian tet's dyadic edge ratios once fell halfway between two
  // steps of similarity_key's rounding grid (387 "classes"): kept as a check.
  for (SimplexShape shape :
       {SimplexShape::Random, SimplexShape::Equilateral, SimplexShape::Cartesian}) {
    Mesh tet = generate_simplex(3, shape, 3);
    Mesh m = extrude_by_propagation(tet, {0.0, 0.8});
    DataArray origin{"origin", 1, {0, 1, 2, 3}};
    m.cell_data.push_back(origin);
    std::vector<std::set<std::vector<long long>>> classes(4);
    std::vector<double> qmin;
    const int generations = 16;
    double pts[20];
    for (int g = 1; g <= generations; ++g) {
      refine_uniform(m);
      REQUIRE(m.num_cells() == std::size_t(4) << g);
      qmin.push_back(quality_summary(m).min);
      if (g > 12)
        continue; // classes over the first 12 generations (16k cells)
      const DataArray &o = m.cell_data.back();
      for (std::size_t c = 0; c < m.num_cells(); ++c) {
        cell_points(m, CellId(c), pts);
        classes[std::size_t(o.values[c])].insert(similarity_key(pts, 4));
      }
    }
    for (int k = 0; k < 4; ++k) {
      INFO("shape " << int(shape) << ", pentatope " << k + 1 << ": " << classes[k].size()
                    << " classes");
      REQUIRE(classes[k].size() <= 384);
    }
    std::cout << "one extruded prism ("
              << (shape == SimplexShape::Random        ? "random"
                  : shape == SimplexShape::Equilateral ? "equilateral"
                                                       : "cartesian")
              << " tet): classes per pentatope " << classes[0].size() << ", " << classes[1].size()
              << ", " << classes[2].size() << ", " << classes[3].size() << "\n";
    // Maubach's cycle: the minimum quality repeats every 4 generations once
    // every class has appeared (generation 6 onwards here).
    for (int k = 5; k + 4 < generations; ++k) {
      INFO("generation " << k + 1);
      REQUIRE(qmin[k] == Approx(qmin[k + 4]).epsilon(1e-9));
    }
  }
}

namespace {

struct Cost {
  std::size_t selected = 0, bisections = 0, passes = 0, max_passes = 0, cells = 0;
  void add(const RefineResult &r) {
    selected += r.selected;
    bisections += r.bisections;
    passes += r.closure_passes;
    max_passes = std::max(max_passes, r.closure_passes);
  }
};

Cost closure_cost(Mesh m, int iterations, const Invariants &inv) {
  Cost cost;
  auto region = moving_sphere(m.dim);
  for (int it = 1; it <= iterations; ++it) {
    cost.add(refine(m, select_cells(m, *region)));
    INFO("iteration " << it);
    REQUIRE_CONFORMING(m, inv);
  }
  cost.cells = m.num_cells();
  return cost;
}

void print_cost(const char *what, const Cost &c, int iterations) {
  std::printf("  %-12s selected %8zu  bisections %9zu  (%.3f per selected)  closure passes %4zu "
              "(%.2f per iteration, max %zu)  cells %zu\n",
              what, c.selected, c.bisections, double(c.bisections) / double(c.selected), c.passes,
              double(c.passes) / iterations, c.max_passes, c.cells);
}

} // namespace

TEST_CASE("extrusion by colour: closure cost of colour order against plain id order",
          "[extrude][colour][4d][3d]") {
  // Prints the comparison; asserts only that both stay conforming.
  for (int dim : {3, 2}) {
    Cost colour, plain;
    const int iterations = dim == 3 ? 4 : 6;
    for (std::uint64_t seed = 1; seed <= 3; ++seed)
      for (const Case &k : cases(dim, seed)) {
        Mesh m = extrude_by_propagation(k.input, k.slices);
        const Invariants inv = prism_invariants(k.input, k.slices);
        Mesh ids = m;
        mark_mesh(ids, Marking::Sorted); // tuples sorted by vertex id instead
        INFO(dim << "D+t, " << k.name << ", seed " << seed);
        Cost a = closure_cost(m, iterations, inv), b = closure_cost(ids, iterations, inv);
        for (Cost *total : {&colour, &plain}) {
          const Cost &c = total == &colour ? a : b;
          total->selected += c.selected;
          total->bisections += c.bisections;
          total->passes += c.passes;
          total->max_passes = std::max(total->max_passes, c.max_passes);
          total->cells += c.cells;
        }
      }
    std::printf("closure cost, %dD+t, 6 meshes x %d moving-sphere iterations:\n", dim, iterations);
    print_cost("colour order", colour, 6 * iterations);
    print_cost("id order", plain, 6 * iterations);
  }
}
