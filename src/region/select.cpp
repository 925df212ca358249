// Region selection: the cells whose closed simplex touches a region.
#include "bisect/region.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <array>
#include <bit>

namespace bisect {

std::vector<CellId> select_cells(const Mesh &mesh, const Region &region) {
  std::vector<CellId> out = select_touching(mesh, region);
  region.filter(mesh, out); // e.g. the levelset indicator keeps a fraction
  return out;
}

std::vector<CellId> select_cells(const Mesh &mesh, const Region &region,
                                 const std::vector<std::uint64_t> &candidates) {
  std::vector<CellId> out = select_touching(mesh, region, &candidates);
  region.filter(mesh, out);
  return out;
}

std::array<double, 20> sorted_cell_coordinates(const Mesh &mesh, CellId c) {
  const int dim = mesh.dim, n = dim + 1;
  std::array<const double *, 5> p{};
  for (int i = 0; i < n; ++i)
    p[std::size_t(i)] = mesh.point(mesh.cell(c)[i]);
  // (insertion sort: at most 5 entries)
  for (int i = 1; i < n; ++i)
    for (int j = i;
         j > 0 && std::lexicographical_compare(p[std::size_t(j)], p[std::size_t(j)] + dim,
                                               p[std::size_t(j - 1)], p[std::size_t(j - 1)] + dim);
         --j)
      std::swap(p[std::size_t(j)], p[std::size_t(j - 1)]);
  std::array<double, 20> out{};
  for (int i = 0; i < n; ++i)
    std::copy_n(p[std::size_t(i)], dim, out.data() + i * dim);
  return out;
}

bool cell_coordinates_less(const Mesh &mesh, CellId a, CellId b) {
  const std::size_t k = std::size_t(mesh.dim) * std::size_t(mesh.dim + 1);
  const std::array<double, 20> x = sorted_cell_coordinates(mesh, a),
                               y = sorted_cell_coordinates(mesh, b);
  return std::lexicographical_compare(x.begin(), x.begin() + std::ptrdiff_t(k), y.begin(),
                                      y.begin() + std::ptrdiff_t(k));
}

std::vector<CellId> select_touching(const Mesh &mesh, const Region &region,
                                    const std::vector<std::uint64_t> *candidates) {
  const int dim = mesh.dim, nv = dim + 1;
  double lo[4], hi[4];
  region.bounds(lo, hi, dim);
  // Blocks of cells, each selecting into its own list, joined in order: the
  // same selection for every thread count.
  constexpr std::size_t kBlock = std::size_t(1) << 14;
  const std::size_t nc = mesh.num_cells(), blocks = (nc + kBlock - 1) / kBlock;
  std::vector<std::vector<CellId>> found(blocks);
  const int workers =
      region.concurrent() ? int(std::clamp<std::size_t>(blocks / 4, 1, std::size_t(threads()))) : 1;
  // The cells' points are scattered over the coordinates: a batch of
  // kBatch cells has its points read first (the reads wait for memory
  // together), then its cells are tested, in order.
  constexpr std::size_t kBatch = 16;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 2)
  for (std::size_t k = 0; k < blocks; ++k) {
    double pts[5 * 4];
    CellId batch[kBatch];
    std::size_t batched = 0;
    auto test_batch = [&] {
      double touched = 0;
      for (std::size_t j = 0; j < batched; ++j) {
        const VertexId *x = mesh.cell(batch[j]);
        for (int i = 0; i < nv; ++i)
          touched += mesh.point(x[i])[0];
      }
      asm volatile("" ::"x"(touched)); // the reads happen
      for (std::size_t j = 0; j < batched; ++j) {
        const VertexId *x = mesh.cell(batch[j]);
        bool outside = false;
        for (int d = 0; d < dim && !outside; ++d) {
          double a = mesh.point(x[0])[d], b = a;
          for (int i = 1; i < nv; ++i) {
            double v = mesh.point(x[i])[d];
            a = std::min(a, v);
            b = std::max(b, v);
          }
          outside = b < lo[d] || a > hi[d];
        }
        if (outside)
          continue;
        for (int i = 0; i < nv; ++i)
          std::copy(mesh.point(x[i]), mesh.point(x[i]) + dim, pts + i * dim);
        if (region.touches(pts, dim))
          found[k].push_back(batch[j]);
      }
      batched = 0;
    };
    for (std::size_t c = k * kBlock; c < std::min(nc, (k + 1) * kBlock); ++c) {
      if (candidates) {
        const std::size_t w = c >> 6;
        if (w >= candidates->size())
          break;
        const std::uint64_t bits = (*candidates)[w] >> (c & 63);
        if (!bits) { // no candidate left in this word
          c |= 63;
          continue;
        }
        c += std::size_t(std::countr_zero(bits)); // the next candidate
        if (c >= std::min(nc, (k + 1) * kBlock))
          break;
      }
      batch[batched++] = CellId(c);
      if (batched == kBatch)
        test_batch();
    }
    test_batch();
  }
  std::size_t total = 0;
  for (const auto &f : found)
    total += f.size();
  std::vector<CellId> out;
  out.reserve(total);
  for (auto &f : found) {
    out.insert(out.end(), f.begin(), f.end());
    std::vector<CellId>().swap(f);
  }
  return out;
}

std::function<std::vector<CellId>(const Mesh &)> region_selector(const Region &region) {
  return [&region](const Mesh &mesh) { return select_cells(mesh, region); };
}

} // namespace bisect
