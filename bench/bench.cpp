// Benchmark (not a test): seed 002 §5.2 and seed 000 §5.3 refinement runs.
// Prints generated cells per second in refine-to-conformity (selection and
// quality measurement timed apart) and peak memory per cell.
//
// Usage: bisect_bench [ball.msh] [iterations3d=40] [iterations4d=25]
#include "bench_util.hpp"
#include "bisect/check.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

using namespace bisect;
using bisect::bench::Clock;
using bisect::bench::proc_status_kb;
using bisect::bench::secs;

namespace {

void run(const char *name, Mesh mesh, Marking marking, const std::string &region_json,
         int iterations) {
  mark_mesh(mesh, marking);
  auto region = parse_region(region_json, mesh.dim, name);
  long rss0 = proc_status_kb("VmRSS:");
  double t_select = 0, t_refine = 0, t_kernel = 0;
  std::size_t bisections = 0;
  const std::size_t cells0 = mesh.num_cells();
  for (int it = 1; it <= iterations; ++it) {
    auto t0 = Clock::now();
    auto sel = select_cells(mesh, *region);
    auto t1 = Clock::now();
    RefineResult r = refine(mesh, sel);
    auto t2 = Clock::now();
    t_select += secs(t0, t1);
    t_refine += secs(t1, t2);
    bisections += r.bisections;
    t_kernel += r.kernel_seconds;
  }
  long hwm = proc_status_kb("VmHWM:");
  QualitySummary q = quality_summary(mesh);
  const double cells = double(mesh.num_cells());
  std::printf("%s (%s marking, %d iterations)\n", name, marking_name(marking), iterations);
  std::printf("  cells %zu -> %zu, vertices %zu, min quality %.4f, max %.4f\n", cells0,
              mesh.num_cells(), mesh.num_vertices(), q.min, q.max);
  std::printf("  refine to conformity: %.3f s for %zu bisections = %.2f M generated cells/s "
              "(2 per bisection), %.2f M bisections/s, one core\n",
              t_refine, bisections, 2e-6 * bisections / t_refine, 1e-6 * bisections / t_refine);
  std::printf("  of which the bisection kernel: %.3f s = %.2f M generated cells/s; finding the "
              "cells to close: %.3f s\n",
              t_kernel, 2e-6 * bisections / t_kernel, t_refine - t_kernel);
  std::printf("  selection (region tests): %.3f s; total %.3f s\n", t_select, t_select + t_refine);
  std::printf(
      "  peak RSS %.1f MiB = %.1f bytes/cell; above the pre-refinement RSS: %.1f bytes/cell\n",
      hwm / 1024.0, hwm * 1024.0 / cells, (hwm - rss0) * 1024.0 / cells);
  std::fflush(stdout);
}

} // namespace

int main(int argc, char **argv) {
  std::string ball = argc > 1 ? argv[1] : std::string(BISECT_DATA_DIR) + "/ball.msh";
  int it3 = argc > 2 ? std::atoi(argv[2]) : 40;
  int it4 = argc > 3 ? std::atoi(argv[3]) : 25;
  std::printf("machine: %u hardware threads; all figures single-threaded\n",
              std::thread::hardware_concurrency());
  try {
    if (it3 > 0) {
      Mesh m = read_mesh(ball);
      prepare_input(m, ball);
      run("seed 002 §5.2: ball r=2, hemisphere", std::move(m), Marking::Index,
          R"({"type":"hemisphere","center":[0.5,0.5,0.5],"radius":1,"normal":[1,0,0],"offset":0.5})",
          it3);
    }
    if (it4 > 0)
      run("seed 000 §5.3: Kuhn [0,1]^4, moving sphere", generate_kuhn(4, 1), Marking::Longest,
          R"({"type":"moving_sphere","center":[0,0,0],"velocity":[0,0,1],"radius":0.2})", it4);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "bisect_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
