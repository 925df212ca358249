// The README's library example for distributed refinement (README, "MPI"):
// rank 0 loads and marks a mesh, the ranks refine their parts around a
// region for three iterations, check across parts and write a .pvtu; with a
// fourth argument, then undo one iteration everywhere (coarsen) and write
// that too.
// usage: mpirun -np P example IN REGION.json OUT.pvtu [COARSENED.pvtu]
#include <bisect/bisect.hpp>
#include <bisect/distributed.hpp>

#include <mpi.h>

#include <cstdio>

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int code = 0;
  {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    bisect::Mesh mesh; // significant on rank 0 only
    if (rank == 0) {
      mesh = bisect::load_mesh(argv[1]); // validated, state restored
      bisect::ensure_marked(mesh);       // else marked (index)
    }
    bisect::DistributedMesh d = bisect::distribute(mesh, 0, MPI_COMM_WORLD);
    const bisect::Invariants part = bisect::measure_invariants(d.local, false);
    const double border = bisect::border_measure(d);
    const auto region = bisect::read_region(argv[2], d.local.dim);
    for (int it = 0; it < 3; ++it) {
      const bisect::DistributedRefineResult r =
          bisect::refine(d, bisect::select_cells(d.local, *region));
      if (rank == 0)
        std::printf("iteration %d: %zu bisections, %zu cells, %d exchange rounds\n", it + 1,
                    r.bisections, d.global_cells, r.rounds);
    }
    const bisect::CheckResult check = bisect::check_refined(d, part, border);
    if (check.ok)
      bisect::write_pvtu(argv[3], d, /*force=*/true);
    else
      code = 2;
    if (argc > 4 && code == 0) {
      // Every cell marked: one pass undoes the newest iteration.
      const std::vector<char> all(d.local.num_cells(), 1);
      const bisect::CoarsenResult c = bisect::coarsen(d, all);
      if (rank == 0)
        std::printf("coarsened: %zu vertices removed, %zu cells\n", c.removed_vertices,
                    d.global_cells);
      const bisect::CheckResult again = bisect::check_refined(
          d, bisect::measure_invariants(d.local, false), bisect::border_measure(d));
      if (again.ok)
        bisect::write_pvtu(argv[4], d, /*force=*/true);
      else
        code = 2;
    }
  }
  MPI_Finalize();
  return code;
}
