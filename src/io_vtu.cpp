// VTK XML unstructured grid (.vtu) reading and writing. The only translation
// unit that includes VTK headers.
//
// Conventions:
//  - 2D: triangles with all z == 0; 3D: tetrahedra.
//  - 4D: field data "SpatialDimension" == 4; Points hold (x, y, z); point
//    array "t" (Float64, 1 component) holds the 4th coordinate; every
//    pentatope is one VTK_POLY_VERTEX cell with 5 ids (VTK_CONVEX_POINT_SET
//    with 5 ids is accepted on reading).
//
// VTK reports errors through its output window, never by exceptions. While a
// file is read or written, every VTK error is collected (observers on the
// reader/writer and a quiet global output window) and turned into one
// InputError naming the file; VTK never prints to stderr.
#include "io.hpp"
#include "output.hpp"
#include "vtu_write.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkFieldData.h>
#include <vtkGenericCell.h>
#include <vtkIntArray.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <algorithm>
#include <string_view>
#include <iterator>
#include <cstdlib>
#include <cctype>
#include <fstream>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace bisect {
namespace {

// ---------------------------------------------------------------------------
// Turning VTK's error reports into one exception.

// Collects the messages of one read or write; the first error is reported.
struct ErrorLog {
  std::vector<std::string> errors;
};

// The log of the read/write in progress on this thread (VTK's output window
// is process-global, so the active log has to be reachable from it).
thread_local ErrorLog *active_log = nullptr;

// Removes VTK's decoration ("ERROR: In file.cxx, line N", "vtkFoo (0x...): ")
// and squeezes the message onto one short line.
std::string clean_vtk_message(std::string text) {
  if (text.rfind("ERROR: In ", 0) == 0) {
    auto nl = text.find('\n');
    text = nl == std::string::npos ? std::string() : text.substr(nl + 1);
  }
  // "vtkClassName (0x55d0c0): message"
  if (text.rfind("vtk", 0) == 0) {
    auto paren = text.find(" (");
    auto close = text.find("): ");
    if (paren != std::string::npos && close != std::string::npos && paren < close &&
        close < 120)
      text = text.substr(close + 3);
  }
  std::string out;
  for (char c : text) {
    bool space = c == '\n' || c == '\r' || c == '\t' || c == ' ';
    if (space) {
      if (!out.empty() && out.back() != ' ')
        out += ' ';
    } else {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == '.'))
    out.pop_back();
  if (out.size() > 200)
    out = out.substr(0, 197) + "...";
  return out.empty() ? std::string("unknown VTK error") : out;
}

// Output window that never prints: errors go to the active log, the rest
// (warnings, debug text) is dropped.
class QuietOutputWindow : public vtkOutputWindow {
public:
  static QuietOutputWindow *New();
  vtkTypeMacro(QuietOutputWindow, vtkOutputWindow);
  void DisplayText(const char *) override {}
  void DisplayErrorText(const char *text) override {
    if (active_log && text)
      active_log->errors.push_back(clean_vtk_message(text));
  }
  void DisplayWarningText(const char *) override {}
  void DisplayGenericWarningText(const char *) override {}
  void DisplayDebugText(const char *) override {}
};
vtkStandardNewMacro(QuietOutputWindow);

// Observer attached to VTK objects: ErrorEvent carries the message text.
class ErrorObserver : public vtkCommand {
public:
  static ErrorObserver *New() { return new ErrorObserver; }
  void Execute(vtkObject *, unsigned long event, void *data) override {
    if (event == vtkCommand::ErrorEvent && active_log)
      active_log->errors.push_back(
          clean_vtk_message(data ? static_cast<const char *>(data) : ""));
  }
};

void install_quiet_output_window() {
  static std::once_flag once;
  std::call_once(once, [] {
    vtkNew<QuietOutputWindow> window;
    vtkOutputWindow::SetInstance(window);
    // The pipeline also logs failures through vtkLogger, straight to stderr.
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  });
}

// Makes `log` the active log for its lifetime.
struct ActiveLog {
  ErrorLog log;
  ErrorLog *previous;
  ActiveLog() : previous(active_log) {
    install_quiet_output_window();
    active_log = &log;
  }
  ~ActiveLog() { active_log = previous; }
  ActiveLog(const ActiveLog &) = delete;
  ActiveLog &operator=(const ActiveLog &) = delete;
};

// A message for an error code set without any error text (vtkErrorCode's
// own string table lives in VTK::CommonMisc, which we do not link).
std::string error_code_text(unsigned long code) {
  switch (code) {
  case vtkErrorCode::FileNotFoundError: return "file not found";
  case vtkErrorCode::CannotOpenFileError: return "cannot open file";
  case vtkErrorCode::UnrecognizedFileTypeError: return "unrecognized file type";
  case vtkErrorCode::PrematureEndOfFileError: return "premature end of file";
  case vtkErrorCode::FileFormatError: return "file format error";
  case vtkErrorCode::OutOfDiskSpaceError: return "out of disk space";
  default: return "VTK error code " + std::to_string(code);
  }
}

// ---------------------------------------------------------------------------
// Reading.

constexpr int kNoDim = -1;

// Topological dimension of a VTK cell type (cached per type: it is a
// property of the type, the generic cell is only used for unusual types).
struct CellDims {
  std::array<int, 256> dim;
  vtkNew<vtkGenericCell> cell;
  CellDims() { dim.fill(-2); }
  int of(vtkUnstructuredGrid *grid, vtkIdType c, int type) {
    if (dim[type] == -2) {
      switch (type) {
      case VTK_EMPTY_CELL: dim[type] = kNoDim; break;
      case VTK_VERTEX:
      case VTK_POLY_VERTEX: dim[type] = 0; break;
      case VTK_LINE:
      case VTK_POLY_LINE: dim[type] = 1; break;
      case VTK_TRIANGLE:
      case VTK_TRIANGLE_STRIP:
      case VTK_POLYGON:
      case VTK_PIXEL:
      case VTK_QUAD: dim[type] = 2; break;
      case VTK_TETRA:
      case VTK_VOXEL:
      case VTK_HEXAHEDRON:
      case VTK_WEDGE:
      case VTK_PYRAMID:
      case VTK_CONVEX_POINT_SET:
      case VTK_POLYHEDRON: dim[type] = 3; break;
      default:
        grid->GetCell(c, cell);
        dim[type] = cell->GetCellDimension();
      }
    }
    return dim[type];
  }
};

// Reads the file; throws with the first VTK error if anything went wrong.
vtkSmartPointer<vtkUnstructuredGrid> load_grid(const std::string &path) {
  ActiveLog active;
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  vtkNew<ErrorObserver> observer;
  reader->AddObserver(vtkCommand::ErrorEvent, observer);
  reader->SetReaderErrorObserver(observer);
  reader->SetParserErrorObserver(observer);
  reader->SetFileName(path.c_str());
  try {
    reader->Update();
  } catch (const std::bad_alloc &) {
    throw InputError(path, "corrupt data: an array claims more memory than the machine has");
  } catch (const std::exception &e) {
    throw InputError(path, std::string("corrupt data (") + e.what() + ")");
  }
  auto &errors = active.log.errors;
  if (!errors.empty())
    throw InputError(path, errors.front());
  if (reader->GetErrorCode() != vtkErrorCode::NoError)
    throw InputError(path, error_code_text(reader->GetErrorCode()));
  vtkUnstructuredGrid *grid = reader->GetOutput();
  if (!grid)
    throw InputError(path, "not a VTK unstructured grid");
  return grid;
}

std::string array_name(vtkAbstractArray *a, int index) {
  const char *n = a->GetName();
  return n && *n ? std::string(n) : "unnamed" + std::to_string(index);
}

// The 4D convention is on when field data "SpatialDimension" says 4.
bool is_4d(vtkUnstructuredGrid *grid) {
  vtkFieldData *fd = grid->GetFieldData();
  vtkDataArray *sd = fd ? fd->GetArray("SpatialDimension") : nullptr;
  return sd && sd->GetNumberOfTuples() >= 1 && sd->GetNumberOfComponents() >= 1 &&
         sd->GetComponent(0, 0) == 4.0;
}

// The cells kept by the reader (file ids) and the dimension they define.
struct KeptCells {
  int dim = 0;
  std::vector<vtkIdType> ids;
};

KeptCells select_cells_4d(const std::string &path, vtkUnstructuredGrid *grid) {
  KeptCells kept{4, {}};
  const vtkIdType nc = grid->GetNumberOfCells();
  for (vtkIdType c = 0; c < nc; ++c) {
    const int type = grid->GetCellType(c);
    vtkIdType npts = 0;
    const vtkIdType *pts = nullptr;
    grid->GetCellPoints(c, npts, pts);
    if (type == VTK_POLY_VERTEX || type == VTK_CONVEX_POINT_SET) {
      if (npts != 5)
        throw InputError(path, "4D mesh: cell " + std::to_string(c) + " has " +
                                   std::to_string(npts) + " vertices, expected 5");
      kept.ids.push_back(c);
    } else if (type != VTK_VERTEX && type != VTK_LINE && type != VTK_TRIANGLE &&
               type != VTK_TETRA && type != VTK_EMPTY_CELL) {
      // Lower-dimensional simplices (boundary pieces) are ignored; anything
      // else cannot be part of a pentatope mesh.
      throw InputError(path, "4D mesh: cell " + std::to_string(c) + " has VTK type " +
                                 std::to_string(type) +
                                 ", expected a 5-vertex poly-vertex (type 2)");
    }
  }
  if (kept.ids.empty())
    throw InputError(path, "4D mesh: no pentatopes (5-vertex poly-vertex cells)");
  return kept;
}

// Keeps the simplices of the highest dimension; lower-dimensional cells are
// ignored, a non-simplex cell of that dimension or higher is an error.
KeptCells select_cells(const std::string &path, vtkUnstructuredGrid *grid) {
  const vtkIdType nc = grid->GetNumberOfCells();
  int dim = 0;
  for (vtkIdType c = 0; c < nc; ++c) {
    const int type = grid->GetCellType(c);
    if (type == VTK_TETRA)
      dim = 3;
    else if (type == VTK_TRIANGLE && dim < 2)
      dim = 2;
  }
  CellDims dims;
  if (dim == 0) {
    for (vtkIdType c = 0; c < nc; ++c) {
      const int type = grid->GetCellType(c);
      if (dims.of(grid, c, type) >= 2)
        throw InputError(path, "no triangles or tetrahedra (found non-simplex cells, VTK "
                               "type " + std::to_string(type) + ")");
    }
    throw InputError(path, "no triangles or tetrahedra");
  }
  const int simplex = dim == 2 ? VTK_TRIANGLE : VTK_TETRA;
  KeptCells kept{dim, {}};
  for (vtkIdType c = 0; c < nc; ++c) {
    const int type = grid->GetCellType(c);
    if (type == simplex)
      kept.ids.push_back(c);
    else if (dims.of(grid, c, type) >= dim)
      throw InputError(path, "mixed non-simplex cells (VTK type " + std::to_string(type) + ")");
  }
  return kept;
}

// A numeric array with one tuple per entity; nullptr for non-numeric arrays.
vtkDataArray *numeric_array(const std::string &path, vtkAbstractArray *a, int index,
                            vtkIdType expected, const char *where) {
  auto *d = vtkDataArray::SafeDownCast(a);
  if (!d)
    return nullptr;
  if (d->GetNumberOfTuples() != expected)
    throw InputError(path, std::string(where) + " array '" + array_name(a, index) + "' has " +
                               std::to_string(d->GetNumberOfTuples()) + " tuples, expected " +
                               std::to_string(expected));
  return d;
}

// Copies the selected tuples (file ids in `rows`) of `d` into a DataArray.
DataArray copy_rows(vtkDataArray *d, const std::string &name, const std::vector<vtkIdType> &rows) {
  DataArray out;
  out.name = name;
  out.components = d->GetNumberOfComponents();
  out.values.reserve(rows.size() * out.components);
  for (vtkIdType r : rows)
    for (int k = 0; k < out.components; ++k)
      out.values.push_back(d->GetComponent(r, k));
  return out;
}

// The 4th coordinate array of the 4D convention, checked.
vtkDataArray *time_array(const std::string &path, vtkUnstructuredGrid *grid) {
  vtkDataArray *t = grid->GetPointData()->GetArray("t");
  if (!t)
    throw InputError(path, "4D mesh: point data array 't' (4th coordinate) is missing or not numeric");
  if (t->GetNumberOfComponents() != 1)
    throw InputError(path, "4D mesh: point data array 't' has " +
                               std::to_string(t->GetNumberOfComponents()) +
                               " components, expected 1");
  if (t->GetNumberOfTuples() != grid->GetNumberOfPoints())
    throw InputError(path, "4D mesh: point data array 't' has " +
                               std::to_string(t->GetNumberOfTuples()) + " values, expected " +
                               std::to_string(grid->GetNumberOfPoints()) + " (one per point)");
  return t;
}

Mesh grid_to_mesh(const std::string &path, vtkUnstructuredGrid *grid) {
  const bool four = is_4d(grid);
  const vtkIdType np = grid->GetNumberOfPoints();
  if (np >= vtkIdType(kNoVertex))
    throw InputError(path, "too many points (" + std::to_string(np) + ")");
  KeptCells kept = four ? select_cells_4d(path, grid) : select_cells(path, grid);
  if (kept.ids.size() >= std::size_t(kNoCell))
    throw InputError(path, "too many cells");
  vtkDataArray *t = four ? time_array(path, grid) : nullptr;

  // Cells, with their vertices numbered compactly in file order.
  const int nvc = kept.dim + 1;
  std::vector<VertexId> new_id(std::size_t(np), kNoVertex);
  for (vtkIdType c : kept.ids) {
    vtkIdType npts = 0;
    const vtkIdType *pts = nullptr;
    grid->GetCellPoints(c, npts, pts);
    if (npts != nvc) // VTK takes the offsets as they come
      throw InputError(path, "cell " + std::to_string(c) + " is a " +
                                 (nvc == 3 ? "triangle" : nvc == 4 ? "tetrahedron" : "pentatope") +
                                 " with " + std::to_string(npts) + " vertices, expected " +
                                 std::to_string(nvc));
    for (int i = 0; i < nvc; ++i) {
      if (pts[i] < 0 || pts[i] >= np)
        throw InputError(path, "cell " + std::to_string(c) + " refers to point " +
                                   std::to_string(pts[i]) + ", but there are " +
                                   std::to_string(np) + " points");
      for (int j = 0; j < i; ++j)
        if (pts[j] == pts[i])
          throw InputError(path, "cell " + std::to_string(c) + " repeats point " +
                                     std::to_string(pts[i]));
      new_id[pts[i]] = 0; // used
    }
  }
  std::vector<vtkIdType> used; // file ids of the kept points, in order
  for (vtkIdType p = 0; p < np; ++p)
    if (new_id[p] != kNoVertex) {
      new_id[p] = VertexId(used.size());
      used.push_back(p);
    }

  Mesh mesh;
  mesh.dim = kept.dim;
  mesh.cells.reserve(kept.ids.size() * nvc);
  for (vtkIdType c : kept.ids) {
    vtkIdType npts = 0;
    const vtkIdType *pts = nullptr;
    grid->GetCellPoints(c, npts, pts);
    for (int i = 0; i < nvc; ++i)
      mesh.cells.push_back(new_id[pts[i]]);
  }

  // Coordinates: (x, y) in 2D, (x, y, z) in 3D, (x, y, z, t) in 4D.
  mesh.coords.reserve(used.size() * mesh.dim);
  for (vtkIdType p : used) {
    double x[4] = {0, 0, 0, 0};
    grid->GetPoint(p, x);
    if (four)
      x[3] = t->GetComponent(p, 0);
    for (int k = 0; k < (four ? 4 : 3); ++k)
      if (!std::isfinite(x[k]))
        throw InputError(path, "point " + std::to_string(p) + " has a non-finite coordinate");
    if (mesh.dim == 2 && x[2] != 0.0)
      throw InputError(path, "surface mesh in 3D not supported (point " + std::to_string(p) +
                                 " of a triangle has z = " + std::to_string(x[2]) + ")");
    mesh.coords.insert(mesh.coords.end(), x, x + mesh.dim);
  }

  // Numeric point and cell arrays; "t" of the 4D convention is a coordinate.
  vtkPointData *pd = grid->GetPointData();
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i) {
    vtkAbstractArray *a = pd->GetAbstractArray(i);
    if (four && a == t)
      continue;
    if (vtkDataArray *d = numeric_array(path, a, i, np, "point data"))
      mesh.point_data.push_back(copy_rows(d, array_name(a, i), used));
  }
  vtkCellData *cd = grid->GetCellData();
  for (int i = 0; i < cd->GetNumberOfArrays(); ++i) {
    vtkAbstractArray *a = cd->GetAbstractArray(i);
    if (vtkDataArray *d = numeric_array(path, a, i, grid->GetNumberOfCells(), "cell data"))
      mesh.cell_data.push_back(copy_rows(d, array_name(a, i), kept.ids));
  }
  return mesh;
}

// ---------------------------------------------------------------------------
// Writing.

void check_mesh_for_writing(const std::string &path, const Mesh &mesh) {
  auto fail = [&](const std::string &what) { throw CheckError(path + ": cannot write: " + what); };
  if (mesh.dim < 2 || mesh.dim > 4)
    fail("mesh dimension " + std::to_string(mesh.dim) + " is not 2, 3 or 4");
  if (mesh.coords.size() % mesh.dim || mesh.cells.size() % (mesh.dim + 1))
    fail("coordinate or cell array has a partial entry");
  const std::size_t nv = mesh.num_vertices(), nc = mesh.num_cells();
  for (VertexId v : mesh.cells)
    if (v >= nv)
      fail("a cell refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
  for (const auto &a : mesh.point_data)
    if (a.components < 1 || a.values.size() != nv * a.components)
      fail("point array '" + a.name + "' does not have one tuple per vertex");
  for (const auto &a : mesh.cell_data)
    if (a.components < 1 || a.values.size() != nc * a.components)
      fail("cell array '" + a.name + "' does not have one tuple per cell");
  if (mesh.dim == 4)
    for (const auto &a : mesh.point_data)
      if (a.name == "t")
        fail("point array 't' is reserved for the 4th coordinate of 4D meshes");
}

} // namespace

namespace {

// VTK 9.1's XML reader reads past the end of an ASCII DataArray that holds
// fewer values than the piece needs (or stops at a non-number) and crashes.
// So before VTK sees the file, every ASCII array is counted and parsed here:
// Points need 3 x NumberOfPoints values, PointData NumberOfPoints x
// components, CellData, offsets and types NumberOfCells x components.
std::string attribute(const std::string &tag, const std::string &name) {
  std::string key = " " + name + "=\"";
  std::size_t at = tag.find(key);
  if (at == std::string::npos) return {};
  at += key.size();
  std::size_t end = tag.find('"', at);
  return end == std::string::npos ? std::string() : tag.substr(at, end - at);
}

// Decodes base64 text (whitespace skipped) until `want` bytes are out.
std::string base64_prefix(std::string_view text, std::size_t want) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string out;
  unsigned acc = 0;
  int bits = 0;
  for (char c : text) {
    if (out.size() >= want || c == '=') break;
    int v = value(c);
    if (v < 0) continue;
    acc = (acc << 6) | unsigned(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(char((acc >> bits) & 0xff));
    }
  }
  return out;
}

// A zlib-compressed inline array starts with a header: block count, block
// size, last block size, then one compressed size per block. VTK 9.1 trusts
// it (a zero block size divides by zero; huge sizes allocate); check it
// against the text that holds the data. Little-endian headers assumed.
void check_compression_header(const std::string &path, const std::string &name,
                              std::string_view content, int w) {
  auto read = [&](const std::string &bytes, std::size_t i) {
    unsigned long long v = 0;
    for (int k = w - 1; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(bytes[i * w + k]);
    return v;
  };
  auto bad = [&](const std::string &what) {
    return InputError(path, "array '" + name + "': corrupt compression header (" + what + ")");
  };
  std::string head = base64_prefix(content, std::size_t(3 * w));
  if (head.size() < std::size_t(3 * w)) throw bad("too short");
  const unsigned long long blocks = read(head, 0), block = read(head, 1), last = read(head, 2);
  const unsigned long long room = content.size(); // compressed bytes <= base64 chars
  if (blocks > room) throw bad(std::to_string(blocks) + " blocks in " + std::to_string(room) + " characters");
  if (blocks == 0) return;
  if (block == 0) throw bad("block size 0");
  if (last > block) throw bad("last block larger than a block");
  // zlib cannot expand data more than about 1032 times.
  if (block > 1100 * room || (blocks - 1) > (1100 * room) / block)
    throw bad("uncompressed size out of proportion to the data");
  std::string all = base64_prefix(content, std::size_t((3 + blocks) * w));
  if (all.size() < (3 + blocks) * w) throw bad("block sizes missing");
  for (unsigned long long b = 0; b < blocks; ++b)
    if (read(all, 3 + b) > room) throw bad("block " + std::to_string(b) + " larger than the data");
}

void check_ascii_arrays(const std::string &path) {
  std::ifstream f(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  long long points = -1, cells = -1;
  bool compressed = false;
  int header_bytes = 4;
  enum { None, InPoints, InPointData, InCellData, InCells } section = None;
  std::set<std::string> names; // of the arrays in the current section
  std::size_t pos = 0;
  while ((pos = text.find('<', pos)) != std::string::npos) {
    if (text.compare(pos, 4, "<!--") == 0) { // a comment may hold anything
      pos = text.find("-->", pos);
      if (pos == std::string::npos) return;
      continue;
    }
    // The tag ends at the first '>' outside quotes. A '>' inside an
    // attribute value is legal XML, but VTK 9.1 takes the first '>' after
    // the element's start as the start of its inline data and crashes.
    std::size_t close = pos;
    for (char quote = 0; close < text.size(); ++close) {
      const char ch = text[close];
      if (quote && ch == '>')
        throw InputError(path, "a '>' inside an attribute value of the element at byte " +
                                   std::to_string(pos) + " (write it as &gt;)");
      if (quote) {
        if (ch == quote) quote = 0;
      } else if (ch == '"' || ch == '\'') {
        quote = ch;
      } else if (ch == '>') {
        break;
      }
    }
    if (close == text.size()) return; // VTK reports broken XML
    std::string tag = text.substr(pos, close - pos + 1);
    pos = close + 1;
    auto starts = [&](const char *t) { return tag.rfind(t, 0) == 0; };
    if (starts("<AppendedData")) return; // raw binary follows
    if (starts("<VTKFile")) {
      compressed = !attribute(tag, "compressor").empty();
      std::string h = attribute(tag, "header_type");
      if (!h.empty() && h != "UInt32" && h != "UInt64")
        throw InputError(path, "header_type \"" + h + "\" is not UInt32 or UInt64");
      header_bytes = h == "UInt64" ? 8 : 4;
    }
    if (starts("<Piece") || starts("<Points") || starts("<PointData") || starts("<CellData") ||
        starts("<Cells") || starts("<FieldData"))
      names.clear();
    if (starts("<DataArray")) {
      // VTK 9.1 crashes on two arrays of one name in a section.
      const std::string name = attribute(tag, "Name");
      if (!name.empty() && !names.insert(name).second)
        throw InputError(path, "two arrays named '" + name + "' in one section");
      static const char *kTypes[] = {"Int8",   "UInt8",  "Int16",   "UInt16",  "Int32", "UInt32",
                                     "Int64",  "UInt64", "Float32", "Float64", "String", "Bit"};
      std::string type = attribute(tag, "type");
      if (std::find(std::begin(kTypes), std::end(kTypes), type) == std::end(kTypes))
        throw InputError(path, "DataArray \"" + attribute(tag, "Name") + "\" has no valid type (\"" +
                                   type + "\")");
      if (compressed && attribute(tag, "format") == "binary") {
        std::size_t end = text.find("</DataArray>", pos);
        if (end != std::string::npos)
          check_compression_header(path, attribute(tag, "Name"),
                                   std::string_view(text).substr(pos, end - pos), header_bytes);
      }
    }
    // Counts far past what a file can hold would overflow the products below.
    auto count_of = [&](const char *attr, long long max) {
      const long long v = std::atoll(attribute(tag, attr).c_str());
      if (v < 0 || v > max)
        throw InputError(path, std::string(attr) + " \"" + attribute(tag, attr) + "\" is out of range");
      return v;
    };
    if (starts("<Piece")) {
      points = count_of("NumberOfPoints", 1LL << 40);
      cells = count_of("NumberOfCells", 1LL << 40);
    } else if (starts("<Points")) section = InPoints;
    else if (starts("<PointData")) section = InPointData;
    else if (starts("<CellData")) section = InCellData;
    else if (starts("<Cells")) section = InCells;
    else if (starts("</Points") || starts("</PointData") || starts("</CellData") || starts("</Cells"))
      section = None;
    else if (starts("<DataArray") && attribute(tag, "format") != "appended" && tag.back() == '>' &&
             tag[tag.size() - 2] != '/') {
      // VTK reads any format but "binary" and "appended" as ascii.
      std::size_t end = text.find("</DataArray>", pos);
      if (end == std::string::npos) return;
      std::string name = attribute(tag, "Name");
      if (name.empty()) name = section == InPoints ? "Points" : "(unnamed)";
      long long comps = std::max(1LL, count_of("NumberOfComponents", 1LL << 20));
      long long want = -1;
      if (section == InPoints) want = 3 * points;
      else if (section == InPointData) want = comps * points;
      else if (section == InCellData) want = comps * cells;
      else if (section == InCells && (name == "offsets" || name == "types")) want = cells;
      if (attribute(tag, "format") == "binary") {
        // Uncompressed inline binary: a byte count, then the bytes, in
        // base64. VTK 9.1 trusts the count (compressed data: see above).
        if (!compressed) {
          const std::string_view content = std::string_view(text).substr(pos, end - pos);
          const std::string head = base64_prefix(content, std::size_t(header_bytes));
          if (head.size() < std::size_t(header_bytes))
            throw InputError(path, "array '" + name + "': binary data too short");
          unsigned long long bytes = 0;
          for (int k = header_bytes - 1; k >= 0; --k) bytes = bytes << 8 | static_cast<unsigned char>(head[k]);
          const std::string type = attribute(tag, "type");
          const int size = type == "Int8" || type == "UInt8" ? 1 : type == "Int16" || type == "UInt16" ? 2
                           : type == "Int32" || type == "UInt32" || type == "Float32" ? 4
                           : type == "Int64" || type == "UInt64" || type == "Float64" ? 8 : 0;
          if (bytes > content.size()) // base64 takes 4 characters for 3 bytes
            throw InputError(path, "array '" + name + "': binary data claims " + std::to_string(bytes) +
                                       " bytes in " + std::to_string(content.size()) + " characters");
          if (want >= 0 && size && bytes != (unsigned long long)(want * size))
            throw InputError(path, "array '" + name + "': binary data holds " + std::to_string(bytes) +
                                       " bytes, expected " + std::to_string(want * size) + " (" +
                                       std::to_string(want) + " values of " + type + ")");
        }
        pos = end;
        continue;
      }
      long long count = 0;
      const char *p = text.c_str() + pos, *stop = text.c_str() + end;
      while (p < stop) {
        while (p < stop && std::isspace(static_cast<unsigned char>(*p))) ++p;
        if (p >= stop) break;
        char *after = nullptr;
        std::strtod(p, &after);
        if (after == p || (after < stop && !std::isspace(static_cast<unsigned char>(*after))))
          throw InputError(path, "array '" + name + "': value " + std::to_string(count + 1) +
                                     " is not a number");
        p = after;
        ++count;
      }
      if (want >= 0 && count != want)
        throw InputError(path, "array '" + name + "' has " + std::to_string(count) +
                                   " values, expected " + std::to_string(want));
      pos = end;
    }
  }
}

} // namespace

Mesh read_vtu(const std::string &path) {
  check_ascii_arrays(path);
  vtkSmartPointer<vtkUnstructuredGrid> grid = load_grid(path);
  return grid_to_mesh(path, grid);
}

void write_vtu(const std::string &path, const Mesh &mesh) {
  check_mesh_for_writing(path, mesh);
  write_vtu_native(path, mesh, vtu_compression());
}

namespace {
VtuCompression g_vtu_compression = VtuCompression::Zlib;
} // namespace

void set_vtu_compression(VtuCompression c) { g_vtu_compression = c; }
VtuCompression vtu_compression() { return g_vtu_compression; }

} // namespace bisect
