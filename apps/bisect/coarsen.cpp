// bisect coarsen: read, undo bisections along the tree where marked, check, write.
#include "cli.hpp"

#include <algorithm>

#include "bisect/coarsen.hpp"
#ifdef BISECT_MPI
#include "mpi/refine_mpi.hpp"
#endif

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

namespace fs = std::filesystem;

namespace bisect::cli {
namespace {

struct CoarsenArgs {
  std::string input, output, indicator, region, format;
  double below = std::nan("");
  bool all = false, force = false, check = false, origin = false;
  int passes = 1;
  std::vector<std::string> sums;
  CommonFlags flags;
};

// The cells that may be merged away: indicator < below (a point array: a
// cell's value is the max of its vertices'), or touching the region, or all.
std::vector<char> marked_cells(const Mesh &mesh, const CoarsenArgs &a) {
  const std::size_t nc = mesh.num_cells();
  std::vector<char> marks(nc, 0);
  if (a.all) {
    std::fill(marks.begin(), marks.end(), 1);
  } else if (!a.region.empty()) {
    auto region = read_region(a.region, mesh.dim);
    for (CellId c : select_cells(mesh, *region))
      marks[c] = 1;
  } else {
    // A cell array, or a point array (a cell takes its vertices' max).
    const std::vector<double> values = cell_indicator(mesh, a.indicator, a.input);
    for (CellId c : mark_by_indicator(values, IndicatorRule::Below, a.below, a.input, &mesh))
      marks[c] = 1;
  }
  return marks;
}

int run_coarsen(const CoarsenArgs &a) {
  const auto t_start = std::chrono::steady_clock::now();
  const bool quiet = a.flags.quiet;
  if (!a.indicator.empty() && std::isnan(a.below))
    throw UsageError("--indicator needs --below X (cells whose value is below X are coarsened)");
  if (a.indicator.empty() && !std::isnan(a.below))
    throw UsageError("--below needs --indicator NAME");
#ifdef BISECT_MPI
  // Under mpirun, or for a .pvtu: the distributed coarsen (README, "MPI").
  if (mpi_world_size() > 1 || a.output.ends_with(".pvtu")) {
    if (a.input == "-")
      throw UsageError("distributed coarsen (mpirun or a .pvtu output) reads a file; - (standard "
                       "input) needs a serial run");
    if (a.output.empty())
      throw UsageError("distributed coarsen needs -o (a .pvtu, or a .vtu/.msh to gather into)");
    if (!a.format.empty() && a.output.ends_with(".pvtu"))
      throw UsageError("--format with a .pvtu output: the pieces are .vtu");
    DistributedCoarsenArgs d;
    d.input = a.input;
    // -o -: gathered and written to standard output by rank 0.
    d.output = output_name(a.output, a.format, a.flags.json);
    d.format = a.format;
    d.origin = a.origin;
    d.region = a.region;
    d.indicator = a.indicator;
    d.below = a.below;
    d.all = a.all;
    d.force = a.force;
    d.quiet = a.flags.quiet;
    d.json = a.flags.json;
    d.check = a.check;
    d.passes = a.passes;
    d.sums = a.sums;
    return run_coarsen_mpi(d);
  }
#endif
  const std::string stem =
      a.input == "-" ? std::string("stdin") : fs::path(a.input).stem().string();
  // -o -: the mesh goes to standard output.
  const std::string out =
      output_name(a.output.empty() ? stem + ".coarsened.vtu" : a.output, a.format, a.flags.json);
  if (a.format.empty())
    check_extension(out);
  OutputSet outputs({a.input, a.region}, a.force);
  const int h_mesh = outputs.add(out);

  Mesh mesh = load_mesh(a.input, load_progress(a.input, a.flags.quiet));
  check_output_format(out, mesh.dim, a.format);
  for (const std::string &name : a.sums)
    if (std::none_of(mesh.cell_data.begin(), mesh.cell_data.end(),
                     [&](const DataArray &d) { return d.name == name; })) {
      std::string have;
      for (const DataArray &d : mesh.cell_data)
        have += (have.empty() ? "'" : ", '") + d.name + "'";
      throw InputError(a.input, "--sum " + name + ": no cell array of that name (the file has " +
                                    (have.empty() ? std::string("none") : have) + ")");
    }
  const std::size_t cells0 = mesh.num_cells(), verts0 = mesh.num_vertices();
  const std::vector<char> marks = marked_cells(mesh, a);
  if (!quiet) {
    std::cerr << "bisect: " << a.input << ": " << mesh.dim << "D, " << with_commas(cells0)
              << " cells, " << with_commas(verts0) << " vertices\n";
    if (!mesh.marked() || !mesh.has_tree())
      std::cerr << "bisect: " << a.input
                << " carries no bisection tree (bisect:generation, bisect:parent_a/b): "
                   "nothing to coarsen\n";
  }
  const Invariants before = measure_invariants(mesh, a.check);

  CoarsenOptions options;
  options.passes = a.passes;
  options.sum_arrays = a.sums;
  if (a.origin) {
    // Each input cell's index; a parent keeps the smaller of its children's
    // (CoarsenOptions).
    add_origin_array(mesh);
    options.min_arrays.push_back(kOriginArray);
  }
  const auto print_pass = coarsen_pass_printer(a.passes, quiet);
  int passes_run = 0; // one "pass" line each, the last one perhaps removing nothing
  const CoarsenResult result = coarsen(mesh, marks, options, [&](const CoarsenPass &p) {
    ++passes_run;
    print_pass(p);
  });

  // The coarsened mesh covers the input's domain exactly and conforms.
  const CheckResult check = a.check ? check_conformity(mesh, &before) : check_refined(mesh, before);
  if (!check.ok) {
    std::cerr << "bisect: internal check failed after coarsening: " << check.failure
              << "; no output written\n";
    return kExitCheck;
  }
  WriteOptions write;
  write.format = a.format;
  write_output_mesh(outputs, h_mesh, mesh, write);
  outputs.commit();
  const double total = seconds_since(t_start);
  if (a.flags.json) {
    nlohmann::json j;
    j["input"] = a.input;
    j["output"] = out;
    j["dim"] = mesh.dim;
    j["passes"] = result.passes;  // passes that removed something
    j["passes_run"] = passes_run; // and the one that found nothing left, if it ran
    j["initial_cells"] = cells0;
    j["initial_vertices"] = verts0;
    j["cells"] = mesh.num_cells();
    j["vertices"] = mesh.num_vertices();
    j["removed_vertices"] = result.removed_vertices;
    j["merged_pairs"] = result.merged_pairs;
    j["seconds"] = total;
    print_json(j);
  }
  if (!quiet)
    std::cerr << "bisect: wrote " << out << " (" << with_commas(mesh.num_cells()) << " cells, "
              << with_commas(result.removed_vertices) << " vertices removed) in " << std::fixed
              << std::setprecision(2) << total << " s\n";
  return kExitOk;
}

} // namespace

std::function<void(const CoarsenPass &)> coarsen_pass_printer(int passes, bool quiet) {
  auto t_pass =
      std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
  return [=](const CoarsenPass &p) {
    if (!quiet) {
      char buf[256];
      // A pass that removes nothing ends the run: it does not count in
      // --json's "passes" (passes that removed something), so it says so.
      std::snprintf(buf, sizeof buf, "pass %d%s: %s cells, %s %s removed, %.2f s%s\n", p.pass,
                    passes ? ("/" + std::to_string(passes)).c_str() : "",
                    with_commas(p.cells).c_str(), with_commas(p.removed_vertices).c_str(),
                    p.removed_vertices == 1 ? "vertex" : "vertices", seconds_since(*t_pass),
                    p.removed_vertices == 0 ? " (nothing left to remove: stopping)" : "");
      std::cerr << buf;
    }
    *t_pass = std::chrono::steady_clock::now();
  };
}

Command add_coarsen(CLI::App &app) {
  auto a = std::make_shared<CoarsenArgs>();
  auto *cmd = app.add_subcommand(
      "coarsen", "Undo bisections where marked: remove vertices made by refinement, pass by pass.");
  cmd->footer("Example: bisect coarsen ball.refined.vtu --all -n 3 -o ball-3.vtu\n"
              "Needs a file written by bisect refine (or coarsen): the bisection tree travels as "
              "the arrays bisect:generation, bisect:parent_a, bisect:parent_b and bisect:level. "
              "A vertex made by bisection can go when its cells are all marked and all children "
              "of its bisection: they merge back into their parents. A pass undoes the newest "
              "refinement iteration around each vertex, so after refine -n N, coarsen --all -n N "
              "gives the input back; vertices of the original mesh are never removed. Cell "
              "arrays: the children's common value, else their mean (--sum: their sum). Before "
              "writing, a check: no degenerate or folded cell, the input's volume and boundary "
              "measure (exit 2 otherwise).\n" +
              std::string(kExitCodesHelp));
  cmd->add_option("input", a->input,
                  "Input mesh (.vtu or .msh) with its bisection tree; - reads standard input")
      ->required();
  auto *ind = cmd->add_option("--indicator", a->indicator,
                              "Cell array (or point array: a cell takes its vertices' max) whose "
                              "value marks a cell when below --below");
  cmd->add_option("--below", a->below, "Threshold for --indicator");
  auto *reg =
      cmd->add_option("--region,-r", a->region, "Region spec (JSON): cells touching it are marked");
  auto *all = cmd->add_flag("--all", a->all, "Mark every cell");
  ind->excludes(reg)->excludes(all);
  reg->excludes(all);
  cmd->add_option("--passes,-n", a->passes,
                  "Coarsening passes (default 1; 0: until a pass removes nothing). A pass "
                  "undoes the newest refinement iteration around each vertex")
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--sum", a->sums,
                  "Cell array whose parent value is the children's sum "
                  "(repeatable)");
  cmd->add_flag("--origin", a->origin,
                "Write the cell array bisect:origin: for each output cell the index, in the "
                "input, of the first (lowest-index) input cell merged into it");
  cmd->add_option("--output,-o", a->output,
                  "Output mesh (.vtu or .msh; - standard output, with --format); default "
                  "<input stem>.coarsened.vtu here");
  add_format_option(cmd, a->format);
  cmd->add_flag("--force,-f", a->force, "Overwrite existing output files (never the input)");
  cmd->add_flag("--check", a->check,
                "Full conformity check (and Euler characteristic) instead of the cheap one");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] {
            if (a->indicator.empty() && a->region.empty() && !a->all)
              throw UsageError("coarsen: give --indicator NAME --below X, --region SPEC or --all");
            return run_coarsen(*a);
          }};
}

} // namespace bisect::cli
