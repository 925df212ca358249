// Region selection: the cells whose closed simplex touches a region.
#include "bisect/region.hpp"

#include <algorithm>

namespace bisect {

std::vector<CellId> select_cells(const Mesh &mesh, const Region &region) {
  const int dim = mesh.dim, nv = dim + 1;
  double lo[4], hi[4];
  region.bounds(lo, hi, dim);
  std::vector<CellId> out;
  double pts[5 * 4];
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    bool outside = false;
    for (int k = 0; k < dim && !outside; ++k) {
      double a = mesh.point(x[0])[k], b = a;
      for (int i = 1; i < nv; ++i) {
        double v = mesh.point(x[i])[k];
        a = std::min(a, v);
        b = std::max(b, v);
      }
      outside = b < lo[k] || a > hi[k];
    }
    if (outside)
      continue;
    for (int i = 0; i < nv; ++i)
      std::copy(mesh.point(x[i]), mesh.point(x[i]) + dim, pts + i * dim);
    if (region.touches(pts, dim))
      out.push_back(CellId(c));
  }
  region.filter(mesh, out); // e.g. the levelset indicator keeps a fraction
  return out;
}

std::function<std::vector<CellId>(const Mesh &)> region_selector(const Region &region) {
  return [&region](const Mesh &mesh) { return select_cells(mesh, region); };
}

} // namespace bisect
