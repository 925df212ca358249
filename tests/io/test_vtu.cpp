// Reading and writing .vtu files, and the checks read_mesh/write_mesh make
// before any format-specific code runs.
#include "bisect/driver.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"
#include "bisect/text.hpp"
#include "bisect/threads.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

using namespace bisect;
namespace fs = std::filesystem;

namespace {

// A fresh directory under the system temp dir, removed at the end of the test.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("bisect_test_vtu_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  std::string file(const std::string &name) const { return (path / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto &e : fs::directory_iterator(path))
      names.push_back(e.path().filename().string());
    return names;
  }
};

void write_text(const std::string &path, const std::string &text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_text(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `f`, returning the message of the InputError it throws and whatever
// was printed to stderr meanwhile (redirected to a file).
struct Failure {
  bool threw = false;
  std::string message;
  std::string stderr_text;
};

Failure capture_failure(const std::function<void()> &f) {
  Failure result;
  const std::string err_file =
      (fs::temp_directory_path() / ("bisect_test_vtu_stderr_" + std::to_string(::getpid())))
          .string();
  std::fflush(stderr);
  const int saved = ::dup(2);
  const int fd = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  ::dup2(fd, 2);
  ::close(fd);
  try {
    f();
  } catch (const InputError &e) {
    result.threw = true;
    result.message = e.what();
  }
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  result.stderr_text = read_text(err_file);
  std::remove(err_file.c_str());
  return result;
}

// Expects reading `path` to fail with one clean line naming the file and
// containing `expected`, with nothing printed to stderr.
void require_clean_read_error(const std::string &path, const std::string &expected) {
  Failure f = capture_failure([&] { read_mesh(path); });
  INFO("message: " << f.message);
  INFO("stderr: " << f.stderr_text);
  REQUIRE(f.threw);
  CHECK(f.message.find(fs::path(path).filename().string()) != std::string::npos);
  CHECK(f.message.find(expected) != std::string::npos);
  CHECK(f.message.find('\n') == std::string::npos);
  CHECK(f.stderr_text.empty());
}

// Two tetrahedra sharing the face (1, 2, 3), with awkward coordinates and
// point/cell arrays of several shapes.
Mesh two_tets() {
  Mesh m;
  m.dim = 3;
  m.coords = {0.1, 0.2, 0.3, 1.0 / 3.0, 0.0, 1e-300, 0.0, 2.0 / 7.0,
              0.0, 0.0, 0.0, -1.7e5,    1.0, 1.0,    1.0};
  m.cells = {0, 1, 2, 3, 4, 3, 2, 1};
  m.point_data.push_back({"temperature", 1, {1.5, -2.25, 0.1, 1e10, std::numbers::pi}});
  m.point_data.push_back({"velocity", 2, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9.5}});
  m.cell_data.push_back({"region", 1, {7, -3}});
  m.cell_data.push_back({"quality", 1, {0.5, 1.0 / 3.0}});
  m.cell_data.push_back({"normal", 3, {1, 0, 0, 0, 1, 0}});
  return m;
}

void require_same(const Mesh &a, const Mesh &b) {
  REQUIRE(testing::mesh_difference(a, b) == "");
}

// A hand-written ASCII .vtu file (VTK's reference layout).
struct AsciiVtu {
  std::string points;       // "x y z  x y z ..."
  std::string connectivity; // "0 1 2 3 ..."
  std::string offsets;
  std::string types;
  std::string point_data; // <DataArray> elements
  std::string cell_data;
  std::string field_data;
  int num_points = 0;
  int num_cells = 0;

  std::string text() const {
    std::ostringstream s;
    s << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n<UnstructuredGrid>\n";
    if (!field_data.empty())
      s << "<FieldData>" << field_data << "</FieldData>\n";
    s << "<Piece NumberOfPoints=\"" << num_points << "\" NumberOfCells=\"" << num_cells
      << "\">\n<PointData>" << point_data << "</PointData>\n<CellData>" << cell_data
      << "</CellData>\n<Points><DataArray type=\"Float64\" Name=\"Points\" "
         "NumberOfComponents=\"3\" format=\"ascii\">"
      << points
      << "</DataArray></Points>\n<Cells>\n"
         "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
      << connectivity
      << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">" << offsets
      << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" << types
      << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    return s.str();
  }
};

std::string ascii_array(const std::string &type, const std::string &name, int components,
                        const std::string &values) {
  return "<DataArray type=\"" + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
         std::to_string(components) + "\" format=\"ascii\">" + values + "</DataArray>\n";
}

// One tetrahedron (4 points, VTK type 10), no arrays.
AsciiVtu one_tet() {
  AsciiVtu f;
  f.num_points = 4;
  f.points = "0 0 0  1 0 0  0 1 0  0 0 1";
  f.num_cells = 1;
  f.connectivity = "0 1 2 3";
  f.offsets = "4";
  f.types = "10";
  return f;
}

// data/square-tagged.msh and data/box-tagged.msh, marked with `marking` and
// refined `iterations` times around a sphere near a corner, by name.
std::vector<std::pair<std::string, Mesh>> refined_tagged(Marking marking, int iterations) {
  std::vector<std::pair<std::string, Mesh>> out;
  for (const char *name : {"square-tagged.msh", "box-tagged.msh"}) {
    Mesh m = load_mesh(testing::data_path(name));
    mark_mesh(m, marking);
    auto r = parse_region(m.dim == 2 ? R"({"type":"sphere","center":[0.3,0.4],"radius":0.3})"
                                     : R"({"type":"sphere","center":[0.3,0.4,0.5],"radius":0.3})",
                          m.dim, "t");
    for (int it = 0; it < iterations; ++it)
      refine(m, select_cells(m, *r));
    out.emplace_back(name, std::move(m));
  }
  return out;
}

const std::string kSpatialDimension4 =
    "<DataArray type=\"Int32\" Name=\"SpatialDimension\" NumberOfTuples=\"1\" "
    "format=\"ascii\">4</DataArray>";

// One pentatope (5 points) in the 4D convention, with `cells` as given.
AsciiVtu pentatope_file() {
  AsciiVtu f;
  f.num_points = 5;
  f.points = "0 0 0  1 0 0  0 1 0  0 0 1  0 0 0";
  f.point_data = ascii_array("Float64", "t", 1, "0 0 0 0 1");
  f.field_data = kSpatialDimension4;
  f.num_cells = 1;
  f.connectivity = "0 1 2 3 4";
  f.offsets = "5";
  f.types = "2";
  return f;
}

} // namespace

TEST_CASE("vtu: 3D round trip preserves coordinates, cells and arrays exactly", "[io][3d]") {
  TempDir dir;
  const Mesh m = two_tets();
  write_mesh(dir.file("m.vtu"), m);
  const Mesh back = read_mesh(dir.file("m.vtu"));
  require_same(m, back);
  CHECK(back.stage.empty());
}

TEST_CASE("vtu: an integer array written in a type too narrow for its values is widened",
          "[io][3d]") {
  // A tool's values in a file's type: coarsen --sum of Int8 counts past 127
  // (written as -56 and 44 before), the mean of two labels.
  TempDir dir;
  Mesh m = two_tets();
  m.cell_data = {{"count", 1, {100, 300}, ValueType::Int8},
                 {"big", 1, {1, 3e9}, ValueType::Int32},
                 {"half", 1, {1, 1.5}, ValueType::UInt8},
                 {"fits", 1, {-3, 127}, ValueType::Int8}};
  write_mesh(dir.file("m.vtu"), m);
  const Mesh back = read_mesh(dir.file("m.vtu"));
  const std::pair<const char *, ValueType> want[] = {{"count", ValueType::Int32},
                                                     {"big", ValueType::Int64},
                                                     {"half", ValueType::Float64},
                                                     {"fits", ValueType::Int8}};
  auto named = [](const std::vector<DataArray> &arrays, const std::string &name) {
    for (const DataArray &a : arrays)
      if (a.name == name)
        return &a;
    return static_cast<const DataArray *>(nullptr);
  };
  for (const auto &[name, type] : want) {
    INFO(name);
    const DataArray *a = named(back.cell_data, name);
    REQUIRE(a);
    CHECK(a->type == type);
    CHECK(a->values == named(m.cell_data, name)->values);
  }
}

TEST_CASE("vtu: 2D mesh comes back 2D", "[io][2d]") {
  TempDir dir;
  Mesh m;
  m.dim = 2;
  m.coords = {0, 0, 1, 0, 0.1, 0.7, 1, 1};
  m.cells = {0, 1, 2, 2, 1, 3};
  m.cell_data.push_back({"gmsh:physical", 1, {1, 2}});
  write_vtu(dir.file("m.vtu"), m);
  require_same(m, read_vtu(dir.file("m.vtu")));
}

TEST_CASE("vtu: 4D round trip through the t array", "[io][4d]") {
  TempDir dir;
  Mesh m;
  m.dim = 4;
  m.coords = {0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0.3, 1, 1, 1, 1.0 / 3.0};
  m.cells = {0, 1, 2, 3, 4, 5, 4, 3, 2, 1};
  m.point_data.push_back({"u", 1, {1, 2, 3, 4, 5, 6}});
  m.cell_data.push_back({"level", 1, {0, 1}});
  write_mesh(dir.file("m.vtu"), m);
  const Mesh back = read_mesh(dir.file("m.vtu"));
  require_same(m, back); // "t" became the 4th coordinate, not a point array
}

TEST_CASE("vtu: written file is zlib-compressed inline binary with 64-bit headers and Int32 ids",
          "[io]") {
  TempDir dir;
  write_vtu(dir.file("m.vtu"), two_tets());
  const std::string text = read_text(dir.file("m.vtu"));
  CHECK(text.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos);
  CHECK(text.find("header_type=\"UInt64\"") != std::string::npos);
  CHECK(text.find("format=\"binary\"") != std::string::npos);
  CHECK(text.find("AppendedData") == std::string::npos);
  // Integer cell arrays stay integers; the others are Float64.
  CHECK(text.find("type=\"Int32\" Name=\"region\"") != std::string::npos);
  CHECK(text.find("type=\"Float64\" Name=\"quality\"") != std::string::npos);
  // Ids and offsets as Int32 while they fit (always, below 2^31 ids).
  CHECK(text.find("type=\"Int32\" Name=\"connectivity\"") != std::string::npos);
  CHECK(text.find("type=\"Int32\" Name=\"offsets\"") != std::string::npos);
}

TEST_CASE("vtu: an array deflate barely shrinks is stored in zlib's format, and reads back exactly",
          "[io][3d]") {
  // 41^3 vertices: each point array spans several 32 KiB blocks. "noise"
  // holds values in [0, 1) like a refined mesh's coordinates (deflate makes
  // them about 0.95 of their size): its blocks after the first of each group
  // are stored, so the array's text is about as long as its raw bytes in
  // base64 (all but a tenth of the first block's). "smooth" compresses well
  // and stays compressed.
  TempDir dir;
  Mesh m = generate_kuhn(3, 40);
  const std::size_t nv = m.num_vertices();
  std::vector<double> noise(nv), smooth(nv);
  std::uint64_t s = 88172645463325252ull;
  for (std::size_t i = 0; i < nv; ++i) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    noise[i] = double(s >> 11) * 0x1p-53;
    smooth[i] = double(i % 7);
  }
  m.point_data.push_back({"noise", 1, noise});
  m.point_data.push_back({"smooth", 1, smooth});
  for (int threads : {1, 2}) {
    INFO("threads " << threads);
    set_threads(threads);
    WriteOptions options;
    options.compression = Compression::Zlib;
    write_mesh(dir.file("m" + std::to_string(threads) + ".vtu"), m, options);
  }
  set_threads(0);
  const std::string text = read_text(dir.file("m1.vtu"));
  CHECK(text == read_text(dir.file("m2.vtu")));
  auto encoded_length = [&](const std::string &name) {
    const std::size_t at = text.find("Name=\"" + name + "\"");
    REQUIRE(at != std::string::npos);
    const std::size_t from = text.find('>', at) + 1;
    return text.find('<', from) - from;
  };
  CHECK(double(encoded_length("noise")) >= 4.0 / 3.0 * (double(nv * sizeof(double)) - 3276.8));
  CHECK(double(encoded_length("smooth")) < 0.2 * double(nv * sizeof(double)));
  const Mesh back = read_mesh(dir.file("m1.vtu"));
  require_same(m, back);
}

TEST_CASE("vtu: lower-dimensional cells are tagged entities with their cell data; unused points "
          "are dropped",
          "[io][3d][entities]") {
  TempDir dir;
  AsciiVtu f;
  // Points 0 and 6 are used by no cell: they are dropped. The vertex, line
  // and triangle are faces of the first tetrahedron.
  f.num_points = 7;
  f.points = "9 9 9  0 0 0  1 0 0  0 1 0  0 0 1  1 1 1  8 8 8";
  f.point_data = ascii_array("Float32", "p", 1, "0 10 20 30 40 50 60") +
                 ascii_array("Int16", "q", 2, "0 0 1 1 2 2 3 3 4 4 5 5 6 6");
  f.num_cells = 5;
  f.connectivity = "1  1 2  1 2 3  1 2 3 4  5 4 3 2";
  f.offsets = "1 3 6 10 14";
  f.types = "1 3 5 10 10";
  f.cell_data = ascii_array("Int32", "id", 1, "100 101 102 103 104");
  write_text(dir.file("lower.vtu"), f.text());

  const Mesh m = read_mesh(dir.file("lower.vtu"));
  REQUIRE(m.dim == 3);
  REQUIRE(m.num_vertices() == 5);
  CHECK(m.coords == std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1});
  CHECK(m.cells == std::vector<VertexId>{0, 1, 2, 3, 4, 3, 2, 1});
  REQUIRE(m.point_data.size() == 2);
  CHECK(m.point_data[0].values == std::vector<double>{10, 20, 30, 40, 50});
  CHECK(m.point_data[1].components == 2);
  CHECK(m.point_data[1].values == std::vector<double>{1, 1, 2, 2, 3, 3, 4, 4, 5, 5});
  REQUIRE(m.cell_data.size() == 1);
  CHECK(m.cell_data[0].values == std::vector<double>{103, 104});
  REQUIRE(m.entities.size() == 3);
  for (int d = 0; d < 3; ++d) {
    const Entities &e = m.entities[std::size_t(d)];
    CHECK(e.dim == d);
    REQUIRE(e.size() == 1);
    const std::vector<VertexId> first{0, 1, 2}; // the entity's vertices: a prefix
    CHECK(e.vertices == std::vector<VertexId>(first.begin(), first.begin() + d + 1));
    REQUIRE(e.data.size() == 1);
    CHECK(e.data[0].name == "id");
    CHECK(e.data[0].values == std::vector<double>{100.0 + d});
  }

  // A line to a point no cell uses is not a face: an error naming the cell.
  f.connectivity = "1  0 2  1 2 3  1 2 3 4  5 4 3 2";
  write_text(dir.file("stray.vtu"), f.text());
  require_clean_read_error(dir.file("stray.vtu"), "cell 1 (line) is not a face of the mesh");
}

TEST_CASE("vtu: triangles not in one plane z = c are rejected", "[io][2d]") {
  TempDir dir;
  AsciiVtu f;
  f.num_points = 3;
  f.points = "0 0 0  1 0 0  0 1 0.5";
  f.num_cells = 1;
  f.connectivity = "0 1 2";
  f.offsets = "3";
  f.types = "5";
  write_text(dir.file("surface.vtu"), f.text());
  require_clean_read_error(dir.file("surface.vtu"), "not in one plane z = c");
}

TEST_CASE("vtu: a triangle mesh in the plane z = c keeps its z through refinement and writing",
          "[io][2d]") {
  TempDir dir;
  AsciiVtu f;
  f.num_points = 4;
  f.points = "0 0 5  1 0 5  1 1 5.000000000000001  0 1 5"; // rounding noise in z too
  f.num_cells = 2;
  f.connectivity = "0 1 2  0 2 3";
  f.offsets = "3 6";
  f.types = "5 5";
  write_text(dir.file("plane.vtu"), f.text());
  Mesh m = read_mesh(dir.file("plane.vtu"));
  REQUIRE(m.dim == 2);
  REQUIRE(m.point_data.size() == 1);
  REQUIRE(m.point_data[0].name == kPlaneZArray);
  write_mesh(dir.file("back.vtu"), m);
  const Mesh back = read_mesh(dir.file("back.vtu"));
  REQUIRE(testing::mesh_difference(m, back) == "");
  // Exactly z = 0: no array.
  f.points = "0 0 0  1 0 0  1 1 0  0 1 0";
  write_text(dir.file("flat.vtu"), f.text());
  REQUIRE(read_mesh(dir.file("flat.vtu")).point_data.empty());
}

TEST_CASE("vtu: 4D file without t array is rejected naming t", "[io][4d]") {
  TempDir dir;
  AsciiVtu f = pentatope_file();
  f.point_data = ascii_array("Float64", "time", 1, "0 0 0 0 1");
  write_text(dir.file("no_t.vtu"), f.text());
  require_clean_read_error(dir.file("no_t.vtu"), "'t'");

  f.point_data = ascii_array("Float64", "t", 2, "0 0  0 0  0 0  0 0  1 1");
  write_text(dir.file("t2.vtu"), f.text());
  require_clean_read_error(dir.file("t2.vtu"), "'t' has 2 components");
}

TEST_CASE("vtu: 4D file with 4-vertex cells is rejected", "[io][4d]") {
  TempDir dir;
  AsciiVtu f = pentatope_file();
  f.num_cells = 2;
  f.connectivity = "0 1 2 3 4  0 1 2 3";
  f.offsets = "5 9";
  f.types = "2 2";
  write_text(dir.file("four.vtu"), f.text());
  require_clean_read_error(dir.file("four.vtu"), "cell 1 has 4 vertices, expected 5");
}

TEST_CASE("vtu: 4D convex point sets are read as pentatopes", "[io][4d]") {
  TempDir dir;
  AsciiVtu f = pentatope_file();
  f.types = "41";
  write_text(dir.file("cps.vtu"), f.text());
  const Mesh m = read_vtu(dir.file("cps.vtu"));
  REQUIRE(m.dim == 4);
  CHECK(m.cells == std::vector<VertexId>{0, 1, 2, 3, 4});
  CHECK(m.coords[4 * 4 + 3] == 1.0);
  CHECK(m.point_data.empty());
}

TEST_CASE("vtu: hexahedra mixed with tetrahedra are rejected", "[io][3d]") {
  TempDir dir;
  AsciiVtu f;
  f.num_points = 8;
  f.points = "0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1";
  f.num_cells = 2;
  f.connectivity = "0 1 3 4  0 1 2 3 4 5 6 7";
  f.offsets = "4 12";
  f.types = "10 12";
  write_text(dir.file("hex.vtu"), f.text());
  require_clean_read_error(dir.file("hex.vtu"), "mixed non-simplex cells (VTK type 12)");
}

TEST_CASE("vtu: a file of quadrilaterals has no triangles or tetrahedra", "[io]") {
  TempDir dir;
  AsciiVtu f;
  f.num_points = 4;
  f.points = "0 0 0  1 0 0  1 1 0  0 1 0";
  f.num_cells = 1;
  f.connectivity = "0 1 2 3";
  f.offsets = "4";
  f.types = "9";
  write_text(dir.file("quad.vtu"), f.text());
  require_clean_read_error(dir.file("quad.vtu"), "no triangles or tetrahedra");
}

TEST_CASE("vtu: point ids out of range are rejected", "[io][2d]") {
  TempDir dir;
  AsciiVtu f;
  f.num_points = 3;
  f.points = "0 0 0  1 0 0  0 1 0";
  f.num_cells = 1;
  f.connectivity = "0 1 7";
  f.offsets = "3";
  f.types = "5";
  write_text(dir.file("range.vtu"), f.text());
  Failure fail = capture_failure([&] { read_vtu(dir.file("range.vtu")); });
  INFO(fail.message);
  REQUIRE(fail.threw);
  CHECK(fail.message.find("range.vtu") != std::string::npos);
  CHECK(fail.stderr_text.empty());
}

TEST_CASE("vtu: a non-finite coordinate is rejected naming the point", "[io][3d]") {
  TempDir dir;
  Mesh m = two_tets();
  m.coords[3 * 3 + 1] = std::numeric_limits<double>::quiet_NaN();
  write_vtu(dir.file("nan.vtu"), m);
  require_clean_read_error(dir.file("nan.vtu"), "point 3");
}

TEST_CASE("vtu: array with the wrong tuple count is rejected naming it", "[io][3d]") {
  TempDir dir;
  AsciiVtu f = one_tet();
  f.point_data = ascii_array("Float64", "short_array", 1, "1 2 3");
  write_text(dir.file("short.vtu"), f.text());
  require_clean_read_error(dir.file("short.vtu"), "short_array");
}

TEST_CASE("vtu: a name that is not UTF-8 text is refused, reading and writing", "[io][3d]") {
  // VTK reads no cells from a .vtu with such a name: no run may write one.
  TempDir dir;
  AsciiVtu f = one_tet();
  f.point_data = ascii_array("Float64", "caf\xE9", 1, "1 2 3 4"); // Latin-1, not UTF-8
  write_text(dir.file("latin1.vtu"), f.text());
  require_clean_read_error(dir.file("latin1.vtu"), "caf\\xE9");
  f.point_data = ascii_array("Float64", "a&#1;b", 1, "1 2 3 4"); // a control character
  write_text(dir.file("control.vtu"), f.text());
  require_clean_read_error(dir.file("control.vtu"), "a\\x01b");
  // Well-formed UTF-8 is kept as it is.
  f.point_data = ascii_array("Float64", "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80", 1, "1 2 3 4");
  write_text(dir.file("utf8.vtu"), f.text());
  REQUIRE(read_mesh(dir.file("utf8.vtu")).point_data.at(0).name ==
          "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80");
  for (const char *bad :
       {"\xC0\xAF", "\xED\xA0\x80", "\xF4\x90\x80\x80", "\xEF\xBF\xBF", "\xE2\x82", "tab\there"}) {
    CHECK_FALSE(is_name_text(bad));
    Mesh m = two_tets();
    m.cell_data[0].name = bad;
    REQUIRE_THROWS_WITH(write_mesh(dir.file("bad.vtu"), m), Catch::Contains("not UTF-8 text"));
    m = two_tets();
    m.physical_names.push_back({3, 1, bad});
    REQUIRE_THROWS_WITH(write_mesh(dir.file("bad.vtu"), m), Catch::Contains("not UTF-8 text"));
  }
  CHECK(is_name_text(""));
  CHECK(is_name_text("\xF4\x8F\xBF\xBF"));
}

TEST_CASE("vtu: physical groups of two dimensions sharing a name keep both, under two names",
          "[io][3d]") {
  // Gmsh allows a 2D and a 3D "domain"; VTK keeps one field array of a name.
  TempDir dir;
  Mesh m = two_tets();
  m.physical_names = {{2, 2, "domain"},
                      {3, 1, "domain"},
                      {2, 3, "wall"},
                      {2, 3, "wall"},
                      {3, 4, "SpatialDimension"}};
  write_mesh(dir.file("m.vtu"), m);
  const Mesh back = read_mesh(dir.file("m.vtu"));
  REQUIRE(back.physical_names.size() == 4);
  // The highest dimension keeps the name, as in meshio's conversion.
  CHECK(back.physical_names[0].name == "domain (2D, tag 2)");
  CHECK((back.physical_names[0].dim == 2 && back.physical_names[0].tag == 2));
  CHECK(back.physical_names[1].name == "domain");
  CHECK((back.physical_names[1].dim == 3 && back.physical_names[1].tag == 1));
  CHECK(back.physical_names[2].name == "wall");
  CHECK(back.physical_names[3].name == "SpatialDimension (3D, tag 4)");
}

TEST_CASE("vtu: broken zlib stream gives one clean error", "[io]") {
  TempDir dir;
  write_vtu(dir.file("zlib.vtu"), two_tets());
  std::string text = read_text(dir.file("zlib.vtu"));
  // Flip a base64 character near the end of the connectivity data, inside
  // the deflate stream (the adler32 check then fails).
  const std::size_t array = text.find("Name=\"connectivity\"");
  REQUIRE(array != std::string::npos);
  std::size_t end = text.find("</DataArray>", array);
  REQUIRE(end != std::string::npos);
  while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1])))
    --end;
  while (text[end - 1] == '=')
    --end;
  char &c = text[end - 3];
  c = c == 'A' ? 'B' : 'A';
  write_text(dir.file("zlib.vtu"), text);
  require_clean_read_error(dir.file("zlib.vtu"), "zlib block 0 is corrupt");
}

TEST_CASE("vtu: truncated file gives one clean error", "[io]") {
  TempDir dir;
  write_vtu(dir.file("cut.vtu"), two_tets());
  const std::string text = read_text(dir.file("cut.vtu"));
  write_text(dir.file("cut.vtu"), text.substr(0, text.size() / 2));
  require_clean_read_error(dir.file("cut.vtu"), "");
}

TEST_CASE("vtu: truncated raw appended data gives one clean error", "[io]") {
  // A valid raw-appended file (uncompressed, UInt64 block sizes), then cut.
  std::string raw;
  auto put = [&](const void *p, std::size_t n) { raw.append(static_cast<const char *>(p), n); };
  const double pts[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::int64_t conn[4] = {0, 1, 2, 3}, offs[1] = {4};
  const std::uint8_t types[1] = {10};
  std::uint64_t n = sizeof pts;
  put(&n, 8), put(pts, sizeof pts);
  n = sizeof conn;
  put(&n, 8), put(conn, sizeof conn);
  n = sizeof offs;
  put(&n, 8), put(offs, sizeof offs);
  n = sizeof types;
  put(&n, 8), put(types, sizeof types);
  const std::string head =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
      "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
      "<Points><DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" "
      "format=\"appended\" offset=\"0\"/></Points>\n<Cells>\n"
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"104\"/>\n"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"144\"/>\n"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"160\"/>\n"
      "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
  const std::string tail = "\n</AppendedData>\n</VTKFile>\n";
  TempDir dir;
  write_text(dir.file("appended.vtu"), head + raw + tail);
  const Mesh m = read_vtu(dir.file("appended.vtu")); // the intact file reads
  CHECK(m.dim == 3);
  CHECK(m.num_cells() == 1);
  write_text(dir.file("appended.vtu"), head + raw.substr(0, 60));
  require_clean_read_error(dir.file("appended.vtu"), "");
}

TEST_CASE("vtu: file without a Piece is rejected cleanly", "[io]") {
  TempDir dir;
  write_text(dir.file("nopiece.vtu"),
             "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
             "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
             "</UnstructuredGrid>\n</VTKFile>\n");
  require_clean_read_error(dir.file("nopiece.vtu"), "");
}

TEST_CASE("vtu: XML that is not a VTK file is rejected cleanly", "[io]") {
  TempDir dir;
  write_text(dir.file("junk.vtu"), "this is <not> xml &&& at all\n");
  require_clean_read_error(dir.file("junk.vtu"), "");
}

TEST_CASE("io: directory given as mesh is rejected", "[io]") {
  TempDir dir;
  fs::create_directory(dir.path / "mesh.vtu");
  require_clean_read_error(dir.file("mesh.vtu"), "is a directory");
}

TEST_CASE("io: missing file is rejected", "[io]") {
  TempDir dir;
  require_clean_read_error(dir.file("absent.vtu"), "cannot open");
}

TEST_CASE("io: empty file is rejected", "[io]") {
  TempDir dir;
  write_text(dir.file("empty.vtu"), "");
  require_clean_read_error(dir.file("empty.vtu"), "empty file");
}

TEST_CASE("io: unknown extension is rejected", "[io]") {
  TempDir dir;
  write_text(dir.file("mesh.stl"), "solid x\n");
  require_clean_read_error(dir.file("mesh.stl"), "unknown mesh format '.stl'");
  Failure f = capture_failure([&] { write_mesh(dir.file("out.obj"), two_tets()); });
  REQUIRE(f.threw);
  CHECK(f.message.find("unknown mesh format '.obj'") != std::string::npos);
  CHECK(!fs::exists(dir.file("out.obj")));
}

TEST_CASE("io: extension is case-insensitive", "[io]") {
  TempDir dir;
  write_mesh(dir.file("MESH.VTU"), two_tets());
  require_same(two_tets(), read_mesh(dir.file("MESH.VTU")));
}

TEST_CASE("io: failed write leaves no file behind", "[io]") {
  TempDir dir;
  // The directory does not exist: the temporary file cannot be created.
  Failure f = capture_failure([&] { write_mesh(dir.file("missing/out.vtu"), two_tets()); });
  INFO(f.message);
  REQUIRE(f.threw);
  CHECK(f.message.find("out.vtu") != std::string::npos);
  CHECK(f.message.find("cannot write") != std::string::npos);
  CHECK(f.message.find(".tmp") == std::string::npos);
  CHECK(f.stderr_text.empty());

  // The target is a directory: writing succeeds, the final rename fails.
  fs::create_directory(dir.path / "taken.vtu");
  f = capture_failure([&] { write_mesh(dir.file("taken.vtu"), two_tets()); });
  INFO(f.message);
  REQUIRE(f.threw);
  CHECK(dir.entries() == std::vector<std::string>{"taken.vtu"});
  CHECK(fs::is_directory(dir.path / "taken.vtu"));

  // An inconsistent mesh is an internal error, reported against the target.
  Mesh bad = two_tets();
  bad.cells[5] = 99;
  try {
    write_mesh(dir.file("bad.vtu"), bad);
    FAIL("no error for a cell referring to vertex 99");
  } catch (const CheckError &e) {
    CHECK(std::string(e.what()).rfind(dir.file("bad.vtu") + ": cannot write", 0) == 0);
  }
  CHECK(dir.entries() == std::vector<std::string>{"taken.vtu"});
}

TEST_CASE("io: write_mesh replaces an existing file and leaves no temporary", "[io]") {
  TempDir dir;
  write_text(dir.file("m.vtu"), "old contents");
  write_mesh(dir.file("m.vtu"), two_tets());
  CHECK(dir.entries() == std::vector<std::string>{"m.vtu"});
  require_same(two_tets(), read_mesh(dir.file("m.vtu")));
}

TEST_CASE("vtu: a marked mesh written with the final check's orientation is the file written "
          "without it",
          "[vtu][state][3d][4d]") {
  // run_iterations hands back each cell's orientation from the final
  // check's pass; the writer orients the cells by it instead of computing
  // their volumes. Children come out of bisection with both orientations,
  // so both kinds of cell are written.
  TempDir dir;
  for (int dim : {3, 4}) {
    INFO("dim " << dim);
    Mesh m = generate_kuhn(dim, dim == 4 ? 2 : 4);
    mark_mesh(m, Marking::Index);
    auto r = parse_region(dim == 4 ? R"({"type":"sphere","center":[0.3,0.4,0.5,0.6],"radius":0.3})"
                                   : R"({"type":"sphere","center":[0.3,0.4,0.5],"radius":0.3})",
                          dim, "t");
    DriverOptions options;
    options.iterations = 3;
    const DriverResult result = run_iterations(m, region_selector(*r), options);
    REQUIRE(result.orientation.size() == m.num_cells());
    std::size_t negative = 0;
    for (std::size_t c = 0; c < m.num_cells(); ++c) {
      double pts[20];
      for (int i = 0; i <= dim; ++i)
        std::copy_n(m.point(m.cell(CellId(c))[i]), dim, pts + i * dim);
      const double v = signed_volume(pts, dim);
      CHECK(int(result.orientation[c]) == (v > 0 ? 1 : -1));
      negative += v < 0;
    }
    CHECK(negative > 0);
    CHECK(negative < m.num_cells());
    const Mesh before = m;
    WriteOptions with;
    with.orientation = &result.orientation;
    save_mesh(dir.file("with.vtu"), m, with);
    save_mesh(dir.file("without.vtu"), m);
    CHECK(read_text(dir.file("with.vtu")) == read_text(dir.file("without.vtu")));
    CHECK(m.cells == before.cells);
    // An orientation of another size is not used.
    const std::vector<std::int8_t> short_one(m.num_cells() - 1, 1);
    with.orientation = &short_one;
    save_mesh(dir.file("short.vtu"), m, with);
    CHECK(read_text(dir.file("short.vtu")) == read_text(dir.file("without.vtu")));
  }
}

TEST_CASE("vtu: the bisection state made while writing gives the same file as encode_state",
          "[vtu][state][2d][3d][4d]") {
  // write_mesh_file_with_state streams the state's arrays into the .vtu
  // writer; the bytes must be those of encode_state + write_mesh_file, with
  // and without a tree, with tagged entities, stale stored state arrays and
  // every compression, and the mesh must come back unchanged.
  TempDir dir;
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (auto &[name, m] : refined_tagged(Marking::Index, 1)) {
    REQUIRE(!m.entities.empty());
    REQUIRE(m.has_tree());
    meshes.emplace_back(name, m);
    Mesh untreed = m;
    untreed.clear_tree();
    untreed.cell_data.push_back(
        DataArray{kGenerationArray, 1, std::vector<double>(m.num_cells(), 7.0)}); // stale
    meshes.emplace_back(std::string(name) + " without a tree", std::move(untreed));
  }
  {
    Mesh m = generate_kuhn(4, 2);
    mark_mesh(m, Marking::Longest);
    auto r = parse_region(R"({"type":"sphere","center":[0.3,0.4,0.5,0.6],"radius":0.3})", 4, "t");
    refine(m, select_cells(m, *r));
    m.cell_data.push_back(DataArray{kStateArray, 1, std::vector<double>(m.num_cells(), 3.0)});
    meshes.emplace_back("4D longest", std::move(m));
  }
  auto bytes = [](const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (auto &[what, mesh] : meshes)
    for (Compression c : {Compression::None, Compression::Zlib, Compression::Lz4}) {
      INFO(what << ", compression " << int(c));
      WriteOptions options;
      options.compression = c;
      Mesh encoded = mesh;
      encode_state(encoded);
      write_mesh_file(dir.file("encoded.vtu"), "encoded.vtu", encoded, options);
      const Mesh before = mesh;
      write_mesh_file_with_state(dir.file("streamed.vtu"), "streamed.vtu", mesh, options);
      CHECK(bytes(dir.file("streamed.vtu")) == bytes(dir.file("encoded.vtu")));
      CHECK(testing::mesh_difference(mesh, before).empty());
      CHECK(mesh.stage == before.stage);
      CHECK(mesh.tag == before.tag);
      // And it reads back as the mesh, state included.
      Mesh back = load_mesh(dir.file("streamed.vtu"));
      CHECK(back.marked());
      CHECK(back.num_cells() == mesh.num_cells());
    }
}

TEST_CASE("vtu: the bisection state read in its file types (StoredState) restores the same mesh "
          "and rejects the same values with the same message",
          "[vtu][state][2d][3d][4d]") {
  // read_mesh(path, stored) keeps a binary .vtu's bisect:state, marking,
  // generation, parent_a, parent_b and level out of the mesh's DataArrays,
  // in their file types; prepare_read_mesh decodes them from there. The
  // result must be what the DataArray path gives, value for value, and so
  // must every refusal.
  TempDir dir;
  std::vector<std::pair<std::string, Mesh>> meshes = refined_tagged(Marking::Longest, 2);
  {
    Mesh m = generate_kuhn(4, 2);
    mark_mesh(m, Marking::Index);
    auto r = parse_region(R"({"type":"sphere","center":[0.3,0.4,0.5,0.6],"radius":0.3})", 4, "t");
    refine(m, select_cells(m, *r));
    meshes.emplace_back("4D", std::move(m));
  }
  auto read_both = [&](const std::string &path, Mesh &a, Mesh &b, std::string &error_a,
                       std::string &error_b) {
    error_a.clear(), error_b.clear();
    try {
      a = read_mesh(path);
      InputFacts facts;
      prepare_read_mesh(a, path, {}, facts);
    } catch (const InputError &e) {
      error_a = e.what();
    }
    try {
      StoredState stored;
      b = read_mesh(path, stored);
      for (const DataArray &x : b.cell_data)
        CHECK(x.name.rfind("bisect:", 0) != 0);
      for (const DataArray &x : b.point_data)
        CHECK(x.name.rfind("bisect:", 0) != 0);
      CHECK(stored.cells.size() == 3);
      CHECK(stored.points.size() == 3);
      InputFacts facts;
      prepare_read_mesh(b, path, {}, facts, &stored);
      CHECK(stored.empty());
    } catch (const InputError &e) {
      error_b = e.what();
    }
  };
  for (auto &[what, mesh] : meshes) {
    INFO(what);
    REQUIRE(mesh.has_tree());
    const std::string path = dir.file("s.vtu");
    save_mesh(path, mesh);
    Mesh a, b;
    std::string error_a, error_b;
    read_both(path, a, b, error_a, error_b);
    REQUIRE(error_a.empty());
    REQUIRE(error_b.empty());
    CHECK(testing::mesh_difference(a, b).empty());
    CHECK(a.cells == b.cells);
    CHECK(a.stage == b.stage);
    CHECK(a.tag == b.tag);
    CHECK(a.marking == b.marking);
    CHECK(a.generation == b.generation);
    CHECK(a.parent_edge == b.parent_edge);
    CHECK(a.level == b.level);
    CHECK(b.cells == mesh.cells);
    CHECK(b.stage == mesh.stage);
    CHECK(b.tag == mesh.tag);
    CHECK(b.generation == mesh.generation);
    CHECK(b.parent_edge == mesh.parent_edge);

    // Tampered values, written in the arrays' own types.
    Mesh encoded = mesh;
    encode_state(encoded);
    const std::size_t made =
        std::size_t(std::find_if(encoded.parent_edge.begin(), encoded.parent_edge.end(),
                                 [](VertexId p) { return p != kNoVertex; }) -
                    encoded.parent_edge.begin()) /
        2;
    REQUIRE(made < encoded.num_vertices());
    struct Tamper {
      const char *array;
      bool cell;
      std::size_t at;
      double value;
    };
    for (const Tamper &t : {Tamper{kStateArray, true, 5, 8 + 7},     // Maubach tag 7
                            Tamper{kStateArray, true, 3, -16},       // negative
                            Tamper{kMarkingArray, true, 7, 2},       // mixed marking
                            Tamper{kGenerationArray, true, 2, 9000}, // too deep
                            Tamper{kParentAArray, false, made, double(made)},
                            Tamper{kLevelArray, false, 0, 3}}) { // an original vertex
      INFO(t.array << "[" << t.at << "] = " << t.value);
      Mesh m = encoded;
      bool found = false;
      for (DataArray &x : t.cell ? m.cell_data : m.point_data)
        if (x.name == t.array) {
          x.values[t.at] = t.value;
          found = true;
        }
      REQUIRE(found);
      write_mesh(path, m);
      read_both(path, a, b, error_a, error_b);
      CHECK(!error_a.empty());
      CHECK(error_b == error_a);
      CHECK(error_a.find(t.cell ? "cell " : "vertex ") != std::string::npos);
    }
  }
}

TEST_CASE("vtu: state arrays read in their file types keep the rows of the kept cells and points",
          "[vtu][state][3d][entities]") {
  // As in the tagged-entities case above: the lower-dimensional cells come
  // first and points 0 and 6 are unused, so the kept rows are not a prefix.
  TempDir dir;
  AsciiVtu f;
  f.num_points = 7;
  f.points = "9 9 9  0 0 0  1 0 0  0 1 0  0 0 1  1 1 1  8 8 8";
  f.point_data = ascii_array("Int32", kParentAArray, 1, "70 -1 -1 -1 -1 -1 71") +
                 ascii_array("Int32", kParentBArray, 1, "72 -1 -1 -1 -1 -1 73") +
                 ascii_array("UInt16", kLevelArray, 1, "9 10 11 12 13 14 60");
  f.num_cells = 5;
  f.connectivity = "1  1 2  1 2 3  1 2 3 4  5 4 3 2";
  f.offsets = "1 3 6 10 14";
  f.types = "1 3 5 10 10";
  f.cell_data = ascii_array("Int8", kStateArray, 1, "-5 1 2 3 4") +
                ascii_array("Int16", kMarkingArray, 1, "9 9 9 0 -1") +
                ascii_array("UInt16", kGenerationArray, 1, "7 7 7 5 65535") +
                ascii_array("Float64", "other", 1, "1 2 3 4 5");
  write_text(dir.file("lower.vtu"), f.text());
  const Mesh plain = read_mesh(dir.file("lower.vtu"));
  StoredState stored;
  const Mesh kept = read_mesh(dir.file("lower.vtu"), stored);
  REQUIRE(stored.cells.size() == 3);
  REQUIRE(stored.points.size() == 3);
  REQUIRE(kept.cell_data.size() == 1); // "other"
  CHECK(kept.cell_data[0].values == std::vector<double>{4, 5});
  CHECK(kept.point_data.empty());
  auto values = [](const StoredArray &a) {
    std::vector<double> v(a.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      v[i] = a[i];
    return v;
  };
  auto plain_values = [](const std::vector<DataArray> &arrays, const std::string &name) {
    for (const DataArray &a : arrays)
      if (a.name == name)
        return a.values;
    FAIL("no array " << name);
    return std::vector<double>{};
  };
  for (const StoredArray &a : stored.cells) {
    INFO(a.name);
    CHECK(values(a) == plain_values(plain.cell_data, a.name));
  }
  for (const StoredArray &a : stored.points) {
    INFO(a.name);
    CHECK(values(a) == plain_values(plain.point_data, a.name));
  }
  CHECK(values(stored.cells[0]) == std::vector<double>{3, 4});
  CHECK(stored.cells[0].type == ValueType::Int8);
  CHECK(values(stored.cells[1]) == std::vector<double>{0, -1});
  CHECK(stored.cells[1].type == ValueType::Int16);
  CHECK(values(stored.cells[2]) == std::vector<double>{5, 65535});
  CHECK(values(stored.points[2]) == std::vector<double>{10, 11, 12, 13, 14});
  CHECK(stored.points[2].type == ValueType::UInt16);
  CHECK(values(stored.points[0]) == std::vector<double>(5, -1.0));
}

TEST_CASE("io: validation's cell pass gives the input's quality when asked", "[io][quality]") {
  // refine's first quality row comes from prepare_input's own pass over
  // the cells (InputFacts::want_quality) instead of one more pass.
  for (const char *name : {"ball.msh", "square-tagged.msh"}) {
    INFO(name);
    const std::string path = testing::data_path(name);
    Mesh m = read_mesh(path);
    InputFacts facts;
    facts.want_quality = true;
    prepare_read_mesh(m, path, {}, facts);
    const QualitySummary q = quality_summary(m);
    REQUIRE(q.max > 0);
    CHECK(facts.quality.min == Approx(q.min).epsilon(1e-12));
    CHECK(facts.quality.max == Approx(q.max).epsilon(1e-12));
    CHECK(facts.quality.mean == Approx(q.mean).epsilon(1e-12));
    InputFacts without;
    Mesh again = read_mesh(path);
    prepare_read_mesh(again, path, {}, without);
    CHECK(without.quality.max == QualitySummary{}.max); // not computed unless asked
  }
}
