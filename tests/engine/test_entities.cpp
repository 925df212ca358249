// Tagged lower-dimensional entities (mesh.hpp, Entities) travel with the
// mesh: refinement splits them with their cells (each physical group keeps
// its measure, every entity stays a face), coarsening merges them back, the
// .msh and .vtu files keep them with their physical names, and an entity
// that is not a face is an input error naming it.
#include "bisect/check.hpp"
#include "bisect/coarsen.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/refine.hpp"
#include "core/faces.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unistd.h>

using namespace bisect;
namespace fs = std::filesystem;

namespace {

std::string temp_path(const std::string &name) {
  return (fs::temp_directory_path() /
          ("bisect-entities-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

const DataArray *array_named(const std::vector<DataArray> &arrays, const std::string &name) {
  for (const DataArray &a : arrays)
    if (a.name == name)
      return &a;
  return nullptr;
}

// The measure of a k-simplex (k = 0..3) in the mesh's space: sqrt(det G)/k!
// with G the Gram matrix of its edge vectors from the first vertex.
double simplex_measure(const Mesh &m, const VertexId *v, int k) {
  if (k == 0)
    return 1;
  double e[3][4] = {};
  for (int i = 0; i < k; ++i)
    for (int d = 0; d < m.dim; ++d)
      e[i][d] = m.point(v[i + 1])[d] - m.point(v[0])[d];
  double g[3][3];
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      g[i][j] = 0;
      for (int d = 0; d < m.dim; ++d)
        g[i][j] += e[i][d] * e[j][d];
    }
  double det = k == 1   ? g[0][0]
               : k == 2 ? g[0][0] * g[1][1] - g[0][1] * g[1][0]
                        : g[0][0] * (g[1][1] * g[2][2] - g[1][2] * g[2][1]) -
                              g[0][1] * (g[1][0] * g[2][2] - g[1][2] * g[2][0]) +
                              g[0][2] * (g[1][0] * g[2][1] - g[1][1] * g[2][0]);
  return std::sqrt(std::max(det, 0.0)) / (k == 3 ? 6 : k == 2 ? 2 : 1);
}

// (dimension, physical tag) -> total measure of the tagged entities.
std::map<std::pair<int, int>, double> group_measures(const Mesh &m) {
  std::map<std::pair<int, int>, double> out;
  for (const Entities &b : m.entities) {
    const DataArray *phys = array_named(b.data, "gmsh:physical");
    REQUIRE(phys);
    for (std::size_t i = 0; i < b.size(); ++i)
      out[{b.dim, int(phys->values[i])}] += simplex_measure(m, b.entity(i), b.dim);
  }
  return out;
}

// Every entity as (dimension, physical, geometrical, sorted vertex
// coordinates), sorted: what must survive files and refine + coarsen.
using EntityShape = std::tuple<int, int, int, std::vector<std::vector<double>>>;
std::vector<EntityShape> entity_shapes(const Mesh &m) {
  std::vector<EntityShape> out;
  for (const Entities &b : m.entities) {
    const DataArray *phys = array_named(b.data, "gmsh:physical");
    const DataArray *geom = array_named(b.data, "gmsh:geometrical");
    for (std::size_t i = 0; i < b.size(); ++i) {
      std::vector<std::vector<double>> pts;
      for (int k = 0; k <= b.dim; ++k)
        pts.emplace_back(m.point(b.entity(i)[k]), m.point(b.entity(i)[k]) + m.dim);
      std::sort(pts.begin(), pts.end());
      out.emplace_back(b.dim, phys ? int(phys->values[i]) : 0, geom ? int(geom->values[i]) : 0,
                       pts);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void require_all_faces(const Mesh &m) {
  for (const Entities &b : m.entities)
    REQUIRE(first_entity_not_a_face(m, b) == std::size_t(-1));
}

std::vector<std::tuple<int, int, std::string>> names_of(const Mesh &m) {
  std::vector<std::tuple<int, int, std::string>> out;
  for (const PhysicalName &n : m.physical_names)
    out.emplace_back(n.dim, n.tag, n.name);
  std::sort(out.begin(), out.end());
  return out;
}

// The cells with a vertex within `r` of p.
std::vector<CellId> cells_near(const Mesh &m, const std::vector<double> &p, double r) {
  std::vector<CellId> out;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    for (int i = 0; i < m.cell_size(); ++i) {
      double d2 = 0;
      for (int k = 0; k < m.dim; ++k)
        d2 += std::pow(m.point(m.cell(CellId(c))[i])[k] - p[k], 2);
      if (d2 < r * r) {
        out.push_back(CellId(c));
        break;
      }
    }
  return out;
}

// The bundled tagged meshes (scripts/make_tagged.py): left, right, walls,
// the embedded plane (line) x = 1/2, a curve (3D) or a point (2D).
const char *const kTaggedMeshes[] = {"box-tagged.msh", "square-tagged.msh"};

} // namespace

TEST_CASE("entities: the bundled meshes read with every group, its names, all faces",
          "[entities][io][2d][3d]") {
  const Mesh box = load_mesh(testing::data_path("box-tagged.msh"));
  REQUIRE(box.dim == 3);
  const auto measures = group_measures(box);
  CHECK(measures.at({2, 1}) == Approx(1)); // left
  CHECK(measures.at({2, 2}) == Approx(1)); // right
  CHECK(measures.at({2, 3}) == Approx(4)); // walls
  CHECK(measures.at({2, 4}) == Approx(1)); // mid (embedded)
  CHECK(measures.at({1, 5}) == Approx(1)); // edge (a curve)
  CHECK(names_of(box).size() == 6);
  require_all_faces(box);
  const Mesh square = load_mesh(testing::data_path("square-tagged.msh"));
  REQUIRE(square.dim == 2);
  const auto m2 = group_measures(square);
  CHECK(m2.at({1, 1}) == Approx(1));
  CHECK(m2.at({1, 3}) == Approx(2));
  CHECK(m2.at({1, 4}) == Approx(1));
  CHECK(m2.at({0, 5}) == Approx(1)); // one point
  require_all_faces(square);
}

TEST_CASE("entities: local refinement keeps each group's measure and every entity a face, and "
          "coarsening gives the entities back",
          "[entities][refine][coarsen][2d][3d]") {
  for (const char *name : kTaggedMeshes) {
    INFO(name);
    Mesh m = load_mesh(testing::data_path(name));
    ensure_marked(m);
    const auto measures = group_measures(m);
    const auto shapes = entity_shapes(m);
    std::size_t entities = 0;
    // Near the corner (0, 0, 0), where left, walls and the curve meet, and
    // near the embedded plane.
    for (int it = 0; it < 6; ++it) {
      const std::vector<double> p =
          it % 2 ? std::vector<double>{0.5, 0.3, 0.2} : std::vector<double>{0.0, 0.0, 0.0};
      const RefineResult r = refine(m, cells_near(m, p, 0.3));
      REQUIRE_FALSE(r.limit_reached);
      require_all_faces(m);
      const auto now = group_measures(m);
      REQUIRE(now.size() == measures.size());
      for (const auto &[group, measure] : measures)
        REQUIRE(now.at(group) == Approx(measure).epsilon(1e-12));
    }
    for (const Entities &b : m.entities)
      entities += b.size();
    CHECK(entities > shapes.size()); // some were split
    CoarsenOptions all;
    all.passes = 0;
    coarsen(m, std::vector<char>(m.num_cells(), 1), all);
    require_all_faces(m);
    CHECK(entity_shapes(m) == shapes);
  }
}

TEST_CASE("entities: a mesh without entities refines as before (no entity blocks appear)",
          "[entities][refine][3d]") {
  Mesh m = load_mesh(testing::data_path("box-tagged.msh"));
  Mesh plain = m;
  plain.entities.clear();
  ensure_marked(m);
  ensure_marked(plain);
  refine(m, cells_near(m, {0, 0, 0}, 0.4));
  refine(plain, cells_near(plain, {0, 0, 0}, 0.4));
  CHECK(plain.entities.empty());
  CHECK(testing::mesh_difference(m, plain).empty()); // the cells do not depend on the entities
}

TEST_CASE("entities: .msh -> .msh and .msh -> .vtu -> .msh keep groups and names",
          "[entities][io][2d][3d]") {
  for (const char *name : kTaggedMeshes) {
    INFO(name);
    const Mesh in = load_mesh(testing::data_path(name));
    const std::string msh = temp_path("a.msh"), vtu = temp_path("b.vtu"), msh2 = temp_path("c.msh");
    write_mesh(msh, in);
    const Mesh a = load_mesh(msh);
    CHECK(entity_shapes(a) == entity_shapes(in));
    CHECK(names_of(a) == names_of(in));
    write_mesh(vtu, a);
    const Mesh b = load_mesh(vtu);
    CHECK(entity_shapes(b) == entity_shapes(in));
    CHECK(names_of(b) == names_of(in));
    CHECK(b.num_cells() == in.num_cells());
    write_mesh(msh2, b);
    const Mesh c = load_mesh(msh2);
    CHECK(entity_shapes(c) == entity_shapes(in));
    CHECK(names_of(c) == names_of(in));
    fs::remove(msh);
    fs::remove(vtu);
    fs::remove(msh2);
  }
}

TEST_CASE("entities: a tagged element that is not a face is an input error naming it",
          "[entities][io][3d]") {
  // Element 1 is the first triangle of "left" (x = 0); move it off the mesh
  // by giving it a node of the right side.
  std::ifstream in(testing::data_path("box-tagged.msh"));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string block = "2 1 2 ";
  const std::size_t at = s.find("\n", s.find(block, s.find("$Elements"))) + 1;
  const std::size_t end = s.find('\n', at);
  std::istringstream row(s.substr(at, end - at));
  std::string tag, a, b, c;
  row >> tag >> a >> b >> c;
  REQUIRE(tag == "1");
  s.replace(at, end - at, "1 " + a + " " + b + " 27"); // node 27 is (1, 1, 1)
  const std::string bad = temp_path("bad.msh");
  std::ofstream(bad) << s;
  REQUIRE_THROWS_WITH(load_mesh(bad), Catch::Contains("element 1 (triangle, physical 1) is not "
                                                      "a face of the mesh"));
  fs::remove(bad);

  // The same in a .vtu: the writer does not check, the reader does.
  Mesh m = load_mesh(testing::data_path("box-tagged.msh"));
  Entities &tri = *std::find_if(m.entities.begin(), m.entities.end(),
                                [](const Entities &e) { return e.dim == 2; });
  // (0, 0, 0) and (1, 1, 1) share no cell.
  tri.vertices[0] = VertexId(0);
  tri.vertices[1] = VertexId(m.num_vertices() - 1);
  tri.vertices[2] = VertexId(1);
  const std::string vtu = temp_path("bad.vtu");
  write_mesh(vtu, m);
  REQUIRE_THROWS_WITH(load_mesh(vtu), Catch::Contains("(triangle) is not a face of the mesh"));
  fs::remove(vtu);
}

TEST_CASE("entities: 4D tetrahedra, triangles and lines in a .vtu split with the pentatopes",
          "[entities][io][refine][coarsen][4d]") {
  // Tag the boundary facets x0 = 0 of a Kuhn hypercube mesh (tetrahedra),
  // one of their triangles and one of its edges.
  Mesh m = generate_kuhn(4, 2);
  Entities tets, tris, lines;
  tets.dim = 3;
  tris.dim = 2;
  lines.dim = 1;
  for (std::size_t c = 0; c < m.num_cells(); ++c)
    for_each_face(m.cell(CellId(c)), 5, 3, [&](const VertexId *f, int) {
      if (std::all_of(f, f + 4, [&](VertexId v) { return m.point(v)[0] == 0; }))
        tets.vertices.insert(tets.vertices.end(), f, f + 4);
    });
  REQUIRE(tets.size() > 0);
  tris.vertices.assign(tets.vertices.begin(), tets.vertices.begin() + 3);
  lines.vertices.assign(tets.vertices.begin(), tets.vertices.begin() + 2);
  for (Entities *b : {&tets, &tris, &lines})
    b->data.push_back(DataArray{"gmsh:physical", 1, std::vector<double>(b->size(), 7.0)});
  m.entities = {lines, tris, tets};
  const std::string vtu = temp_path("4d.vtu");
  write_mesh(vtu, m);
  Mesh in = load_mesh(vtu);
  fs::remove(vtu);
  REQUIRE(in.entities.size() == 3);
  require_all_faces(in);
  ensure_marked(in);
  const auto shapes = entity_shapes(in);
  double measures[3] = {};
  for (const Entities &b : in.entities)
    for (std::size_t i = 0; i < b.size(); ++i)
      measures[b.dim - 1] += simplex_measure(in, b.entity(i), b.dim);
  CHECK(measures[2] == Approx(1.0)); // the facet x0 = 0 of the unit hypercube
  for (int it = 0; it < 3; ++it)
    refine(in, cells_near(in, {0, 0, 0, 0}, 0.6));
  require_all_faces(in);
  double after[3] = {};
  for (const Entities &b : in.entities)
    for (std::size_t i = 0; i < b.size(); ++i)
      after[b.dim - 1] += simplex_measure(in, b.entity(i), b.dim);
  for (int d = 0; d < 3; ++d)
    CHECK(after[d] == Approx(measures[d]).epsilon(1e-12));
  CoarsenOptions all;
  all.passes = 0;
  coarsen(in, std::vector<char>(in.num_cells(), 1), all);
  CHECK(entity_shapes(in) == shapes);
}

TEST_CASE("entities: a facet in two physical groups splits and merges as two entities",
          "[entities][refine][coarsen][2d]") {
  // Gmsh 2.2 writes an element once per physical group: the left side is
  // also in group 9 here.
  Mesh m = load_mesh(testing::data_path("square-tagged.msh"));
  Entities &lines = *std::find_if(m.entities.begin(), m.entities.end(),
                                  [](const Entities &e) { return e.dim == 1; });
  const std::size_t n = lines.size();
  DataArray &phys = *std::find_if(lines.data.begin(), lines.data.end(),
                                  [](const DataArray &a) { return a.name == "gmsh:physical"; });
  for (std::size_t i = 0; i < n; ++i)
    if (phys.values[i] == 1) {
      lines.vertices.insert(lines.vertices.end(), lines.entity(i), lines.entity(i) + 2);
      for (DataArray &a : lines.data)
        a.values.push_back(&a == &phys ? 9.0 : a.values[i]);
    }
  ensure_marked(m);
  const auto shapes = entity_shapes(m);
  const auto measures = group_measures(m);
  REQUIRE(measures.at({1, 9}) == Approx(1));
  for (int it = 0; it < 4; ++it)
    refine(m, cells_near(m, {0, 0.5}, 0.3));
  require_all_faces(m);
  CHECK(group_measures(m).at({1, 9}) == Approx(1).epsilon(1e-12));
  CHECK(group_measures(m).at({1, 1}) == Approx(1).epsilon(1e-12));
  CoarsenOptions all;
  all.passes = 0;
  coarsen(m, std::vector<char>(m.num_cells(), 1), all);
  CHECK(entity_shapes(m) == shapes);
}
