// 4D: random Delaunay meshes, forced mark types, the extruded octant
// (ALGORITHMS.md §4, seed 000 §5.1-5.2).
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <random>

using namespace bisect;

namespace {

// Delaunay mesh of the 16 corners of [0,1]^4 plus `extra` random points
// inside, with random vertex numbering (the corners are not ids 0..15).
Mesh random_delaunay_4d(int extra, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  std::vector<double> pts;
  for (int c = 0; c < 16; ++c)
    for (int k = 0; k < 4; ++k)
      pts.push_back((c >> k) & 1);
  for (int i = 0; i < extra; ++i)
    for (int k = 0; k < 4; ++k)
      pts.push_back(u(rng));
  double spacing = 1;
  const std::size_t n = pts.size() / 4;
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      double s = 0;
      for (int k = 0; k < 4; ++k)
        s += std::pow(pts[4 * a + k] - pts[4 * b + k], 2);
      spacing = std::min(spacing, std::sqrt(s));
    }
  Mesh m = delaunay(4, pts, spacing);
  prepare_input(m, "delaunay");
  return testing::renumbered(m, seed * 7919 + 1);
}

} // namespace

TEST_CASE("Delaunay of random 4D points fills the hypercube conformingly", "[4d][delaunay]") {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Mesh m = random_delaunay_4d(30, seed);
    Invariants inv = measure_invariants(m);
    INFO("seed " << seed);
    REQUIRE(inv.volume == Approx(1.0).epsilon(1e-12));
    REQUIRE(inv.boundary_measure == Approx(8.0).epsilon(1e-12)); // 8 unit cubes
    REQUIRE(check_conformity(m).ok);
  }
}

TEST_CASE("4D: local refinement of random Delaunay meshes with random numbering stays conforming",
          "[refine][4d][delaunay]") {
  // One region through the interior, one through the boundary (a sphere
  // centred on a corner and a slanted halfspace cutting several facets).
  const char *regions[] = {
      R"({"type":"sphere","center":[0.45,0.5,0.55,0.5],"radius":0.3})",
      R"({"type":"sphere","center":[1,0,1,0],"radius":0.6})",
      R"({"type":"halfspace","normal":[1,2,-1,0.5],"offset":0.9})",
  };
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    for (Marking mk : {Marking::Index, Marking::Longest, Marking::Sorted}) {
      const char *spec = regions[(seed + int(mk)) % 3];
      Mesh m = random_delaunay_4d(20, seed);
      mark_mesh(m, mk);
      Invariants inv = measure_invariants(m);
      auto region = parse_region(spec, 4, "region");
      for (int it = 1; it <= 4; ++it) {
        refine(m, select_cells(m, *region));
        INFO("seed " << seed << " marking " << marking_name(mk) << " region " << spec
                     << " iteration " << it);
        REQUIRE_CONFORMING(m, inv);
        ++checked;
      }
    }
  }
  REQUIRE(checked == 4 * 3 * 4);
}

TEST_CASE("4D: many seeds of random Delaunay meshes stay conforming",
          "[refine][4d][delaunay][slow]") {
  for (std::uint64_t seed = 100; seed < 116; ++seed) {
    for (Marking mk : {Marking::Index, Marking::Longest, Marking::Sorted}) {
      Mesh m = random_delaunay_4d(40, seed);
      mark_mesh(m, mk);
      Invariants inv = measure_invariants(m);
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> u(0, 1);
      std::string spec = "{\"type\":\"sphere\",\"center\":[" + std::to_string(u(rng)) + "," +
                         std::to_string(u(rng)) + "," + std::to_string(u(rng)) + "," +
                         std::to_string(u(rng)) +
                         "],\"radius\":" + std::to_string(0.2 + 0.4 * u(rng)) + "}";
      auto region = parse_region(spec, 4, "region");
      for (int it = 1; it <= 5; ++it) {
        refine(m, select_cells(m, *region));
        INFO("seed " << seed << " marking " << marking_name(mk) << " region " << spec
                     << " iteration " << it);
        REQUIRE_CONFORMING(m, inv);
      }
    }
  }
}

TEST_CASE("Forced mark types: the marks have the type asked for", "[mark][4d]") {
  for (const char *type : {"P_PP", "P_AA", "A_PO", "A_AA", "M_PO", "O_OO"}) {
    Mesh m = generate_simplex(4, SimplexShape::Equilateral);
    force_type(m, type);
    REQUIRE(m.marking == Marking::Explicit);
    REQUIRE(m.edge_rank.size() == 10);
    REQUIRE(m.stage[0] == Stage::Opposite);
    REQUIRE(simplex_type(edge_order(m), m.cell(0), 4) == type);
  }
  for (const char *type : {"P", "A", "M", "O"}) {
    Mesh m = generate_simplex(3, SimplexShape::Equilateral);
    force_type(m, type);
    REQUIRE(simplex_type(edge_order(m), m.cell(0), 3) == type);
  }
  Mesh m = generate_simplex(4, SimplexShape::Equilateral);
  REQUIRE_THROWS_WITH(force_type(m, "P_AO"),
                      Catch::Contains("does not arise") && Catch::Contains("A_PO"));
  Mesh two = generate_kuhn(3, 1);
  REQUIRE_THROWS(force_type(two, "P"));
}

TEST_CASE("Forced marks survive a file and decide the first bisections", "[mark][4d][vtu]") {
  auto dir = std::filesystem::temp_directory_path() / "bisect-forced";
  std::filesystem::create_directories(dir);
  for (const char *type : {"P_AA", "A_PO"}) {
    Mesh m = generate_simplex(4, SimplexShape::Equilateral);
    force_type(m, type);
    Mesh direct = m;
    std::string path = (dir / (std::string(type) + ".vtu")).string();
    encode_state(m);
    write_mesh(path, m);
    Mesh back = read_mesh(path);
    REQUIRE(decode_state(back, path));
    REQUIRE(back.marking == Marking::Explicit);
    REQUIRE(back.edge_rank == direct.edge_rank);
    REQUIRE(simplex_type(edge_order(back), back.cell(0), 4) == type);
    // The same refinement from the file as from memory, three generations.
    for (int it = 0; it < 3; ++it) {
      refine_uniform(direct);
      refine_uniform(back);
    }
    REQUIRE(back.cells == direct.cells);
    REQUIRE(back.coords == direct.coords);
  }
  // A rank table that gives one edge two ranks is refused. Every Kuhn
  // pentatope of one hypercube holds the diagonal from corner 0 to corner 15.
  Mesh m = generate_kuhn(4, 1);
  mark_mesh(m, Marking::Explicit);
  encode_state(m);
  DataArray *rank = nullptr;
  for (DataArray &a : m.cell_data)
    if (a.name == kEdgeRankArray)
      rank = &a;
  REQUIRE(rank);
  REQUIRE(rank->components == 10);
  for (CellId c = 0; c < 2; ++c) {
    const VertexId *x = m.cell(c);
    for (int i = 0, k = 0; i < 5; ++i)
      for (int j = i + 1; j < 5; ++j, ++k)
        if (edge_key(x[i], x[j]) == edge_key(0, 15))
          rank->values[c * 10 + k] = 3 + c;
  }
  REQUIRE_THROWS_WITH(decode_state(m, "forced.vtu"),
                      Catch::Contains("forced.vtu") && Catch::Contains("two different ranks"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("Forced P_AA and A_PO pentatopes cycle with period 4 (seed 000 §5.1)",
          "[refine][4d][quality]") {
  for (const char *type : {"P_AA", "A_PO"}) {
    Mesh m = generate_simplex(4, SimplexShape::Equilateral);
    force_type(m, type);
    Invariants inv = measure_invariants(m);
    Mesh all = m;
    std::vector<double> qmin, qmax;
    const int iterations = 17;
    for (int it = 1; it <= iterations; ++it) {
      refine_uniform(m);
      if (it <= 8)
        REQUIRE_CONFORMING(m, inv);
      QualitySummary q = quality_summary(m);
      qmin.push_back(q.min);
      qmax.push_back(q.max);
      if (it <= 12) {
        all.coords = m.coords;
        all.cells.insert(all.cells.end(), m.cells.begin(), m.cells.end());
      }
    }
    all.stage.clear();
    INFO(type);
    REQUIRE(count_similarity_classes(all) <= 1536u);
    REQUIRE(qmin.back() > 0.2); // bounded away from zero (P_AA 0.33, A_PO 0.21)
    for (int k = 8; k + 4 < iterations; ++k) {
      REQUIRE(qmin[k] == Approx(qmin[k + 4]).epsilon(1e-9));
      REQUIRE(qmax[k] == Approx(qmax[k + 4]).epsilon(1e-9));
    }
  }
}

TEST_CASE("The faceted octant extrudes only with --hull, then refines conformingly (seed 000 §5.2)",
          "[extrude][4d]") {
  Mesh oct = read_mesh(testing::data_path("octant.msh"));
  prepare_input(oct, "octant.msh");
  REQUIRE_THROWS_WITH(extrude_delaunay(oct, {0.0, 1.0}), Catch::Contains("not convex"));
  Mesh m = extrude_delaunay(oct, {0.0, 1.0}, true);
  REQUIRE(m.num_vertices() == 2 * oct.num_vertices());
  REQUIRE(check_conformity(m).ok);
  for (Marking mk : {Marking::Longest, Marking::Index}) {
    Mesh r = m;
    mark_mesh(r, mk);
    Invariants inv = measure_invariants(r);
    auto region =
        parse_region(R"({"type":"sphere","center":[0,0,0,0],"radius":0.25})", 4, "hypersphere");
    for (int it = 1; it <= 6; ++it) {
      refine(r, select_cells(r, *region));
      INFO("marking " << marking_name(mk) << " iteration " << it);
      REQUIRE_CONFORMING(r, inv);
    }
  }
}
