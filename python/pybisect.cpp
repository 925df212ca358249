// pybisect: the bisect library as a Python module (pybind11).
//
//   import pybisect
//   mesh = pybisect.read("data/ball.msh")            # load_mesh: validated, state restored
//   mesh.refine(region={"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.3})
//   mesh.refine(marked=mesh.cell_data["gmsh:physical"] == 1, depth=2)
//   mesh.check()                                      # raises pybisect.Error if not conforming
//   mesh.write("ball-refined.vtu")                    # save_mesh: with the bisection state
//
// The module is a thin layer: every operation is one library call (io.hpp,
// mark.hpp, driver.hpp, region.hpp, check.hpp, measure.hpp). What it adds is
// the conversion between numpy arrays and the Mesh's flat vectors, and the
// zero-copy views (see "Views" below).
//
// Views: mesh.points, mesh.cells and the arrays of mesh.point_data /
// mesh.cell_data are numpy arrays over the Mesh's own vectors (no copy; the
// Mesh object is kept alive by them). points and cells are read-only (the
// bisection state depends on them); data arrays are writable. An operation
// that changes the mesh (refine) first hands the buffers that views still
// look at over to those views and gives the mesh a copy: an old view stays
// valid but shows the mesh as it was; read the property again to see the
// refined mesh.
#include "bisect/bisect.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

using bisect::CellId;
using bisect::DataArray;
using bisect::ErrorKind;
using bisect::Mesh;
using bisect::VertexId;

// ---------------------------------------------------------------------------
// Errors: bisect::Error -> pybisect.Error (a RuntimeError) with .kind and
// .file, and the message the command line prints (without its "bisect: ").

PyObject *g_error_type = nullptr;

const char *kind_name(ErrorKind kind) {
  switch (kind) {
  case ErrorKind::Input:
    return "input";
  case ErrorKind::Usage:
    return "usage";
  case ErrorKind::Check:
    return "check";
  case ErrorKind::Limit:
    return "limit";
  case ErrorKind::Resource:
    return "resource";
  }
  return "input";
}

void raise_error(const bisect::Error &e) {
  std::string message = bisect::one_line(e.what());
  if (e.kind == ErrorKind::Check && message.rfind("check failed: ", 0) != 0)
    message = "internal check failed: " + message;
  py::object type = py::reinterpret_borrow<py::object>(g_error_type);
  py::object instance = type(message);
  instance.attr("kind") = kind_name(e.kind);
  instance.attr("file") = e.file.empty() ? py::object(py::none()) : py::object(py::str(e.file));
  PyErr_SetObject(g_error_type, instance.ptr());
}

// ---------------------------------------------------------------------------
// The Python Mesh: the library's Mesh plus the invariants it had when it was
// made (read or built), which check() compares with, and the bookkeeping of
// the views handed out.

// Owns a buffer the mesh gave up while views still looked at it (empty while
// the mesh still owns it).
struct ViewBuffer {
  std::vector<double> doubles;
  std::vector<VertexId> ids;
};

struct PyMesh {
  Mesh mesh;
  // Measured on first need (check, or before the first refine), so reading
  // costs what `bisect refine` spends on it.
  std::optional<bisect::Invariants> original;
  bool busy = false; // an operation with the GIL released is running
  std::weak_ptr<ViewBuffer> coords_view, cells_view;
  std::map<std::string, std::weak_ptr<ViewBuffer>> point_views, cell_views;
};

// What a view's numpy base owns: its buffer (while the mesh owns it, an
// empty one that may receive it) and a reference to the Mesh object.
struct ViewBase {
  std::shared_ptr<ViewBuffer> buffer;
  py::object owner;
};

// Views of `values`: the buffer goes to the views when the mesh is about to
// change it, and the mesh keeps a copy.
template <class T> void hand_over(std::weak_ptr<ViewBuffer> &slot, std::vector<T> &values) {
  if (std::shared_ptr<ViewBuffer> buffer = slot.lock()) {
    std::vector<T> &keep = [&]() -> std::vector<T> & {
      if constexpr (std::is_same_v<T, double>)
        return buffer->doubles;
      else
        return buffer->ids;
    }();
    keep = std::move(values);
    values = keep;
  }
  slot.reset();
}

void hand_over_data(std::map<std::string, std::weak_ptr<ViewBuffer>> &slots,
                    std::vector<DataArray> &arrays) {
  for (DataArray &a : arrays)
    if (auto it = slots.find(a.name); it != slots.end())
      hand_over(it->second, a.values);
  slots.clear();
}

// Before the mesh changes: no view may see the change (or a freed buffer).
void release_views(PyMesh &m) {
  hand_over(m.coords_view, m.mesh.coords);
  hand_over(m.cells_view, m.mesh.cells);
  hand_over_data(m.point_views, m.mesh.point_data);
  hand_over_data(m.cell_views, m.mesh.cell_data);
}

template <class T>
py::array make_view(py::handle self, std::weak_ptr<ViewBuffer> &slot, const T *data,
                    std::vector<py::ssize_t> shape, bool writable) {
  std::shared_ptr<ViewBuffer> buffer = slot.lock();
  if (!buffer) {
    buffer = std::make_shared<ViewBuffer>();
    slot = buffer;
  }
  auto *base = new ViewBase{buffer, py::reinterpret_borrow<py::object>(self)};
  py::capsule capsule(base, [](void *p) { delete static_cast<ViewBase *>(p); });
  py::ssize_t count = 1;
  for (py::ssize_t s : shape)
    count *= s;
  // numpy needs a pointer even for an empty array.
  static const T empty{};
  py::array a(py::dtype::of<T>(), shape, {}, count ? data : &empty, capsule);
  if (!writable)
    a.attr("setflags")(py::arg("write") = false);
  return a;
}

// Refuses a second operation on a mesh another thread is refining.
struct BusyGuard {
  explicit BusyGuard(PyMesh &m) : m(m) {
    if (m.busy)
      throw bisect::UsageError("the mesh is in use by another thread (refine/check)");
    m.busy = true;
  }
  ~BusyGuard() { m.busy = false; }
  BusyGuard(const BusyGuard &) = delete;
  BusyGuard &operator=(const BusyGuard &) = delete;
  PyMesh &m;
};

void check_idle(const PyMesh &m) {
  if (m.busy)
    throw bisect::UsageError("the mesh is in use by another thread (refine/check)");
}

// The invariants of the mesh as read or built; call before it first changes
// (without the GIL: it walks every facet).
const bisect::Invariants &original(PyMesh &m) {
  if (!m.original)
    m.original = bisect::measure_invariants(m.mesh);
  return *m.original;
}

// ---------------------------------------------------------------------------
// numpy -> Mesh

DataArray data_array(const std::string &name, const py::handle &value, std::size_t count,
                     const char *what, const std::string &origin) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a)
    throw bisect::InputError(origin, std::string(what) + " array '" + name + "' is not numeric");
  if (a.ndim() < 1 || a.ndim() > 2 || std::size_t(a.shape(0)) != count)
    throw bisect::InputError(origin, std::string(what) + " array '" + name + "' has " +
                                         std::to_string(a.ndim() ? a.shape(0) : 0) +
                                         " rows, expected " + std::to_string(count));
  DataArray d;
  d.name = name;
  d.components = a.ndim() == 2 ? int(a.shape(1)) : 1;
  if (d.components < 1)
    throw bisect::InputError(origin, std::string(what) + " array '" + name + "' has no components");
  d.values.assign(a.data(), a.data() + a.size());
  return d;
}

std::vector<DataArray> data_arrays(const py::object &dict, std::size_t count, const char *what,
                                   const std::string &origin) {
  std::vector<DataArray> out;
  if (dict.is_none())
    return out;
  for (auto item : py::cast<py::dict>(dict))
    out.push_back(data_array(py::cast<std::string>(item.first), item.second, count, what, origin));
  return out;
}

// Triangles given with a third coordinate: as the file readers do, they must
// lie in one plane z = c (up to 1e-12 of the extent); a c other than 0 travels
// as the point array bisect:z.
void settle_plane(Mesh &mesh, const std::vector<double> &z, const std::string &origin) {
  double lo = HUGE_VAL, hi = -HUGE_VAL, extent = 0;
  for (std::size_t v = 0; v < z.size(); ++v) {
    lo = std::min(lo, z[v]);
    hi = std::max(hi, z[v]);
  }
  for (int k = 0; k < 2; ++k) {
    double a = HUGE_VAL, b = -HUGE_VAL;
    for (std::size_t v = 0; v < z.size(); ++v) {
      a = std::min(a, mesh.coords[2 * v + k]);
      b = std::max(b, mesh.coords[2 * v + k]);
    }
    extent = std::max(extent, b - a);
  }
  extent = std::max({extent, std::abs(lo), std::abs(hi)});
  if (!(hi - lo <= 1e-12 * extent) && !z.empty()) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the triangles are not in one plane z = c (z goes from %.17g to %.17g)", lo, hi);
    throw bisect::InputError(origin, buf);
  }
  if (z.empty() || (lo == 0 && hi == 0))
    return;
  mesh.point_data.erase(
      std::remove_if(mesh.point_data.begin(), mesh.point_data.end(),
                     [](const DataArray &a) { return a.name == bisect::kPlaneZArray; }),
      mesh.point_data.end());
  mesh.point_data.push_back({bisect::kPlaneZArray, 1, z});
}

// What load_mesh does after reading: validate and orient (prepare_input),
// restore the bisection state the bisect:* cell arrays carry (decode_state);
// then the invariants check() compares with.
std::unique_ptr<PyMesh> finish(Mesh mesh, const std::string &origin) {
  auto m = std::make_unique<PyMesh>();
  m->mesh = std::move(mesh);
  py::gil_scoped_release release;
  bisect::prepare_input(m->mesh, origin);
  bisect::decode_state(m->mesh, origin);
  return m;
}

std::unique_ptr<PyMesh> mesh_from_arrays(const py::object &points_in, const py::object &cells_in,
                                         const py::object &point_data, const py::object &cell_data,
                                         const std::string &origin) {
  auto points = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points_in);
  if (!points || points.ndim() != 2)
    throw bisect::InputError(origin, "points must be a 2-dimensional numeric array (n, dim)");
  py::array cells_any = py::array::ensure(cells_in);
  if (!cells_any || cells_any.ndim() != 2)
    throw bisect::InputError(origin, "cells must be a 2-dimensional integer array (m, dim+1)");
  const char kind = cells_any.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw bisect::InputError(origin, "cells must be an integer array, not dtype " +
                                         py::cast<std::string>(py::str(cells_any.dtype())));
  auto cells =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(cells_any);
  const int dim = int(cells.shape(1)) - 1;
  if (dim < 2 || dim > 4)
    throw bisect::InputError(origin, "cells have " + std::to_string(cells.shape(1)) +
                                         " vertices; expected 3 (triangles), 4 (tetrahedra) or 5 "
                                         "(pentatopes)");
  const int columns = int(points.shape(1));
  if (columns != dim && !(dim == 2 && columns == 3))
    throw bisect::InputError(origin, "points have " + std::to_string(columns) + " coordinates; " +
                                         std::to_string(dim + 1) + "-vertex cells need " +
                                         std::to_string(dim) +
                                         (dim == 2 ? " (or 3 with a constant z)" : ""));
  const std::size_t nv = std::size_t(points.shape(0)), nc = std::size_t(cells.shape(0));
  if (nc == 0)
    throw bisect::InputError(origin, "no cells");
  Mesh mesh;
  mesh.dim = dim;
  mesh.coords.resize(nv * dim);
  std::vector<double> z;
  const double *p = points.data();
  for (std::size_t v = 0; v < nv; ++v) {
    for (int k = 0; k < dim; ++k)
      mesh.coords[v * dim + k] = p[v * columns + k];
    if (columns == 3 && dim == 2)
      z.push_back(p[v * columns + 2]);
  }
  mesh.cells.resize(nc * (dim + 1));
  const std::int64_t *c = cells.data();
  for (std::size_t i = 0; i < mesh.cells.size(); ++i) {
    if (c[i] < 0 || std::uint64_t(c[i]) >= nv)
      throw bisect::InputError(origin, "cell " + std::to_string(i / (dim + 1)) + " has vertex id " +
                                           std::to_string(c[i]) + ", not in 0.." +
                                           std::to_string(nv ? nv - 1 : 0));
    mesh.cells[i] = VertexId(c[i]);
  }
  mesh.point_data = data_arrays(point_data, nv, "point", origin);
  mesh.cell_data = data_arrays(cell_data, nc, "cell", origin);
  if (dim == 2 && columns == 3)
    settle_plane(mesh, z, origin);
  return finish(std::move(mesh), origin);
}

// ---------------------------------------------------------------------------
// refine: the cells to bisect

std::vector<CellId> cells_of(const py::object &marked, std::size_t nc) {
  py::array a = py::array::ensure(marked);
  if (!a)
    throw bisect::UsageError("marked: expected a boolean mask or an array of cell ids");
  std::vector<CellId> out;
  if (a.dtype().kind() == 'b') {
    auto mask = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(a);
    if (mask.ndim() != 1 || std::size_t(mask.shape(0)) != nc)
      throw bisect::UsageError("marked: a boolean mask needs one value per cell (" +
                               std::to_string(nc) + "), got " +
                               std::to_string(mask.ndim() == 1 ? mask.shape(0) : mask.size()));
    for (std::size_t c = 0; c < nc; ++c)
      if (mask.data()[c])
        out.push_back(CellId(c));
    return out;
  }
  if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u' && a.size() != 0)
    throw bisect::UsageError("marked: expected a boolean mask or integer cell ids, not dtype " +
                             py::cast<std::string>(py::str(a.dtype())));
  auto ids = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (ids.ndim() > 1)
    throw bisect::UsageError("marked: cell ids must be a 1-dimensional array");
  for (py::ssize_t i = 0; i < ids.size(); ++i) {
    const std::int64_t c = ids.data()[i];
    if (c < 0 || std::uint64_t(c) >= nc)
      throw bisect::UsageError("marked: cell index " + std::to_string(c) +
                               " out of range (the mesh has " + std::to_string(nc) + " cells)");
    out.push_back(CellId(c));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// A region given as a dict (a JSON object), JSON text, or a path to a spec file.
std::unique_ptr<bisect::Region> region_of(const py::object &region, int dim) {
  if (py::isinstance<py::dict>(region)) {
    // numpy arrays and scalars in the dict become JSON lists and numbers.
    const py::cpp_function to_list([](const py::object &o) { return o.attr("tolist")(); });
    const std::string text = py::cast<std::string>(
        py::module_::import("json").attr("dumps")(region, py::arg("default") = to_list));
    return bisect::parse_region(text, dim, "<region>");
  }
  const py::object os = py::module_::import("os");
  if (py::isinstance(region, os.attr("PathLike")))
    return bisect::read_region(py::cast<std::string>(os.attr("fspath")(region)), dim);
  if (!py::isinstance<py::str>(region))
    throw bisect::UsageError("region: expected a dict, JSON text or a spec file's path");
  const std::string s = py::cast<std::string>(region);
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && s[first] == '{')
    return bisect::parse_region(s, dim, "<region>");
  return bisect::read_region(s, dim);
}

py::dict refine(py::object self, const py::object &marked, const py::object &region, int depth,
                const std::string &marking_name, std::size_t max_cells) {
  PyMesh &m = self.cast<PyMesh &>();
  BusyGuard guard(m);
  const std::optional<bisect::Marking> marking = bisect::parse_marking(marking_name);
  if (!marking)
    throw bisect::UsageError("unknown marking '" + marking_name +
                             "' (expected index, longest or sorted)");
  if (marked.is_none() && region.is_none())
    throw bisect::UsageError("refine: give marked cells, a region, or both");
  if (depth < 1)
    throw bisect::UsageError("refine: depth must be at least 1");
  std::vector<CellId> selected;
  if (!marked.is_none())
    selected = cells_of(marked, m.mesh.num_cells());
  std::unique_ptr<bisect::Region> spec;
  if (!region.is_none())
    spec = region_of(region, m.mesh.dim);

  release_views(m);
  bisect::RefineResult r;
  {
    py::gil_scoped_release release;
    original(m);
    bisect::ensure_marked(m.mesh, *marking);
    if (spec) {
      std::vector<CellId> touched = bisect::select_cells(m.mesh, *spec);
      std::vector<CellId> both;
      both.reserve(selected.size() + touched.size());
      std::set_union(selected.begin(), selected.end(), touched.begin(), touched.end(),
                     std::back_inserter(both));
      selected = std::move(both);
    }
    if (std::string why = bisect::memory_shortfall(m.mesh, selected.size(), 0); !why.empty())
      throw bisect::Error(ErrorKind::Limit, {}, "refine: " + why);
    bisect::RefineLimits limits;
    if (max_cells)
      limits.max_cells = max_cells;
    r = bisect::refine_marked(m.mesh, selected, depth, limits);
  }
  if (r.precision_reached)
    throw bisect::Error(
        ErrorKind::Limit, {},
        "refine: it would bisect an edge finer than doubles resolve (extent below "
        "2^-40 of its coordinates' magnitude, or below 2^-100); nothing was bisected");
  if (r.limit_reached)
    throw bisect::Error(ErrorKind::Limit, {},
                        "refine: it would pass " +
                            (max_cells ? "max_cells " + std::to_string(max_cells)
                                       : std::string("the 32-bit id limit")) +
                            " (" + std::to_string(m.mesh.num_cells()) +
                            " cells now); nothing was bisected");
  py::dict out;
  out["selected"] = selected.size();
  out["bisections"] = r.bisections;
  out["closure_passes"] = r.closure_passes;
  out["cells"] = m.mesh.num_cells();
  out["vertices"] = m.mesh.num_vertices();
  return out;
}

// mesh.coarsen(marked=None, passes=1, sum=()): undoes bisections where the
// whole star of a created vertex is marked (all cells when marked is None).
py::dict coarsen(py::object self, const py::object &marked, int passes,
                 const std::vector<std::string> &sum) {
  PyMesh &m = self.cast<PyMesh &>();
  BusyGuard guard(m);
  if (passes < 0)
    throw bisect::UsageError("coarsen: passes must be 0 (until done) or more");
  std::vector<char> mask(m.mesh.num_cells(), marked.is_none() ? 1 : 0);
  if (!marked.is_none())
    for (CellId c : cells_of(marked, m.mesh.num_cells()))
      mask[c] = 1;
  release_views(m);
  bisect::CoarsenResult r;
  {
    py::gil_scoped_release release;
    bisect::CoarsenOptions options;
    options.passes = passes;
    options.sum_arrays = sum;
    r = bisect::coarsen(m.mesh, mask, options);
  }
  py::dict out;
  out["passes"] = r.passes;
  out["removed_vertices"] = r.removed_vertices;
  out["merged_pairs"] = r.merged_pairs;
  out["cells"] = m.mesh.num_cells();
  out["vertices"] = m.mesh.num_vertices();
  return out;
}

// ---------------------------------------------------------------------------
// meshio

// meshio has no cell type for a pentatope: bisect's .vtu stores them as
// VTK_POLY_VERTEX cells (src/io/vtu.cpp), a type meshio drops.
const char *kNoMeshio4d =
    "meshio has no cell type for 4D simplices (bisect's .vtu stores pentatopes as VTK_POLY_VERTEX "
    "cells, which meshio drops); use mesh.write(path.vtu) and pybisect.read";

py::object to_meshio(const PyMesh &m) {
  check_idle(m);
  if (m.mesh.dim == 4)
    throw bisect::UsageError(std::string("to_meshio: ") + kNoMeshio4d);
  py::object meshio = py::module_::import("meshio");
  // What save_mesh writes: cells positively oriented, the state as bisect:* arrays.
  Mesh copy = m.mesh;
  if (copy.marked())
    bisect::encode_state(copy);
  const std::size_t nv = copy.num_vertices(), nc = copy.num_cells();
  const int dim = copy.dim;
  // Points are 3D, as in the .vtu file: a 2D mesh gets z = 0 or its bisect:z.
  py::array_t<double> points({py::ssize_t(nv), py::ssize_t(3)});
  const DataArray *plane = nullptr;
  for (const DataArray &a : copy.point_data)
    if (a.name == bisect::kPlaneZArray)
      plane = &a;
  double *p = points.mutable_data();
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k)
      p[3 * v + k] = k < dim ? copy.coords[v * dim + k] : plane ? plane->values[v] : 0.0;
  py::array_t<std::int64_t> cells({py::ssize_t(nc), py::ssize_t(dim + 1)});
  std::copy(copy.cells.begin(), copy.cells.end(), cells.mutable_data());
  auto as_array = [](const DataArray &a, std::size_t count) {
    py::array_t<double> out =
        a.components == 1 ? py::array_t<double>(py::ssize_t(count))
                          : py::array_t<double>({py::ssize_t(count), py::ssize_t(a.components)});
    std::copy(a.values.begin(), a.values.end(), out.mutable_data());
    return out;
  };
  py::dict point_data, cell_data;
  for (const DataArray &a : copy.point_data)
    if (&a != plane)
      point_data[py::str(a.name)] = as_array(a, nv);
  for (const DataArray &a : copy.cell_data) {
    py::list blocks;
    blocks.append(as_array(a, nc));
    cell_data[py::str(a.name)] = blocks;
  }
  py::list blocks;
  blocks.append(py::make_tuple(dim == 2 ? "triangle" : "tetra", cells));
  return meshio.attr("Mesh")(points, blocks, py::arg("point_data") = point_data,
                             py::arg("cell_data") = cell_data);
}

// The cells of the highest dimension (tetra, else triangle), every block of
// that type in order, with their cell data; the points and point data as they are.
std::unique_ptr<PyMesh> from_meshio(const py::object &m) {
  const std::string origin = "<meshio>";
  py::list blocks = m.attr("cells");
  std::string type;
  for (auto b : blocks) {
    const std::string t = py::cast<std::string>(b.attr("type"));
    if (t == "tetra")
      type = t;
    else if (t == "triangle" && type.empty())
      type = t;
  }
  if (type.empty()) {
    throw bisect::InputError(origin, std::string("no triangle or tetra cells (") +
                                         "4D: " + kNoMeshio4d + ")");
  }
  const py::object np = py::module_::import("numpy");
  py::list chosen, chosen_index;
  for (py::ssize_t i = 0; i < py::ssize_t(blocks.size()); ++i)
    if (py::cast<std::string>(blocks[i].attr("type")) == type) {
      chosen.append(blocks[i].attr("data"));
      chosen_index.append(i);
    }
  py::object cells = np.attr("concatenate")(chosen);
  py::dict cell_data;
  for (auto item : py::cast<py::dict>(m.attr("cell_data"))) {
    py::list per_block = py::cast<py::list>(item.second);
    py::list parts;
    bool numeric = true;
    for (auto i : chosen_index) {
      py::array a = np.attr("asarray")(per_block[py::cast<py::ssize_t>(i)]);
      const char k = a.dtype().kind();
      numeric = numeric && (k == 'f' || k == 'i' || k == 'u' || k == 'b');
      parts.append(a);
    }
    if (numeric)
      cell_data[item.first] = np.attr("concatenate")(parts);
  }
  py::dict point_data;
  for (auto item : py::cast<py::dict>(m.attr("point_data"))) {
    // Gmsh's node entities: meaningless once vertices are added (read() has no such array).
    if (py::cast<std::string>(item.first) == "gmsh:dim_tags")
      continue;
    py::array a = np.attr("asarray")(item.second);
    const char k = a.dtype().kind();
    if (k == 'f' || k == 'i' || k == 'u' || k == 'b')
      point_data[item.first] = a;
  }
  // meshio keeps 2D points as given, (n, 2) or (n, 3) (what it reads).
  return mesh_from_arrays(m.attr("points"), cells, point_data, cell_data, origin);
}

// ---------------------------------------------------------------------------

py::dict check(PyMesh &m, bool full) {
  BusyGuard guard(m);
  bisect::CheckResult r;
  bisect::Invariants now;
  {
    py::gil_scoped_release release;
    const bisect::Invariants &before = original(m);
    r = full ? bisect::check_conformity(m.mesh, &before) : bisect::check_refined(m.mesh, before);
    if (r.ok)
      now = bisect::measure_invariants(m.mesh, full);
  }
  if (!r.ok)
    throw bisect::Error(ErrorKind::Check, {}, "check failed: " + r.failure);
  py::dict out;
  out["conforming"] = true;
  out["cells"] = m.mesh.num_cells();
  out["vertices"] = m.mesh.num_vertices();
  out["volume"] = now.volume;
  out["boundary_measure"] = now.boundary_measure;
  out["boundary_facets"] = now.boundary_facets;
  if (full)
    out["euler"] = now.euler;
  out["original_volume"] = m.original->volume;
  out["original_boundary_measure"] = m.original->boundary_measure;
  return out;
}

py::dict quality(PyMesh &m) {
  BusyGuard guard(m);
  bisect::QualitySummary q;
  {
    py::gil_scoped_release release;
    q = bisect::quality_summary(m.mesh);
  }
  py::dict out;
  out["min"] = q.min;
  out["max"] = q.max;
  out["mean"] = q.mean;
  return out;
}

void mesh_write(PyMesh &m, const py::object &path_in, const std::string &compression) {
  BusyGuard guard(m);
  bisect::WriteOptions options;
  if (compression == "zlib")
    options.compression = bisect::Compression::Zlib;
  else if (compression == "lz4")
    options.compression = bisect::Compression::Lz4;
  else if (compression == "none")
    options.compression = bisect::Compression::None;
  else
    throw bisect::UsageError("unknown compression '" + compression +
                             "' (expected zlib, lz4 or none)");
  const std::string path = py::cast<std::string>(py::module_::import("os").attr("fspath")(path_in));
  bisect::check_output_format(path, m.mesh.dim);
  // save_mesh reorders the cells while it writes and restores them: views
  // must not see that, so the GIL stays held.
  release_views(m);
  bisect::save_mesh(path, m.mesh, options);
}

py::dict data_views(py::object self, bool cells) {
  PyMesh &m = self.cast<PyMesh &>();
  check_idle(m);
  auto &arrays = cells ? m.mesh.cell_data : m.mesh.point_data;
  auto &slots = cells ? m.cell_views : m.point_views;
  const std::size_t count = cells ? m.mesh.num_cells() : m.mesh.num_vertices();
  py::dict out;
  for (DataArray &a : arrays) {
    std::vector<py::ssize_t> shape{py::ssize_t(count)};
    if (a.components != 1)
      shape.push_back(a.components);
    out[py::str(a.name)] = make_view(self, slots[a.name], a.values.data(), shape, true);
  }
  return out;
}

// mesh.cell_data / mesh.point_data: the arrays by name, as views
// (data_views); assigning adds or replaces an array, del removes one. (A
// dict made on each access took assignments and dropped them.)
struct DataArrays {
  py::object mesh;
  bool cells;

  py::dict views() const { return data_views(mesh, cells); }
  std::vector<DataArray> &arrays() const {
    PyMesh &m = mesh.cast<PyMesh &>();
    return cells ? m.mesh.cell_data : m.mesh.point_data;
  }
  void set(const std::string &name, const py::handle &value) const {
    PyMesh &m = mesh.cast<PyMesh &>();
    check_idle(m);
    if (name.rfind("bisect:", 0) == 0) // the state's, and a plane's z (bisect:z)
      throw bisect::UsageError("'" + name + "': names bisect:* are bisect's own");
    const std::size_t count = cells ? m.mesh.num_cells() : m.mesh.num_vertices();
    DataArray a = data_array(name, value, count, cells ? "cell" : "point", "");
    auto &slots = cells ? m.cell_views : m.point_views;
    std::vector<DataArray> &list = arrays();
    for (DataArray &old : list)
      if (old.name == name) {
        // Views of the old array keep its values.
        if (auto it = slots.find(name); it != slots.end()) {
          hand_over(it->second, old.values);
          slots.erase(it);
        }
        old = std::move(a);
        return;
      }
    list.push_back(std::move(a));
  }
  void remove(const std::string &name) const {
    PyMesh &m = mesh.cast<PyMesh &>();
    check_idle(m);
    std::vector<DataArray> &list = arrays();
    auto at =
        std::find_if(list.begin(), list.end(), [&](const DataArray &a) { return a.name == name; });
    if (at == list.end())
      throw py::key_error(name);
    if (name.rfind("bisect:", 0) == 0)
      throw bisect::UsageError("'" + name + "': names bisect:* are bisect's own");
    auto &slots = cells ? m.cell_views : m.point_views;
    if (auto it = slots.find(name); it != slots.end()) {
      hand_over(it->second, at->values);
      slots.erase(it);
    }
    list.erase(at);
  }
};

} // namespace

PYBIND11_MODULE(pybisect, m) {
  m.doc() = "bisect: conformal local refinement of triangle, tetrahedral and 4D simplicial meshes "
            "by edge bisection (the bisect C++ library as a Python module).";

  py::object runtime_error = py::reinterpret_borrow<py::object>(PyExc_RuntimeError);
  g_error_type = PyErr_NewExceptionWithDoc(
      "pybisect.Error",
      "An error of the bisect library. str(e) is the one-line message the bisect command line "
      "prints; e.kind is 'input', 'usage', 'check', 'limit' or 'resource'; e.file names the file "
      "it concerns (None when none).",
      runtime_error.ptr(), nullptr);
  if (!g_error_type)
    throw py::error_already_set();
  m.add_object("Error", py::handle(g_error_type)); // add_object keeps its own reference
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p)
        std::rethrow_exception(p);
    } catch (const bisect::Error &e) {
      raise_error(e);
    }
  });

  py::class_<PyMesh>(m, "Mesh",
                     "A conforming simplicial mesh (triangles, tetrahedra or 4D pentatopes) with "
                     "its bisection state.\n\n"
                     "points, cells and the arrays of point_data/cell_data are numpy views of the "
                     "mesh's memory (no copy). points and cells are read-only. refine() does not "
                     "change an existing view: it keeps showing the mesh as it was before; read "
                     "the property again after refine.")
      .def(py::init([](const py::object &points, const py::object &cells,
                       const py::object &point_data, const py::object &cell_data) {
             return mesh_from_arrays(points, cells, point_data, cell_data, "<arrays>");
           }),
           py::arg("points"), py::arg("cells"), py::arg("point_data") = py::none(),
           py::arg("cell_data") = py::none(),
           "Mesh(points, cells, point_data=None, cell_data=None)\n\n"
           "points: (n, dim) floats; for triangles also (n, 3) with one z for all points. "
           "cells: (m, dim+1) integer vertex ids. point_data/cell_data: dicts name -> array of "
           "n (m) rows. Validated and oriented like a file (load_mesh); bisect:* cell arrays "
           "restore a bisection state.")
      .def_property_readonly("dim", [](const PyMesh &p) { return p.mesh.dim; })
      .def_property_readonly("num_cells", [](const PyMesh &p) { return p.mesh.num_cells(); })
      .def_property_readonly("num_vertices", [](const PyMesh &p) { return p.mesh.num_vertices(); })
      .def_property_readonly(
          "marked", [](const PyMesh &p) { return p.mesh.marked(); },
          "Whether the cells carry a bisection state (after refine, or read "
          "from a file bisect wrote)")
      .def_property_readonly("marking",
                             [](const PyMesh &p) -> py::object {
                               if (!p.mesh.marked())
                                 return py::none();
                               return py::str(bisect::marking_name(p.mesh.marking));
                             })
      .def_property_readonly(
          "points",
          [](py::object self) {
            PyMesh &p = self.cast<PyMesh &>();
            check_idle(p);
            return make_view(self, p.coords_view, p.mesh.coords.data(),
                             {py::ssize_t(p.mesh.num_vertices()), py::ssize_t(p.mesh.dim)}, false);
          },
          "(n, dim) float64, read-only view of the coordinates")
      .def_property_readonly(
          "cells",
          [](py::object self) {
            PyMesh &p = self.cast<PyMesh &>();
            check_idle(p);
            return make_view(self, p.cells_view, p.mesh.cells.data(),
                             {py::ssize_t(p.mesh.num_cells()), py::ssize_t(p.mesh.dim + 1)}, false);
          },
          "(m, dim+1) uint32, read-only view of the vertex ids in bisection-tuple order "
          "(to_meshio and write orient them positively)")
      .def_property_readonly(
          "point_data",
          [](py::object self) {
            return DataArrays{self, false};
          },
          "name -> writable float64 view (n,) or (n, k); assign an array of n rows to add or "
          "replace one, del to remove one")
      .def_property_readonly(
          "cell_data",
          [](py::object self) {
            return DataArrays{self, true};
          },
          "name -> writable float64 view (m,) or (m, k); assign an array of m rows to add or "
          "replace one, del to remove one")
      .def("coarsen", &coarsen, py::arg("marked") = py::none(), py::arg("passes") = 1,
           py::arg("sum") = std::vector<std::string>{},
           "Undo bisections along the bisection tree: a created vertex goes when its whole star "
           "is marked (marked: boolean mask or cell ids; None: every cell) and pairs up into "
           "siblings; a pass undoes the newest refinement iteration around each vertex, so n "
           "refine calls are undone by n passes; passes=0 runs until a pass removes nothing. "
           "Cell arrays named in "
           "`sum` are summed, others take the children's common value or their mean.")
      .def("refine", &refine, py::arg("marked") = py::none(), py::arg("region") = py::none(),
           py::arg("depth") = 1, py::arg("marking") = "index", py::arg("max_cells") = 0,
           "refine(marked=None, region=None, depth=1, marking='index', max_cells=0) -> dict\n\n"
           "Bisects the cells of `marked` (a boolean mask over cells or an array of cell ids) "
           "and those whose closed simplex touches `region` (a dict or JSON text in bisect's "
           "region spec, or a spec file's path), each `depth` generations down, then refines to "
           "conformity (refine_marked). An unmarked mesh is first marked with `marking` (index, "
           "longest, sorted). One call with a region is one iteration of `bisect refine`. "
           "Returns {selected, bisections, closure_passes, cells, vertices}. Raises "
           "pybisect.Error (kind 'limit', nothing bisected) when it would pass max_cells, the "
           "32-bit ids, the memory available or the precision limit. Releases the GIL.")
      .def("check", &check, py::arg("full") = true,
           "check(full=True) -> dict\n\n"
           "Raises pybisect.Error (kind 'check') unless the mesh is conforming and has the volume, "
           "boundary measure (and with full, Euler characteristic) it had when it was read or "
           "built (check_conformity; full=False: the cheaper check_refined bisect refine runs "
           "before writing). Returns {conforming, cells, vertices, volume, boundary_measure, "
           "boundary_facets, euler (full), original_volume, original_boundary_measure}.")
      .def("quality", &quality, "Mean-ratio quality of the cells: {min, max, mean}")
      .def("write", &mesh_write, py::arg("path"), py::arg("compression") = "zlib",
           "write(path, compression='zlib')\n\n"
           "Writes .vtu or .msh (by extension) with the bisection state, through a temporary "
           "file renamed when complete (save_mesh); compression: zlib, lz4 or none (.vtu).")
      .def("to_meshio", &to_meshio,
           "A meshio.Mesh: points (n, 3) as in the .vtu file, one triangle or tetra block "
           "(positively oriented), point and cell data with the bisect:* state arrays, so "
           "from_meshio continues the same bisection. Not for 4D meshes (meshio has no pentatope).")
      .def(
          "copy",
          [](const PyMesh &p) {
            check_idle(p);
            auto out = std::make_unique<PyMesh>();
            out->mesh = p.mesh;
            out->original = p.original;
            return out;
          },
          "An independent copy (same cells, state, arrays and original invariants)")
      .def("__repr__", [](const PyMesh &p) {
        return "<pybisect.Mesh " + std::to_string(p.mesh.dim) + "D, " +
               std::to_string(p.mesh.num_cells()) + " cells, " +
               std::to_string(p.mesh.num_vertices()) + " vertices" +
               (p.mesh.marked() ? std::string(", marking ") + bisect::marking_name(p.mesh.marking)
                                : std::string(", unmarked")) +
               ">";
      });

  m.def(
      "read",
      [](const py::object &path_in) {
        const std::string path =
            py::cast<std::string>(py::module_::import("os").attr("fspath")(path_in));
        auto out = std::make_unique<PyMesh>();
        {
          py::gil_scoped_release release;
          out->mesh = bisect::load_mesh(path);
        }
        return out;
      },
      py::arg("path"),
      "read(path) -> Mesh: a .vtu or .msh file, validated, oriented, with its bisection state "
      "restored when bisect wrote it (load_mesh).");
  py::class_<DataArrays>(m, "DataArrays",
                         "A Mesh's cell or point arrays by name (a mapping): numpy views over "
                         "the mesh's memory; assigning an array with a row per cell (vertex) adds "
                         "or replaces one, del removes one; refinement carries them on.")
      .def("__getitem__",
           [](const DataArrays &d, const std::string &name) -> py::object {
             py::dict v = d.views();
             if (!v.contains(name))
               throw py::key_error(name);
             return v[py::str(name)];
           })
      .def("__setitem__", &DataArrays::set)
      .def("__delitem__", &DataArrays::remove)
      .def("__contains__",
           [](const DataArrays &d, const std::string &name) { return d.views().contains(name); })
      .def("__len__", [](const DataArrays &d) { return d.views().size(); })
      .def("__iter__", [](const DataArrays &d) { return py::iter(d.views()); })
      .def("keys", [](const DataArrays &d) { return d.views().attr("keys")(); })
      .def("values", [](const DataArrays &d) { return d.views().attr("values")(); })
      .def("items", [](const DataArrays &d) { return d.views().attr("items")(); })
      .def(
          "get",
          [](const DataArrays &d, const std::string &name, py::object fallback) -> py::object {
            py::dict v = d.views();
            return v.contains(name) ? py::object(v[py::str(name)]) : fallback;
          },
          py::arg("name"), py::arg("default") = py::none())
      .def("__repr__", [](const DataArrays &d) { return py::repr(d.views()); });

  m.def("from_meshio", &from_meshio, py::arg("mesh"),
        "from_meshio(m) -> Mesh: the tetra cells of a meshio.Mesh (else its triangles), with its "
        "numeric point and cell data; bisect:* arrays (from to_meshio or a .vtu bisect wrote) "
        "restore the bisection state.");
}
