// 4D Delaunay extrusion through Qhull's convex hull of the paraboloid lift.
#include "extrude.hpp"

#include "measure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace bisect {

namespace {

void check_slices(const std::vector<double> &slices) {
  if (slices.size() < 2) throw InputError("", "extrude: need at least 2 time slices");
  for (std::size_t i = 0; i < slices.size(); ++i) {
    if (!std::isfinite(slices[i])) throw InputError("", "extrude: time slice " + std::to_string(i) + " is not finite");
    if (i > 0 && !(slices[i] > slices[i - 1]))
      throw InputError("", "extrude: time slices must be strictly ascending (slice " + std::to_string(i) + ")");
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
        for (int k = 0; k < 3; ++k) s += std::pow(m.point(x[i])[k] - m.point(x[j])[k], 2);
        h2 = std::min(h2, s);
      }
  }
  return std::sqrt(h2);
}

// Runs Qhull on the 5D lifted points and returns the 5-tuples of vertex ids
// of the lower facets (outward normal pointing down in the lift direction).
std::vector<VertexId> lower_hull(std::vector<double> &lifted, int npoints) {
  qhT qh_storage;
  qhT *qh = &qh_storage;
  qh_zero(qh, stderr);
  char options[] = "qhull Qt";
  int code = qh_new_qhull(qh, 5, npoints, lifted.data(), False, options, nullptr, stderr);
  std::vector<VertexId> cells;
  if (code == 0) {
    facetT *facet;
    vertexT *vertex, **vertexp;
    FORALLfacets {
      if (!(facet->normal[4] < -1e-12) || qh_setsize(qh, facet->vertices) != 5) continue;
      FOREACHvertex_(facet->vertices) cells.push_back(VertexId(qh_pointid(qh, vertex->point)));
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  if (code != 0) throw CheckError("extrude: qhull failed with code " + std::to_string(code));
  return cells;
}

} // namespace

Mesh extrude_delaunay(const Mesh &mesh3, const std::vector<double> &slices) {
  if (mesh3.dim != 3) throw InputError("", "extrude: the input mesh must be 3D");
  if (mesh3.num_cells() == 0) throw InputError("", "extrude: the input mesh has no cells");
  check_slices(slices);
  const std::size_t nv = mesh3.num_vertices(), ns = slices.size();
  Mesh out;
  out.dim = 4;
  out.coords.reserve(4 * nv * ns);
  for (double t : slices)
    for (std::size_t v = 0; v < nv; ++v) {
      out.coords.insert(out.coords.end(), mesh3.point(VertexId(v)), mesh3.point(VertexId(v)) + 3);
      out.coords.push_back(t);
    }
  for (const DataArray &a : mesh3.point_data) {
    DataArray b{a.name, a.components, {}};
    for (std::size_t s = 0; s < ns; ++s) b.values.insert(b.values.end(), a.values.begin(), a.values.end());
    out.point_data.push_back(std::move(b));
  }

  // Normalize to a unit box around the origin, then lift to the paraboloid
  // |p|^2 plus a tiny deterministic offset: the offset breaks cospherical
  // ties consistently (a regular triangulation of the exact points). It stays
  // far below the squared spacing so that every point remains a lower vertex.
  const std::size_t n = nv * ns;
  double lo[4], hi[4];
  for (int k = 0; k < 4; ++k) lo[k] = hi[k] = out.coords[k];
  for (std::size_t v = 0; v < n; ++v)
    for (int k = 0; k < 4; ++k) lo[k] = std::min(lo[k], out.coords[4 * v + k]), hi[k] = std::max(hi[k], out.coords[4 * v + k]);
  double scale = 0;
  for (int k = 0; k < 4; ++k) scale = std::max(scale, hi[k] - lo[k]);
  double gap = shortest_edge(mesh3);
  for (std::size_t s = 1; s < ns; ++s) gap = std::min(gap, slices[s] - slices[s - 1]);
  if (!(gap > 1e-9 * scale)) throw InputError("", "extrude: points too close together");
  const double eps = 1e-4 * std::pow(gap / scale, 2);
  std::mt19937_64 rng(20241);
  std::uniform_real_distribution<double> jitter(0.0, eps);
  std::vector<double> lifted(5 * n);
  for (std::size_t v = 0; v < n; ++v) {
    double r2 = 0;
    for (int k = 0; k < 4; ++k) {
      double x = (out.coords[4 * v + k] - 0.5 * (lo[k] + hi[k])) / scale;
      lifted[5 * v + k] = x;
      r2 += x * x;
    }
    lifted[5 * v + 4] = r2 + jitter(rng);
  }
  std::vector<VertexId> tuples = lower_hull(lifted, int(n));

  // Keep the full-dimensional simplices, positively oriented.
  const double flat = 1e-12 * std::pow(scale, 4);
  double total = 0;
  std::vector<char> used(n, 0);
  for (std::size_t c = 0; c < tuples.size() / 5; ++c) {
    VertexId *x = tuples.data() + 5 * c;
    double pts[20];
    for (int i = 0; i < 5; ++i) std::copy(out.point(x[i]), out.point(x[i]) + 4, pts + 4 * i);
    double vol = signed_volume(pts, 4);
    if (std::abs(vol) <= flat) continue;
    if (vol < 0) std::swap(x[0], x[1]);
    total += std::abs(vol);
    for (int i = 0; i < 5; ++i) used[x[i]] = 1;
    out.cells.insert(out.cells.end(), x, x + 5);
  }

  // Coverage: the triangulation fills the hull; it is the prism only for a
  // convex 3D domain.
  double vol3 = 0;
  for (std::size_t c = 0; c < mesh3.num_cells(); ++c) {
    double pts[12];
    cell_points(mesh3, CellId(c), pts);
    vol3 += std::abs(signed_volume(pts, 3));
  }
  const double expected = vol3 * (slices.back() - slices.front());
  if (std::abs(total - expected) > 1e-9 * expected)
    throw InputError("", "domain is not convex: Delaunay extrusion needs a convex 3D mesh (hull volume " +
                             std::to_string(total) + ", prism volume " + std::to_string(expected) + ")");
  if (std::count(used.begin(), used.end(), 0) != 0)
    throw CheckError("extrude: a point is missing from the Delaunay triangulation");
  return out;
}

} // namespace bisect
