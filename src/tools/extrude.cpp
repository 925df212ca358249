// 4D Delaunay extrusion through Qhull's convex hull of the paraboloid lift.
#include "bisect/extrude.hpp"

#include "bisect/colour.hpp"
#include "bisect/measure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <random>
#include <string>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace bisect {

namespace {

void check_slices(const std::vector<double> &slices) {
  if (slices.size() < 2)
    throw InputError("", "extrude: need at least 2 time slices");
  for (std::size_t i = 0; i < slices.size(); ++i) {
    if (!std::isfinite(slices[i]))
      throw InputError("", "extrude: time slice " + std::to_string(i) + " is not finite");
    if (i > 0 && !(slices[i] > slices[i - 1]))
      throw InputError("", "extrude: time slices must be strictly ascending (slice " +
                               std::to_string(i) + ")");
  }
}

// Shortest edge length of the 3D mesh: sets the size of the tie-breaking lift.
double shortest_edge(const Mesh &m) {
  double h2 = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < m.num_cells(); ++c) {
    const VertexId *x = m.cell(CellId(c));
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        double s = 0;
        for (int k = 0; k < 3; ++k)
          s += std::pow(m.point(x[i])[k] - m.point(x[j])[k], 2);
        h2 = std::min(h2, s);
      }
  }
  return std::sqrt(h2);
}

// Runs Qhull with the options `how` on the (d+1)-dimensional lifted points and
// returns the (d+1)-tuples of vertex ids of the lower facets (outward normal
// pointing down in the lift direction); throws when Qhull fails.
std::vector<VertexId> lower_hull_with(std::vector<double> &lifted, int npoints, int d,
                                      const char *how) {
  // Qhull reports into a stream of ours, not onto stderr: its warnings (up
  // to dozens of lines for a degenerate input, whose result the callers
  // validate anyway) are dropped, and a failure's first line goes into the
  // error's one line.
  char *report = nullptr;
  std::size_t report_size = 0;
  std::FILE *err = open_memstream(&report, &report_size);
  if (!err)
    throw std::bad_alloc();
  qhT qh_storage;
  qhT *qh = &qh_storage;
  qh_zero(qh, err);
  char options[32];
  std::snprintf(options, sizeof options, "qhull %s", how);
  int code = qh_new_qhull(qh, d + 1, npoints, lifted.data(), False, options, nullptr, err);
  std::vector<VertexId> cells;
  if (code == 0) {
    facetT *facet;
    vertexT *vertex, **vertexp;
    FORALLfacets {
      if (!(facet->normal[d] < -1e-12) || qh_setsize(qh, facet->vertices) != d + 1)
        continue;
      FOREACHvertex_(facet->vertices) cells.push_back(VertexId(qh_pointid(qh, vertex->point)));
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(err);
  std::string text(report ? report : "", report_size);
  std::free(report);
  if (code != 0) {
    // Qhull's messages start "QH6154 qhull precision error: ...".
    std::string first;
    for (std::size_t at = 0; at < text.size() && first.empty();) {
      std::size_t end = text.find('\n', at);
      if (end == std::string::npos)
        end = text.size();
      std::string line = text.substr(at, end - at);
      if (line.rfind("QH", 0) == 0)
        first = line.substr(0, 200);
      at = end + 1;
    }
    throw CheckError("delaunay: Qhull failed (code " + std::to_string(code) + ")" +
                     (first.empty() ? std::string() : ": " + first) +
                     " (degenerate or nearly degenerate points, e.g. a slab far thinner than "
                     "the mesh)");
  }
  return cells;
}

// The lower hull, first with no merging of facets (Qhull's Q0): the lift's
// tie-breaking offsets (delaunay() below) make the points general, and Qhull
// then builds the regular triangulation they define. With its default
// merging (Qt: merge facets coplanar within its tolerance, then triangulate
// the merged ones) it spent nearly all its time merging the many ties of an
// extruded lattice, and triangulated merged facets by its own choice
// instead of the offsets': `extrude` of a 4^3 Kuhn cube over 50 slabs took
// 6.4-6.9 s with Qt and 1.2-1.3 s without merging, over 100 slabs 39.4 and
// 5.2 s, with the same cell count and quality; a single cube over 1,000
// slabs took 30.7 s and gave a non-conforming mesh (refused), without
// merging 8.4 s and a conforming one; a slab 10^-6 as thick as the mesh
// failed to conform, and now conforms (2026-12-06, load 2.4). When
// Qhull cannot build the hull without merging (nearly degenerate points,
// such as a faceted sphere's), it is built again with merging, as before.
std::vector<VertexId> lower_hull(std::vector<double> &lifted, int npoints, int d) {
  try {
    return lower_hull_with(lifted, npoints, d, "Q0");
  } catch (const CheckError &) {
    return lower_hull_with(lifted, npoints, d, "Qt");
  }
}

} // namespace

Mesh delaunay(int dim, std::vector<double> coords, double spacing) {
  if (dim < 2 || dim > 4)
    throw InputError("", "delaunay: dimension must be 2, 3 or 4");
  Mesh out;
  out.dim = dim;
  out.coords = std::move(coords);
  const std::size_t n = out.num_vertices();
  if (n < std::size_t(dim + 1))
    throw InputError("", "delaunay: too few points");
  std::vector<double> lo(dim), hi(dim);
  for (int k = 0; k < dim; ++k)
    lo[k] = hi[k] = out.coords[k];
  for (std::size_t v = 0; v < n; ++v)
    for (int k = 0; k < dim; ++k)
      lo[k] = std::min(lo[k], out.coords[dim * v + k]),
      hi[k] = std::max(hi[k], out.coords[dim * v + k]);
  double scale = 0;
  for (int k = 0; k < dim; ++k)
    scale = std::max(scale, hi[k] - lo[k]);
  if (!(spacing > 1e-9 * scale))
    throw InputError("", "delaunay: points too close together");

  // Normalize to a unit box around the origin, then lift to the paraboloid
  // |p|^2 plus a tiny deterministic offset: the offset breaks cospherical
  // ties consistently (a regular triangulation of the exact points). It stays
  // far below the squared spacing so that every point remains a lower vertex.
  const double eps = 1e-4 * std::pow(spacing / scale, 2);
  std::mt19937_64 rng(20241);
  std::uniform_real_distribution<double> jitter(0.0, eps);
  std::vector<double> lifted((dim + 1) * n);
  for (std::size_t v = 0; v < n; ++v) {
    double r2 = 0;
    for (int k = 0; k < dim; ++k) {
      double x = (out.coords[dim * v + k] - 0.5 * (lo[k] + hi[k])) / scale;
      lifted[(dim + 1) * v + k] = x;
      r2 += x * x;
    }
    lifted[(dim + 1) * v + dim] = r2 + jitter(rng);
  }
  std::vector<VertexId> tuples = lower_hull(lifted, int(n), dim);

  // Keep the full-dimensional simplices, positively oriented.
  const double flat = 1e-12 * std::pow(scale, dim);
  const int nv = dim + 1;
  std::vector<char> used(n, 0);
  for (std::size_t c = 0; c < tuples.size() / nv; ++c) {
    VertexId *x = tuples.data() + nv * c;
    double pts[20];
    for (int i = 0; i < nv; ++i)
      std::copy(out.point(x[i]), out.point(x[i]) + dim, pts + dim * i);
    double vol = signed_volume(pts, dim);
    if (std::abs(vol) <= flat)
      continue;
    if (vol < 0)
      std::swap(x[0], x[1]);
    for (int i = 0; i < nv; ++i)
      used[x[i]] = 1;
    out.cells.insert(out.cells.end(), x, x + nv);
  }
  if (std::count(used.begin(), used.end(), 0) != 0)
    throw CheckError("delaunay: a point is missing from the triangulation");
  return out;
}

// A 4D .vtu keeps the time coordinate as the point array t: an input point
// array of that name would be taken for it.
static void check_no_t_array(const Mesh &mesh) {
  for (const DataArray &a : mesh.point_data)
    if (a.name == "t")
      throw InputError("", "extrude: point array 't' would be taken for the 4D result's time "
                           "coordinate (kept as the point array t): rename it");
}

Mesh extrude_delaunay(const Mesh &mesh3, const std::vector<double> &slices, bool fill_hull) {
  if (mesh3.dim != 3)
    throw InputError("", "extrude: the input mesh must be 3D");
  if (mesh3.num_cells() == 0)
    throw InputError("", "extrude: the input mesh has no cells");
  check_slices(slices);
  check_no_t_array(mesh3);
  const std::size_t nv = mesh3.num_vertices(), ns = slices.size();
  std::vector<double> coords;
  coords.reserve(4 * nv * ns);
  for (double t : slices)
    for (std::size_t v = 0; v < nv; ++v) {
      coords.insert(coords.end(), mesh3.point(VertexId(v)), mesh3.point(VertexId(v)) + 3);
      coords.push_back(t);
    }
  double gap = shortest_edge(mesh3);
  for (std::size_t s = 1; s < ns; ++s)
    gap = std::min(gap, slices[s] - slices[s - 1]);
  Mesh out;
  try {
    out = delaunay(4, std::move(coords), gap);
  } catch (const InputError &e) {
    throw InputError("", std::string("extrude: ") + e.what());
  }
  for (const DataArray &a : mesh3.point_data) {
    DataArray b{a.name, a.components, {}};
    for (std::size_t s = 0; s < ns; ++s)
      b.values.insert(b.values.end(), a.values.begin(), a.values.end());
    out.point_data.push_back(std::move(b));
  }

  // Coverage: the triangulation fills the hull; it is the prism only for a
  // convex 3D domain.
  double total = 0;
  for (std::size_t c = 0; c < out.num_cells(); ++c) {
    double pts[20];
    cell_points(out, CellId(c), pts);
    total += std::abs(signed_volume(pts, 4));
  }
  double vol3 = 0;
  for (std::size_t c = 0; c < mesh3.num_cells(); ++c) {
    double pts[12];
    cell_points(mesh3, CellId(c), pts);
    vol3 += std::abs(signed_volume(pts, 3));
  }
  const double expected = vol3 * (slices.back() - slices.front());
  if (!fill_hull && std::abs(total - expected) > 1e-9 * expected)
    throw InputError(
        "", "domain is not convex: Delaunay extrusion needs a convex 3D mesh (hull volume " +
                std::to_string(total) + ", prism volume " + std::to_string(expected) +
                "; --hull triangulates the convex hull instead)");
  return out;
}

// Extrusion by colour (seed 001): see the rule in extrude.hpp.
Mesh extrude_coloured(const Mesh &mesh, const std::vector<std::uint8_t> &colour,
                      const std::vector<double> &slices) {
  const int n = mesh.dim, N = n + 1, m = n + 1; // m: the output dimension
  if (n != 2 && n != 3)
    throw InputError("", "extrude by colouring needs a 2D or 3D mesh, this one is " +
                             std::to_string(n) + "D");
  if (mesh.num_cells() == 0)
    throw InputError("", "extrude: the input mesh has no cells");
  check_slices(slices);
  if (m == 4)
    check_no_t_array(mesh);
  // The result's point array "slice" (each point's slab) would make two
  // arrays of one name, which no reader takes.
  for (const DataArray &a : mesh.point_data)
    if (a.name == "slice")
      throw InputError("", "extrude: point array 'slice' would clash with the result's array of "
                           "each point's slab index: rename it");
  if (std::string why = check_colouring(mesh, colour); !why.empty())
    throw InputError("", "the colouring is not proper: " + why);
  const std::size_t nv = mesh.num_vertices(), ns = slices.size(), nc = mesh.num_cells();
  Mesh out;
  out.dim = m;
  out.coords.reserve(m * nv * ns);
  for (double t : slices)
    for (std::size_t v = 0; v < nv; ++v) {
      out.coords.insert(out.coords.end(), mesh.point(VertexId(v)), mesh.point(VertexId(v)) + n);
      out.coords.push_back(t);
    }
  for (const DataArray &a : mesh.point_data) {
    DataArray b{a.name, a.components, {}};
    for (std::size_t s = 0; s < ns; ++s)
      b.values.insert(b.values.end(), a.values.begin(), a.values.end());
    out.point_data.push_back(std::move(b));
  }
  DataArray slice{"slice", 1, {}};
  slice.values.reserve(nv * ns);
  for (std::size_t s = 0; s < ns; ++s)
    slice.values.insert(slice.values.end(), nv, double(s));
  out.point_data.push_back(std::move(slice));

  const std::size_t per_prism = std::size_t(N), ncells = nc * (ns - 1) * per_prism;
  out.cells.reserve(ncells * (m + 1));
  std::vector<std::size_t> source; // input cell of each output cell
  source.reserve(ncells);
  for (std::size_t s = 0; s + 1 < ns; ++s)
    for (std::size_t c = 0; c < nc; ++c) {
      const VertexId *x = mesh.cell(CellId(c));
      VertexId by_colour[4];
      for (int i = 0; i < N; ++i)
        by_colour[colour[x[i]]] = x[i];
      // (x_n, ..., x_0, x'_n, ..., x'_0)
      VertexId seq[8];
      for (int k = 0; k < N; ++k) {
        seq[k] = VertexId(s * nv + by_colour[n - k]);
        seq[N + k] = VertexId((s + 1) * nv + by_colour[n - k]);
      }
      for (int w = 0; w < N; ++w) {
        out.cells.insert(out.cells.end(), seq + w, seq + w + m + 1);
        source.push_back(c);
      }
    }
  for (const DataArray &a : mesh.cell_data) {
    if (a.name.rfind("bisect:", 0) == 0)
      continue;
    DataArray b{a.name, a.components, {}};
    b.values.reserve(ncells * a.components);
    for (std::size_t c : source)
      b.values.insert(b.values.end(), a.values.begin() + c * a.components,
                      a.values.begin() + (c + 1) * a.components);
    out.cell_data.push_back(std::move(b));
  }
  out.marking = Marking::Sorted;
  out.stage.assign(ncells, Stage::Maubach);
  out.tag.assign(ncells, std::uint8_t(m));
  return out;
}

} // namespace bisect
