// libFuzzer target: any text as a region spec for 2D, 3D and 4D meshes.
// parse_region may only throw InputError; an accepted region answers
// touches() and bounds() on the cells of a Kuhn mesh without crashing, and a
// simplex it touches meets its bounds box (select_cells skips cells outside
// the box, so a wrong box would silently miss cells). Intersections are
// conservative and are not held to the box.
#include "bisect/generate.hpp"
#include "fuzz_common.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  using namespace bisect;
  const std::string text(reinterpret_cast<const char *>(data), size);
  const bool conservative =
      text.find("ntersection") != std::string::npos || text.find("\\u") != std::string::npos;
  for (int dim = 2; dim <= 4; ++dim) {
    std::unique_ptr<Region> region;
    try {
      region = parse_region(text, dim, "fuzz.json");
    } catch (const InputError &) {
      continue;
    }
    if (!region)
      bisect_fuzz::fail("parse_region returned null");
    std::vector<double> lo(dim), hi(dim);
    region->bounds(lo.data(), hi.data(), dim);
    static const Mesh kuhns[3] = {generate_kuhn(2, 2, -1.0, 2.0), generate_kuhn(3, 2, -1.0, 2.0),
                                  generate_kuhn(4, 2, -1.0, 2.0)}; // made once
    const Mesh &kuhn = kuhns[dim - 2];
    std::vector<double> verts((dim + 1) * dim);
    for (std::size_t c = 0; c < kuhn.num_cells(); ++c) {
      for (int i = 0; i <= dim; ++i)
        for (int d = 0; d < dim; ++d)
          verts[i * dim + d] = kuhn.point(kuhn.cell(CellId(c))[i])[d];
      if (!region->touches(verts.data(), dim))
        continue;
      if (conservative)
        continue;
      for (int d = 0; d < dim; ++d) {
        double cmin = INFINITY, cmax = -INFINITY;
        for (int i = 0; i <= dim; ++i)
          cmin = std::min(cmin, verts[i * dim + d]), cmax = std::max(cmax, verts[i * dim + d]);
        if (cmax < lo[d] || cmin > hi[d])
          bisect_fuzz::fail("cell " + std::to_string(c) +
                            " touched but outside bounds in coordinate " + std::to_string(d));
      }
    }
  }
  return 0;
}
