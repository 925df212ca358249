// The `bisect` command line: refine, info, check, quality, generate.
// Exit codes: 0 success, 1 usage or input error, 2 internal check failed,
// 3 limit reached (the output is still a valid conforming mesh).
#include "check.hpp"
#include "extrude.hpp"
#include "generate.hpp"
#include "io.hpp"
#include "mark.hpp"
#include "measure.hpp"
#include "refine.hpp"
#include "region.hpp"
#include "slice.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace bisect;

namespace {

constexpr int kExitOk = 0, kExitInput = 1, kExitCheck = 2, kExitLimit = 3, kExitInterrupted = 130;

const char *kExitCodesHelp = "Exit codes: 0 success; 1 usage or input error (one line on stderr names "
                             "the file and the problem); 2 an internal check failed; 3 a limit "
                             "(--max-elements, --max-memory, 32-bit ids) was reached, the output is still written "
                             "and conforming; 130 interrupted (no output written).";

std::atomic<bool> g_interrupted{false};
extern "C" void on_signal(int) { g_interrupted = true; }

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string with_commas(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

// Reads, validates and marks (or restores the marks of) an input mesh.
Mesh load_mesh(const std::string &path, std::optional<Marking> requested, bool quiet) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  if (decode_state(mesh, path)) {
    if (requested && *requested != mesh.marking && !quiet)
      std::cerr << "bisect: " << path << " carries bisection state with --marking "
                << marking_name(mesh.marking) << "; continuing it (--marking "
                << marking_name(*requested) << " ignored)\n";
  } else {
    mark_mesh(mesh, requested.value_or(Marking::Index));
  }
  return mesh;
}

bool same_file(const std::string &a, const std::string &b) {
  std::error_code ec;
  return fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

// Fails early when `path` could not be written: its directory is missing or
// not writable, or the path is a directory.
void require_writable(const std::string &path) {
  fs::path p(path);
  fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw UsageError(path + ": cannot write: directory " + dir.string() + " does not exist");
  if (fs::is_directory(p, ec)) throw UsageError(path + ": cannot write: it is a directory");
  if (::access(dir.c_str(), W_OK) != 0)
    throw UsageError(path + ": cannot write: directory " + dir.string() + " is not writable");
}

void refuse_overwrite(const std::string &out, const std::string &input, bool force) {
  require_writable(out);
  if (same_file(input, out))
    throw UsageError(out + ": refusing to overwrite the input mesh; choose another -o");
  std::error_code ec;
  if (!force && fs::exists(out, ec))
    throw UsageError(out + ": already exists (use --force to overwrite)");
}

// Writes `text` to path through a temporary file renamed when complete.
void write_text_file(const std::string &path, const std::string &text) {
  fs::path p(path);
  fs::path tmp = p.parent_path() / ("." + p.filename().string() + ".tmp");
  {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    if (!f.flush()) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw InputError(path, "cannot write");
    }
  }
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, "cannot write: " + ec.message());
  }
}

void write_output_mesh(const std::string &path, Mesh &mesh) {
  encode_state(mesh);
  write_mesh(path, mesh);
}

// ---------------------------------------------------------------- refine ---

// Memory the machine can still give, from /proc/meminfo (0 when unknown).
double available_bytes() {
  std::ifstream f("/proc/meminfo");
  std::string key;
  double kb = 0;
  std::string unit;
  while (f >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024.0;
  return 0;
}

// Non-empty when the next iteration would likely not fit in memory. The
// estimate: each selected cell costs about four new cells with closure, and a
// cell costs its ids, state and arrays twice over while vectors grow.
std::string memory_shortfall(const Mesh &mesh, std::size_t selected, double max_gib) {
  double per_cell = 2.5 * (4.0 * (mesh.dim + 1) + 2.0) + 8.0;
  for (const DataArray &a : mesh.cell_data) per_cell += 2.0 * 8.0 * a.components;
  // --max-memory bounds the whole mesh; otherwise what it adds must fit in
  // the memory available now.
  double need = per_cell * 4.0 * double(selected);
  if (max_gib > 0) need += per_cell * double(mesh.num_cells());
  double avail = max_gib > 0 ? max_gib * 1073741824.0 : available_bytes();
  if (avail <= 0 || need < 0.9 * avail) return {};
  char buf[160];
  std::snprintf(buf, sizeof buf, "it would need about %.2f GiB %s, %.2f GiB %s",
                need / 1073741824.0, max_gib > 0 ? "in all" : "more memory",
                avail / 1073741824.0, max_gib > 0 ? "allowed by --max-memory" : "available");
  return buf;
}

struct RefineArgs {
  std::string input, region, output, csv;
  int iterations = 1;
  std::string marking;
  std::int64_t max_elements = 0;
  double max_memory_gib = 0;
  bool json = false, quiet = false, force = false, check = false;
  std::vector<double> slices; // t values: 3D sections of the final 4D mesh
};

// "<output stem>.t<value>.vtu" beside the output.
std::string slice_path(const std::string &output, const char *axis, double value) {
  fs::path p(output);
  std::ostringstream name;
  name << p.stem().string() << "." << axis << value << ".vtu";
  return (p.parent_path() / name.str()).string();
}

void write_slice(const Mesh &mesh, int axis, double value, const std::string &path, bool quiet) {
  Mesh s = slice_mesh(mesh, axis, value);
  // The 4D bisection state means nothing on a 3D section.
  std::erase_if(s.cell_data, [](const DataArray &d) { return d.name.rfind("bisect:", 0) == 0; });
  write_mesh(path, s);
  if (!quiet)
    std::cerr << "bisect: wrote " << path << " (" << with_commas(s.num_cells())
              << " tetrahedra: the section " << "xyzt"[axis] << " = " << value << ")\n";
}

std::string default_output(const std::string &input) {
  fs::path p(input);
  return (p.stem().string() + ".refined.vtu");
}

std::string default_csv(const std::string &output) {
  fs::path p(output);
  return (p.parent_path() / (p.stem().string() + ".quality.csv")).string();
}

int run_refine(const RefineArgs &a) {
  auto t_start = std::chrono::steady_clock::now();
  std::optional<Marking> marking;
  if (!a.marking.empty()) marking = parse_marking(a.marking);
  std::string out = a.output.empty() ? default_output(a.input) : a.output;
  std::string csv = a.csv.empty() ? default_csv(out) : a.csv;
  refuse_overwrite(out, a.input, a.force);
  refuse_overwrite(csv, a.input, a.force);
  for (double t : a.slices) refuse_overwrite(slice_path(out, "t", t), a.input, a.force);
  if (fs::path(out).extension() != ".vtu" && fs::path(out).extension() != ".msh")
    throw UsageError(out + ": output must end in .vtu or .msh");

  Mesh mesh = load_mesh(a.input, marking, a.quiet);
  if (!a.slices.empty() && mesh.dim != 4)
    throw UsageError("--slices needs a 4D mesh; " + a.input + " is " + std::to_string(mesh.dim) + "D");
  auto region = read_region(a.region, mesh.dim);
  Invariants before;
  if (a.check) before = measure_invariants(mesh);

  std::ostringstream rows;
  rows << "iteration,cells,vertices,selected,bisections,min_quality,max_quality,mean_quality,seconds\n";
  auto row = [&](int it, std::size_t sel, std::size_t bis, const QualitySummary &q, double sec) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%d,%zu,%zu,%zu,%zu,%.9g,%.9g,%.9g,%.6f\n", it, mesh.num_cells(),
                  mesh.num_vertices(), sel, bis, q.min, q.max, q.mean, sec);
    rows << buf;
  };
  QualitySummary q = quality_summary(mesh);
  row(0, 0, 0, q, 0.0);
  const std::size_t cells0 = mesh.num_cells(), verts0 = mesh.num_vertices();
  if (!a.quiet)
    std::cerr << "bisect: " << a.input << ": " << mesh.dim << "D, " << with_commas(cells0)
              << " cells, " << with_commas(verts0) << " vertices, marking "
              << marking_name(mesh.marking) << "\n";

  RefineLimits limits;
  if (a.max_elements) limits.max_cells = std::size_t(a.max_elements);
  limits.cancel = &g_interrupted;
  bool limit_reached = false;
  int done = 0;
  std::size_t total_bisections = 0;
  for (int it = 1; it <= a.iterations; ++it) {
    if (g_interrupted) break;
    auto t0 = std::chrono::steady_clock::now();
    std::vector<CellId> selected = select_cells(mesh, *region);
    if (std::string why = memory_shortfall(mesh, selected.size(), a.max_memory_gib); !why.empty()) {
      limit_reached = true;
      if (!a.quiet) std::cerr << "bisect: stopping before iteration " << it << ": " << why << "\n";
      break;
    }
    RefineResult r = refine(mesh, selected, limits);
    if (r.cancelled) break;
    if (r.limit_reached) {
      limit_reached = true;
      if (!a.quiet)
        std::cerr << "bisect: stopping before iteration " << it << ": it would pass "
                  << (a.max_elements ? "--max-elements " + with_commas(std::size_t(a.max_elements))
                                     : std::string("the 32-bit id limit"))
                  << " (" << with_commas(mesh.num_cells()) << " cells now)\n";
      break;
    }
    q = quality_summary(mesh);
    double sec = seconds_since(t0);
    row(it, r.selected, r.bisections, q, sec);
    total_bisections += r.bisections;
    done = it;
    if (!a.quiet) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "iteration %d/%d: %s cells, %s vertices, %s selected, %s bisections "
                    "(%zu closure passes), quality min %.4f max %.4f, %.2f s\n",
                    it, a.iterations, with_commas(mesh.num_cells()).c_str(),
                    with_commas(mesh.num_vertices()).c_str(), with_commas(r.selected).c_str(),
                    with_commas(r.bisections).c_str(), r.closure_passes, q.min, q.max, sec);
      std::cerr << buf;
    }
    if (selected.empty()) {
      if (!a.quiet) std::cerr << "bisect: the region touches no cell; nothing more to refine\n";
    }
  }
  if (g_interrupted) {
    std::cerr << "bisect: interrupted; no output written\n";
    return kExitInterrupted;
  }
  if (a.check) {
    CheckResult c = check_conformity(mesh, &before);
    if (!c.ok) {
      std::cerr << "bisect: internal check failed after refinement: " << c.failure << "\n";
      return kExitCheck;
    }
  }
  write_text_file(csv, rows.str());
  try {
    write_output_mesh(out, mesh);
  } catch (...) {
    std::error_code ec;
    fs::remove(csv, ec); // never half a result
    throw;
  }
  for (double t : a.slices) write_slice(mesh, 3, t, slice_path(out, "t", t), a.quiet);
  double total = seconds_since(t_start);
  if (a.json) {
    nlohmann::json j;
    j["input"] = a.input;
    j["output"] = out;
    j["quality_csv"] = csv;
    j["dim"] = mesh.dim;
    j["marking"] = marking_name(mesh.marking);
    j["iterations"] = done;
    j["initial_cells"] = cells0;
    j["initial_vertices"] = verts0;
    j["cells"] = mesh.num_cells();
    j["vertices"] = mesh.num_vertices();
    j["bisections"] = total_bisections;
    j["min_quality"] = q.min;
    j["max_quality"] = q.max;
    j["mean_quality"] = q.mean;
    j["limit_reached"] = limit_reached;
    j["seconds"] = total;
    std::cout << j.dump() << std::endl;
  }
  if (!a.quiet)
    std::cerr << "bisect: wrote " << out << " (" << with_commas(mesh.num_cells()) << " cells) and "
              << csv << " in " << std::fixed << std::setprecision(2) << total << " s\n";
  return limit_reached ? kExitLimit : kExitOk;
}

// "0,0.5,1" or "start:stop:count" (count slabs, count + 1 slices).
std::vector<double> parse_slices(const std::string &text) {
  auto number = [&](const std::string &t) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(t, &used);
    } catch (const std::exception &) {
      used = 0;
    }
    if (used != t.size() || t.empty() || !std::isfinite(v))
      throw UsageError("--slices: \"" + t + "\" is not a number (expected T0,T1,... or START:STOP:COUNT)");
    return v;
  };
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream in(text);
    for (std::string p; std::getline(in, p, ':');) parts.push_back(p);
    if (parts.size() != 3) throw UsageError("--slices: expected START:STOP:COUNT, got \"" + text + "\"");
    double a = number(parts[0]), b = number(parts[1]), n = number(parts[2]);
    if (!(n >= 1 && n <= 10000 && n == std::floor(n)))
      throw UsageError("--slices: COUNT must be a whole number from 1 to 10000");
    for (int i = 0; i <= int(n); ++i) out.push_back(a + (b - a) * i / n);
  } else {
    std::stringstream in(text);
    for (std::string p; std::getline(in, p, ',');) out.push_back(number(p));
  }
  if (out.size() < 2) throw UsageError("--slices: need at least two slices");
  for (std::size_t i = 1; i < out.size(); ++i)
    if (!(out[i] > out[i - 1])) throw UsageError("--slices: values must increase");
  return out;
}

// ------------------------------------------------------------------ info ---

void print_bbox(const Mesh &mesh) {
  const int d = mesh.dim;
  std::vector<double> lo(d, 1e300), hi(d, -1e300);
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < d; ++k) {
      lo[k] = std::min(lo[k], mesh.point(VertexId(v))[k]);
      hi[k] = std::max(hi[k], mesh.point(VertexId(v))[k]);
    }
  std::cout << "bounding box:";
  const char *names = "xyzt";
  for (int k = 0; k < d; ++k) std::cout << " " << names[k] << " [" << lo[k] << ", " << hi[k] << "]";
  std::cout << "\n";
}

int run_info(const std::string &path) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  bool has_state = decode_state(mesh, path);
  Invariants inv = measure_invariants(mesh);
  QualitySummary q = quality_summary(mesh);
  std::cout << "file: " << path << "\n"
            << "dimension: " << mesh.dim << "\n"
            << "cells: " << mesh.num_cells() << "\n"
            << "vertices: " << mesh.num_vertices() << "\n";
  print_bbox(mesh);
  std::cout << std::setprecision(10) << "volume: " << inv.volume << "\n"
            << "boundary facets: " << inv.boundary_facets << "\n"
            << "boundary measure: " << inv.boundary_measure << "\n"
            << "euler characteristic: " << inv.euler << "\n"
            << std::setprecision(6) << "quality: min " << q.min << " max " << q.max << " mean "
            << q.mean << "\n"
            << "bisection state: "
            << (has_state ? std::string("present (marking ") + marking_name(mesh.marking) + ")"
                          : std::string("none (will be marked on refine)"))
            << "\n";
  for (const DataArray &a : mesh.cell_data)
    std::cout << "cell array: " << a.name << " (" << a.components << " components)\n";
  for (const DataArray &a : mesh.point_data)
    std::cout << "point array: " << a.name << " (" << a.components << " components)\n";
  return kExitOk;
}

// ----------------------------------------------------------------- check ---

int run_check(const std::string &path, const std::string &against) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  Invariants original;
  const Invariants *orig = nullptr;
  if (!against.empty()) {
    Mesh o = read_mesh(against);
    prepare_input(o, against);
    if (o.dim != mesh.dim)
      throw InputError(against, "dimension " + std::to_string(o.dim) + " differs from " + path +
                                    "'s " + std::to_string(mesh.dim));
    original = measure_invariants(o);
    orig = &original;
  }
  CheckResult r = check_conformity(mesh, orig);
  if (!r.ok) {
    std::cerr << "bisect: " << path << ": check failed: " << r.failure << "\n";
    return kExitCheck;
  }
  std::cout << path << ": conforming (" << mesh.num_cells() << " cells"
            << (orig ? ", volume, boundary and Euler characteristic match " + against : std::string())
            << ")\n";
  return kExitOk;
}

// --------------------------------------------------------------- quality ---

int run_quality(const std::string &path, bool classes, int bins) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  std::vector<std::size_t> hist(std::size_t(bins), 0);
  double pts[5 * 4];
  double qmin = 1, qmax = 0, sum = 0;
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    cell_points(mesh, CellId(c), pts);
    double q = mean_ratio(pts, mesh.dim);
    qmin = std::min(qmin, q);
    qmax = std::max(qmax, q);
    sum += q;
    hist[std::min<std::size_t>(std::size_t(q * bins), std::size_t(bins - 1))]++;
  }
  std::cout << "cells: " << mesh.num_cells() << "\n"
            << "quality: min " << qmin << " max " << qmax << " mean "
            << (mesh.num_cells() ? sum / double(mesh.num_cells()) : 0.0) << "\n"
            << "histogram (mean ratio):\n";
  for (int b = 0; b < bins; ++b) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "  [%.2f, %.2f%c %zu\n", double(b) / bins, double(b + 1) / bins,
                  b + 1 == bins ? ']' : ')', hist[std::size_t(b)]);
    std::cout << buf;
  }
  if (classes) std::cout << "classes: " << count_similarity_classes(mesh) << "\n";
  return kExitOk;
}

// -------------------------------------------------------------- generate ---

int write_generated(Mesh mesh, const std::string &out, bool force) {
  std::error_code ec;
  if (!force && fs::exists(out, ec)) throw UsageError(out + ": already exists (use --force to overwrite)");
  write_mesh(out, mesh);
  std::cout << "wrote " << out << " (" << mesh.num_cells() << " cells, " << mesh.num_vertices()
            << " vertices)\n";
  return kExitOk;
}

} // namespace

int main(int argc, char **argv) {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  CLI::App app{"bisect: conformal local refinement of triangle, tetrahedral and 4D simplicial "
               "meshes by edge bisection (Maubach / Arnold-Mukherjee-Pouly marking, seeds "
               "000-002)."};
  app.footer(kExitCodesHelp);
  app.require_subcommand(1);
  app.set_version_flag("--version", "bisect 0.1");

  RefineArgs ra;
  auto *refine_cmd = app.add_subcommand(
      "refine", "Refine a mesh locally around a region, iteration after iteration, to conformity.");
  refine_cmd->footer("Example: bisect refine data/ball.msh --region data/regions/hemisphere.json "
                     "--iterations 10 -o ball-10.vtu\n"
                     "Writes the mesh (.vtu or .msh by extension, with the bisection state as "
                     "cell arrays bisect:*, so refining the output continues the same sequence) "
                     "and a CSV with one row per iteration.\n" +
                     std::string(kExitCodesHelp));
  refine_cmd->add_option("input", ra.input, "Input mesh (.vtu or .msh)")->required();
  refine_cmd->add_option("--region,-r", ra.region, "Region spec (JSON): sphere, hemisphere, box, "
                                                  "halfspace, moving_sphere, union, intersection")
      ->required();
  refine_cmd->add_option("--iterations,-n", ra.iterations, "Refinement iterations (default 1)")
      ->check(CLI::Range(0, 10000));
  refine_cmd->add_option("--output,-o", ra.output,
                         "Output mesh (.vtu or .msh); default <input stem>.refined.vtu here");
  refine_cmd->add_option("--quality-csv", ra.csv,
                         "Per-iteration quality CSV; default <output stem>.quality.csv");
  refine_cmd->add_option("--marking,-m", ra.marking,
                         "Global edge order: index (default; every tet unflagged planar), "
                         "longest (longest edge first), sorted ((x0<...<xn)_n)")
      ->check(CLI::IsMember({"index", "longest", "sorted"}));
  refine_cmd->add_option("--max-elements", ra.max_elements,
                         "Stop before an iteration would make more cells than this (exit 3)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(kNoCell) - 1));
  refine_cmd->add_option("--max-memory", ra.max_memory_gib,
                         "Stop (exit 3) before an iteration estimated to need more than this many "
                         "GiB; default: the memory available now")
      ->check(CLI::PositiveNumber);
  refine_cmd->add_option("--slices", ra.slices,
                         "4D only: also write the sections t = T1,T2,... of the final mesh as 3D "
                         "meshes <output stem>.t<T>.vtu")
      ->delimiter(',');
  refine_cmd->add_flag("--json", ra.json, "Print a JSON summary on stdout");
  refine_cmd->add_flag("--quiet,-q", ra.quiet, "No progress output on stderr");
  refine_cmd->add_flag("--force,-f", ra.force, "Overwrite existing output files (never the input)");
  refine_cmd->add_flag("--check", ra.check,
                       "Check conformity, volume, boundary and Euler characteristic at the end "
                       "(exit 2 on failure)");

  std::string slice_in, slice_out, slice_axis = "t";
  double slice_value = 0;
  bool slice_force = false;
  auto *slice_cmd = app.add_subcommand(
      "slice", "Cut a 4D mesh by the hyperplane {axis = value} into a conforming 3D tetrahedral "
               "mesh for ParaView (prisms are split into three tetrahedra).");
  slice_cmd->footer("Example: bisect slice hypercube-25.vtu --t 0.5 -o section.vtu");
  slice_cmd->add_option("input", slice_in, "4D mesh (.vtu)")->required();
  auto *t_opt = slice_cmd->add_option("--t", slice_value, "Shorthand for --axis t --value VALUE");
  slice_cmd->add_option("--axis", slice_axis, "x, y, z or t (default t)")
      ->check(CLI::IsMember({"x", "y", "z", "t"}));
  slice_cmd->add_option("--value", slice_value, "Where the hyperplane cuts the axis")->excludes(t_opt);
  slice_cmd->add_option("--output,-o", slice_out, "Output 3D mesh (.vtu or .msh)")->required();
  slice_cmd->add_flag("--force,-f", slice_force, "Overwrite an existing file");

  std::string ex_in, ex_out, ex_slices, ex_method = "delaunay";
  bool ex_force = false;
  auto *extrude_cmd = app.add_subcommand(
      "extrude", "Extrude a 3D tetrahedral mesh over time slices into a 4D pentatope mesh.");
  extrude_cmd->footer("Example: bisect extrude cube.vtu --slices 0,0.5,1 -o spacetime.vtu\n"
                      "         bisect extrude cube.vtu --slices 0:1:4 -o spacetime.vtu   "
                      "(4 slabs between 0 and 1)\n"
                      "--method delaunay triangulates the 4D points with Qhull: the 3D mesh must be "
                      "convex (a non-convex one is rejected).");
  extrude_cmd->add_option("input", ex_in, "3D mesh (.vtu or .msh)")->required();
  extrude_cmd->add_option("--slices", ex_slices, "T0,T1,... or START:STOP:COUNT (COUNT slabs)")
      ->required();
  extrude_cmd->add_option("--method", ex_method, "delaunay (the only one so far)")
      ->check(CLI::IsMember({"delaunay"}));
  extrude_cmd->add_option("--output,-o", ex_out, "Output 4D mesh (.vtu)")->required();
  extrude_cmd->add_flag("--force,-f", ex_force, "Overwrite an existing file");

  std::string info_in;
  auto *info_cmd = app.add_subcommand("info", "Dimension, counts, bounding box, volume, quality.");
  info_cmd->footer("Example: bisect info data/ball.msh");
  info_cmd->add_option("input", info_in, "Mesh file")->required();

  std::string check_in, check_against;
  auto *check_cmd = app.add_subcommand(
      "check", "Check conformity: facets shared by at most two cells, no degenerate or inverted "
               "cell; with --against, volume, boundary measure and Euler characteristic unchanged.");
  check_cmd->footer("Example: bisect check ball-10.vtu --against data/ball.msh   (exit 2 names the "
                    "first failure)");
  check_cmd->add_option("input", check_in, "Mesh file")->required();
  check_cmd->add_option("--against", check_against, "The original mesh it was refined from");

  std::string quality_in;
  bool quality_classes = false;
  int quality_bins = 10;
  auto *quality_cmd = app.add_subcommand("quality", "Mean-ratio quality histogram and similarity classes.");
  quality_cmd->footer("Example: bisect quality tet-12.vtu --classes");
  quality_cmd->add_option("input", quality_in, "Mesh file")->required();
  quality_cmd->add_flag("--classes", quality_classes, "Count similarity classes");
  quality_cmd->add_option("--bins", quality_bins, "Histogram bins (default 10)")->check(CLI::Range(1, 1000));

  auto *gen_cmd = app.add_subcommand("generate", "Make small meshes: one simplex, or a Kuhn cube.");
  gen_cmd->require_subcommand(1);
  int g_dim = 3;
  std::string g_shape = "equilateral", g_out;
  std::uint64_t g_seed = 1;
  bool g_force = false;
  auto *gen_simplex = gen_cmd->add_subcommand("simplex", "One simplex.");
  gen_simplex->footer("Example: bisect generate simplex --dim 3 --shape random --seed 7 -o tet.vtu");
  gen_simplex->add_option("--dim,-d", g_dim, "2, 3 or 4")->check(CLI::Range(2, 4));
  gen_simplex->add_option("--shape", g_shape, "equilateral, cartesian or random")
      ->check(CLI::IsMember({"equilateral", "cartesian", "random"}));
  gen_simplex->add_option("--seed", g_seed, "Seed for --shape random");
  gen_simplex->add_option("--output,-o", g_out, "Output mesh")->required();
  gen_simplex->add_flag("--force,-f", g_force, "Overwrite an existing file");
  int k_cells = 2;
  double k_lo = 0, k_hi = 1;
  auto *gen_kuhn = gen_cmd->add_subcommand("kuhn", "Freudenthal-Kuhn cubes: K^dim cubes of dim! simplices.");
  gen_kuhn->footer("Example: bisect generate kuhn --dim 3 --cells 4 -o cube.vtu");
  gen_kuhn->add_option("--dim,-d", g_dim, "2, 3 or 4")->check(CLI::Range(2, 4));
  gen_kuhn->add_option("--cells,-k", k_cells, "Cubes per side")->check(CLI::Range(1, 1000));
  gen_kuhn->add_option("--lo", k_lo, "Lower corner coordinate (default 0)");
  gen_kuhn->add_option("--hi", k_hi, "Upper corner coordinate (default 1)");
  gen_kuhn->add_option("--output,-o", g_out, "Output mesh")->required();
  gen_kuhn->add_flag("--force,-f", g_force, "Overwrite an existing file");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion &e) {
    return app.exit(e);
  } catch (const CLI::ParseError &e) {
    std::cerr << "bisect: " << e.what() << " (see bisect --help)\n";
    return kExitInput;
  }

  try {
    if (*refine_cmd) return run_refine(ra);
    if (*info_cmd) return run_info(info_in);
    if (*extrude_cmd) {
      refuse_overwrite(ex_out, ex_in, ex_force);
      std::vector<double> ts = parse_slices(ex_slices);
      Mesh mesh = read_mesh(ex_in);
      prepare_input(mesh, ex_in);
      if (mesh.dim != 3)
        throw InputError(ex_in, "extrude needs a 3D tetrahedral mesh, this one is " +
                                    std::to_string(mesh.dim) + "D");
      Mesh m4;
      try {
        m4 = extrude_delaunay(mesh, ts);
      } catch (const InputError &e) {
        throw InputError(ex_in, e.what());
      }
      return write_generated(std::move(m4), ex_out, true);
    }
    if (*slice_cmd) {
      refuse_overwrite(slice_out, slice_in, slice_force);
      Mesh mesh = read_mesh(slice_in);
      prepare_input(mesh, slice_in);
      if (mesh.dim != 4)
        throw InputError(slice_in, "slice needs a 4D mesh, this one is " + std::to_string(mesh.dim) + "D");
      int axis = int(std::string("xyzt").find(slice_axis[0]));
      write_slice(mesh, axis, slice_value, slice_out, false);
      return kExitOk;
    }
    if (*check_cmd) return run_check(check_in, check_against);
    if (*quality_cmd) return run_quality(quality_in, quality_classes, quality_bins);
    if (*gen_simplex) {
      SimplexShape s = g_shape == "cartesian" ? SimplexShape::Cartesian
                       : g_shape == "random"  ? SimplexShape::Random
                                              : SimplexShape::Equilateral;
      return write_generated(generate_simplex(g_dim, s, g_seed), g_out, g_force);
    }
    if (*gen_kuhn) {
      if (!(k_lo < k_hi)) throw UsageError("generate kuhn: --lo must be below --hi");
      return write_generated(generate_kuhn(g_dim, k_cells, k_lo, k_hi), g_out, g_force);
    }
  } catch (const InputError &e) {
    std::cerr << "bisect: " << e.what() << "\n";
    return kExitInput;
  } catch (const UsageError &e) {
    std::cerr << "bisect: " << e.what() << "\n";
    return kExitInput;
  } catch (const CheckError &e) {
    std::cerr << "bisect: internal check failed: " << e.what() << "\n";
    return kExitCheck;
  } catch (const std::bad_alloc &) {
    std::cerr << "bisect: out of memory; no output written (try --max-elements)\n";
    return kExitInput;
  } catch (const std::exception &e) {
    std::cerr << "bisect: internal error: " << e.what() << "\n";
    return kExitCheck;
  }
  return kExitOk;
}
