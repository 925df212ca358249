// bisect refine under mpirun (a BISECT_MPI build): rank 0 reads and marks
// the mesh, the ranks refine their parts (distributed.hpp), and the result
// is written as a .pvtu with a piece per rank, or gathered into one file.
#include "mpi/refine_mpi.hpp"
#include "cli.hpp"

#include "bisect/distributed.hpp"
#include "bisect/driver.hpp"
#include "bisect/refine.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <limits>
#include <sstream>

namespace bisect::cli {

// The test hook of refine.cpp (set only in the bisect_mpi_hooked test
// binary): here it sees each rank's part after each iteration.
extern void (*g_after_iteration_hook)(int iteration, Mesh &mesh, std::size_t first_new_vertex);

namespace {

bool g_we_initialised = false;

// Whether some edge of a selected cell is within 2^10 of the precision limit
// (refine.hpp), as the serial refine's undo log decides.
bool near_precision_limit(const Mesh &m, const std::vector<CellId> &selected) {
  for (CellId c : selected) {
    const VertexId *x = m.cell(c);
    for (int i = 0; i <= m.dim; ++i)
      for (int j = i + 1; j <= m.dim; ++j) {
        const double *p = m.point(x[i]), *q = m.point(x[j]);
        double extent = 0, magnitude = 0;
        for (int k = 0; k < m.dim; ++k) {
          extent = std::max(extent, std::abs(p[k] - q[k]));
          magnitude = std::max({magnitude, std::abs(p[k]), std::abs(q[k])});
        }
        if (extent < 1024 * std::max(kRelativeResolution * magnitude, kAbsoluteResolution))
          return true;
      }
  }
  return false;
}

// The ranks of this job on this machine (they share its memory).
int local_ranks() {
  if (const char *local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE"))
    return std::max(1, std::atoi(local));
  return 1;
}

// The message of the lowest rank whose `mine` is not empty, on every rank
// (empty when none is). Collective on MPI_COMM_WORLD.
std::string first_failing_rank(const std::string &mine, int rank) {
  int me = mine.empty() ? std::numeric_limits<int>::max() : rank, lowest = 0;
  MPI_Allreduce(&me, &lowest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (lowest == std::numeric_limits<int>::max())
    return {};
  std::uint64_t n = mine.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, lowest, MPI_COMM_WORLD);
  std::string text(n, ' ');
  if (rank == lowest)
    text = mine;
  MPI_Bcast(text.data(), int(n), MPI_CHAR, lowest, MPI_COMM_WORLD);
  return "rank " + std::to_string(lowest) + ": " + text;
}

// The cells an indicator marked, while they travel to their parts.
constexpr const char *kMarkedArray = "bisect:indicator_marked";

} // namespace

bool launched_by_mpirun() {
  for (const char *v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(v))
      return true;
  return false;
}

void mpi_start(int *argc, char ***argv) {
  if (!launched_by_mpirun())
    return;
  MPI_Init(argc, argv);
  g_we_initialised = true;
  // The ranks on this machine share its cores: each gets its share of
  // threads unless --threads says otherwise (parsed after this).
  set_threads(std::max(1, threads() / local_ranks()));
}

void mpi_stop() {
  int done = 0;
  MPI_Finalized(&done);
  if (g_we_initialised && !done)
    MPI_Finalize();
}

int mpi_world_size() {
  int on = 0;
  MPI_Initialized(&on);
  if (!on)
    return 1;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

void mpi_init_alone() {
  int on = 0;
  MPI_Initialized(&on);
  if (!on) {
    MPI_Init(nullptr, nullptr);
    g_we_initialised = true;
  }
}

int run_refine_mpi(const DistributedArgs &a) {
  const auto t_start = std::chrono::steady_clock::now();
  // bisect refine ... -o X.pvtu without mpirun: one rank.
  mpi_init_alone();
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const bool pvtu = a.output.size() > 5 && a.output.substr(a.output.size() - 5) == ".pvtu";
  const bool quiet = a.quiet || rank != 0;

  // A .pvtu that bisect wrote (its pieces carry bisect:global_id) is read by
  // every rank, a stretch of its pieces each (read_pvtu_parts), unless an
  // indicator must rank the input's cells together; any other input is
  // read, validated and marked by rank 0. A failure there ends every rank
  // with its exit code (only rank 0 prints it).
  const bool parallel = pieces_read_in_parallel(a.input, a.indicator.empty(), rank);
  Mesh mesh;
  Invariants original;
  std::unique_ptr<OutputSet> outputs;
  int h_mesh = -1, h_csv = -1;
  std::vector<int> h_slices;
  const int failure = on_rank_zero(rank, [&] {
    if (!pvtu) {
      if (a.format.empty())
        check_extension(a.output);
      std::vector<std::string> inputs{a.input};
      if (!a.region.empty())
        inputs.push_back(a.region);
      outputs = std::make_unique<OutputSet>(inputs, a.force);
      h_mesh = outputs->add(a.output);
      for (double t : a.slices)
        h_slices.push_back(outputs->add(slice_path(a.output, "t", t)));
    } else {
      outputs = std::make_unique<OutputSet>(a.region.empty()
                                                ? std::vector<std::string>{a.input}
                                                : std::vector<std::string>{a.input, a.region},
                                            a.force);
    }
    if (a.csv != "none")
      h_csv = outputs->add(a.csv);
    if (parallel)
      return;
    mesh = load_for_refinement(a.input, a.marking, quiet);
    if (!pvtu)
      check_output_format(a.output, mesh.dim, a.format);
    if (!a.slices.empty() && mesh.dim < 3)
      throw UsageError("--slices needs a 3D (2D+t) or 4D mesh; " + a.input + " is 2D");
    // Cell arrays travel with their cells and pass to their children.
    if (a.origin)
      add_origin_array(mesh);
    if (!a.region.empty())
      (void)read_region(a.region, mesh.dim);
    original = measure_invariants(mesh, false);
    if (!a.indicator.empty()) {
      // The indicator marks the input's cells (one iteration): the marks
      // travel with the cells as a cell array, removed after selecting.
      const std::vector<double> values = cell_indicator(mesh, a.indicator, a.input);
      const std::vector<CellId> marked =
          mark_by_indicator(values, IndicatorRule(a.rule), a.parameter, a.input, &mesh);
      DataArray flag{kMarkedArray, 1, std::vector<double>(mesh.num_cells(), 0.0), ValueType::Int8};
      for (CellId c : marked)
        flag.values[c] = 1;
      mesh.cell_data.push_back(std::move(flag));
    }
  });
  if (failure)
    return failure;
  double inv[2] = {original.volume, original.boundary_measure};
  MPI_Bcast(inv, 2, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  original.volume = inv[0];
  original.boundary_measure = inv[1];
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
      if (!a.slices.empty() && dim < 3)
        throw UsageError("--slices needs a 3D (2D+t) or 4D mesh; " + a.input + " is 2D");
      if (a.marking && *a.marking != d.local.marking && !quiet)
        std::cerr << "bisect: " << a.input << " carries bisection state with --marking "
                  << marking_name(d.local.marking) << "; continuing it (--marking "
                  << marking_name(*a.marking) << " ignored)\n";
    }
    mesh = Mesh{};
    Invariants part_original = measure_invariants(d.local, false);
    double border_original = border_measure(d);
    std::unique_ptr<Region> region = a.region.empty() ? nullptr : read_region(a.region, dim);
    if (!quiet)
      std::cerr << "bisect: " << a.input << ": " << dim << "D, " << with_commas(cells0)
                << " cells, " << with_commas(verts0) << " vertices, marking "
                << marking_name(d.local.marking) << "; " << d.size << " ranks, "
                << (parallel ? "its pieces read by all of them, " : "") << "largest part "
                << "of " << with_commas(d.local.num_cells()) << " cells\n";
    std::ostringstream rows;
    rows << "iteration,cells,vertices,selected,bisections,min_quality,max_quality,mean_quality,"
            "seconds,exchange_rounds,imbalance,imbalance_after_rebalance\n";
    auto row = [&](int it, std::size_t sel, std::size_t bis, const QualitySummary &q, double sec,
                   int rounds, double before, double after) {
      char buf[320];
      std::snprintf(buf, sizeof buf, "%d,%zu,%zu,%zu,%zu,%.9g,%.9g,%.9g,%.6f,%d,%.4f,%.4f\n", it,
                    d.global_cells, d.global_vertices, sel, bis, q.min, q.max, q.mean, sec, rounds,
                    before, after);
      rows << buf;
    };
    QualitySummary q = quality_summary(d);
    const double imbalance0 = imbalance(d);
    row(0, 0, 0, q, 0.0, 0, imbalance0, imbalance0);
    double rebalance_seconds = 0, worst_imbalance = imbalance0;
    int rebalances = 0;
    std::size_t bisections = 0, selected_total = 0, edges_sent = 0;
    int rounds_total = 0, iterations = 0;
    std::string stop_message; // the precision limit stopped the run
    double exchange_seconds = 0;
    for (int it = 1; it <= a.iterations; ++it) {
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<CellId> selected;
      if (region)
        selected = select_cells(d, *region);
      for (auto f = d.local.cell_data.begin(); f != d.local.cell_data.end(); ++f)
        if (f->name == kMarkedArray) {
          std::vector<CellId> by_indicator, both;
          for (std::size_t c = 0; c < d.local.num_cells(); ++c)
            if (f->values[c] != 0)
              by_indicator.push_back(CellId(c));
          std::set_union(selected.begin(), selected.end(), by_indicator.begin(), by_indicator.end(),
                         std::back_inserter(both));
          selected = std::move(both);
          d.local.cell_data.erase(f);
          break;
        }
      // The memory estimate of the serial refine (driver.hpp), each rank for
      // its part: with --max-memory against that bound, else against the
      // memory available now, which the ranks on this machine share.
      {
        const std::string why =
            a.max_memory_gib > 0
                ? memory_shortfall(d.local, selected.size(), a.max_memory_gib)
                : memory_shortfall(d.local, selected.size() * std::size_t(local_ranks()), 0);
        const std::string first = first_failing_rank(why, rank);
        if (!first.empty()) {
          stop_message = "stopping before iteration " + std::to_string(it) + ": " + first;
          break;
        }
      }
      // Near the precision limit (a selected cell's edge within 2^10 of it:
      // closure bisects cells about as coarse), every rank keeps its part as
      // it is, so that passing the limit anywhere undoes the iteration; so
      // with --max-elements, to go back when the iteration passes it.
      const bool near = near_precision_limit(d.local, selected) || a.max_elements > 0;
      int any_near = near, keep = 0;
      MPI_Allreduce(&any_near, &keep, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
      std::unique_ptr<Mesh> kept_part;
      std::vector<std::vector<int>> kept_sharers;
      if (keep) {
        kept_part = std::make_unique<Mesh>(d.local);
        kept_sharers = d.sharers;
      }
      static const std::atomic<bool> never{false}; // keeps each part's undo log
      RefineLimits limits;
      if (keep)
        limits.cancel = &never;
      const std::size_t first_new = d.local.num_vertices();
      const DistributedRefineResult r = refine_marked(d, selected, a.depth, limits);
      if (r.precision_reached) {
        if (!kept_part)
          throw UsageError("distributed refinement passed the precision limit (an edge below "
                           "2^-40 of its coordinates' magnitude) in iteration " +
                           std::to_string(it) +
                           " far from where it was expected; no output written; refine "
                           "without mpirun to stop there");
        d.local = std::move(*kept_part);
        d.sharers = std::move(kept_sharers);
        count_global(d);
        stop_message = "stopping before iteration " + std::to_string(it) +
                       ": it would bisect an edge finer than doubles resolve (extent below "
                       "2^-40 of its coordinates' magnitude, or below 2^-100); writing the "
                       "mesh after iteration " +
                       std::to_string(it - 1);
        break;
      }
      if (a.max_elements > 0 && d.global_cells > a.max_elements) {
        const std::size_t passed = d.global_cells;
        d.local = std::move(*kept_part);
        d.sharers = std::move(kept_sharers);
        count_global(d);
        stop_message = "stopping before iteration " + std::to_string(it) + ": it would pass " +
                       "--max-elements " + with_commas(a.max_elements) + " (" +
                       with_commas(passed) + " cells; " + with_commas(d.global_cells) + " now)";
        break;
      }
      if (r.selected == 0) {
        if (!quiet)
          std::cerr << (a.indicator.empty()
                            ? "bisect: the region touches no cell; nothing more to refine\n"
                            : "bisect: nothing is marked; the mesh is written unchanged\n");
        break;
      }
      if (g_after_iteration_hook)
        g_after_iteration_hook(it, d.local, first_new);
      // --check: the final check across ranks after every iteration, so a
      // failure names the iteration it happened in.
      if (a.check) {
        const CheckResult c = check_refined(d, part_original, border_original);
        if (!c.ok)
          throw CheckError("internal check failed after iteration " + std::to_string(it) + ": " +
                           c.failure + "; no output written");
      }
      q = quality_summary(d);
      // Parts more than 10% above the mean are made again along the curve
      // for the next iteration.
      const auto t_balance = std::chrono::steady_clock::now();
      const double before = imbalance(d);
      // (not after the last iteration: nothing is refined after it)
      const bool moved = it < a.iterations && rebalance(d, part_original, border_original, 0.1);
      if (moved) {
        part_original = measure_invariants(d.local, false);
        border_original = border_measure(d);
      }
      const double after = moved ? imbalance(d) : before;
      rebalance_seconds += seconds_since(t_balance);
      rebalances += moved;
      worst_imbalance = std::max(worst_imbalance, after);
      const double sec = seconds_since(t0);
      ++iterations;
      bisections += r.bisections;
      selected_total += r.selected;
      rounds_total += r.rounds;
      edges_sent += r.edges_sent;
      exchange_seconds += r.exchange_seconds;
      row(it, r.selected, r.bisections, q, sec, r.rounds, before, after);
      if (!quiet) {
        char buf[320];
        std::snprintf(buf, sizeof buf,
                      "iteration %d/%d: %s cells, %s vertices, %s selected, %s bisections "
                      "(%d exchange rounds), quality min %.4f max %.4f, largest part %.2fx "
                      "the mean%s, %.2f s\n",
                      it, a.iterations, with_commas(d.global_cells).c_str(),
                      with_commas(d.global_vertices).c_str(), with_commas(r.selected).c_str(),
                      with_commas(r.bisections).c_str(), r.rounds, q.min, q.max, before,
                      moved ? (" (rebalanced: " + std::to_string(after).substr(0, 4) + "x)").c_str()
                            : "",
                      sec);
        std::cerr << buf;
      }
    }
    if (!stop_message.empty() && !quiet)
      std::cerr << "bisect: " << stop_message << "\n";
    const auto t_check = std::chrono::steady_clock::now();
    const CheckResult check = check_refined(d, part_original, border_original);
    const double check_seconds = seconds_since(t_check);
    if (!check.ok) {
      if (rank == 0)
        std::cerr << "bisect: internal check failed: " << one_line(check.failure)
                  << "; no output written\n";
      return kExitCheck;
    }
    const auto t_write = std::chrono::steady_clock::now();
    WriteOptions write_options;
    write_options.compression = a.compression;
    write_options.format = a.format;
    std::string slice_lines;
    if (pvtu) {
      write_pvtu(a.output, d, a.force, write_options);
    }
    if (rank == 0 && h_csv >= 0)
      write_text_file(outputs->file(h_csv), a.csv, rows.str());
    if (!pvtu) {
      Mesh g = gather(d, 0);
      if (rank == 0) {
        // The gathered mesh passes the serial final check too.
        const CheckResult whole = check_refined(g, original);
        if (!whole.ok) {
          std::cerr << "bisect: internal check failed: " << one_line(whole.failure)
                    << "; no output written\n";
          MPI_Abort(MPI_COMM_WORLD, kExitCheck);
        }
        write_output_mesh(*outputs, h_mesh, g, write_options);
        // Sections of the gathered mesh: the serial run's files.
        for (std::size_t i = 0; i < a.slices.size(); ++i)
          slice_lines += write_slice(g, g.dim - 1, a.slices[i], *outputs, h_slices[i]).line;
      }
    }
    if (rank == 0)
      outputs->commit();
    if (!quiet)
      std::cerr << slice_lines;
    const double write_seconds = seconds_since(t_write);
    double exchange_max = 0;
    MPI_Reduce(&exchange_seconds, &exchange_max, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    std::uint64_t sent = edges_sent, sent_max = 0, part = d.local.num_cells(), part_max = 0;
    MPI_Reduce(&sent, &sent_max, 1, MPI_UINT64_T, MPI_MAX, 0, MPI_COMM_WORLD);
    MPI_Reduce(&part, &part_max, 1, MPI_UINT64_T, MPI_MAX, 0, MPI_COMM_WORLD);
    double rss = peak_rss_bytes(), rss_max = 0;
    MPI_Reduce(&rss, &rss_max, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    const double total = seconds_since(t_start);
    if (rank == 0 && a.json) {
      nlohmann::json j;
      j["input"] = a.input;
      j["output"] = a.output;
      j["quality_csv"] = h_csv >= 0 ? nlohmann::json(a.csv) : nlohmann::json(nullptr);
      j["dim"] = dim;
      j["ranks"] = d.size;
      j["pieces_read_in_parallel"] = parallel != 0;
      j["marking"] = marking_name(d.local.marking);
      j["iterations"] = iterations;
      j["initial_cells"] = cells0;
      j["initial_vertices"] = verts0;
      j["cells"] = d.global_cells;
      j["vertices"] = d.global_vertices;
      j["bisections"] = bisections;
      j["selected"] = selected_total;
      j["exchange_rounds"] = rounds_total;
      j["largest_part_cells"] = part_max;
      j["edges_sent_max_rank"] = sent_max;
      j["exchange_seconds_max_rank"] = exchange_max;
      j["rebalances"] = rebalances;
      j["rebalance_seconds"] = rebalance_seconds;
      j["largest_imbalance_after_rebalance"] = worst_imbalance;
      j["min_quality"] = q.min;
      j["max_quality"] = q.max;
      j["mean_quality"] = q.mean;
      j["seconds"] = total;
      j["final_check_seconds"] = check_seconds;
      j["write_seconds"] = write_seconds;
      j["peak_rss_bytes_max_rank"] = rss_max;
      j["limit_reached"] = !stop_message.empty();
      print_json(j);
    }
    if (!quiet)
      std::cerr << "bisect: wrote " << a.output << " (" << with_commas(d.global_cells) << " cells"
                << (pvtu ? ", " + std::to_string(d.size) + (d.size == 1 ? " piece" : " pieces")
                         : std::string())
                << ")" << (h_csv >= 0 ? " and " + a.csv : std::string()) << " in " << std::fixed
                << std::setprecision(2) << total << " s\n";
    return stop_message.empty() ? kExitOk : kExitLimit;
  } catch (...) {
    return distributed_exit_code(rank);
  }
}

bool pieces_read_in_parallel(const std::string &input, bool allowed, int rank) {
  int parallel = 0;
  if (rank == 0 && allowed && input.size() > 5) {
    std::string ext = input.substr(input.size() - 5);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    try {
      parallel = ext == ".pvtu" && pvtu_has_global_ids(input);
    } catch (const Error &) {
      // (rank 0's own read says what is wrong)
    }
  }
  MPI_Bcast(&parallel, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return parallel != 0;
}

DistributedMesh input_parts(bool parallel, const Mesh &mesh, const std::string &input, bool origin,
                            bool quiet, bool gathered, const std::string &output,
                            const std::string &format, const std::string &region,
                            PartsFacts &facts) {
  if (!parallel)
    return distribute(mesh, 0, MPI_COMM_WORLD);
  PartsReadOptions read_options;
  read_options.progress = load_progress(input, quiet);
  read_options.origin = origin;
  DistributedMesh d = read_pvtu_parts(input, MPI_COMM_WORLD, read_options);
  facts.dim = d.local.dim;
  facts.cells = d.global_cells;
  facts.vertices = d.global_vertices;
  facts.whole = whole_invariants(d);
  if (gathered)
    check_output_format(output, facts.dim, format);
  if (!region.empty())
    (void)read_region(region, facts.dim);
  return d;
}

int on_rank_zero(int rank, const std::function<void()> &step) {
  int failure = 0;
  std::string message;
  if (rank == 0) {
    try {
      step();
    } catch (const Error &e) {
      failure = e.kind == ErrorKind::Check ? kExitCheck : kExitInput;
      message = e.what();
    } catch (const std::bad_alloc &) {
      failure = kExitMemory;
      message = "out of memory reading the input";
    }
  }
  MPI_Bcast(&failure, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (failure && rank == 0)
    std::cerr << "bisect: " << one_line(message) << "\n";
  return failure;
}

int distributed_exit_code(int rank) {
  try {
    throw;
  } catch (const Error &e) {
    // The distributed steps throw on every rank alike (a refusal, a failed
    // write): rank 0 speaks for all.
    if (rank == 0)
      std::cerr << "bisect: " << one_line(e.what()) << "\n";
    return e.kind == ErrorKind::Check   ? kExitCheck
           : e.kind == ErrorKind::Limit ? kExitLimit
                                        : kExitInput;
  } catch (const std::exception &e) {
    // One rank alone (an internal error): the job cannot go on.
    std::cerr << "bisect: rank " << rank << ": " << one_line(e.what()) << "\n";
    MPI_Abort(MPI_COMM_WORLD, kExitCheck);
  }
  return kExitCheck;
}

} // namespace bisect::cli
