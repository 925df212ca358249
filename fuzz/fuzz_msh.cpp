// libFuzzer target: any bytes as a .msh file (see fuzz_mesh_file).
#include "bisect/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  return bisect_fuzz::fuzz_mesh_file(data, size, ".msh", bisect::read_msh, 3);
}
