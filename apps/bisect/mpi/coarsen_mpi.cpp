// bisect coarsen under mpirun (a BISECT_MPI build): rank 0 reads the mesh
// and its tree, the ranks mark their parts, coarsen() of distributed.hpp
// undoes the bisections on every part, and the result is written
// as a .pvtu with a piece per rank, or gathered into one file.
#include "cli.hpp"
#include "mpi/refine_mpi.hpp"

#include "bisect/coarsen.hpp"
#include "bisect/distributed.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>

namespace bisect::cli {

namespace {

// Whether the parts carry the bisection tree (a part without cells has none
// to show). Collective.
bool any_rank_has_tree(const DistributedMesh &d) {
  int mine = d.local.has_tree(), any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_LOR, d.comm.get());
  return any != 0;
}

} // namespace

int run_coarsen_mpi(const DistributedCoarsenArgs &a) {
  const auto t_start = std::chrono::steady_clock::now();
  // bisect coarsen ... -o X.pvtu without mpirun: one rank.
  mpi_init_alone();
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const bool pvtu = a.output.ends_with(".pvtu");
  const bool quiet = a.quiet || rank != 0;

  // A .pvtu that bisect wrote is read by every rank, a stretch of its pieces
  // each (read_pvtu_parts; not with --check, whose Euler characteristic is
  // the whole input's); any other input is read and validated by rank 0. A
  // failure there ends every rank with its exit code (only rank 0 prints it).
  const bool parallel = pieces_read_in_parallel(a.input, !a.check, rank);
  Mesh mesh;
  Invariants original;
  std::unique_ptr<OutputSet> outputs;
  int h_mesh = -1;
  const int failure = on_rank_zero(rank, [&] {
    std::vector<std::string> inputs{a.input};
    if (!a.region.empty())
      inputs.push_back(a.region);
    if (!pvtu && a.format.empty())
      check_extension(a.output);
    outputs = std::make_unique<OutputSet>(inputs, a.force);
    if (!pvtu)
      h_mesh = outputs->add(a.output);
    if (parallel)
      return;
    mesh = load_mesh(a.input, load_progress(a.input, quiet));
    if (!pvtu)
      check_output_format(a.output, mesh.dim, a.format);
    if (!a.region.empty())
      (void)read_region(a.region, mesh.dim);
    if (!a.indicator.empty())
      (void)cell_indicator(mesh, a.indicator, a.input);
    // (The serial coarsen writes such a mesh unchanged.)
    if (!mesh.marked() || !mesh.has_tree())
      throw InputError(a.input, "carries no bisection tree (bisect:generation, "
                                "bisect:parent_a/b): nothing to coarsen");
    original = measure_invariants(mesh, a.check);
    // The input cells' indices travel with the cells (CoarsenOptions).
    if (a.origin)
      add_origin_array(mesh);
    if (!quiet)
      std::cerr << "bisect: " << a.input << ": " << mesh.dim << "D, "
                << with_commas(mesh.num_cells()) << " cells, " << with_commas(mesh.num_vertices())
                << " vertices\n";
  });
  if (failure)
    return failure;
  int dim = mesh.dim;
  MPI_Bcast(&dim, 1, MPI_INT, 0, MPI_COMM_WORLD);

  try {
    PartsFacts in{dim, mesh.num_cells(), mesh.num_vertices(), original};
    DistributedMesh d = input_parts(parallel, mesh, a.input, a.origin, quiet, !pvtu, a.output,
                                    a.format, a.region, in);
    const std::size_t cells0 = in.cells, verts0 = in.vertices;
    dim = in.dim;
    original = in.whole;
    if (parallel) {
      if (!any_rank_has_tree(d))
        throw InputError(a.input, "carries no bisection tree (bisect:piece_generation, "
                                  "bisect:piece_level, bisect:piece_parents): nothing to coarsen");
      if (!quiet)
        std::cerr << "bisect: " << a.input << ": " << dim << "D, " << with_commas(cells0)
                  << " cells, " << with_commas(verts0) << " vertices; its pieces read by "
                  << (d.size == 1 ? std::string("one rank")
                                  : "all " + std::to_string(d.size) + " ranks")
                  << "\n";
    }
    mesh = Mesh{};
    // Each rank marks its cells as the serial coarsen marks them (a cell's
    // mark depends on the cell alone).
    std::vector<char> marks(d.local.num_cells(), 0);
    if (a.all) {
      std::fill(marks.begin(), marks.end(), 1);
    } else if (!a.region.empty()) {
      for (CellId c : select_cells(d, *read_region(a.region, dim)))
        marks[c] = 1;
    } else {
      const std::vector<double> values = cell_indicator(d.local, a.indicator, a.input);
      for (CellId c : mark_by_indicator(values, IndicatorRule::Below, a.below, a.input, &d.local))
        marks[c] = 1;
    }
    CoarsenOptions options;
    options.passes = a.passes;
    options.sum_arrays = a.sums;
    if (a.origin)
      options.min_arrays.push_back(kOriginArray);
    const auto print_pass = coarsen_pass_printer(a.passes, quiet);
    int rounds = 0, passes_run = 0; // (on rank 0, which sees the passes)
    std::size_t moved = 0;
    const auto on_pass = [&](const CoarsenPass &pass) {
      ++passes_run;
      rounds += pass.rounds;
      moved += pass.moved_cells;
      if (print_pass)
        print_pass(pass);
    };
    // (For a .pvtu output; a gathered one is checked whole on rank 0.)
    const Invariants whole_before = pvtu ? whole_invariants(d) : Invariants{};
    const CoarsenResult result = coarsen(d, marks, options, on_pass);

    // The final check across the new parts: each part against itself as
    // distributed, then the border between parts; and the whole mesh's
    // volume and boundary measure against the input's.
    if (pvtu) {
      const Invariants part = measure_invariants(d.local, false);
      CheckResult check = check_refined(d, part, border_measure(d));
      const Invariants whole_after = whole_invariants(d);
      auto changed = [](double before, double after) {
        return std::abs(after - before) > 1e-9 * std::max(std::abs(before), std::abs(after));
      };
      if (check.ok && (changed(whole_before.volume, whole_after.volume) ||
                       changed(whole_before.boundary_measure, whole_after.boundary_measure))) {
        check.ok = false;
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "the whole mesh's volume or boundary measure changed: %.10g, %.10g -> "
                      "%.10g, %.10g",
                      whole_before.volume, whole_before.boundary_measure, whole_after.volume,
                      whole_after.boundary_measure);
        check.failure = buf;
      }
      if (!check.ok) {
        if (rank == 0)
          std::cerr << "bisect: internal check failed after coarsening: " << one_line(check.failure)
                    << "; no output written\n";
        return kExitCheck;
      }
      write_pvtu(a.output, d, a.force);
    }
    Mesh g;
    if (!pvtu)
      g = gather(d, 0);
    int bad = 0;
    if (rank == 0) {
      if (!pvtu) {
        // The whole mesh: the serial coarsen's check (--check: the full one).
        const CheckResult check =
            a.check ? check_conformity(g, &original) : check_refined(g, original);
        if (!check.ok) {
          std::cerr << "bisect: internal check failed after coarsening: " << one_line(check.failure)
                    << "; no output written\n";
          bad = 1;
        } else {
          WriteOptions write_options;
          write_options.format = a.format;
          write_output_mesh(*outputs, h_mesh, g, write_options);
        }
      }
      if (!bad)
        outputs->commit();
    }
    MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (bad)
      return kExitCheck;
    const double total = seconds_since(t_start);
    double rss = peak_rss_bytes(), rss_max = 0;
    MPI_Reduce(&rss, &rss_max, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    if (rank == 0 && a.json) {
      nlohmann::json j;
      j["input"] = a.input;
      j["output"] = a.output;
      j["dim"] = dim;
      j["ranks"] = d.size;
      j["pieces_read_in_parallel"] = parallel != 0;
      j["passes"] = result.passes;  // passes that removed something
      j["passes_run"] = passes_run; // and the one that found nothing left, if it ran
      j["initial_cells"] = cells0;
      j["initial_vertices"] = verts0;
      j["cells"] = d.global_cells;
      j["vertices"] = d.global_vertices;
      j["removed_vertices"] = result.removed_vertices;
      j["merged_pairs"] = result.merged_pairs;
      j["seconds"] = total;
      j["peak_rss_bytes_max_rank"] = rss_max;
      j["rounds"] = rounds;     // in which cells moved between parts
      j["moved_cells"] = moved; // in those rounds, over all passes
      print_json(j);
    }
    if (!quiet)
      std::cerr << "bisect: wrote " << a.output << " (" << with_commas(d.global_cells) << " cells"
                << (pvtu ? ", " + std::to_string(d.size) + (d.size == 1 ? " piece" : " pieces")
                         : std::string())
                << ", " << with_commas(result.removed_vertices) << " vertices removed) in "
                << std::fixed << std::setprecision(2) << total << " s\n";
    return kExitOk;
  } catch (...) {
    return distributed_exit_code(rank);
  }
}

} // namespace bisect::cli
