// The bisection state read from a file (mark.cpp decode_state): values out of
// range and states whose neighbours would refine a shared facet differently
// are input errors; every state bisect writes itself is accepted.
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/mark.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "bisect/threads.hpp"
#include "measure/check_testing.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <random>
#include <string>

using namespace bisect;

namespace {

DataArray &array_named(Mesh &m, const char *name) {
  for (DataArray &a : m.cell_data)
    if (a.name == name)
      return a;
  FAIL("no array " << name);
  return m.cell_data.front();
}

// A mesh refined locally a few times with `marking`, as bisect writes it.
Mesh refined(int dim, Marking marking, int iterations, std::uint64_t seed) {
  Mesh m = testing::renumbered(generate_kuhn(dim, 2), seed);
  mark_mesh(m, marking);
  const std::string region =
      dim == 2   ? R"({"type": "sphere", "center": [0.3, 0.4], "radius": 0.3})"
      : dim == 3 ? R"({"type": "sphere", "center": [0.3, 0.4, 0.5], "radius": 0.3})"
                 : R"({"type": "sphere", "center": [0.3, 0.4, 0.5, 0.6], "radius": 0.3})";
  auto r = parse_region(region, dim, "test");
  for (int it = 0; it < iterations; ++it)
    refine(m, select_cells(m, *r));
  return m;
}

// What bisect does on reading a file it wrote.
void reload(Mesh &m) {
  prepare_input(m, "in.vtu");
  const bool had_state = decode_state(m, "in.vtu"); // outside REQUIRE: errors propagate
  REQUIRE(had_state);
}

// Refines a reloaded mesh uniformly twice and locally thrice: it must stay
// conforming.
void require_refines_conformingly(Mesh m) {
  Invariants inv = measure_invariants(m);
  refine_uniform(m);
  REQUIRE_CONFORMING(m, inv);
  refine_uniform(m);
  REQUIRE_CONFORMING(m, inv);
  std::vector<double> c(std::size_t(m.dim), 0.37);
  std::string spec = R"({"type": "sphere", "center": [)";
  for (int k = 0; k < m.dim; ++k)
    spec += (k ? ", " : "") + std::to_string(0.37 + 0.05 * k);
  spec += R"(], "radius": 0.2})";
  auto r = parse_region(spec, m.dim, "test");
  for (int it = 0; it < 3; ++it) {
    refine(m, select_cells(m, *r));
    REQUIRE_CONFORMING(m, inv);
  }
}

} // namespace

TEST_CASE("state: every state bisect writes is accepted as consistent", "[state][2d][3d][4d]") {
  for (int dim : {2, 3, 4})
    for (Marking marking : {Marking::Index, Marking::Longest, Marking::Sorted})
      for (int iterations : {0, 1, 3}) {
        INFO("dim " << dim << ", marking " << marking_name(marking) << ", iterations "
                    << iterations);
        Mesh m = refined(dim, marking, iterations, 7 + iterations);
        encode_state(m);
        REQUIRE_NOTHROW(reload(m));
      }
}

TEST_CASE("state: an extruded space-time mesh and a forced type are accepted", "[state][3d][4d]") {
  for (int dim : {2, 3}) {
    Mesh base = generate_kuhn(dim, 2);
    std::vector<std::uint8_t> colour(base.num_vertices());
    // Kuhn meshes are coloured by the coordinate sum (mod dim + 1) of the lattice point.
    for (std::size_t v = 0; v < base.num_vertices(); ++v) {
      double s = 0;
      for (int k = 0; k < dim; ++k)
        s += base.point(VertexId(v))[k] * 2;
      colour[v] = std::uint8_t(int(std::lround(s)) % (dim + 1));
    }
    Mesh st = extrude_coloured(base, colour, {0.0, 0.5, 1.0});
    Mesh copy = st;
    auto r = parse_region(
        dim == 2 ? R"({"type": "sphere", "center": [0.3, 0.4, 0.5], "radius": 0.3})"
                 : R"({"type": "sphere", "center": [0.3, 0.4, 0.5, 0.6], "radius": 0.3})",
        st.dim, "test");
    refine(st, select_cells(st, *r));
    encode_state(st);
    REQUIRE_NOTHROW(reload(st));
    encode_state(copy);
    REQUIRE_NOTHROW(reload(copy));
  }
  for (const char *type : {"A_PO", "P_AA"}) {
    Mesh m = generate_simplex(4, SimplexShape::Equilateral);
    force_type(m, type);
    for (int i = 0; i < 4; ++i)
      refine_uniform(m);
    encode_state(m);
    REQUIRE_NOTHROW(reload(m));
  }
}

TEST_CASE("state: values out of range are rejected, naming the cell", "[state][io]") {
  Mesh base = refined(3, Marking::Longest, 1, 3);
  encode_state(base);
  {
    // bisect:state: a vertex order beyond the 24 permutations, a fraction, NaN, a negative.
    for (double bad : {24.0 * 16, 3.5, double(NAN), -16.0}) {
      Mesh m = base;
      array_named(m, kStateArray).values[5] = bad;
      INFO("bisect:state = " << bad);
      REQUIRE_THROWS_WITH(reload(m), Catch::Contains("in.vtu") && Catch::Contains("cell 5") &&
                                         Catch::Contains(kStateArray));
    }
    // Read from a .msh: the cell is named by its element tag.
    {
      Mesh m = base;
      array_named(m, kStateArray).values[5] = 3.5;
      m.numbering.gmsh = true;
      m.numbering.vertices = m.num_vertices();
      m.numbering.cells = m.num_cells();
      m.numbering.element_base = 1000;
      prepare_input(m, "in.msh");
      REQUIRE_THROWS_WITH(decode_state(m, "in.msh"),
                          Catch::StartsWith("in.msh: element 1005: invalid bisection state"));
    }
    // A Maubach tag 0 (stage bit set, tag bits 0).
    Mesh m = base;
    array_named(m, kStateArray).values[5] = 8;
    REQUIRE_THROWS_WITH(reload(m), Catch::Contains("cell 5") && Catch::Contains("tag"));
  }
  testing::to_legacy_state(base);
  struct Case {
    const char *array;
    double value;
    const char *message;
  };
  for (const Case &k :
       {Case{kStageArray, 2, "stage"}, Case{kStageArray, -1, "stage"}, Case{kTagArray, 4, "tag"},
        Case{kTagArray, 0.5, "tag"}, Case{kOrderArray, 7, "permutation"},
        Case{kOrderArray, NAN, "permutation"}, Case{kMarkingArray, 9, kMarkingArray}}) {
    Mesh m = base;
    array_named(m, k.array).values[array_named(m, k.array).components * 5] = k.value;
    INFO(k.array << " = " << k.value);
    REQUIRE_THROWS_WITH(reload(m), Catch::Contains("in.vtu") && Catch::Contains(k.message));
  }
}

// The fuzzer's two tampers: one cell's bisect:order permuted, or two vertices
// of one cell's connectivity swapped. Either the state is rejected as
// inconsistent, or (when the tamper happens to keep it consistent) it refines
// to a conforming mesh.
TEST_CASE("state: decoded by several threads, the first invalid cell is named",
          "[state][threads]") {
  // 41,154 cells: ten blocks of the decoding, shared by the threads.
  Mesh base = generate_kuhn(3, 19);
  mark_mesh(base, Marking::Longest);
  encode_state(base);
  DataArray &state = array_named(base, kStateArray);
  state.values[31000] = 3.5;
  state.values[9000] = 24.0 * 16;
  for (int threads : {1, 2, 3}) {
    set_threads(threads);
    Mesh m = base;
    INFO(threads << " threads");
    REQUIRE_THROWS_WITH(reload(m), Catch::StartsWith("in.vtu: cell 9000: invalid bisection state"));
  }
  set_threads(0);
}

TEST_CASE("state: tampered order or connectivity is rejected or still refines conformingly",
          "[state][2d][3d][4d]") {
  std::mt19937_64 rng(2024);
  int rejected = 0, accepted = 0;
  for (int dim : {2, 3, 4})
    for (Marking marking : {Marking::Index, Marking::Longest, Marking::Sorted}) {
      Mesh base = refined(dim, marking, 2, 11);
      encode_state(base);
      if (marking != Marking::Sorted)
        testing::to_legacy_state(base); // both encodings
      const int nv = dim + 1;
      for (int trial = 0; trial < 12; ++trial) {
        Mesh m = base;
        const std::size_t c = std::uniform_int_distribution<std::size_t>(0, m.num_cells() - 1)(rng);
        const bool permute_order = trial % 2 == 0;
        if (permute_order && marking == Marking::Sorted) {
          // bisect:state: another vertex order (rank), same stage and tag.
          double &v = array_named(m, kStateArray).values[c];
          int nperm = 1;
          for (int f = 2; f <= nv; ++f)
            nperm *= f;
          const int w = int(v), r = w >> 4;
          const int r2 = (r + 1 + std::uniform_int_distribution<int>(0, nperm - 2)(rng)) % nperm;
          v = double(r2 * 16 + (w & 15));
        } else if (permute_order) {
          DataArray &order = array_named(m, kOrderArray);
          auto first = order.values.begin() + std::ptrdiff_t(c * nv);
          std::vector<double> before(first, first + nv);
          while (std::equal(before.begin(), before.end(), first))
            std::shuffle(first, first + nv, rng);
        } else {
          int i = std::uniform_int_distribution<int>(0, nv - 1)(rng), j = i;
          while (j == i)
            j = std::uniform_int_distribution<int>(0, nv - 1)(rng);
          std::swap(m.cell(CellId(c))[i], m.cell(CellId(c))[j]);
        }
        INFO("dim " << dim << ", marking " << marking_name(marking) << ", cell " << c << ", "
                    << (permute_order ? "order permuted" : "connectivity swapped"));
        try {
          reload(m);
        } catch (const InputError &e) {
          REQUIRE_THAT(e.what(), Catch::Contains("in.vtu") && Catch::Contains("inconsistent"));
          ++rejected;
          continue;
        }
        ++accepted;
        require_refines_conformingly(m);
      }
    }
  // In 3D and 4D most tampers change how a cell splits a shared facet.
  REQUIRE(rejected > 20);
  WARN("tampered states rejected: " << rejected << ", still consistent: " << accepted);
}

// ALGORITHMS.md §4: skipping Stage 1 with the index order gives every
// pentatope the tuple (a, c, b, e, d)_2 (sorted ids a < ... < e). For the two
// pentatopes {0..4} and {1..5} the marks on the shared tet agree three levels
// deep, yet three uniform refinements split it differently from the two
// sides. The check has to look that deep.
TEST_CASE("state: the 4D pair that skips Stage 1 is inconsistent, found before refining",
          "[state][4d]") {
  Mesh m;
  m.dim = 4;
  m.coords = {0.1, 0.2, 0.1, 0.3, // 0, below the hyperplane of 1..4
              0,   0,   0,   1,   1, 0,   0,   1,   0,   1,
              0,   1,   0,   0,   1, 1.2, 0.2, 0.3, 0.2, 1.9}; // 5, above it
  m.cells = {0, 1, 2, 3, 4, 1, 2, 3, 4, 5};
  prepare_input(m, "pair");
  m.marking = Marking::Index;
  m.stage.assign(2, Stage::Maubach);
  m.tag.assign(2, 2);
  for (CellId c = 0; c < 2; ++c) {
    VertexId *x = m.cell(c);
    std::sort(x, x + 5);
    const VertexId a = x[0], b = x[1], cc = x[2], d = x[3], e = x[4];
    x[0] = a, x[1] = cc, x[2] = b, x[3] = e, x[4] = d;
  }
  // Refined as it is, the pair ends non-conforming...
  Mesh r = m;
  Invariants inv = measure_invariants(r);
  for (int i = 0; i < 3; ++i)
    refine_uniform(r);
  REQUIRE_FALSE(check_conformity(r, &inv).ok);
  // ...so the state is rejected on reading.
  REQUIRE_THAT(check_state_consistency(m), Catch::Contains("cells 0 and 1"));
  encode_state(m);
  REQUIRE_THROWS_WITH(reload(m), Catch::Contains("inconsistent"));
}

// On reading, the consistency check walks the interior facets validation
// recorded, in pieces, on all threads; with several tampered cells it must
// name the same facet as the serial walk over the mesh: the first in facet
// order.
TEST_CASE("state: the check on several threads names the first inconsistent facet, as the serial "
          "walk does",
          "[state][threads][3d][4d]") {
  std::mt19937_64 rng(77);
  for (int dim : {3, 4}) {
    Mesh base = refined(dim, Marking::Sorted, dim == 3 ? 4 : 2, 5);
    encode_state(base);
    DataArray &state = array_named(base, kStateArray);
    for (int k = 0; k < 12; ++k) { // another vertex order (rank) in 12 cells
      const std::size_t c =
          std::uniform_int_distribution<std::size_t>(0, base.num_cells() - 1)(rng);
      const int w = int(state.values[c]);
      state.values[c] = double(((w >> 4) + 1) % (dim == 3 ? 24 : 120) * 16 + (w & 15));
    }
    std::string serial;
    try {
      Mesh m = base;
      prepare_input(m, "in.vtu");
      decode_state(m, "in.vtu"); // no record: one walk over the mesh
    } catch (const InputError &e) {
      serial = e.what();
    }
    INFO(dim << "D, " << base.num_cells() << " cells");
    REQUIRE_THAT(serial, Catch::Contains("inconsistent"));
    testing::set_walk_chunk_bytes(std::size_t(1) << 14); // many pieces
    for (int threads : {1, 2, 3}) {
      set_threads(threads);
      Mesh m = base;
      InputFacts facts;
      facts.want_interior = true;
      prepare_input(m, "in.vtu", {}, &facts);
      REQUIRE(facts.interior.size() > 4);
      std::string message;
      try {
        decode_state(m, "in.vtu", &facts.interior);
      } catch (const InputError &e) {
        message = e.what();
      }
      CHECK(message == serial);
    }
    set_threads(0);
    testing::set_walk_chunk_bytes(0);
  }
}

TEST_CASE("state: arrays without one value per cell are rejected, wherever they are",
          "[state][io]") {
  Mesh base = refined(3, Marking::Index, 1, 5);
  encode_state(base);
  {
    Mesh m = base;
    array_named(m, kStateArray).values.pop_back();
    prepare_input(m, "in.vtu");
    REQUIRE_THROWS_WITH(decode_state(m, "in.vtu"),
                        Catch::StartsWith("in.vtu: bisection state arrays do not have one tuple"));
  }
  {
    // The same arrays in a StoredState, bisect:marking one value short.
    Mesh m = base;
    StoredState stored;
    for (const char *name : {kStateArray, kMarkingArray}) {
      const DataArray &a = array_named(m, name);
      std::vector<std::int16_t> v(a.values.begin(), a.values.end());
      if (name == std::string(kMarkingArray))
        v.pop_back();
      stored.cells.push_back({name, 1, ValueType::Int16, std::move(v)});
    }
    std::erase_if(m.cell_data, [](const DataArray &a) {
      return a.name == kStateArray || a.name == kMarkingArray;
    });
    prepare_input(m, "in.vtu");
    REQUIRE_THROWS_WITH(decode_state(m, "in.vtu", nullptr, &stored),
                        Catch::StartsWith("in.vtu: bisection state arrays do not have one tuple"));
  }
}
