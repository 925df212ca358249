// bisect refine: read, refine iteration after iteration, check, write.
#include "cli.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
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
  std::string marking;
  std::int64_t max_elements = 0;
  double max_memory_gib = 0;
  bool force = false, check = false;
  CommonFlags flags;
  std::vector<double> slices; // t values (last coordinate): sections of the final mesh
};

std::string default_output(const std::string &input) {
  return fs::path(input).stem().string() + ".refined.vtu";
}

std::string default_csv(const std::string &output) {
  fs::path p(output);
  return (p.parent_path() / (p.stem().string() + ".quality.csv")).string();
}

// Wall seconds per stage of a run, for --json (and bench/e2e.sh).
struct StageSeconds {
  double read = 0, validate = 0, select = 0, refine = 0, quality = 0, final_check = 0, write = 0;
};

int run_refine(const RefineArgs &a) {
  const auto t_start = std::chrono::steady_clock::now();
  const bool quiet = a.flags.quiet;
  std::optional<Marking> marking;
  if (!a.marking.empty()) marking = parse_marking(a.marking);
  std::string out = a.output.empty() ? default_output(a.input) : a.output;
  // -o -: the mesh goes to standard output (then no CSV unless asked for).
  if (out == "-") {
    if (a.format.empty()) throw UsageError("-o -: give the format with --format vtu or --format msh");
    if (a.flags.json) throw UsageError("--json and -o - both write to standard output; choose one");
    out = "/dev/stdout";
  }
  const std::string csv = !a.csv.empty() ? a.csv : a.output == "-" ? "none" : default_csv(out);
  if (a.format.empty()) check_extension(out);
  // Every output is checked before any work and written as one transaction.
  OutputSet outputs({a.input, a.region}, a.force);
  const int h_mesh = outputs.add(out);
  const int h_csv = csv == "none" ? -1 : outputs.add(csv);
  std::vector<int> h_slices;
  for (double t : a.slices) h_slices.push_back(outputs.add(slice_path(out, "t", t)));

  StageSeconds stages;
  auto t0 = std::chrono::steady_clock::now();
  Mesh mesh = read_mesh(a.input);
  stages.read = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  prepare_input(mesh, a.input);
  if (decode_state(mesh, a.input)) {
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
  auto region = read_region(a.region, mesh.dim);

  std::ostringstream rows;
  rows << "iteration,cells,vertices,selected,bisections,min_quality,max_quality,mean_quality,seconds\n";
  auto row = [&](int it, std::size_t sel, std::size_t bis, const QualitySummary &q, double sec) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d,%zu,%zu,%zu,%zu,%.9g,%.9g,%.9g,%.6f\n", it, mesh.num_cells(),
                  mesh.num_vertices(), sel, bis, q.min, q.max, q.mean, sec);
    rows << buf;
  };
  row(0, 0, 0, quality_summary(mesh), 0.0);
  const std::size_t cells0 = mesh.num_cells(), verts0 = mesh.num_vertices();
  if (!quiet)
    std::cerr << "bisect: " << a.input << ": " << mesh.dim << "D, " << with_commas(cells0)
              << " cells, " << with_commas(verts0) << " vertices, marking "
              << marking_name(mesh.marking) << "\n";

  DriverOptions options;
  options.iterations = a.iterations;
  options.max_cells = std::size_t(a.max_elements);
  options.max_memory_gib = a.max_memory_gib;
  // --check (always on in a BISECT_PARANOID build): the full conformity check
  // against the input's invariants after every iteration.
#ifdef BISECT_PARANOID
  options.check_every_iteration = true;
#else
  options.check_every_iteration = a.check;
#endif
  auto on_iteration = [&](const IterationReport &r, Mesh &m) {
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
    if (g_after_iteration_hook) g_after_iteration_hook(r.iteration, m, r.first_new_vertex);
  };
  DriverResult result;
  try {
    result = run_iterations(mesh, region_selector(*region), options, on_iteration);
  } catch (const CheckError &e) {
    std::cerr << "bisect: internal check failed " << e.what() << "; no output written\n";
    return kExitCheck;
  }
  stages.select = result.select_seconds;
  stages.refine = result.refine_seconds;
  stages.quality = result.quality_seconds;
  stages.final_check = options.check_every_iteration ? 0.0 : result.check_seconds;
  if (!quiet) {
    if (!result.stop_message.empty()) std::cerr << "bisect: " << result.stop_message << "\n";
    if (result.stop == StopReason::NothingSelected)
      std::cerr << "bisect: the region touches no cell; nothing more to refine\n";
  }
  const QualitySummary q = result.quality;

  const auto t_write = std::chrono::steady_clock::now();
  if (h_csv >= 0) write_text_file(outputs.file(h_csv), csv, rows.str());
  WriteOptions write_options;
  write_options.format = a.format;
  write_options.compression = a.compression == "lz4"    ? Compression::Lz4
                              : a.compression == "none" ? Compression::None
                                                        : Compression::Zlib;
  write_output_mesh(outputs, h_mesh, mesh, write_options);
  std::string slice_lines;
  for (std::size_t i = 0; i < a.slices.size(); ++i)
    slice_lines += write_slice(mesh, mesh.dim - 1, a.slices[i], outputs, h_slices[i]);
  outputs.commit();
  stages.write = seconds_since(t_write);
  if (!quiet) std::cerr << slice_lines;
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
      "refine", "Refine a mesh locally around a region, iteration after iteration, to conformity.");
  cmd->footer("Example: bisect refine data/ball.msh --region data/regions/hemisphere.json "
                     "--iterations 10 -o ball-10.vtu\n"
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
  cmd->add_option("input", a->input, "Input mesh (.vtu or .msh)")->required();
  cmd->add_option("--region,-r", a->region, "Region spec (JSON): sphere, hemisphere, box, "
                                                  "halfspace, moving_sphere, levelset, union, intersection")
      ->required();
  cmd->add_option("--iterations,-n", a->iterations, "Refinement iterations (default 1)")
      ->check(CLI::Range(0, 10000));
  cmd->add_option("--output,-o", a->output,
                         "Output mesh (.vtu or .msh); default <input stem>.refined.vtu here; "
                         "- for standard output (with --format)");
  cmd->add_option("--format", a->format,
                         "Output format when the output's name has no .vtu/.msh extension "
                         "(e.g. -o /dev/stdout --format vtu)")
      ->check(CLI::IsMember({"vtu", "msh"}));
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
                         "GiB; default: the memory available now")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--slices", a->slices,
                         "Also write the sections t = T1,T2,... of the final mesh (t: the last "
                         "coordinate; 4D -> 3D tets, 2D+t -> 2D triangles) as <output stem>.t<T>.vtu")
      ->delimiter(',');
  add_common_flags(cmd, a->flags);
  cmd->add_flag("--force,-f", a->force, "Overwrite existing output files (never the input)");
  cmd->add_flag("--check", a->check,
                       "After every iteration, check conformity and that volume, boundary measure "
                       "and Euler characteristic are those of the input (exit 2 naming the "
                       "iteration and the failure, no output written); always on in a "
                       "BISECT_PARANOID build");

  return {cmd, [a] { return run_refine(*a); }};
}

} // namespace bisect::cli
