// Shared by the fuzz targets: a temporary file holding the fuzzer's bytes,
// and the property every accepted mesh must keep under refinement.
#pragma once

#include "bisect/check.hpp"
#include "bisect/mark.hpp"
#include "bisect/mesh.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/state.hpp"

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
  std::string path =
      std::string(dir && *dir ? dir : "/tmp") + "/bisect-fuzz-" + std::to_string(::getpid()) + ext;
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

struct RefineCheck {
  int iterations = 2;
  std::size_t max_input_cells = 400; // larger accepted meshes are not refined
  std::size_t max_cells = 20000;     // refine's limit: an iteration past it is undone
  int roundtrip_after = 0;           // after this iteration (0: never), the state goes
                                     // through its cell arrays and back
};

// An accepted (prepared, marked) mesh must refine to a conforming mesh with
// the same volume, boundary measure and Euler characteristic, checked in full
// (check_conformity against the input's invariants) after every iteration.
// The sizes are capped so that one input stays fast. With BISECT_FUZZ_TRACE
// set, one line per iteration on stderr (for tuning the caps).
inline void refine_and_check(bisect::Mesh &mesh, const bisect::Region &region,
                             const RefineCheck &how) {
  using namespace bisect;
  if (mesh.num_cells() > how.max_input_cells)
    return;
  static const bool trace = std::getenv("BISECT_FUZZ_TRACE") != nullptr;
  const Invariants before = measure_invariants(mesh);
  // The full check, with the measure standing in for the vertex search where
  // that is exact (see CheckOptions): the meshes here are small.
  CheckOptions options;
  options.refined_from_original = true;
  RefineLimits limits;
  limits.max_cells = how.max_cells;
  for (int it = 1; it <= how.iterations; ++it) {
    const std::vector<CellId> selected = select_cells(mesh, region);
    if (selected.empty()) // nothing changes now or in any later iteration
      break;
    const std::size_t cells_before = mesh.num_cells();
    const RefineResult r = refine(mesh, selected, limits);
    if (r.limit_reached) {
      if (mesh.num_cells() != cells_before)
        fail("iteration " + std::to_string(it) + " passed the limit but was not undone");
      break;
    }
    if (mesh.num_cells() < cells_before + selected.size())
      fail("iteration " + std::to_string(it) + ": " + std::to_string(selected.size()) +
           " cells selected but only " + std::to_string(mesh.num_cells() - cells_before) +
           " cells added");
    const CheckResult c = check_conformity(mesh, &before, options);
    if (!c.ok)
      fail("after iteration " + std::to_string(it) + ": " + c.failure);
    if (trace)
      std::fprintf(stderr, "TRACE dim %d it %d cells %zu\n", mesh.dim, it, mesh.num_cells());
    if (it == how.roundtrip_after) {
      // What a file carries: encode, decode, and the same tuples, Stage and tag.
      const std::vector<VertexId> cells = mesh.cells;
      const std::vector<Stage> stage = mesh.stage;
      const std::vector<std::uint8_t> tag = mesh.tag;
      encode_state(mesh);
      if (!decode_state(mesh, "fuzz"))
        fail("decode_state found no state after encode_state");
      if (mesh.cells != cells || mesh.stage != stage || mesh.tag != tag)
        fail("the bisection state changed through encode_state/decode_state");
    }
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
  const auto region =
      parse_region("{\"type\":\"sphere\",\"solid\":true,\"radius\":0.5,\"center\":" + c + "]}",
                   mesh.dim, "fuzz");
  RefineCheck how;
  how.iterations = 2;
  how.max_cells = 5000;
  refine_and_check(mesh, *region, how);
  return 0;
}

} // namespace bisect_fuzz
