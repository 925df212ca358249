// The native .vtu reader against files written at test time by VTK's own
// vtkXMLUnstructuredGridWriter, in every data mode, compressor, header
// type, id type and byte order, in 2D, 3D and 4D: read_vtu must give back
// exactly the mesh that was written.
#include "bisect/io.hpp"
#include "bisect/threads.hpp"
#include "io/file_bytes.hpp"
#include "support.hpp"

#include <catch2/catch.hpp>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkShortArray.h>
#include <vtkSignedCharArray.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTypeInt64Array.h>
#include <vtkTypeUInt32Array.h>
#include <vtkTypeUInt64Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedShortArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

using namespace bisect;
namespace fs = std::filesystem;

namespace {

std::string temp_file(const std::string &name) {
  static const fs::path dir = [] {
    fs::path d =
        fs::temp_directory_path() / ("bisect_test_vtu_formats_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return (dir / name).string();
}

std::string read_text(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A small mesh of the given dimension with point and cell arrays of several
// numeric types, and the VTK grid that holds it. `float_points` stores the
// points as Float32 (the expected coordinates are then the rounded floats).
struct Case {
  Mesh expected;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
};

template <class ArrayT>
vtkSmartPointer<ArrayT> typed_array(const char *name, int components, const std::vector<double> &v,
                                    std::vector<DataArray> *expected,
                                    std::string expected_name = "") {
  auto a = vtkSmartPointer<ArrayT>::New();
  if (name)
    a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(vtkIdType(v.size()) / components);
  DataArray e{
      expected_name.empty() ? std::string(name ? name : "") : expected_name, components, {}};
  for (std::size_t i = 0; i < v.size(); ++i) {
    a->SetValue(vtkIdType(i), static_cast<typename ArrayT::ValueType>(v[i]));
    e.values.push_back(static_cast<double>(a->GetValue(vtkIdType(i))));
  }
  a->GetRange(-1); // computed ranges become InformationKey elements in the file
  if (expected)
    expected->push_back(e);
  return a;
}

Case make_case(int dim, bool float_points) {
  Case c;
  Mesh &m = c.expected;
  m.dim = dim;
  std::vector<double> xyz, t;
  std::vector<std::vector<vtkIdType>> cells;
  if (dim == 2) {
    xyz = {0, 0, 0, 1, 0, 0, 0.1, 0.7, 0, 1, 1, 0};
    cells = {{0, 1, 2}, {2, 1, 3}};
  } else if (dim == 3) {
    xyz = {0.1, 0.2, 0.3, 1.0 / 3.0, 0, 1e-300, 0, 2.0 / 7.0, 0, 0, 0, -1.7e5, 1, 1, 1};
    cells = {{0, 1, 2, 3}, {4, 3, 2, 1}};
  } else {
    xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1};
    t = {0, 0, 0, 0, 1, 1.0 / 3.0};
    cells = {{0, 1, 2, 3, 4}, {5, 4, 3, 2, 1}};
  }
  const std::size_t nv = xyz.size() / 3;
  vtkNew<vtkPoints> points;
  if (float_points)
    points->SetDataTypeToFloat();
  else
    points->SetDataTypeToDouble();
  points->SetNumberOfPoints(vtkIdType(nv));
  for (std::size_t v = 0; v < nv; ++v) {
    points->SetPoint(vtkIdType(v), xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
    double x[3];
    points->GetPoint(vtkIdType(v), x);
    m.coords.insert(m.coords.end(), x, x + std::min(dim, 3));
    if (dim == 4)
      m.coords.push_back(t[v]);
  }
  points->GetData()->GetRange(-1);
  c.grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  c.grid->SetPoints(points);
  c.grid->Allocate(vtkIdType(cells.size()));
  const int type = dim == 2 ? VTK_TRIANGLE : dim == 3 ? VTK_TETRA : VTK_POLY_VERTEX;
  for (const auto &cell : cells) {
    c.grid->InsertNextCell(type, vtkIdType(cell.size()), cell.data());
    for (vtkIdType id : cell)
      m.cells.push_back(VertexId(id));
  }

  vtkPointData *pd = c.grid->GetPointData();
  std::vector<double> p1, p2;
  for (std::size_t v = 0; v < nv; ++v) {
    p1.push_back(0.1 * double(v) - 0.25);
    p2.push_back(-double(v)), p2.push_back(1000.0 * double(v));
  }
  pd->AddArray(typed_array<vtkFloatArray>("f32", 1, p1, &m.point_data));
  pd->AddArray(typed_array<vtkShortArray>("i16", 2, p2, &m.point_data));
  std::vector<double> big;
  for (std::size_t v = 0; v < nv; ++v)
    big.push_back(double(std::uint64_t(1) << 40) + double(v));
  pd->AddArray(typed_array<vtkTypeUInt64Array>("u64", 1, big, &m.point_data));
  if (dim == 4) {
    pd->AddArray(typed_array<vtkDoubleArray>("t", 1, t, nullptr));
    vtkNew<vtkIntArray> sd;
    sd->SetName("SpatialDimension");
    sd->SetNumberOfValues(1);
    sd->SetValue(0, 4);
    c.grid->GetFieldData()->AddArray(sd);
  }
  vtkNew<vtkDoubleArray> info; // field data other than the 4D marker is read and ignored
  info->SetName("TimeValue");
  info->InsertNextValue(2.5);
  c.grid->GetFieldData()->AddArray(info);

  vtkCellData *cd = c.grid->GetCellData();
  cd->AddArray(typed_array<vtkIntArray>("i32", 1, {7, -3}, &m.cell_data));
  vtkNew<vtkStringArray> names; // not numeric: skipped
  names->SetName("label");
  names->InsertNextValue("first");
  names->InsertNextValue("second");
  cd->AddArray(names);
  cd->AddArray(typed_array<vtkSignedCharArray>("i8", 1, {-128, 127}, &m.cell_data));
  cd->AddArray(typed_array<vtkDoubleArray>("normal", 3, {1, 0, 0, 0, 1.0 / 3.0, 0}, &m.cell_data));
  cd->AddArray(typed_array<vtkTypeInt64Array>("i64", 1, {-1099511627776.0, 42}, &m.cell_data));
  cd->AddArray(typed_array<vtkUnsignedShortArray>("u16", 1, {65535, 0}, &m.cell_data));
  cd->AddArray(typed_array<vtkUnsignedCharArray>("u8", 1, {255, 1}, &m.cell_data));
  cd->AddArray(typed_array<vtkTypeUInt32Array>("u32", 2, {4294967295.0, 0, 1, 2}, &m.cell_data));
  return c;
}

void require_same(const Mesh &a, const Mesh &b) {
  REQUIRE(testing::mesh_difference(a, b) == "");
}

enum class Mode { Ascii, Binary, AppendedRaw, AppendedBase64 };
const char *mode_name(Mode m) {
  switch (m) {
  case Mode::Ascii:
    return "ascii";
  case Mode::Binary:
    return "binary";
  case Mode::AppendedRaw:
    return "appended-raw";
  default:
    return "appended-base64";
  }
}

struct Settings {
  Mode mode = Mode::Binary;
  int compressor = 0; // 0 none, 1 zlib, 2 lz4, 3 lzma
  bool header64 = false;
  bool id64 = false;
  bool big_endian = false;
  int block_size = 0; // 0: VTK's default
  int pieces = 1;
};

std::string write_with_vtk(const Case &c, const Settings &s, const std::string &name) {
  const std::string path = temp_file(name);
  vtkNew<vtkXMLUnstructuredGridWriter> w;
  w->SetInputData(c.grid);
  w->SetFileName(path.c_str());
  switch (s.mode) {
  case Mode::Ascii:
    w->SetDataModeToAscii();
    break;
  case Mode::Binary:
    w->SetDataModeToBinary();
    break;
  case Mode::AppendedRaw:
    w->SetDataModeToAppended();
    w->EncodeAppendedDataOff();
    break;
  case Mode::AppendedBase64:
    w->SetDataModeToAppended();
    w->EncodeAppendedDataOn();
    break;
  }
  switch (s.compressor) {
  case 0:
    w->SetCompressorTypeToNone();
    break;
  case 1:
    w->SetCompressorTypeToZLib();
    break;
  case 2:
    w->SetCompressorTypeToLZ4();
    break;
  default:
    w->SetCompressorTypeToLZMA();
    break;
  }
  if (s.header64)
    w->SetHeaderTypeToUInt64();
  else
    w->SetHeaderTypeToUInt32();
  if (s.id64)
    w->SetIdTypeToInt64();
  else
    w->SetIdTypeToInt32();
  if (s.big_endian)
    w->SetByteOrderToBigEndian();
  else
    w->SetByteOrderToLittleEndian();
  if (s.block_size)
    w->SetBlockSize(s.block_size);
  w->SetNumberOfPieces(s.pieces);
  REQUIRE(w->Write() == 1);
  return path;
}

// The mesh read from a file of `pieces` copies of `m` (VTK's writer, given
// a grid with no pipeline behind it, writes the whole grid as every piece).
Mesh repeated(const Mesh &m, int pieces) {
  Mesh out = m;
  const auto nv = VertexId(m.num_vertices());
  for (int p = 1; p < pieces; ++p) {
    out.coords.insert(out.coords.end(), m.coords.begin(), m.coords.end());
    for (VertexId v : m.cells)
      out.cells.push_back(v + VertexId(p) * nv);
    for (std::size_t i = 0; i < m.point_data.size(); ++i)
      out.point_data[i].values.insert(out.point_data[i].values.end(),
                                      m.point_data[i].values.begin(), m.point_data[i].values.end());
    for (std::size_t i = 0; i < m.cell_data.size(); ++i)
      out.cell_data[i].values.insert(out.cell_data[i].values.end(), m.cell_data[i].values.begin(),
                                     m.cell_data[i].values.end());
  }
  return out;
}

} // namespace

TEST_CASE("vtu formats: every VTK writer setting reads back exactly", "[io][2d][3d][4d]") {
  int files = 0;
  for (int dim = 2; dim <= 4; ++dim)
    for (Mode mode : {Mode::Ascii, Mode::Binary, Mode::AppendedRaw, Mode::AppendedBase64})
      for (int comp = 0; comp < 4; ++comp)
        for (int header64 = 0; header64 < 2; ++header64)
          for (int id64 = 0; id64 < 2; ++id64)
            for (int big = 0; big < 2; ++big) {
              if (mode == Mode::Ascii && (comp || big))
                continue; // ascii text has no compressor and no byte order
              Settings s;
              s.mode = mode;
              s.compressor = comp;
              s.header64 = header64;
              s.id64 = id64;
              s.big_endian = big;
              s.block_size = (header64 + id64 + big) % 2 ? 40 : 0; // several blocks, or one
              const Case c = make_case(dim, /*float_points=*/!id64 && dim != 4);
              const std::string name = std::to_string(dim) + "d-" + mode_name(mode) + "-c" +
                                       std::to_string(comp) + "-h" + (header64 ? "64" : "32") +
                                       "-id" + (id64 ? "64" : "32") + (big ? "-be" : "-le") +
                                       ".vtu";
              INFO(name);
              const std::string path = write_with_vtk(c, s, name);
              const std::string text = read_text(path);
              if (mode == Mode::Ascii)
                REQUIRE(text.find("<InformationKey") != std::string::npos);
              if (big)
                REQUIRE(text.find("byte_order=\"BigEndian\"") != std::string::npos);
              require_same(c.expected, read_vtu(path));
              fs::remove(path);
              ++files;
            }
  CHECK(files == 3 * (4 + 3 * 4 * 2 * 2 * 2));
}

TEST_CASE("vtu formats: several pieces are concatenated with point ids offset", "[io][3d][4d]") {
  for (int dim : {3, 4})
    for (Mode mode : {Mode::Ascii, Mode::Binary, Mode::AppendedRaw}) {
      Settings s;
      s.mode = mode;
      s.compressor = 1;
      s.pieces = 3;
      const Case c = make_case(dim, false);
      const std::string path = write_with_vtk(c, s, "pieces.vtu");
      INFO(dim << "D " << mode_name(mode));
      require_same(repeated(c.expected, 3), read_vtu(path));
      fs::remove(path);
    }
}

namespace {

void write_text(const std::string &path, const std::string &text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// The message of the InputError that reading `text` as a .vtu file throws.
std::string read_error(const std::string &text) {
  const std::string path = temp_file("error.vtu");
  write_text(path, text);
  try {
    read_vtu(path);
  } catch (const InputError &e) {
    const std::string what = e.what();
    CHECK(what.find("error.vtu") != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
    return what;
  }
  FAIL("no error for " << text.substr(0, 400));
  return {};
}

// One triangle, hand-written, with the given pieces of XML spliced in.
std::string triangle_file(const std::string &point_data, const std::string &cell_data,
                          const std::string &piece_attrs = "NumberOfPoints='3' NumberOfCells='1'") {
  return "<?xml version='1.0' encoding='utf-8'?>\n<!-- written by hand -->\n"
         "<VTKFile type='UnstructuredGrid' version='2.2' byte_order='LittleEndian'>\n"
         "<UnstructuredGrid><!-- a comment -->\n<Piece " +
         piece_attrs +
         ">\n"
         "<PointData>" +
         point_data + "</PointData><CellData>" + cell_data +
         "</CellData>\n"
         "<Points><DataArray type='Float32' NumberOfComponents='3' format='ascii'>"
         "0 0 0 1 0 0 0 1 0</DataArray></Points>\n"
         "<Cells><DataArray type='Int32' Name='connectivity'>0 1 2</DataArray>"
         "<DataArray type='Int8' Name=\"offsets\" format='ascii'>+3</DataArray>"
         "<DataArray type='UInt16' Name='types' format='ascii'>5</DataArray></Cells>\n"
         "</Piece></UnstructuredGrid></VTKFile>\n";
}

} // namespace

TEST_CASE("vtu formats: comments, single quotes and unnamed arrays numbered as VTK does",
          "[io][2d]") {
  const std::string path = temp_file("by-hand.vtu");
  write_text(path, triangle_file(
                       "<DataArray type='String' Name='s' format='ascii'>97 0 98 0 99 0</DataArray>"
                       "<DataArray type='Float64' format='ascii'>1 2 nan</DataArray>"
                       "<DataArray type='Float64' Name='a&amp;b' format='ascii'>4e-320 5 6"
                       "<InformationKey name='X' location='Y' length='1'><Value index='0'>1"
                       "</Value></InformationKey></DataArray>",
                       "<DataArray type='UInt64' format='ascii'>18446744073709551615</DataArray>"));
  const Mesh m = read_vtu(path);
  REQUIRE(m.dim == 2);
  CHECK(m.cells == std::vector<VertexId>{0, 1, 2});
  REQUIRE(m.point_data.size() == 2);
  CHECK(m.point_data[0].name == "unnamed1");
  CHECK(std::isnan(m.point_data[0].values[2]));
  CHECK(m.point_data[1].name == "a&b");
  CHECK(m.point_data[1].values == std::vector<double>{4e-320, 5, 6});
  REQUIRE(m.cell_data.size() == 1);
  CHECK(m.cell_data[0].name == "unnamed0");
  CHECK(m.cell_data[0].values == std::vector<double>{18446744073709551615.0});
}

TEST_CASE("vtu formats: integer arrays hold integers of their type, named in the error", "[io]") {
  const auto cell = [](const std::string &type, const std::string &value) {
    return triangle_file("", "<DataArray type='" + type + "' Name='m' format='ascii'>" + value +
                                 "</DataArray>");
  };
  CHECK_THAT(
      read_error(cell("Int32", "nan")),
      Catch::Contains("cell data array 'm': value 0 ('nan') is not an integer of type Int32"));
  CHECK_THAT(read_error(cell("UInt8", "-1")), Catch::Contains("('-1') is out of range for UInt8"));
  CHECK_THAT(read_error(cell("Int8", "128")), Catch::Contains("('128') is out of range for Int8"));
  CHECK_THAT(read_error(cell("Float32", "1e39")), Catch::Contains("is out of range for Float32"));
  CHECK_THAT(read_error(cell("Int32", "1 2")),
             Catch::Contains("cell data array 'm': has more than the 1 values expected"));
  CHECK_THAT(read_error(cell("Int32", "")),
             Catch::Contains("cell data array 'm': has 0 values, expected 1"));
  CHECK_THAT(read_error(cell("Int33", "1")), Catch::Contains("unknown type 'Int33'"));
}

TEST_CASE("vtu formats: sizes claimed far beyond the file are refused before allocating", "[io]") {
  CHECK_THAT(read_error(triangle_file("", "", "NumberOfPoints='4000000000' NumberOfCells='1'")),
             Catch::Contains("Points: has 9 values, expected 12000000000"));
  CHECK_THAT(read_error(triangle_file("", "", "NumberOfPoints='3000000000000' NumberOfCells='1'")),
             Catch::Contains("too many points (3000000000000)"));
  CHECK_THAT(read_error(triangle_file("", "", "NumberOfPoints='3' NumberOfCells='100000000000'")),
             Catch::Contains("Cells array 'types': has 1 values, expected 100000000000"));
  // An uncompressed inline array whose header claims 2^62 bytes.
  const std::string huge = "AAAAAAAAAEA="; // base64 of the UInt64 2^62, little-endian
  std::string text = triangle_file("", "<DataArray type='Int32' Name='m' format='binary'>" + huge +
                                           "AQAAAA==</DataArray>");
  text.replace(text.find("version='2.2'"), 13, "version='1.0' header_type='UInt64'");
  CHECK_THAT(read_error(text),
             Catch::Contains("cell data array 'm': header claims 4611686018427387904 bytes"));
}

TEST_CASE("vtu formats: malformed XML is refused with the byte offset", "[io]") {
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid'><UnstructuredGrid></VTKFile>"),
             Catch::Contains("XML error at byte 51: </VTKFile> does not close <UnstructuredGrid>"));
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid' a='1' a='2'/>"),
             Catch::Contains("attribute a given twice"));
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid'/><VTKFile/>"),
             Catch::Contains("a second root element"));
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid'><UnstructuredGrid/></VTKFile>"),
             Catch::Contains("<UnstructuredGrid> has no <Piece>"));
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid' version='3.0'/>"),
             Catch::Contains("version '3.0'"));
  CHECK_THAT(read_error("<VTKFile type='UnstructuredGrid' compressor='vtkBZip'/>"),
             Catch::Contains("unknown compressor 'vtkBZip'"));
}

TEST_CASE("vtu formats: pieces with different arrays are refused", "[io]") {
  std::string text =
      triangle_file("<DataArray type='Float64' Name='p' format='ascii'>1 2 3</DataArray>", "");
  const std::size_t b = text.find("<Piece"), e = text.find("</Piece>") + 8;
  std::string second = text.substr(b, e - b);
  second.replace(second.find("Name='p'"), 8, "Name='q'");
  text.insert(e, second);
  CHECK_THAT(read_error(text), Catch::Contains("piece 1 has other point data arrays than piece 0"));
}

TEST_CASE("vtu formats: a corrupt lzma or zlib block is refused naming the array", "[io][3d]") {
  for (int comp : {1, 3}) {
    Settings s;
    s.mode = Mode::Binary;
    s.compressor = comp;
    const Case c = make_case(3, false);
    const std::string path = write_with_vtk(c, s, "corrupt.vtu");
    std::string text = read_text(path);
    // A character near the end of the connectivity's base64 text lies in
    // the last compressed block (its checksum then fails).
    const std::size_t array = text.find("Name=\"connectivity\"");
    REQUIRE(array != std::string::npos);
    std::size_t end = text.find('<', text.find('>', array));
    while (text[end - 1] == '=' || std::isspace(static_cast<unsigned char>(text[end - 1])))
      --end;
    char &ch = text[end - 4];
    ch = ch == 'A' ? 'B' : 'A';
    INFO((comp == 1 ? "zlib" : "lzma"));
    CHECK_THAT(read_error(text), Catch::Contains("Cells array 'connectivity': ") &&
                                     Catch::Contains(comp == 1 ? "zlib block" : "lzma block"));
  }
}

TEST_CASE("vtu formats: arrays read in parallel report the first error in file order", "[io]") {
  // Each file has errors in two or more places; the reader reads the arrays
  // on all threads but must report what a reading in order meets first:
  // Points, the Cells arrays and their check, point data, cell data.
  const std::string bad_m = "<DataArray type='Int32' Name='m' format='ascii'>x</DataArray>";
  const std::string bad_p = "<DataArray type='Float64' Name='p' format='ascii'>1 y 3</DataArray>";
  const std::string bad_q = "<DataArray type='Int33' Name='q' format='ascii'>1 2 3</DataArray>";
  auto with = [](std::string text, const std::string &from, const std::string &to) {
    const std::size_t at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
  };
  const std::string plain = triangle_file(bad_p, bad_m);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {with(plain, "0 0 0 1 0 0", "0 0 z 1 0 0"), "Points: value 2 ('z')"},
      {with(plain, ">5<", ">w<"), "Cells array 'types': value 0 ('w')"},
      {with(plain, ">+3<", ">v<"), "Cells array 'offsets': value 0 ('v')"},
      {with(plain, "0 1 2<", "0 1 7<"), "cell 0 refers to point 7, but there are 3 points"},
      {with(plain, "Name='types'", "Name='typo'"), "<Cells> has no 'types' array"},
      {plain, "point data array 'p': value 1 ('y')"},
      {triangle_file(bad_q, bad_m), "point data array 'q' has unknown type 'Int33'"},
      {triangle_file("", bad_q + bad_m), "cell data array 'q' has unknown type 'Int33'"},
      {triangle_file("", bad_m + bad_q), "cell data array 'q' has unknown type 'Int33'"},
      {triangle_file("", bad_m), "cell data array 'm': value 0 ('x')"},
  };
  for (int threads : {1, 2, 3}) {
    set_threads(threads);
    for (const auto &[text, message] : cases) {
      INFO("threads " << threads << ", expecting " << message);
      CHECK_THAT(read_error(text), Catch::Contains(message));
    }
  }
  set_threads(0);
}

TEST_CASE("file bytes: a file of several pieces reads whole on every thread count", "[io]") {
  // 8 MiB pieces: 20 MiB and some bytes, every byte position-dependent.
  const std::string path = temp_file("bytes.bin");
  std::string text(std::size_t(20) << 20, '\0');
  text.append("tail");
  for (std::size_t i = 0; i < text.size() - 4; ++i)
    text[i] = char((i * 2654435761u) >> 13);
  write_text(path, text);
  for (int threads : {1, 2, 3}) {
    set_threads(threads);
    const FileBytes bytes(path);
    const bool same = bytes.view() == text; // not stringified by Catch: 20 MiB
    CHECK(same);
  }
  set_threads(0);
  write_text(path, "");
  CHECK(FileBytes(path).size() == 0);
  CHECK_THROWS_WITH(FileBytes(fs::path(path).parent_path().string()),
                    Catch::Contains("not a regular file"));
  CHECK_THROWS_WITH(FileBytes(path + ".missing"), Catch::Contains("cannot open"));
}
