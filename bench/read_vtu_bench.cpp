// Benchmark (not a test): bisect's native .vtu reader against VTK's own
// vtkXMLUnstructuredGridReader on the same file, in the same run. Each is
// run `repeats` times (the file is in the page cache after the first read);
// the best time of each is printed.
//
// Usage: bisect_read_vtu_bench FILE.vtu [repeats=3] [ours]  ("ours": skip
// VTK's reader, for profiling ours alone)
#include "bisect/io.hpp"

#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

using Clock = std::chrono::steady_clock;

namespace {

double secs(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

} // namespace

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE.vtu [repeats=3]\n", argv[0]);
    return 1;
  }
  const std::string path = argv[1];
  const int repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  const bool only_ours = argc > 3 && std::string(argv[3]) == "ours";
  double ours = 1e300, vtk = 1e300;
  std::size_t cells = 0, vtk_cells = 0;
  for (int r = 0; r < repeats; ++r) {
    auto t0 = Clock::now();
    const bisect::Mesh mesh = bisect::read_vtu(path);
    auto t1 = Clock::now();
    ours = std::min(ours, secs(t0, t1));
    cells = mesh.num_cells();

    if (only_ours)
      continue;
    t0 = Clock::now();
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    t1 = Clock::now();
    vtk = std::min(vtk, secs(t0, t1));
    vtk_cells = std::size_t(reader->GetOutput()->GetNumberOfCells());
  }
  std::printf("file %s (%.1f MB), %zu cells (VTK: %zu), best of %d\n", path.c_str(),
              double(std::filesystem::file_size(path)) / 1e6, cells, vtk_cells, repeats);
  std::printf("  bisect read_vtu (to Mesh)            %8.3f s\n", ours);
  std::printf("  vtkXMLUnstructuredGridReader::Update %8.3f s\n", vtk);
  std::printf("  ratio ours / VTK                     %8.2f\n", ours / vtk);
  return 0;
}
