// Shared by the fuzz targets: a temporary file holding the fuzzer's bytes,
// and the property every accepted mesh must keep under refinement.
#pragma once

#include "check.hpp"
#include "mark.hpp"
#include "mesh.hpp"
#include "refine.hpp"
#include "region.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

namespace bisect_fuzz {

// A file in $TMPDIR (or /tmp) named after the process, with the given
// extension so that read_mesh-style dispatch sees the right format.
inline std::string write_temp(const std::uint8_t *data, std::size_t size, const char *ext) {
  const char *dir = std::getenv("TMPDIR");
  std::string path = std::string(dir && *dir ? dir : "/tmp") + "/bisect-fuzz-" +
                     std::to_string(::getpid()) + ext;
  std::FILE *f = std::fopen(path.c_str(), "wb");
  if (!f)
    std::abort();
  if (size && std::fwrite(data, 1, size, f) != size)
    std::abort();
  std::fclose(f);
  return path;
}

[[noreturn]] inline void fail(const std::string &what) {
  std::fprintf(stderr, "FUZZ PROPERTY FAILED: %s\n", what.c_str());
  std::abort();
}

// An accepted (prepared, marked) mesh must refine to a conforming mesh with
// the same volume, boundary measure and Euler characteristic. Small meshes
// only, with a cell limit, so one input stays fast.
inline void refine_and_check(bisect::Mesh &mesh, const bisect::Region &region, int iterations) {
  using namespace bisect;
  if (mesh.num_cells() > 400)
    return;
  const Invariants before = measure_invariants(mesh);
  RefineLimits limits;
  limits.max_cells = 20000;
  for (int it = 0; it < iterations; ++it) {
    const std::vector<CellId> selected = select_cells(mesh, region);
    const RefineResult r = refine(mesh, selected, limits);
    if (r.limit_reached)
      break;
    const CheckResult c = check_conformity(mesh, &before);
    if (!c.ok)
      fail("after iteration " + std::to_string(it + 1) + ": " + c.failure);
  }
}

// Any bytes as a mesh file read by `read` (read_msh or read_vtu): reading and
// prepare_input may only throw InputError; an accepted mesh must refine
// conformally around the closed ball at its first vertex.
inline int fuzz_mesh_file(const std::uint8_t *data, std::size_t size, const char *ext,
                          bisect::Mesh (*read)(const std::string &), int max_dim) {
  using namespace bisect;
  const std::string path = write_temp(data, size, ext);
  Mesh mesh;
  try {
    mesh = read(path);
    prepare_input(mesh, path);
    if (!decode_state(mesh, path))
      mark_mesh(mesh, Marking(size % 3));
  } catch (const InputError &) {
    std::remove(path.c_str());
    return 0;
  }
  std::remove(path.c_str());
  if (mesh.dim < 2 || mesh.dim > max_dim)
    fail(std::string("the reader returned a ") + std::to_string(mesh.dim) + "D mesh");
  std::string c = "[";
  for (int d = 0; d < mesh.dim; ++d)
    c += (d ? "," : "") + std::to_string(mesh.coords[d]);
  const auto region = parse_region(
      "{\"type\":\"sphere\",\"solid\":true,\"radius\":0.5,\"center\":" + c + "]}", mesh.dim, "fuzz");
  refine_and_check(mesh, *region, 2);
  return 0;
}

} // namespace bisect_fuzz
