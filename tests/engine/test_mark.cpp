// Marking: the global edge order and the initial state (ALGORITHMS.md §2-4).
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/refine.hpp"
#include "bisect/state.hpp"
#include "core/numbering.hpp"
#include "engine/mark_testing.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <numeric>
#include <random>
#include <set>
#include <sstream>

using namespace bisect;

namespace {

Mesh ball() {
  Mesh m = read_mesh(testing::data_path("ball.msh"));
  prepare_input(m, "ball.msh");
  return m;
}

} // namespace

TEST_CASE("index marking: every tet is unflagged planar, the tuple (a, c, b, d)_2", "[mark][3d]") {
  Mesh m = testing::renumbered(ball(), 11);
  EdgeOrder order = edge_order(m);
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    REQUIRE(classify_tet(order, m.cell(CellId(c))) == TetType::Planar);
  mark_mesh(m, Marking::Index);
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const VertexId *x = m.cell(CellId(c));
    REQUIRE(m.stage[c] == Stage::Maubach);
    REQUIRE(m.tag[c] == 2);
    // sorted a < b < c < d: (x0, x1, x2, x3) = (a, c, b, d) or its
    // reflection (b, c, a, d), which has the same children.
    REQUIRE(std::max(x[0], x[2]) < x[1]);
    REQUIRE(x[1] < x[3]);
  }
}

TEST_CASE("longest marking: planar tets start in Maubach, A/M/O tets in Stage 1", "[mark][3d]") {
  Mesh m = ball();
  EdgeOrder order = edge_order(m);
  order.marking = Marking::Longest;
  std::vector<TetType> types;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    types.push_back(classify_tet(order, m.cell(CellId(c))));
  mark_mesh(m, Marking::Longest);
  std::size_t nonplanar = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    bool planar = types[c] == TetType::Planar;
    nonplanar += !planar;
    REQUIRE((m.stage[c] == Stage::Maubach) == planar);
  }
  // An unstructured mesh has all four types under the longest-edge order.
  REQUIRE(nonplanar > 0);
  REQUIRE(nonplanar < m.num_cells());
}

// The marks a Maubach tuple (x0, x1, x2, x3)_2 implies: refinement edge
// (x0, x2); face opposite x0 marked (x1, x2); face opposite x2 marked (x0, x1).
TEST_CASE("longest marking: children of A, M, O tets are planar with Arnold's marks",
          "[mark][3d]") {
  Mesh m = ball();
  mark_mesh(m, Marking::Longest);
  EdgeOrder order;
  std::vector<CellId> stage1;
  std::vector<std::vector<VertexId>> parents;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    if (m.stage[c] == Stage::Opposite) {
      stage1.push_back(CellId(c));
      parents.emplace_back(m.cell(CellId(c)), m.cell(CellId(c)) + 4);
    }
  REQUIRE(!stage1.empty());
  const std::size_t nv0 = m.num_vertices();
  refine(m, stage1);
  order = edge_order(m);
  // Each first child sits in its parent's slot; check it against Arnold's rule.
  std::size_t checked = 0;
  for (std::size_t i = 0; i < stage1.size(); ++i) {
    const VertexId *x = m.cell(stage1[i]);
    if (m.stage[stage1[i]] != Stage::Maubach || m.tag[stage1[i]] != 2 || x[3] < nv0)
      continue;
    // The child (v, F) keeps the parent face F = {x0, x1, x2}; its refinement
    // edge is F's consistent edge; each face containing v is marked by its
    // edge opposite v.
    VertexId f[3] = {x[0], x[1], x[2]};
    EdgePick e = consistent_edge(order, f, 3);
    std::set<VertexId> want{f[e.first], f[e.second]}, got{x[0], x[2]};
    REQUIRE(want == got);
    std::set<VertexId> parent(parents[i].begin(), parents[i].end());
    for (int k = 0; k < 3; ++k)
      REQUIRE(parent.count(f[k]) == 1);
    // Maubach marks: (x1, x2) and (x0, x1): both lie in F (opposite v) and
    // share x1, so the three marks bound one triangle: planar.
    ++checked;
  }
  REQUIRE(checked > 0);
}

TEST_CASE("sorted marking: every cell is (x0 < ... < xn)_n", "[mark][2d][3d][4d]") {
  for (int dim : {2, 3, 4}) {
    Mesh m = testing::renumbered(generate_kuhn(dim, 2), 5);
    mark_mesh(m, Marking::Sorted);
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      const VertexId *x = m.cell(CellId(c));
      REQUIRE(std::is_sorted(x, x + dim + 1));
      REQUIRE(m.tag[c] == dim);
    }
  }
}

TEST_CASE("state arrays round-trip the tuples through positive orientation", "[mark][io]") {
  for (int dim : {2, 3, 4}) {
    Mesh m = testing::renumbered(generate_kuhn(dim, 2), 3);
    mark_mesh(m, dim == 3 ? Marking::Longest : Marking::Index);
    refine_uniform(m);
    Mesh saved = m;
    encode_state(m);
    REQUIRE(decode_state(m, "x"));
    REQUIRE(m.cells == saved.cells);
    REQUIRE(m.stage == saved.stage);
    REQUIRE(m.tag == saved.tag);
    REQUIRE(m.marking == saved.marking);
  }
}

TEST_CASE("state arrays that are not a permutation are rejected", "[mark][io]") {
  Mesh m = generate_kuhn(2, 1);
  mark_mesh(m, Marking::Index);
  encode_state(m);
  testing::to_legacy_state(m);
  for (DataArray &a : m.cell_data)
    if (a.name == kOrderArray)
      a.values[1] = a.values[0];
  REQUIRE_THROWS_WITH(decode_state(m, "in.vtu"),
                      Catch::Contains("in.vtu") && Catch::Contains("permutation"));
}

// check_state_consistency answers a pair of Maubach cells from a table of
// renamed pairs (the facet's ids by rank, the opposite vertices after them),
// filled as pairs are met. Every kind of 3D pair, and a sample of the 4D
// ones, each with random ids and facet orders: one table shared by all
// pairs gives each pair the verdict of the walk over its real ids; and the
// check of a mesh of one pair gives the walk's message.
TEST_CASE("state check: the table of renamed Maubach pairs gives the walk's verdict",
          "[mark][state][3d][4d]") {
  std::mt19937_64 rng(4242);
  for (int dim : {3, 4}) {
    const int n = dim + 1;
    const VertexId nv = 60;
    const int kinds = dim * n; // a side's tag (1..dim) and opposite position
    std::vector<VertexId> cells;
    std::vector<std::uint8_t> tags;
    auto add_pair = [&](int sa, int sb) {
      std::vector<VertexId> ids(nv);
      std::iota(ids.begin(), ids.end(), 0);
      std::shuffle(ids.begin(), ids.end(), rng);
      std::vector<int> orders(n - 1); // the facet's ids in tuple order
      for (int side = 0; side < 2; ++side) {
        const int s = side ? sb : sa, opposite = (s / dim) % n;
        std::iota(orders.begin(), orders.end(), 0);
        std::shuffle(orders.begin(), orders.end(), rng);
        for (int k = 0, f = 0; k < n; ++k)
          cells.push_back(k == opposite ? ids[n - 1 + side] : ids[orders[f++]]);
        tags.push_back(std::uint8_t(1 + s % dim));
      }
    };
    if (dim == 3) {
      for (int sa = 0; sa < kinds; ++sa) // every kind of each side
        for (int sb = 0; sb < kinds; ++sb)
          for (int k = 0; k < 36; ++k) // random facet orders
            add_pair(sa, sb);
    } else {
      for (int k = 0; k < 20000; ++k)
        add_pair(std::uniform_int_distribution<int>(0, kinds - 1)(rng),
                 std::uniform_int_distribution<int>(0, kinds - 1)(rng));
    }
    const std::vector<bool> walked = testing::state_pair_verdicts(dim, cells, tags, false),
                            tabled = testing::state_pair_verdicts(dim, cells, tags, true);
    const std::size_t pairs = walked.size();
    std::size_t alike = 0;
    for (std::size_t k = 0; k < pairs; ++k) {
      INFO(dim << "D, pair " << k);
      REQUIRE(tabled[k] == walked[k]);
      alike += walked[k];
    }
    INFO(dim << "D: " << pairs << " pairs, " << alike << " alike");
    REQUIRE(alike > pairs / 100);
    REQUIRE(alike < pairs / 2);
    // The whole check on meshes of one pair, with and without the table.
    Mesh m;
    m.dim = dim;
    m.marking = Marking::Sorted;
    m.coords.assign(std::size_t(nv) * dim, 0.0);
    m.stage.assign(2, Stage::Maubach);
    for (std::size_t k = 0; k < pairs; k += 7) {
      m.cells.assign(cells.begin() + std::ptrdiff_t(2 * k * n),
                     cells.begin() + std::ptrdiff_t(2 * (k + 1) * n));
      m.tag = {tags[2 * k], tags[2 * k + 1]};
      testing::set_state_pair_table(false);
      const std::string walk = check_state_consistency(m);
      testing::set_state_pair_table(true);
      INFO(dim << "D, pair " << k);
      REQUIRE(check_state_consistency(m) == walk);
      REQUIRE(walk.empty() == walked[k]);
    }
  }
  testing::set_state_pair_table(true);
}
