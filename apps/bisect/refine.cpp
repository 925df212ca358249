// bisect refine: read, refine iteration after iteration, check, write.
#include "cli.hpp"
#ifdef BISECT_MPI
#include "mpi/refine_mpi.hpp"
#endif

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>

namespace fs = std::filesystem;

namespace bisect::cli {

// Test hook: set by tests/support/corrupt_hook.cpp in the bisect_hooked
// binary the tests build, called after every iteration; nullptr in bisect.
void (*g_after_iteration_hook)(int iteration, Mesh &mesh, std::size_t first_new_vertex) = nullptr;

namespace {

struct RefineArgs {
  std::string input, region, output, csv, format, compression = "zlib";
  int iterations = 1;
  // Marking by an indicator (one of above/top/dorfler), and its depth.
  std::string indicator;
  std::optional<double> above, top, dorfler;
  int depth = 1;
  std::string marking;
  std::int64_t max_elements = 0;
  double max_memory_gib = 0;
  bool force = false, check = false, origin = false;
  CommonFlags flags;
  std::optional<std::string> slices_text; // --slices as given (parse_slices)
  std::vector<double> slices;             // t values (last coordinate): sections of the final mesh
};

std::string default_output(const std::string &input) {
  return (input == "-" ? std::string("stdin") : fs::path(input).stem().string()) + ".refined.vtu";
}

std::string default_csv(const std::string &output) {
  fs::path p(output);
  return (p.parent_path() / (p.stem().string() + ".quality.csv")).string();
}

// Wall seconds per stage of a run, for --json (and bench/e2e.sh).
struct StageSeconds {
  double read = 0, validate = 0, select = 0, refine = 0, quality = 0, final_check = 0, write = 0;
};

int run_refine(RefineArgs &a) {
  const auto t_start = std::chrono::steady_clock::now();
  // The same T0,T1,... or START:STOP:COUNT as extrude's, one slice allowed.
  if (a.slices_text)
    a.slices = parse_slices(*a.slices_text, 1);
  const bool quiet = a.flags.quiet;
  if (a.region.empty() && a.indicator.empty())
    throw UsageError("refine needs --region SPEC or --indicator NAME (or both)");
  const int rules = a.above.has_value() + a.top.has_value() + a.dorfler.has_value();
  if (!a.indicator.empty() && rules != 1)
    throw UsageError("--indicator needs exactly one of --above X, --top F, --dorfler THETA");
  if (a.indicator.empty() && rules)
    throw UsageError("--above, --top and --dorfler need --indicator NAME");
  if (!a.indicator.empty() && a.iterations != 1)
    throw UsageError("--iterations with --indicator: the indicator belongs to the input's cells, "
                     "so it marks one iteration; run refine again with a new indicator");
  std::optional<Marking> marking;
  if (!a.marking.empty())
    marking = parse_marking(a.marking);
#ifdef BISECT_MPI
  // Under mpirun, or for a .pvtu: the distributed refine (README, "MPI").
  if (mpi_world_size() > 1 || a.output.ends_with(".pvtu")) {
    if (a.output.empty())
      throw UsageError("distributed refine needs -o (a .pvtu, or a .vtu/.msh to gather into)");
    if (!a.slices.empty() && a.output.ends_with(".pvtu"))
      throw UsageError("--slices with a .pvtu output: cut the pieces afterwards (bisect slice " +
                       a.output + " --t T -o SECTION.vtu), or gather into a .vtu under mpirun");
    if (!a.format.empty() && a.output.ends_with(".pvtu"))
      throw UsageError("--format with a .pvtu output: the pieces are .vtu");
    DistributedArgs d;
    d.input = a.input;
    d.region = a.region;
    // -o -: gathered and written to standard output by rank 0 (no CSV
    // unless asked for), as the serial run does.
    d.output = output_name(a.output, a.format, a.flags.json);
    d.format = a.format;
    d.csv = !a.csv.empty() ? a.csv : a.output == "-" ? "none" : default_csv(a.output);
    d.origin = a.origin;
    d.slices = a.slices;
    d.iterations = a.iterations;
    d.depth = a.depth;
    d.indicator = a.indicator;
    d.rule = int(a.above ? IndicatorRule::Above
                 : a.top ? IndicatorRule::Top
                         : IndicatorRule::Dorfler);
    d.parameter = a.above ? *a.above : a.top ? *a.top : a.dorfler ? *a.dorfler : 0.0;
    d.marking = marking;
    d.max_elements = std::size_t(a.max_elements);
    d.max_memory_gib = a.max_memory_gib;
    d.check = a.check;
    d.compression = a.compression == "lz4"    ? Compression::Lz4
                    : a.compression == "none" ? Compression::None
                                              : Compression::Zlib;
    d.force = a.force;
    d.quiet = a.flags.quiet;
    d.json = a.flags.json;
    return run_refine_mpi(d);
  }
#endif
  // -o -: the mesh goes to standard output (then no CSV unless asked for).
  const std::string out =
      output_name(a.output.empty() ? default_output(a.input) : a.output, a.format, a.flags.json);
  const std::string csv = !a.csv.empty() ? a.csv : a.output == "-" ? "none" : default_csv(out);
  if (a.format.empty())
    check_extension(out);
  // Every output is checked before any work and written as one transaction.
  std::vector<std::string> inputs{a.input};
  if (!a.region.empty())
    inputs.push_back(a.region);
  OutputSet outputs(inputs, a.force);
  const int h_mesh = outputs.add(out);
  const int h_csv = csv == "none" ? -1 : outputs.add(csv);
  std::vector<int> h_slices;
  const int digits = slice_digits(a.slices);
  for (double t : a.slices)
    h_slices.push_back(outputs.add(slice_path(out, "t", t, digits)));

  StageSeconds stages;
  auto t0 = std::chrono::steady_clock::now();
  const LoadProgress progress = load_progress(a.input, quiet);
  StoredState stored; // the state's arrays in their file types, beside the mesh
  Mesh mesh = read_mesh(a.input, stored);
  stages.read = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  // Validation's walks give the input's invariants (the final check's
  // reference) and, for a file with a bisection state, the interior facets
  // the state's consistency check visits: none of them is walked again.
  InputFacts facts;
  facts.want_quality = true; // the quality CSV's first row, from validation's cell pass
  const bool continued = prepare_read_mesh(mesh, a.input, progress, facts, &stored);
  if (continued) {
    if (marking && *marking != mesh.marking && !quiet)
      std::cerr << "bisect: " << a.input << " carries bisection state with --marking "
                << marking_name(mesh.marking) << "; continuing it (--marking "
                << marking_name(*marking) << " ignored)\n";
  } else {
    mark_mesh(mesh, marking.value_or(Marking::Index));
  }
  stages.validate = seconds_since(t0);
  check_output_format(out, mesh.dim, a.format);
  if (!a.slices.empty() && mesh.dim < 3)
    throw UsageError("--slices needs a 3D (2D+t) or 4D mesh; " + a.input + " is 2D");
  if (a.origin)
    add_origin_array(mesh);
  std::unique_ptr<Region> region;
  if (!a.region.empty())
    region = read_region(a.region, mesh.dim);
  // The cells the indicator marks, in the input's numbering (one iteration).
  std::vector<CellId> by_indicator;
  if (!a.indicator.empty()) {
    const std::vector<double> values = cell_indicator(mesh, a.indicator, a.input);
    const IndicatorRule rule = a.above ? IndicatorRule::Above
                               : a.top ? IndicatorRule::Top
                                       : IndicatorRule::Dorfler;
    by_indicator = mark_by_indicator(values, rule,
                                     a.above ? *a.above
                                     : a.top ? *a.top
                                             : *a.dorfler,
                                     a.input, &mesh);
  }
  Selector select = [&](const Mesh &m) {
    if (a.indicator.empty())
      return select_cells(m, *region);
    if (!region)
      return by_indicator;
    std::vector<CellId> both = select_cells(m, *region), out;
    std::set_union(both.begin(), both.end(), by_indicator.begin(), by_indicator.end(),
                   std::back_inserter(out));
    return out;
  };

  std::ostringstream rows;
  rows << "iteration,cells,vertices,selected,bisections,min_quality,max_quality,mean_quality,"
          "seconds\n";
  auto row = [&](int it, std::size_t sel, std::size_t bis, const QualitySummary &q, double sec) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d,%zu,%zu,%zu,%zu,%.9g,%.9g,%.9g,%.6f\n", it, mesh.num_cells(),
                  mesh.num_vertices(), sel, bis, q.min, q.max, q.mean, sec);
    rows << buf;
  };
  t0 = std::chrono::steady_clock::now();
  const QualitySummary quality0 = facts.quality;
  const double quality0_seconds = seconds_since(t0);
  row(0, 0, 0, quality0, 0.0);
  const std::size_t cells0 = mesh.num_cells(), verts0 = mesh.num_vertices();
  if (!quiet)
    std::cerr << "bisect: " << a.input << ": " << mesh.dim << "D, " << with_commas(cells0)
              << " cells, " << with_commas(verts0) << " vertices, marking "
              << marking_name(mesh.marking) << "\n";

  DriverOptions options;
  options.iterations = a.iterations;
  options.depth = a.depth;
  options.max_cells = std::size_t(a.max_elements);
  options.max_memory_gib = a.max_memory_gib;
  options.input_invariants = &facts.invariants;
  options.input_quality = &quality0;
  // A region that stays put, tested exactly: each iteration after the first
  // tests only the descendants of the cells the one before selected.
  if (region && a.indicator.empty() && region->monotone()) {
    options.select_among = [&](const Mesh &m, const std::vector<std::uint64_t> &candidates) {
      return select_cells(m, *region, candidates);
    };
  }
  // --check (always on in a BISECT_PARANOID build): the full conformity check
  // against the input's invariants after every iteration.
#ifdef BISECT_PARANOID
  options.check_every_iteration = true;
#else
  options.check_every_iteration = a.check;
#endif
  // The callback below only reads the mesh, unless a test installs its hook.
  options.on_iteration_changes_mesh = g_after_iteration_hook != nullptr;
  // Neither the selection nor the callback reads the cell arrays (a test's
  // hook may): they travel as each cell's input cell until the end.
  options.cell_data_by_origin = g_after_iteration_hook == nullptr;
  std::size_t selected_total = 0;
  auto on_iteration = [&](const IterationReport &r, Mesh &m) {
    selected_total += r.selected;
    row(r.iteration, r.selected, r.bisections, r.quality, r.seconds);
    if (!quiet) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "iteration %d/%d: %s cells, %s vertices, %s selected, %s bisections "
                    "(%zu closure passes), quality min %.4f max %.4f, %.2f s\n",
                    r.iteration, a.iterations, with_commas(r.cells).c_str(),
                    with_commas(r.vertices).c_str(), with_commas(r.selected).c_str(),
                    with_commas(r.bisections).c_str(), r.closure_passes, r.quality.min,
                    r.quality.max, r.seconds);
      std::cerr << buf;
    }
    if (g_after_iteration_hook)
      g_after_iteration_hook(r.iteration, m, r.first_new_vertex);
  };
  DriverResult result;
  try {
    result = run_iterations(mesh, select, options, on_iteration);
  } catch (const CheckError &e) {
    std::cerr << "bisect: internal check failed " << e.what() << "; no output written\n";
    return kExitCheck;
  }
  stages.select = result.select_seconds;
  stages.refine = result.refine_seconds;
  stages.quality = quality0_seconds + result.quality_seconds;
  stages.final_check = options.check_every_iteration ? 0.0 : result.check_seconds;
  if (!quiet) {
    if (!result.stop_message.empty())
      std::cerr << "bisect: " << result.stop_message << "\n";
    if (result.stop == StopReason::NothingSelected)
      std::cerr << (a.indicator.empty()
                        ? "bisect: the region touches no cell; nothing more to refine\n"
                        : "bisect: nothing is marked; the mesh is written unchanged\n");
  }
  const QualitySummary q = result.quality;

  const auto t_write = std::chrono::steady_clock::now();
  if (h_csv >= 0)
    write_text_file(outputs.file(h_csv), csv, rows.str());
  WriteOptions write_options;
  write_options.format = a.format;
  write_options.compression = a.compression == "lz4"    ? Compression::Lz4
                              : a.compression == "none" ? Compression::None
                                                        : Compression::Zlib;
  // The final check found every cell's orientation: the writer need not.
  if (!result.orientation.empty())
    write_options.orientation = &result.orientation;
  write_output_mesh(outputs, h_mesh, mesh, write_options);
  std::string slice_lines;
  for (std::size_t i = 0; i < a.slices.size(); ++i)
    slice_lines += write_slice(mesh, mesh.dim - 1, a.slices[i], outputs, h_slices[i], digits).line;
  outputs.commit();
  stages.write = seconds_since(t_write);
  if (!quiet)
    std::cerr << slice_lines;
  const double total = seconds_since(t_start);
  if (a.flags.json) {
    nlohmann::json j;
    j["input"] = a.input;
    j["output"] = out;
    j["quality_csv"] = h_csv >= 0 ? nlohmann::json(csv) : nlohmann::json(nullptr);
    j["dim"] = mesh.dim;
    j["marking"] = marking_name(mesh.marking);
    j["iterations"] = result.iterations;
    j["initial_cells"] = cells0;
    j["initial_vertices"] = verts0;
    j["cells"] = mesh.num_cells();
    j["vertices"] = mesh.num_vertices();
    j["bisections"] = result.bisections;
    j["selected"] = selected_total;
    j["min_quality"] = q.min;
    j["max_quality"] = q.max;
    j["mean_quality"] = q.mean;
    j["limit_reached"] = result.limit_reached();
    j["seconds"] = total;
    j["stages"] = {{"read", stages.read},       {"validate", stages.validate},
                   {"select", stages.select},   {"refine", stages.refine},
                   {"quality", stages.quality}, {"final_check", stages.final_check},
                   {"write", stages.write}};
    j["peak_rss_bytes"] = peak_rss_bytes();
    print_json(j);
  }
  if (!quiet)
    std::cerr << "bisect: wrote " << out << " (" << with_commas(mesh.num_cells()) << " cells)"
              << (h_csv >= 0 ? " and " + csv : std::string()) << " in " << std::fixed
              << std::setprecision(2) << total << " s\n";
  return result.limit_reached() ? kExitLimit : kExitOk;
}

} // namespace

Command add_refine(CLI::App &app) {
  auto a = std::make_shared<RefineArgs>();
  auto *cmd = app.add_subcommand(
      "refine", "Refine a mesh locally around a region (iteration after iteration) or where a "
                "solver's error indicator marks it, to conformity.");
  cmd->footer("Example: bisect refine data/ball.msh --region data/regions/hemisphere.json "
              "--iterations 10 -o ball-10.vtu\n"
              "         bisect refine mesh.vtu --indicator eta --dorfler 0.5 -o next.vtu\n"
              "         bisect refine st.vtu --region r4.json -n 5 --slices 0:1:4 -o st5.vtu   "
              "(and st5.t0.vtu, st5.t0.25.vtu, ..., st5.t1.vtu)\n"
              "Writes the mesh (.vtu or .msh by extension, with the bisection state as "
              "cell arrays bisect:*, so refining the output continues the same sequence) "
              "and a CSV with one row per iteration. A file's bisection state is checked on "
              "reading (an altered one is an input error).\n"
              "Before writing, a final check runs (unless --check checked every iteration): "
              "no degenerate or folded cell, every facet in at most two cells, the input's "
              "volume and boundary measure; a failure exits 2 and writes nothing. Refinement "
              "stops (exit 3, the mesh before that iteration written) before it would bisect "
              "an edge whose extent is below 2^-40 of its ends' largest coordinate magnitude "
              "or below 2^-100.\n" +
              std::string(kExitCodesHelp));
  cmd->add_option("input", a->input, "Input mesh (.vtu or .msh; - reads standard input)")
      ->required();
  cmd->add_option("--region,-r", a->region,
                  "Region spec (JSON): sphere, hemisphere, box, "
                  "halfspace, moving_sphere, levelset, union, intersection");
  cmd->add_option(
      "--indicator", a->indicator,
      "Mark cells by this one-component cell array of the input (a point array: a "
      "cell's value is the largest of its vertices'), with --above, --top or --dorfler; "
      "with --region too, a cell is refined when either marks it");
  auto *above =
      cmd->add_option("--above", a->above, "--indicator: the cells whose value is greater than X");
  auto *top = cmd->add_option(
      "--top", a->top,
      "--indicator: the ceil(F * cells) cells with the largest values (0 < F <= 1)");
  auto *dorfler = cmd->add_option(
      "--dorfler", a->dorfler,
      "--indicator: Dorfler's bulk criterion: the fewest cells, largest values first, whose sum of "
      "squared values reaches THETA times the total (0 < THETA <= 1, values >= 0)");
  above->excludes(top)->excludes(dorfler);
  top->excludes(dorfler);
  cmd->add_option("--depth", a->depth,
                  "Bisect each marked cell K times (its descendants inside it), then refine to "
                  "conformity (default 1; K = dimension halves the marked cells' size)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--iterations,-n", a->iterations, "Refinement iterations (default 1)")
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--output,-o", a->output,
                  "Output mesh (.vtu or .msh); default <input stem>.refined.vtu here; "
                  "- for standard output (with --format)");
  add_format_option(cmd, a->format);
  cmd->add_option("--compression", a->compression,
                  ".vtu output: zlib (default), lz4 (faster, larger) or none; ParaView and "
                  "VTK read all three")
      ->check(CLI::IsMember({"zlib", "lz4", "none"}));
  cmd->add_option("--quality-csv", a->csv,
                  "Per-iteration quality CSV; default <output stem>.quality.csv; none: no CSV");
  cmd->add_option("--marking,-m", a->marking,
                  "Global edge order: index (default; every tet unflagged planar), "
                  "longest (longest edge first), sorted ((x0<...<xn)_n)")
      ->check(CLI::IsMember({"index", "longest", "sorted"}));
  cmd->add_option("--max-elements", a->max_elements,
                  "Stop before an iteration would make more cells than this (exit 3)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(kNoCell) - 1));
  cmd->add_option("--max-memory", a->max_memory_gib,
                  "Stop (exit 3) before an iteration estimated to need more than this many "
                  "GiB (under mpirun: per rank); default: the memory available now")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--slices", a->slices_text,
                  "Also write the sections t = T of the final mesh (t: the last coordinate; 4D "
                  "-> 3D tets, 2D+t -> 2D triangles) as <output stem>.t<T>.vtu: T1,T2,... "
                  "(increasing; one is enough) or START:STOP:COUNT (COUNT + 1 sections from "
                  "START to STOP, as extrude's)");
  add_common_flags(cmd, a->flags);
  cmd->add_flag("--force,-f", a->force, "Overwrite existing output files (never the input)");
  cmd->add_flag("--origin", a->origin,
                "Write the cell array bisect:origin: for each output cell the index of the input "
                "cell it descends from (the parent map for a solver's own transfer)");
  cmd->add_flag("--check", a->check,
                "After every iteration, check conformity and that volume, boundary measure "
                "and Euler characteristic are those of the input (exit 2 naming the "
                "iteration and the failure, no output written); always on in a "
                "BISECT_PARANOID build");

  return {cmd, [a] { return run_refine(*a); }};
}

} // namespace bisect::cli
