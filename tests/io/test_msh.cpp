// Gmsh .msh reading and writing (src/io_msh.cpp).
#include "bisect/io.hpp"
#include "io/msh_testing.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

using namespace bisect;
using Catch::Matchers::Contains;

namespace {

namespace fs = std::filesystem;

std::string msh_data(const std::string &name) {
  return std::string(BISECT_TESTS_DIR) + "/data/msh/" + name;
}

// A path in the temporary directory, unique to this process.
std::string temp_path(const std::string &name) {
  return (fs::temp_directory_path() /
          ("bisect_test_msh_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

std::string write_file(const std::string &name, const std::string &content) {
  const std::string path = temp_path(name);
  std::ofstream(path, std::ios::binary) << content;
  return path;
}

std::string read_file(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The message read_msh throws for `path`, or "(no error)".
std::string read_error(const std::string &path) {
  try {
    read_msh(path);
  } catch (const InputError &e) {
    return e.what();
  }
  return "(no error)";
}

std::string replaced(std::string text, const std::string &from, const std::string &to) {
  const std::size_t p = text.find(from);
  REQUIRE(p != std::string::npos);
  return text.replace(p, from.size(), to);
}

const DataArray *find_array(const std::vector<DataArray> &arrays, const std::string &name) {
  for (const DataArray &a : arrays)
    if (a.name == name)
      return &a;
  return nullptr;
}

// A structured n^dim grid of unit-ish boxes, each split into dim! simplices
// (Kuhn), with coordinates that are not short decimals so that exactness
// matters, and every kind of array the writer handles. The two tag arrays
// come in interleaved runs so that one entity has several element blocks.
Mesh sample_mesh(int dim, int n) {
  Mesh m;
  m.dim = dim;
  const int side = n + 1;
  const int nv = dim == 2 ? side * side : side * side * side;
  for (int v = 0; v < nv; ++v) {
    int rest = v;
    for (int k = 0; k < dim; ++k) {
      const int i = rest % side;
      rest /= side;
      m.coords.push_back(i / 3.0 + std::sqrt(2.0) * 1e-3 * ((v * 7 + k) % 5));
    }
  }
  auto id = [&](int i, int j, int k) { return VertexId(i + side * (j + side * k)); };
  for (int k = 0; k < (dim == 3 ? n : 1); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (dim == 2) {
          const VertexId a = id(i, j, 0), b = id(i + 1, j, 0), c = id(i + 1, j + 1, 0),
                         d = id(i, j + 1, 0);
          m.cells.insert(m.cells.end(), {a, b, c, a, c, d});
        } else {
          // Kuhn: the 6 paths from corner 0 to corner 7 through the cube.
          const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
          for (const auto &p : perms) {
            int x[3] = {i, j, k};
            m.cells.push_back(id(x[0], x[1], x[2]));
            for (int s = 0; s < 3; ++s) {
              ++x[p[s]];
              m.cells.push_back(id(x[0], x[1], x[2]));
            }
          }
        }
      }
  const std::size_t nc = m.num_cells();
  DataArray phys{"gmsh:physical", 1, {}}, geom{"gmsh:geometrical", 1, {}}, vec{"velocity", 3, {}};
  for (std::size_t c = 0; c < nc; ++c) {
    phys.values.push_back(c % 5 < 3 ? 7 : 9);
    geom.values.push_back(c % 5 < 3 ? 1 : (c % 2 ? 4 : 3));
    for (int k = 0; k < 3; ++k)
      vec.values.push_back(std::exp(double(c)) / 7.0 - k);
  }
  m.cell_data = {phys, geom, vec};
  DataArray temp{"temperature", 1, {}};
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    temp.values.push_back(1.0 / (3.0 + double(v)));
  m.point_data = {temp};
  return m;
}

void require_same_arrays(const std::vector<DataArray> &a, const std::vector<DataArray> &b) {
  REQUIRE(a.size() == b.size());
  for (const DataArray &x : a) {
    INFO("array " << x.name);
    const DataArray *y = find_array(b, x.name);
    REQUIRE(y);
    REQUIRE(y->components == x.components);
    REQUIRE(y->values == x.values);
  }
}

// The mesh as a .msh file gives it back: its cells grouped by entity (a
// distinct (gmsh:geometrical, gmsh:physical) pair), entities in order of
// first appearance, cells of one entity in mesh order; cell data with them.
Mesh grouped_by_entity(const Mesh &m) {
  const DataArray *geom = find_array(m.cell_data, "gmsh:geometrical");
  const DataArray *phys = find_array(m.cell_data, "gmsh:physical");
  std::vector<std::pair<double, double>> firsts;
  std::vector<std::size_t> entity(m.num_cells());
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const std::pair<double, double> key{geom ? geom->values[c] : 0.0, phys ? phys->values[c] : 0.0};
    auto it = std::find(firsts.begin(), firsts.end(), key);
    entity[c] = std::size_t(it - firsts.begin());
    if (it == firsts.end())
      firsts.push_back(key);
  }
  std::vector<std::size_t> order(m.num_cells());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return entity[a] < entity[b]; });
  Mesh g = m;
  const std::size_t n = std::size_t(m.cell_size());
  for (std::size_t i = 0; i < order.size(); ++i)
    std::copy_n(m.cells.begin() + std::ptrdiff_t(order[i] * n), n,
                g.cells.begin() + std::ptrdiff_t(i * n));
  for (std::size_t k = 0; k < m.cell_data.size(); ++k) {
    const std::size_t nc = std::size_t(m.cell_data[k].components);
    for (std::size_t i = 0; i < order.size(); ++i)
      std::copy_n(m.cell_data[k].values.begin() + std::ptrdiff_t(order[i] * nc), nc,
                  g.cell_data[k].values.begin() + std::ptrdiff_t(i * nc));
  }
  return g;
}

void require_identical(const Mesh &a, const Mesh &b) {
  REQUIRE(a.dim == b.dim);
  REQUIRE(a.coords == b.coords);
  REQUIRE(a.cells == b.cells);
  require_same_arrays(a.cell_data, b.cell_data);
  require_same_arrays(a.point_data, b.point_data);
}

// A 2D mesh in MSH 2.2 ASCII: the unit square as two triangles plus a
// boundary line. Line numbers: nodes on lines 6-9, elements on lines 13-15.
const std::string kSquare22 = "$MeshFormat\n"
                              "2.2 0 8\n"
                              "$EndMeshFormat\n"
                              "$Nodes\n"
                              "4\n"
                              "1 0 0 0\n"
                              "2 1 0 0\n"
                              "3 1 1 0\n"
                              "4 0 1 0\n"
                              "$EndNodes\n"
                              "$Elements\n"
                              "3\n"
                              "1 1 2 7 1 1 2\n"
                              "2 2 2 5 1 1 2 3\n"
                              "3 2 2 5 1 1 3 4\n"
                              "$EndElements\n";

// The same kind of mesh in MSH 4.1 ASCII with entities, out-of-order and
// unused nodes, a boundary line, and node and element data.
const std::string kSquare41 = "$MeshFormat\n"
                              "4.1 0 8\n"
                              "$EndMeshFormat\n"
                              "$PhysicalNames\n"
                              "1\n"
                              "2 42 \"square\"\n"
                              "$EndPhysicalNames\n"
                              "$Entities\n"
                              "0 1 1 0\n"
                              "5 0 0 0 1 0 0 1 9 0\n"
                              "1 0 0 0 1 1 0 1 42 0\n"
                              "$EndEntities\n"
                              "$Nodes\n"
                              "2 5 1 7\n"
                              "1 5 0 1\n"
                              "7\n"
                              "0 1 0\n"
                              "2 1 0 4\n"
                              "3\n"
                              "1\n"
                              "2\n"
                              "5\n"
                              "1 1 0\n"
                              "0 0 0\n"
                              "1 0 0\n"
                              "2 2 0\n"
                              "$EndNodes\n"
                              "$Elements\n"
                              "2 3 1 12\n"
                              "1 5 1 1\n"
                              "10 7 1\n"
                              "2 1 2 2\n"
                              "11 1 2 3\n"
                              "12 1 3 7\n"
                              "$EndElements\n"
                              "$Comments\n"
                              "anything at all, 1 2 3\n"
                              "$EndComments\n"
                              "$NodeData\n"
                              "1\n"
                              "\"temp\"\n"
                              "1\n"
                              "0.0\n"
                              "3\n"
                              "0\n"
                              "1\n"
                              "5\n"
                              "1 10\n"
                              "2 20\n"
                              "3 30\n"
                              "5 50\n"
                              "7 70\n"
                              "$EndNodeData\n"
                              "$NodeData\n"
                              "1\n"
                              "\"temp\"\n"
                              "1\n"
                              "1.0\n"
                              "3\n"
                              "1\n"
                              "1\n"
                              "4\n"
                              "7 0.7\n"
                              "3 0.3\n"
                              "2 0.2\n"
                              "1 0.1\n"
                              "$EndNodeData\n"
                              "$ElementData\n"
                              "1\n"
                              "\"flux\"\n"
                              "1\n"
                              "0.0\n"
                              "3\n"
                              "0\n"
                              "2\n"
                              "3\n"
                              "12 1.5 -2.5\n"
                              "10 9 9\n"
                              "11 0.25 1e-300\n"
                              "$EndElementData\n";

} // namespace

TEST_CASE("msh: 4.1 binary round trip preserves coordinates, cells and arrays exactly", "[io]") {
  for (int dim : {2, 3}) {
    INFO("dim " << dim);
    const Mesh m = testing::renumbered(sample_mesh(dim, 3), 5);
    const std::string path = temp_path("round_trip.msh");
    write_msh(path, m);
    const Mesh back = read_msh(path);
    require_identical(grouped_by_entity(m), back);
    // And the file written from what was read is byte for byte the same.
    const std::string again = temp_path("round_trip_again.msh");
    write_msh(again, back);
    REQUIRE(read_file(again) == read_file(path));
    fs::remove(path);
    fs::remove(again);
  }
}

TEST_CASE("msh: one element block per entity, data paired by position and by tag", "[io]") {
  // sample_mesh interleaves its tag arrays in runs: many runs, few entities.
  const Mesh m = sample_mesh(3, 3);
  std::set<std::pair<double, double>> entities;
  const DataArray *geom = find_array(m.cell_data, "gmsh:geometrical");
  const DataArray *phys = find_array(m.cell_data, "gmsh:physical");
  REQUIRE((geom && phys));
  std::size_t runs = 0;
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    entities.insert({geom->values[c], phys->values[c]});
    if (c == 0 || geom->values[c] != geom->values[c - 1] || phys->values[c] != phys->values[c - 1])
      ++runs;
  }
  REQUIRE(runs > entities.size());
  const std::string path = temp_path("blocks.msh");
  write_msh(path, m);
  const std::string text = read_file(path);
  const std::size_t at = text.find("$Elements\n");
  REQUIRE(at != std::string::npos);
  std::uint64_t blocks = 0, elements = 0;
  std::memcpy(&blocks, text.data() + at + 10, 8);
  std::memcpy(&elements, text.data() + at + 18, 8);
  CHECK(blocks == entities.size());
  CHECK(elements == m.num_cells());
  // Element data rows come in file order (what meshio pairs by position,
  // and its binary reader wants tagged 1, 2, 3, ...): the row tags are the
  // element tags, in the same sequence.
  std::vector<std::uint64_t> element_tags;
  std::size_t p = at + 10 + 32; // past "$Elements\n" and its four counts
  for (std::uint64_t b = 0; b < blocks; ++b) {
    std::int32_t dim = 0;
    std::uint64_t count = 0;
    std::memcpy(&dim, text.data() + p, 4);
    std::memcpy(&count, text.data() + p + 12, 8);
    p += 20;
    for (std::uint64_t e = 0; e < count; ++e) {
      std::uint64_t tag = 0;
      std::memcpy(&tag, text.data() + p, 8);
      element_tags.push_back(tag);
      p += 8 * std::size_t(dim + 2);
    }
  }
  REQUIRE(element_tags.size() == m.num_cells());
  const std::size_t data = text.find("$ElementData\n");
  REQUIRE(data != std::string::npos);
  // "...\n3\n0\n<components>\n<count>\n" then the rows.
  const std::size_t components_line = text.find("\n3\n0\n", data) + 5;
  const int components = std::stoi(text.substr(components_line));
  const std::size_t count_line = text.find('\n', components_line) + 1;
  std::size_t row = text.find('\n', count_line) + 1;
  std::vector<std::uint64_t> row_tags;
  for (std::size_t i = 0; i < m.num_cells(); ++i, row += 4 + 8 * std::size_t(components)) {
    std::int32_t tag = 0;
    std::memcpy(&tag, text.data() + row, 4);
    row_tags.push_back(std::uint64_t(tag));
  }
  CHECK(row_tags == element_tags);
  std::vector<std::uint64_t> one_two_three(element_tags.size());
  std::iota(one_two_three.begin(), one_two_three.end(), std::uint64_t(1));
  CHECK(element_tags == one_two_three);
  // Read back (by tags): the cells grouped by entity, with their data.
  const Mesh back = read_msh(path);
  require_identical(grouped_by_entity(m), back);
  CHECK(back.cells != m.cells); // this mesh's entities come in runs
  // A mesh read back writes the same file, and reads back unchanged.
  const std::string again = temp_path("blocks_again.msh");
  write_msh(again, back);
  CHECK(read_file(again) == text);
  require_identical(back, read_msh(again));
  fs::remove(again);
  fs::remove(path);
}

TEST_CASE("msh: a mesh without gmsh tag arrays round trips without gaining any", "[io]") {
  Mesh m = sample_mesh(3, 2);
  m.cell_data.erase(m.cell_data.begin(), m.cell_data.begin() + 2); // keep "velocity"
  const std::string path = temp_path("no_tags.msh");
  write_msh(path, m);
  require_identical(m, read_msh(path));
  m.cell_data.clear();
  m.point_data.clear();
  write_msh(path, m);
  require_identical(m, read_msh(path));
  fs::remove(path);
}

TEST_CASE("msh: geometrical tags alone round trip without a physical array", "[io]") {
  Mesh m = sample_mesh(2, 2);
  m.cell_data.erase(m.cell_data.begin()); // drop gmsh:physical
  const std::string path = temp_path("geom_only.msh");
  write_msh(path, m);
  require_identical(grouped_by_entity(m), read_msh(path));
  fs::remove(path);
}

TEST_CASE("msh: 2.2 ascii, 2.2 binary, 4.1 ascii and 4.1 binary of the same mesh read identically",
          "[io]") {
  const Mesh ref = read_msh(msh_data("two_boxes_41b.msh"));
  REQUIRE(ref.dim == 3);
  REQUIRE(ref.num_cells() == 24);
  REQUIRE(ref.num_vertices() == 16);
  for (const char *name : {"two_boxes_22a.msh", "two_boxes_22b.msh", "two_boxes_41a.msh"}) {
    INFO(name);
    const Mesh m = read_msh(msh_data(name));
    REQUIRE(m.dim == ref.dim);
    REQUIRE(m.cells == ref.cells);
    REQUIRE(m.coords.size() == ref.coords.size());
    for (std::size_t i = 0; i < m.coords.size(); ++i) // ASCII has 16 digits
      REQUIRE(m.coords[i] == Approx(ref.coords[i]).margin(1e-15));
    require_same_arrays(m.cell_data, ref.cell_data);
    REQUIRE(m.point_data.empty());
  }
}

TEST_CASE("msh: binary 2.2 written by gmsh reads", "[io]") {
  const Mesh m = read_msh(msh_data("two_boxes_22b.msh"));
  REQUIRE(m.dim == 3);
  REQUIRE(m.num_cells() == 24);
  REQUIRE(m.num_vertices() == 16);
  const DataArray *phys = find_array(m.cell_data, "gmsh:physical");
  const DataArray *geom = find_array(m.cell_data, "gmsh:geometrical");
  REQUIRE(phys);
  REQUIRE(geom);
  REQUIRE(std::count(phys->values.begin(), phys->values.end(), 10.0) == 12);
  REQUIRE(std::count(phys->values.begin(), phys->values.end(), 20.0) == 12);
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    REQUIRE(geom->values[c] == (phys->values[c] == 10.0 ? 1.0 : 2.0));
    // the "left" box is x <= 1
    for (int k = 0; k < 4; ++k)
      if (phys->values[c] == 10.0)
        REQUIRE(m.point(m.cell(CellId(c))[k])[0] <= 1.0);
  }
}

TEST_CASE("msh: the bundled square reads as a 2D triangle mesh with its tags", "[io]") {
  const Mesh m = read_msh(testing::data_path("square.msh"));
  REQUIRE(m.dim == 2);
  REQUIRE(m.num_cells() == 404);
  REQUIRE(m.num_vertices() == 229);
  const DataArray *phys = find_array(m.cell_data, "gmsh:physical");
  REQUIRE(phys);
  REQUIRE(std::all_of(phys->values.begin(), phys->values.end(), [](double v) { return v == 1.0; }));
}

TEST_CASE("msh: files written by write_msh are read back by gmsh", "[io]") {
  // Gmsh (scripts/install-deps.sh installs it) reads our file and writes it
  // again as ASCII 4.1, binary 4.1 and binary 2.2, which we read back: the
  // binary ones through the reader's runs of elements and data tags.
  if (std::system("command -v gmsh > /dev/null 2>&1") != 0)
    FAIL("gmsh is not installed (scripts/install-deps.sh installs it)");
  for (const char *format : {"-format msh41", "-bin -format msh41", "-bin -format msh22"})
    for (int dim : {2, 3}) {
      INFO("dim " << dim << ", gmsh " << format);
      Mesh m = sample_mesh(dim, 2);
      // Gmsh writes elements grouped by entity; keep one run per entity so
      // that the order survives.
      m.cell_data.erase(m.cell_data.begin(), m.cell_data.begin() + 2);
      m.cell_data.push_back({"gmsh:physical", 1, std::vector<double>(m.num_cells(), 3.0)});
      const std::string in = temp_path("for_gmsh.msh"), out = temp_path("from_gmsh.msh"),
                        log = temp_path("gmsh.log");
      write_msh(in, m);
      const std::string cmd =
          "gmsh '" + in + "' -0 " + format + " -o '" + out + "' > '" + log + "' 2>&1";
      REQUIRE(std::system(cmd.c_str()) == 0);
      INFO(read_file(log));
      REQUIRE(read_file(log).find("Error") == std::string::npos);
      const Mesh back = read_msh(out);
      REQUIRE(back.dim == dim);
      REQUIRE(back.cells == m.cells);
      REQUIRE(back.coords.size() == m.coords.size());
      for (std::size_t i = 0; i < m.coords.size(); ++i)
        REQUIRE(back.coords[i] == Approx(m.coords[i]).margin(1e-15));
      const DataArray *phys = find_array(back.cell_data, "gmsh:physical");
      REQUIRE(phys);
      REQUIRE(phys->values == m.cell_data.back().values);
      fs::remove(in);
      fs::remove(out);
      fs::remove(log);
    }
}

TEST_CASE(
    "msh: unused nodes are dropped, vertices follow node tags, data of the last time step is kept",
    "[io]") {
  const std::string path = write_file("square41.msh", kSquare41);
  const Mesh m = read_msh(path);
  REQUIRE(m.dim == 2);
  // node tags 1, 2, 3, 7 -> vertices 0..3; node 5 is unused
  REQUIRE(m.coords == std::vector<double>{0, 0, 1, 0, 1, 1, 0, 1});
  REQUIRE(m.cells == std::vector<VertexId>{0, 1, 2, 0, 2, 3});
  const DataArray *phys = find_array(m.cell_data, "gmsh:physical");
  const DataArray *geom = find_array(m.cell_data, "gmsh:geometrical");
  const DataArray *flux = find_array(m.cell_data, "flux");
  REQUIRE(phys);
  REQUIRE(geom);
  REQUIRE(flux);
  REQUIRE(phys->values == std::vector<double>{42, 42});
  REQUIRE(geom->values == std::vector<double>{1, 1});
  REQUIRE(flux->components == 2);
  REQUIRE(flux->values ==
          std::vector<double>{0.25, 1e-300, 1.5, -2.5}); // the line's data is dropped
  REQUIRE(m.point_data.size() == 1);
  REQUIRE(m.point_data[0].name == "temp");
  REQUIRE(m.point_data[0].values == std::vector<double>{0.1, 0.2, 0.3, 0.7});
  fs::remove(path);
}

TEST_CASE("msh: 2.2 elements with two tags give physical and geometrical arrays", "[io]") {
  const std::string path = write_file("square22.msh", kSquare22);
  const Mesh m = read_msh(path);
  REQUIRE(m.dim == 2);
  REQUIRE(m.num_cells() == 2);
  REQUIRE(find_array(m.cell_data, "gmsh:physical")->values == std::vector<double>{5, 5});
  REQUIRE(find_array(m.cell_data, "gmsh:geometrical")->values == std::vector<double>{1, 1});
  // without tags there are no tag arrays
  const std::string untagged = write_file(
      "square22_untagged.msh", replaced(replaced(kSquare22, "2 2 2 5 1 1 2 3", "2 2 0 1 2 3"),
                                        "3 2 2 5 1 1 3 4", "3 2 0 1 3 4"));
  REQUIRE(read_msh(untagged).cell_data.empty());
  fs::remove(path);
  fs::remove(untagged);
}

TEST_CASE("msh: a 4.1 entity in several physical groups gives its faces once per group", "[io]") {
  // The boundary line's entity 5 in groups 9 and 4 (9 listed twice), as
  // Gmsh writes `Physical Curve(9) = {5}; Physical Curve(4) = {5};`. A 2.2
  // file lists such an element once per group; the 4.1 reader must keep the
  // line in both groups, not only the first.
  const std::string path =
      write_file("square41_groups.msh",
                 replaced(kSquare41, "5 0 0 0 1 0 0 1 9 0\n", "5 0 0 0 1 0 0 3 9 4 9 0\n"));
  const Mesh m = read_msh(path);
  REQUIRE(m.entities.size() == 1);
  const Entities &lines = m.entities[0];
  REQUIRE(lines.dim == 1);
  REQUIRE(lines.vertices.size() == 4); // the one line, twice
  CHECK(lines.vertices[0] == lines.vertices[2]);
  CHECK(lines.vertices[1] == lines.vertices[3]);
  CHECK(find_array(lines.data, "gmsh:physical")->values == std::vector<double>{9, 4});
  CHECK(find_array(lines.data, "gmsh:geometrical")->values == std::vector<double>{5, 5});
  // The cells keep their entity's first group (a cell is in the mesh once).
  CHECK(find_array(m.cell_data, "gmsh:physical")->values == std::vector<double>{42, 42});
  // Both groups survive a write and a read.
  const std::string again = temp_path("square41_groups_again.msh");
  write_msh(again, m);
  const Mesh back = read_msh(again);
  REQUIRE(back.entities.size() == 1);
  CHECK(find_array(back.entities[0].data, "gmsh:physical")->values == std::vector<double>{9, 4});
  CHECK(back.entities[0].vertices.size() == 4);
  // An entity in 64 groups is kept 64 times; in 65, the file is refused with
  // one line (each group multiplies what the entity's elements hold).
  std::string tags;
  for (int t = 1; t <= 65; ++t) {
    tags += ' ';
    tags += std::to_string(t);
  }
  const std::string many =
      write_file("square41_many.msh",
                 replaced(kSquare41, "5 0 0 0 1 0 0 1 9 0\n", "5 0 0 0 1 0 0 65" + tags + " 0\n"));
  CHECK_THAT(read_error(many), Contains(many) && Contains("line 10") &&
                                   Contains("entity (dimension 1, tag 5)") &&
                                   Contains("more than 64 physical groups"));
  const std::string sixty_four =
      write_file("square41_64.msh",
                 replaced(kSquare41, "5 0 0 0 1 0 0 1 9 0\n",
                          "5 0 0 0 1 0 0 66" + tags.substr(0, tags.rfind(' ')) + " 1 2 0\n"));
  CHECK(read_msh(sixty_four).entities.at(0).vertices.size() == 2 * 64);
  fs::remove(path);
  fs::remove(again);
  fs::remove(many);
  fs::remove(sixty_four);
}

TEST_CASE("msh: triangles off z = 0 are fine as the boundary of tetrahedra", "[io]") {
  const std::string path =
      write_file("tet.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                            "$Nodes\n4\n1 0 0 1\n2 1 0 1\n3 0 1 1\n4 0 0 2\n$EndNodes\n"
                            "$Elements\n2\n1 2 0 1 2 3\n2 4 0 1 2 3 4\n$EndElements\n");
  const Mesh m = read_msh(path);
  REQUIRE(m.dim == 3);
  REQUIRE(m.cells == std::vector<VertexId>{0, 1, 2, 3});
  REQUIRE(m.coords[2] == 1.0);
  fs::remove(path);
}

TEST_CASE("msh: truncated file names the line", "[io]") {
  const std::string text = kSquare22.substr(0, kSquare22.find("4 0 1 0")); // ends after line 8
  const std::string path = write_file("truncated.msh", text);
  const std::string e = read_error(path);
  CHECK_THAT(e,
             Contains(path) && Contains("line 9") && Contains("file ends") && Contains("node tag"));
  fs::remove(path);
}

TEST_CASE("msh: element data rows in another order than the cells go to their cells", "[io]") {
  // One row per cell, as the fast path's files have, but listed backwards,
  // and again in order; and a row missing.
  const std::string data = "$ElementData\n1\n\"heat\"\n1\n0.0\n3\n0\n1\n2\n";
  for (const auto &[rows, want] : std::vector<std::pair<std::string, std::vector<double>>>{
           {"3 30\n2 20\n", {20, 30}}, {"2 20\n3 30\n", {20, 30}}}) {
    const std::string path =
        write_file("data_order.msh", kSquare22 + data + rows + "$EndElementData\n");
    const Mesh m = read_msh(path);
    const DataArray *heat = find_array(m.cell_data, "heat");
    REQUIRE(heat);
    CHECK(heat->values == want);
    fs::remove(path);
  }
  const std::string path = write_file(
      "data_short.msh", kSquare22 + replaced(data, "\n2\n", "\n1\n") + "3 30\n$EndElementData\n");
  CHECK_THROWS_WITH(read_msh(path), Contains("has no value for element 2"));
  fs::remove(path);
}

TEST_CASE("msh: element referencing missing node is rejected", "[io]") {
  const std::string path =
      write_file("missing_node.msh", replaced(kSquare22, "1 1 3 4\n", "1 1 3 9\n"));
  CHECK_THAT(read_error(path), Contains(path) && Contains("line 15") && Contains("element 3") &&
                                   Contains("node 9") && Contains("not in $Nodes"));
  fs::remove(path);
}

TEST_CASE("msh: quads mixed with triangles are rejected", "[io]") {
  const std::string path =
      write_file("quads.msh", replaced(replaced(kSquare22, "$Elements\n3\n", "$Elements\n4\n"),
                                       "$EndElements", "4 3 2 5 1 1 2 3 4\n$EndElements"));
  CHECK_THAT(read_error(path), Contains(path) && Contains("line 16") &&
                                   Contains("mixed non-simplex cells") && Contains("quadrangle"));
  fs::remove(path);
}

TEST_CASE("msh: triangles not in one plane z = c are rejected, with a hint", "[io]") {
  const std::string path =
      write_file("off_plane.msh", replaced(kSquare22, "3 1 1 0\n", "3 1 1 0.5\n"));
  std::string e;
  try {
    read_mesh(path);
  } catch (const InputError &x) {
    e = x.what();
  }
  CHECK_THAT(e,
             Contains(path) && Contains("not in one plane z = c") && Contains("Physical Volume"));
  fs::remove(path);
}

TEST_CASE("msh: a triangle mesh in the plane z = 5 is read, refined and written back at z = 5",
          "[io]") {
  std::string text = kSquare22;
  for (const char *node : {"1 0 0 0\n", "2 1 0 0\n", "3 1 1 0\n", "4 0 1 0\n"}) {
    std::string n = node;
    text = replaced(text, n, n.substr(0, n.size() - 2) + "5\n");
  }
  const std::string path = write_file("plane5.msh", text);
  const Mesh m = read_mesh(path);
  REQUIRE(m.dim == 2);
  const DataArray *z = find_array(m.point_data, kPlaneZArray);
  REQUIRE(z);
  for (double v : z->values)
    CHECK(v == 5.0);
  const std::string out = temp_path("plane5-out.msh");
  write_mesh(out, m);
  const std::string written = read_file(out);
  CHECK(written.find("bisect:z") == std::string::npos); // in the nodes, not an array
  const Mesh back = read_mesh(out);
  const DataArray *zb = find_array(back.point_data, kPlaneZArray);
  REQUIRE(zb);
  CHECK(zb->values == z->values);
  fs::remove(path);
  fs::remove(out);
}

TEST_CASE("msh: higher-order simplices are rejected", "[io]") {
  const std::string path = write_file(
      "second_order.msh", replaced(replaced(kSquare22, "$Elements\n3\n", "$Elements\n4\n"),
                                   "$EndElements", "4 9 2 5 1 1 2 3 4 1 2\n$EndElements"));
  CHECK_THAT(read_error(path), Contains(path) && Contains("line 16") &&
                                   Contains("6-node triangle") && Contains("higher-order"));
  fs::remove(path);
}

TEST_CASE("msh: duplicate node tags and duplicate element tags are rejected", "[io]") {
  const std::string nodes =
      write_file("dup_nodes.msh", replaced(kSquare22, "4 0 1 0\n", "2 0 1 0\n"));
  CHECK_THAT(read_error(nodes), Contains(nodes) && Contains("line 9") &&
                                    Contains("duplicate node tag 2") && Contains("line 7"));
  const std::string elements =
      write_file("dup_elements.msh", replaced(kSquare22, "3 2 2 5", "2 2 2 5"));
  CHECK_THAT(read_error(elements),
             Contains(elements) && Contains("line 15") && Contains("duplicate element tag 2"));
  fs::remove(nodes);
  fs::remove(elements);
}

TEST_CASE("msh: non-finite coordinates are rejected", "[io]") {
  for (const char *bad : {"nan", "inf", "-inf", "1e999"}) {
    INFO(bad);
    const std::string path =
        write_file("nan.msh", replaced(kSquare22, "2 1 0 0\n", std::string("2 ") + bad + " 0 0\n"));
    const std::string e = read_error(path);
    CHECK_THAT(e, Contains(path) && Contains("line 7"));
    CHECK((e.find("non-finite") != std::string::npos ||
           e.find("expected node coordinate") != std::string::npos));
    fs::remove(path);
  }
}

TEST_CASE("msh: garbage where a number is expected names the line and the token", "[io]") {
  const std::string path =
      write_file("garbage.msh", replaced(kSquare22, "2 1 0 0\n", "2 1 zero 0\n"));
  CHECK_THAT(read_error(path), Contains(path) && Contains("line 7") && Contains("'zero'"));
  const std::string count =
      write_file("garbage_count.msh", replaced(kSquare22, "$Nodes\n4\n", "$Nodes\n4x\n"));
  CHECK_THAT(read_error(count),
             Contains("line 5") && Contains("number of nodes") && Contains("'4x'"));
  fs::remove(path);
  fs::remove(count);
}

TEST_CASE("msh: wrong counts and missing $End markers are rejected", "[io]") {
  const std::string more =
      write_file("count_more.msh", replaced(kSquare22, "$Nodes\n4\n", "$Nodes\n5\n"));
  CHECK_THAT(read_error(more),
             Contains("line 10") && Contains("node tag") && Contains("'$EndNodes'"));
  const std::string fewer =
      write_file("count_fewer.msh", replaced(kSquare22, "$Elements\n3\n", "$Elements\n2\n"));
  CHECK_THAT(read_error(fewer), Contains("line 15") && Contains("expected $EndElements"));
  const std::string no_end = write_file("no_end.msh", replaced(kSquare22, "$EndElements\n", ""));
  CHECK_THAT(read_error(no_end),
             Contains(no_end) && Contains("file ends") && Contains("$EndElements"));
  const std::string no_end_unknown = write_file("no_end_unknown.msh", kSquare22 + "$Periodic\n1\n");
  CHECK_THAT(read_error(no_end_unknown), Contains("line 17") && Contains("$EndPeriodic"));
  const std::string no_elements =
      write_file("no_elements.msh", kSquare22.substr(0, kSquare22.find("$Elements")));
  CHECK_THAT(read_error(no_elements), Contains("no $Elements section"));
  for (const std::string &p : {more, fewer, no_end, no_end_unknown, no_elements})
    fs::remove(p);
}

TEST_CASE("msh: unsupported versions are rejected", "[io]") {
  for (const char *v : {"4.0", "3.0", "2.1", "1"}) {
    INFO(v);
    const std::string path =
        write_file("version.msh", replaced(kSquare22, "2.2 0 8", std::string(v) + " 0 8"));
    CHECK_THAT(read_error(path),
               Contains(path) && Contains("line 2") && Contains("unsupported MSH version"));
    fs::remove(path);
  }
  const std::string v1 = write_file("version1.msh", "$NOD\n1\n1 0 0 0\n$ENDNOD\n");
  CHECK_THAT(read_error(v1), Contains("line 1") && Contains("version 1"));
  fs::remove(v1);
}

TEST_CASE("msh: a file with no triangles or tetrahedra is rejected", "[io]") {
  const std::string path = write_file(
      "lines_only.msh", replaced(replaced(replaced(kSquare22, "$Elements\n3\n", "$Elements\n1\n"),
                                          "2 2 2 5 1 1 2 3\n", ""),
                                 "3 2 2 5 1 1 3 4\n", ""));
  CHECK_THAT(read_error(path), Contains(path) && Contains("no triangles or tetrahedra"));
  fs::remove(path);
}

TEST_CASE("msh: node data must cover every kept node", "[io]") {
  const std::string path = write_file("partial_data.msh", replaced(kSquare41, "4\n7 0.7\n", "3\n"));
  CHECK_THAT(read_error(path),
             Contains(path) && Contains("'temp'") && Contains("no value for node 7"));
  fs::remove(path);
}

TEST_CASE("msh: a 4D mesh cannot be written as .msh", "[io][4d]") {
  Mesh m;
  m.dim = 4;
  m.coords = {0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  m.cells = {0, 1, 2, 3, 4};
  const std::string path = temp_path("four.msh");
  REQUIRE_THROWS_WITH(write_msh(path, m),
                      Contains(path) && Contains("cannot hold a 4D mesh; write .vtu"));
  REQUIRE(!fs::exists(path));
}

TEST_CASE("msh: corrupted huge counts in a binary file are rejected without allocating", "[io]") {
  const std::string good = temp_path("good.msh");
  write_msh(good, sample_mesh(2, 2));
  const std::string bytes = read_file(good);
  // 4.1 binary: "$Nodes\n" then size_t numBlocks, numNodes, minTag, maxTag.
  const std::size_t nodes = bytes.find("$Nodes\n") + 7;
  const std::size_t elements = bytes.find("$Elements\n") + 10;
  for (std::size_t offset : {nodes, nodes + 8, elements, elements + 8, elements + 32 + 12}) {
    for (std::uint64_t huge : {std::uint64_t(-1), std::uint64_t(1) << 62, std::uint64_t(1) << 40}) {
      INFO("offset " << offset << " value " << huge);
      std::string bad = bytes;
      std::memcpy(bad.data() + offset, &huge, sizeof huge);
      const std::string path = write_file("huge.msh", bad);
      CHECK_THAT(read_error(path), Contains(path) && Contains("byte offset"));
      fs::remove(path);
    }
  }
  fs::remove(good);
}

TEST_CASE("msh: every truncation or single-byte corruption of a binary file fails cleanly",
          "[io]") {
  // Each damaged file either still reads or throws InputError: no crash, no
  // other exception (run under the sanitizer build to check memory too).
  const std::string good = temp_path("fuzz_source.msh");
  write_msh(good, sample_mesh(2, 1));
  const std::string bytes = read_file(good);
  const std::string path = temp_path("fuzz.msh");
  std::size_t rejected = 0;
  auto attempt = [&](const std::string &content) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
    try {
      read_msh(path);
    } catch (const InputError &) {
      ++rejected;
    }
  };
  for (std::size_t n = 0; n < bytes.size(); ++n)
    attempt(bytes.substr(0, n));
  REQUIRE(rejected + 8 >= bytes.size()); // only cuts just after an $End marker may pass
  for (std::size_t i = 0; i < bytes.size(); ++i)
    for (unsigned char flip : {0x01, 0xFF}) {
      std::string bad = bytes;
      bad[i] = char(static_cast<unsigned char>(bad[i]) ^ flip);
      attempt(bad);
    }
  fs::remove(good);
  fs::remove(path);
}

// The reader keeps a binary file's elements as runs while their tags run on
// by one, else one reference each (the runs so far expanded), and a data
// section's row tags as a first tag and a count while they do. Both must give
// the same mesh, or the same message, for every single-byte corruption and
// every truncation of binary files of both versions: tags in one range
// (runs throughout), tags out of order (write_msh's blocks per entity: the
// expansion), several dimensions with tagged entities, and Gmsh's own.
TEST_CASE("msh: elements kept as runs read as one reference each would, damaged or not", "[io]") {
  std::vector<std::pair<std::string, std::string>> files; // name, bytes
  Mesh plain = sample_mesh(3, 1);
  plain.cell_data.erase(plain.cell_data.begin(), plain.cell_data.begin() + 2); // one block
  const std::string path = temp_path("runs.msh");
  write_msh(path, plain);
  files.emplace_back("one block", read_file(path));
  write_msh(path, sample_mesh(2, 1));
  files.emplace_back("blocks per entity", read_file(path));
  write_msh(path, read_msh(testing::data_path("box-tagged.msh")));
  files.emplace_back("tagged entities", read_file(path));
  files.emplace_back("gmsh 2.2 binary", read_file(msh_data("two_boxes_22b.msh")));
  files.emplace_back("gmsh 4.1 binary", read_file(msh_data("two_boxes_41b.msh")));
  std::size_t compared = 0, read = 0;
  for (const auto &[name, bytes] : files) {
    auto outcome = [&](bool runs) {
      testing::set_msh_element_runs(runs);
      std::pair<std::string, Mesh> o;
      try {
        o.second = read_msh(path);
      } catch (const InputError &e) {
        o.first = e.what();
      }
      testing::set_msh_element_runs(true);
      return o;
    };
    auto same = [&](const std::string &content) {
      std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
      const auto [message, mesh] = outcome(true);
      const auto [expected, reference] = outcome(false);
      INFO(name << ": " << expected);
      REQUIRE(message == expected);
      if (message.empty()) {
        require_identical(mesh, reference);
        REQUIRE(mesh.entities.size() == reference.entities.size());
        for (std::size_t k = 0; k < mesh.entities.size(); ++k) {
          REQUIRE(mesh.entities[k].vertices == reference.entities[k].vertices);
          require_same_arrays(mesh.entities[k].data, reference.entities[k].data);
        }
        ++read;
      }
      ++compared;
    };
    same(bytes);
    for (std::size_t n = 0; n < bytes.size(); n += 11)
      same(bytes.substr(0, n));
    for (std::size_t i = 0; i < bytes.size(); ++i)
      for (unsigned char flip : {0x01, 0x80}) {
        std::string bad = bytes;
        bad[i] = char(static_cast<unsigned char>(bad[i]) ^ flip);
        same(bad);
      }
  }
  INFO(compared << " files compared, " << read << " read");
  REQUIRE(read > 100);
  fs::remove(path);
}
