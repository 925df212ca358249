// libFuzzer target: any bytes as a .msh file. read_msh and prepare_input may
// only throw InputError; an accepted mesh must refine conformally.
#include "fuzz_common.hpp"
#include "io.hpp"

#include <memory>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  using namespace bisect;
  const std::string path = bisect_fuzz::write_temp(data, size, ".msh");
  Mesh mesh;
  try {
    mesh = read_msh(path);
    prepare_input(mesh, path);
    if (!decode_state(mesh, path))
      mark_mesh(mesh, Marking(size % 3));
  } catch (const InputError &) {
    std::remove(path.c_str());
    return 0;
  }
  std::remove(path.c_str());
  if (mesh.dim < 2 || mesh.dim > 3)
    bisect_fuzz::fail("read_msh returned a " + std::to_string(mesh.dim) + "D mesh");
  // The closed ball around the first vertex: always touches some cell.
  std::string c = "[";
  for (int d = 0; d < mesh.dim; ++d)
    c += (d ? "," : "") + std::to_string(mesh.coords[d]);
  const auto region = parse_region(
      "{\"type\":\"sphere\",\"solid\":true,\"radius\":0.5,\"center\":" + c + "]}", mesh.dim, "fuzz");
  bisect_fuzz::refine_and_check(mesh, *region, 2);
  return 0;
}
