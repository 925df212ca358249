// libFuzzer target: any bytes as a .vtu file (see fuzz_mesh_file). The
// whole read path is bisect's own (vtu_read.cpp, io_vtu.cpp); seeds from
// scripts/vtu_seeds.py cover every VTK writer setting.
#include "bisect/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  return bisect_fuzz::fuzz_mesh_file(data, size, ".vtu", bisect::read_vtu, 4);
}
