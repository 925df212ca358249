// The `bisect` command line: refine, info, check, quality, generate.
// Exit codes: 0 success, 1 usage or input error, 2 internal check failed,
// 3 limit reached (the output is still a valid conforming mesh).
#include "bisect/check.hpp"
#include "bisect/colour.hpp"
#include "bisect/extrude.hpp"
#include "bisect/generate.hpp"
#include "bisect/io.hpp"
#include "bisect/mark.hpp"
#include "bisect/measure.hpp"
#include "bisect/output.hpp"
#include "bisect/refine.hpp"
#include "bisect/region.hpp"
#include "bisect/slice.hpp"
#include "bisect/state.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cerrno>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <sys/resource.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace bisect;

namespace {

constexpr int kExitOk = 0, kExitInput = 1, kExitCheck = 2, kExitLimit = 3, kExitInterrupted = 130;

const char *kExitCodesHelp = "Exit codes: 0 success; 1 usage or input error (one line on stderr names "
                             "the file and the problem); 2 an internal check failed; 3 a limit "
                             "(--max-elements, --max-memory, 32-bit ids, the precision limit) was reached, the output is still written "
                             "and conforming; 130 interrupted (no output written).";

std::atomic<bool> g_interrupted{false};

// SIGINT, SIGTERM, SIGHUP: before the outputs are committed nothing of the
// run's result exists but temporary files, so they are removed and the
// process ends at once, whatever it was doing (reading, refining, writing).
// After the commit the run is complete and the signal is only noted.
extern "C" void on_signal(int) {
  if (outputs_committed()) {
    g_interrupted = true;
    return;
  }
  remove_pending_outputs();
  static const char msg[] = "bisect: interrupted; no output written\n";
  (void)!::write(STDERR_FILENO, msg, sizeof msg - 1);
  ::_exit(kExitInterrupted);
}

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
  // A file size limit or a reader that went away makes write() fail with
  // EFBIG or EPIPE, reported as such, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  std::signal(SIGPIPE, SIG_IGN);
}

// An error message as one line: control characters a hostile file put into
// it (a newline inside an attribute) are shown escaped.
std::string one_line(const std::string &text) {
  std::string out;
  for (unsigned char c : text) {
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    } else out += char(c);
  }
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string with_commas(std::size_t n) {
  const std::string digits = std::to_string(n);
  std::string s;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) s += ',';
    s += digits[i];
  }
  return s;
}

// Wall seconds per stage of a run, for --json (and bench/e2e.sh).
struct StageSeconds {
  double read = 0, validate = 0, select = 0, refine = 0, quality = 0, final_check = 0, write = 0;
};

// Peak resident memory of this process so far, in bytes.
double peak_rss_bytes() {
  struct rusage u {};
  ::getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) * 1024.0;
}

// Reads, validates and marks (or restores the marks of) an input mesh.
Mesh load_mesh(const std::string &path, std::optional<Marking> requested, bool quiet,
               StageSeconds *stages = nullptr) {
  auto t0 = std::chrono::steady_clock::now();
  Mesh mesh = read_mesh(path);
  auto t1 = std::chrono::steady_clock::now();
  prepare_input(mesh, path);
  if (decode_state(mesh, path)) {
    if (requested && *requested != mesh.marking && !quiet)
      std::cerr << "bisect: " << path << " carries bisection state with --marking "
                << marking_name(mesh.marking) << "; continuing it (--marking "
                << marking_name(*requested) << " ignored)\n";
  } else {
    mark_mesh(mesh, requested.value_or(Marking::Index));
  }
  if (stages) {
    stages->read += std::chrono::duration<double>(t1 - t0).count();
    stages->validate += seconds_since(t1);
  }
  return mesh;
}

// Writes `text` into `file` (an OutputSet's file for output `name`).
void write_text_file(const std::string &file, const std::string &name, const std::string &text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw InputError(name, "cannot write: " + write_failure(errno));
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      throw InputError(name, "cannot write: " + write_failure(err));
    }
    done += std::size_t(n);
  }
  if (::close(fd) != 0) throw InputError(name, "cannot write: " + write_failure(errno));
}

// One output file, checked before any work (see output.hpp for the rules).
void check_extension(const std::string &out) {
  const std::string ext = [&] {
    std::string e = fs::path(out).extension().string();
    for (char &c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
  }();
  if (ext != ".vtu" && ext != ".msh") throw UsageError(out + ": output must end in .vtu or .msh");
}

// Writes `mesh` with its bisection state into output `h` of `outputs`.
void write_output_mesh(OutputSet &outputs, int h, Mesh &mesh, const WriteOptions &options = {}) {
  encode_state(mesh);
  write_mesh_file(outputs.file(h), outputs.name(h), mesh, options);
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
  std::string input, region, output, csv, format, compression = "zlib";
  int iterations = 1;
  std::string marking;
  std::int64_t max_elements = 0;
  double max_memory_gib = 0;
  bool json = false, quiet = false, force = false, check = false;
  std::vector<double> slices; // t values (last coordinate): sections of the final mesh
};

// "<output stem>.t<value>.vtu" beside the output.
std::string slice_path(const std::string &output, const char *axis, double value) {
  fs::path p(output);
  std::ostringstream name;
  name << p.stem().string() << "." << axis << value << ".vtu";
  return (p.parent_path() / name.str()).string();
}

// Writes the section of `mesh` at coordinate `axis` = `value` into output
// `h`; returns the line to print once the outputs are committed.
std::string write_slice(const Mesh &mesh, int axis, double value, OutputSet &outputs, int h) {
  Mesh s = slice_mesh(mesh, axis, value);
  // The 4D bisection state means nothing on a 3D section.
  std::erase_if(s.cell_data, [](const DataArray &d) { return d.name.rfind("bisect:", 0) == 0; });
  write_mesh_file(outputs.file(h), outputs.name(h), s);
  std::ostringstream line;
  line << "bisect: wrote " << outputs.name(h) << " (" << with_commas(s.num_cells())
       << (s.dim == 3 ? " tetrahedra" : " triangles") << ": the section "
       << (axis == mesh.dim - 1 ? 't' : "xyz"[axis]) << " = " << value << ")\n";
  return line.str();
}

std::string default_output(const std::string &input) {
  fs::path p(input);
  return (p.stem().string() + ".refined.vtu");
}

std::string default_csv(const std::string &output) {
  fs::path p(output);
  return (p.parent_path() / (p.stem().string() + ".quality.csv")).string();
}

// Test hook, not for users: BISECT_TEST_CORRUPT_ITERATION=k makes `refine`
// undo one bisection made in iteration k, so that tests/cli/paranoid.sh can
// watch --check catch a non-conforming mesh end to end. Of the vertices made
// in that iteration (ids from `first_new`), the newest whose edge (a, b) was
// bisected in at least two cells gets one pair of siblings (z, a, rest) and
// (z, b, rest) merged back into (b, a, rest): z then hangs on the edge of
// that cell. Cell arrays follow (the second sibling's slot takes the last
// cell). Returns the vertex left hanging, or kNoVertex if none fitted.
VertexId corrupt_one_bisection(Mesh &mesh, std::size_t first_new) {
  const int n = mesh.cell_size(), dim = mesh.dim;
  std::vector<std::vector<CellId>> around(mesh.num_vertices() - first_new);
  for (std::size_t c = 0; c < mesh.num_cells(); ++c)
    for (int i = 0; i < n; ++i)
      if (mesh.cell(CellId(c))[i] >= first_new)
        around[mesh.cell(CellId(c))[i] - first_new].push_back(CellId(c));
  for (std::size_t z = mesh.num_vertices(); z-- > first_new;) {
    const std::vector<CellId> &cells = around[z - first_new];
    // Sibling pairs (cell with a, cell with b), keyed by the edge (a, b).
    std::map<std::pair<VertexId, VertexId>, std::vector<std::pair<CellId, CellId>>> pairs;
    for (std::size_t i = 0; i < cells.size(); ++i)
      for (std::size_t j = 0; j < cells.size(); ++j) {
        if (i == j) continue;
        const VertexId *x = mesh.cell(cells[i]), *y = mesh.cell(cells[j]);
        int only_x = -1, missing = 0;
        for (int p = 0; p < n; ++p)
          if (std::find(y, y + n, x[p]) == y + n) only_x = p, ++missing;
        if (missing != 1) continue;
        VertexId b = kNoVertex;
        for (int p = 0; p < n; ++p)
          if (std::find(x, x + n, y[p]) == x + n) b = y[p];
        const VertexId va = x[only_x];
        bool midpoint = true;
        for (int d = 0; d < dim; ++d)
          midpoint &= mesh.point(VertexId(z))[d] == 0.5 * (mesh.point(va)[d] + mesh.point(b)[d]);
        if (midpoint && va < b) pairs[{va, b}].push_back({cells[i], cells[j]});
      }
    for (const auto &[edge, list] : pairs) {
      if (list.size() < 2) continue; // one parent only: merging would leave no hanging node
      const auto [keep, drop] = list.front();
      VertexId *x = mesh.cell(CellId(keep));
      std::replace(x, x + n, VertexId(z), edge.second); // (z, a, rest) -> (b, a, rest)
      const std::size_t last = mesh.num_cells() - 1;
      std::copy_n(mesh.cell(CellId(last)), n, mesh.cell(CellId(drop)));
      mesh.cells.resize(last * n);
      if (mesh.stage.size() > last) {
        mesh.stage[drop] = mesh.stage[last];
        mesh.tag[drop] = mesh.tag[last];
        mesh.stage.resize(last);
        mesh.tag.resize(last);
      }
      for (DataArray &arr : mesh.cell_data) {
        const std::size_t k = std::size_t(arr.components);
        std::copy_n(arr.values.begin() + std::ptrdiff_t(last * k), k,
                    arr.values.begin() + std::ptrdiff_t(drop * k));
        arr.values.resize(last * k);
      }
      return VertexId(z);
    }
  }
  return kNoVertex;
}

int run_refine(const RefineArgs &a) {
  auto t_start = std::chrono::steady_clock::now();
  std::optional<Marking> marking;
  if (!a.marking.empty()) marking = parse_marking(a.marking);
  std::string out = a.output.empty() ? default_output(a.input) : a.output;
  // -o -: the mesh goes to standard output (then no CSV unless asked for).
  if (out == "-") {
    if (a.format.empty()) throw UsageError("-o -: give the format with --format vtu or --format msh");
    if (a.json) throw UsageError("--json and -o - both write to standard output; choose one");
    out = "/dev/stdout";
  }
  std::string csv = !a.csv.empty() ? a.csv : a.output == "-" ? "none" : default_csv(out);
  if (a.format.empty()) check_extension(out);
  // Every output is checked before any work and written as one transaction.
  OutputSet outputs({a.input, a.region}, a.force);
  const int h_mesh = outputs.add(out);
  const int h_csv = csv == "none" ? -1 : outputs.add(csv);
  std::vector<int> h_slices;
  for (double t : a.slices) h_slices.push_back(outputs.add(slice_path(out, "t", t)));

  StageSeconds stages;
  Mesh mesh = load_mesh(a.input, marking, a.quiet, &stages);
  check_output_format(out, mesh.dim, a.format);
  if (!a.slices.empty() && mesh.dim < 3)
    throw UsageError("--slices needs a 3D (2D+t) or 4D mesh; " + a.input + " is 2D");
  auto region = read_region(a.region, mesh.dim);
  // --check (always on in a BISECT_PARANOID build): the full conformity check
  // against the input's invariants after every iteration.
#ifdef BISECT_PARANOID
  const bool check = true;
#else
  const bool check = a.check;
#endif
  // Without --check, volume and boundary measure are enough for the final check.
  const Invariants before = measure_invariants(mesh, check);
  int corrupt_after = 0; // the test hook, see corrupt_one_bisection
  if (const char *e = std::getenv("BISECT_TEST_CORRUPT_ITERATION")) corrupt_after = std::atoi(e);

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
  bool limit_reached = false;
  int done = 0;
  std::size_t total_bisections = 0;
  for (int it = 1; it <= a.iterations; ++it) {
    auto t0 = std::chrono::steady_clock::now();
    std::vector<CellId> selected = select_cells(mesh, *region);
    stages.select += seconds_since(t0);
    if (std::string why = memory_shortfall(mesh, selected.size(), a.max_memory_gib); !why.empty()) {
      limit_reached = true;
      if (!a.quiet) std::cerr << "bisect: stopping before iteration " << it << ": " << why << "\n";
      break;
    }
    const std::size_t verts_before = mesh.num_vertices();
    auto t_refine = std::chrono::steady_clock::now();
    RefineResult r = refine(mesh, selected, limits);
    stages.refine += seconds_since(t_refine);
    if (r.cancelled) break;
    if (r.precision_reached) {
      limit_reached = true;
      if (!a.quiet)
        std::cerr << "bisect: stopping before iteration " << it
                  << ": it would bisect an edge finer than doubles resolve (extent below 2^-40 "
                     "of its coordinates' magnitude, or below 2^-100); writing the mesh after "
                     "iteration "
                  << it - 1 << "\n";
      break;
    }
    if (r.limit_reached) {
      limit_reached = true;
      if (!a.quiet)
        std::cerr << "bisect: stopping before iteration " << it << ": it would pass "
                  << (a.max_elements ? "--max-elements " + with_commas(std::size_t(a.max_elements))
                                     : std::string("the 32-bit id limit"))
                  << " (" << with_commas(mesh.num_cells()) << " cells now)\n";
      break;
    }
    auto t_quality = std::chrono::steady_clock::now();
    q = quality_summary(mesh);
    stages.quality += seconds_since(t_quality);
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
    if (selected.empty()) { // the same would hold for every later iteration
      if (!a.quiet) std::cerr << "bisect: the region touches no cell; nothing more to refine\n";
      break;
    }
    if (it == corrupt_after && corrupt_one_bisection(mesh, verts_before) == kNoVertex)
      std::cerr << "bisect: BISECT_TEST_CORRUPT_ITERATION=" << it << ": no bisection to undo\n";
    if (check) {
      CheckResult c = check_conformity(mesh, &before);
      if (!c.ok) {
        std::cerr << "bisect: internal check failed after iteration " << it << ": " << c.failure
                  << "\n";
        return kExitCheck;
      }
    }
  }
  // The final check, on by default (--check has checked every iteration in
  // full): whatever went wrong, a non-conforming mesh is never written.
  if (!check) {
    auto t_check = std::chrono::steady_clock::now();
    CheckResult c = check_refined(mesh, before);
    stages.final_check = seconds_since(t_check);
    if (!c.ok) {
      std::cerr << "bisect: internal check failed on the refined mesh: " << c.failure
                << "; no output written\n";
      return kExitCheck;
    }
  }
  auto t_write = std::chrono::steady_clock::now();
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
  if (!a.quiet) std::cerr << slice_lines;
  double total = seconds_since(t_start);
  if (a.json) {
    nlohmann::json j;
    j["input"] = a.input;
    j["output"] = out;
    j["quality_csv"] = h_csv >= 0 ? nlohmann::json(csv) : nlohmann::json(nullptr);
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
    j["stages"] = {{"read", stages.read},       {"validate", stages.validate},
                   {"select", stages.select},   {"refine", stages.refine},
                   {"quality", stages.quality}, {"final_check", stages.final_check},
                   {"write", stages.write}};
    j["peak_rss_bytes"] = peak_rss_bytes();
    std::cout << j.dump() << std::endl;
  }
  if (!a.quiet)
    std::cerr << "bisect: wrote " << out << " (" << with_commas(mesh.num_cells()) << " cells)"
              << (h_csv >= 0 ? " and " + csv : std::string()) << " in " << std::fixed << std::setprecision(2) << total << " s\n";
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

// Writes a made mesh to `out` (an OutputSet of one; `inputs` may not be it).
int write_generated(Mesh mesh, const std::string &out, bool force,
                    std::vector<std::string> inputs = {}) {
  check_extension(out);
  OutputSet outputs(std::move(inputs), force);
  const int h = outputs.add(out);
  check_output_format(out, mesh.dim);
  if (mesh.marked()) encode_state(mesh);
  write_mesh_file(outputs.file(h), out, mesh);
  outputs.commit();
  std::cerr << "bisect: wrote " << out << " (" << mesh.num_cells() << " cells, " << mesh.num_vertices()
            << " vertices)\n";
  return kExitOk;
}

// ---------------------------------------------------------------- colour ---

// Reads a 2D or 3D mesh for `colour` and `extrude --method colouring`.
Mesh read_colourable(const std::string &path, const char *command) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  if (mesh.dim != 2 && mesh.dim != 3)
    throw InputError(path, std::string(command) + " needs a 2D triangle or 3D tetrahedral mesh, this one is " +
                               std::to_string(mesh.dim) + "D");
  return mesh;
}

// The colouring of `mesh`: with `barycentric` the mesh is replaced by its
// barycentric subdivision, coloured by vertex kind; otherwise its point array
// `colour` when present (it must be proper) unless `recompute`, else found by
// propagation and stored as the point array `colour`. `how` says which.
// Throws InputError naming `path` when there is none.
std::vector<std::uint8_t> colouring_of(Mesh &mesh, const std::string &path, bool barycentric,
                                       bool recompute, std::string &how) {
  const std::string colours = std::to_string(mesh.dim + 1) + "-colouring";
  std::vector<std::uint8_t> colour;
  if (barycentric) {
    try {
      mesh = barycentric_subdivision(mesh, &colour);
    } catch (const InputError &e) {
      throw InputError(path, e.what());
    }
    how = colours + " of the barycentric subdivision by vertex kind (" +
          (mesh.dim == 3 ? "A vertex, B edge centre, C face centre, D cell centre)"
                         : "A vertex, B edge centre, C cell centre)");
    return colour;
  }
  std::optional<std::vector<std::uint8_t>> given;
  if (!recompute) {
    try {
      given = colour_array(mesh);
    } catch (const InputError &e) {
      throw InputError(path, e.what());
    }
  }
  if (given) {
    if (std::string why = check_colouring(mesh, *given); !why.empty())
      throw InputError(path, std::string("point array ") + kColourArray + " is not a proper " + colours +
                                 ": " + why);
    how = colours + " given by the point array " + kColourArray;
    return *given;
  }
  Colouring c = colour_mesh(mesh);
  const bool partial = !recompute && std::any_of(mesh.point_data.begin(), mesh.point_data.end(),
                                                 [](const DataArray &a) { return a.name == kColourArray; });
  const std::string note = partial ? std::string(" (the point array ") + kColourArray +
                                         " leaves vertices made by refinement uncoloured (-1), so it was ignored)"
                                   : "";
  if (!c.ok)
    throw InputError(path, "no proper " + colours + ": " + c.why + note +
                               "; --barycentric subdivides the mesh into one that has");
  how = colours + " found by propagation (" + std::to_string(c.components) +
        (c.components == 1 ? " component)" : " components)") + note;
  // The mesh carries the colouring used (replacing a stale array), so what
  // extrude copies to every slice and colour -o writes are that colouring.
  set_colour_array(mesh, c.colour);
  return std::move(c.colour);
}

int run_colour(const std::string &in, bool barycentric, bool recompute, const std::string &out, bool force) {
  OutputSet outputs({in}, force);
  int h = -1;
  if (!out.empty()) {
    check_extension(out);
    h = outputs.add(out);
  }
  Mesh mesh = read_colourable(in, "colour");
  std::string how;
  std::vector<std::uint8_t> colour = colouring_of(mesh, in, barycentric, recompute, how);
  std::vector<std::size_t> count(std::size_t(mesh.dim + 1), 0);
  std::vector<char> used(mesh.num_vertices(), 0);
  for (VertexId v : mesh.cells) used[v] = 1;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) count[colour[v]]++;
  std::cout << in << ": " << how << "\n" << "cells: " << mesh.num_cells() << "\n";
  for (int k = 0; k <= mesh.dim; ++k)
    std::cout << "colour " << k << " (" << "ABCD"[k] << "): " << count[std::size_t(k)] << " vertices\n";
  if (!out.empty()) {
    set_colour_array(mesh, colour);
    write_mesh_file(outputs.file(h), out, mesh);
    outputs.commit();
    std::cerr << "bisect: wrote " << out << " (" << mesh.num_cells() << " cells, " << mesh.num_vertices()
              << " vertices, point array " << kColourArray << ")\n";
  }
  return kExitOk;
}

// extrude --method colouring: prisms cut and tagged by the colouring (seed 001).
int run_extrude_colouring(const std::string &in, const std::vector<double> &slices, bool barycentric,
                          const std::string &out, bool force) {
  check_extension(out);
  OutputSet outputs({in}, force);
  const int h = outputs.add(out);
  Mesh mesh = read_colourable(in, "extrude --method colouring");
  check_output_format(out, mesh.dim + 1);
  std::string how;
  std::vector<std::uint8_t> colour = colouring_of(mesh, in, barycentric, false, how);
  Mesh st;
  try {
    st = extrude_coloured(mesh, colour, slices);
  } catch (const InputError &e) {
    throw InputError(in, e.what());
  }
  write_output_mesh(outputs, h, st);
  outputs.commit();
  std::cerr << "bisect: wrote " << out << " (" << st.num_cells() << (st.dim == 4 ? " pentatopes, " : " tetrahedra, ")
            << st.num_vertices() << " vertices; tagged by the " << how << ")\n";
  return kExitOk;
}

} // namespace

int main(int argc, char **argv) {
  install_signal_handlers();

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
                     "and a CSV with one row per iteration. A file's bisection state is checked on "
                     "reading (an altered one is an input error).\n"
                     "Before writing, a final check runs (unless --check checked every iteration): "
                     "no degenerate or folded cell, every facet in at most two cells, the input's "
                     "volume and boundary measure; a failure exits 2 and writes nothing. Refinement "
                     "stops (exit 3, the mesh before that iteration written) before it would bisect "
                     "an edge whose extent is below 2^-40 of its ends' largest coordinate magnitude "
                     "or below 2^-100.\n" +
                     std::string(kExitCodesHelp));
  refine_cmd->add_option("input", ra.input, "Input mesh (.vtu or .msh)")->required();
  refine_cmd->add_option("--region,-r", ra.region, "Region spec (JSON): sphere, hemisphere, box, "
                                                  "halfspace, moving_sphere, levelset, union, intersection")
      ->required();
  refine_cmd->add_option("--iterations,-n", ra.iterations, "Refinement iterations (default 1)")
      ->check(CLI::Range(0, 10000));
  refine_cmd->add_option("--output,-o", ra.output,
                         "Output mesh (.vtu or .msh); default <input stem>.refined.vtu here; "
                         "- for standard output (with --format)");
  refine_cmd->add_option("--format", ra.format,
                         "Output format when the output's name has no .vtu/.msh extension "
                         "(e.g. -o /dev/stdout --format vtu)")
      ->check(CLI::IsMember({"vtu", "msh"}));
  refine_cmd->add_option("--compression", ra.compression,
                         ".vtu output: zlib (default), lz4 (faster, larger) or none; ParaView and "
                         "VTK read all three")
      ->check(CLI::IsMember({"zlib", "lz4", "none"}));
  refine_cmd->add_option("--quality-csv", ra.csv,
                         "Per-iteration quality CSV; default <output stem>.quality.csv; none: no CSV");
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
                         "Also write the sections t = T1,T2,... of the final mesh (t: the last "
                         "coordinate; 4D -> 3D tets, 2D+t -> 2D triangles) as <output stem>.t<T>.vtu")
      ->delimiter(',');
  refine_cmd->add_flag("--json", ra.json, "Print a JSON summary on stdout");
  refine_cmd->add_flag("--quiet,-q", ra.quiet, "No progress output on stderr");
  refine_cmd->add_flag("--force,-f", ra.force, "Overwrite existing output files (never the input)");
  refine_cmd->add_flag("--check", ra.check,
                       "After every iteration, check conformity and that volume, boundary measure "
                       "and Euler characteristic are those of the input (exit 2 naming the "
                       "iteration and the failure, no output written); always on in a "
                       "BISECT_PARANOID build");

  std::string slice_in, slice_out, slice_axis = "t";
  double slice_value = 0;
  bool slice_force = false;
  auto *slice_cmd = app.add_subcommand(
      "slice", "Cut a 4D mesh by the hyperplane {axis = value} into a conforming 3D tetrahedral "
               "mesh for ParaView (prisms are split into three tetrahedra), or a 3D (2D+t) mesh "
               "by a plane into a conforming triangle mesh.");
  slice_cmd->footer("Example: bisect slice hypercube-25.vtu --t 0.5 -o section.vtu");
  slice_cmd->add_option("input", slice_in, "4D mesh (.vtu), or 3D mesh")->required();
  auto *t_opt = slice_cmd->add_option("--t", slice_value, "Shorthand for --axis t --value VALUE");
  slice_cmd->add_option("--axis", slice_axis, "x, y, z or t (default t: the last coordinate, z of a 3D mesh)")
      ->check(CLI::IsMember({"x", "y", "z", "t"}));
  slice_cmd->add_option("--value", slice_value, "Where the hyperplane cuts the axis")->excludes(t_opt);
  slice_cmd->add_option("--output,-o", slice_out, "Output 3D mesh (.vtu or .msh)")->required();
  slice_cmd->add_flag("--force,-f", slice_force, "Overwrite an existing file");

  std::string ex_in, ex_out, ex_slices, ex_method = "delaunay";
  bool ex_force = false, ex_barycentric = false;
  auto *extrude_cmd = app.add_subcommand(
      "extrude", "Extrude a 3D tetrahedral mesh over time slices into a 4D pentatope mesh (or, with "
                 "--method colouring, a 2D triangle mesh into a 3D tetrahedral one).");
  extrude_cmd->footer("Example: bisect extrude cube.vtu --slices 0,0.5,1 -o spacetime.vtu\n"
                      "         bisect extrude cube.vtu --slices 0:1:4 -o spacetime.vtu   "
                      "(4 slabs between 0 and 1)\n"
                      "--method delaunay triangulates the 4D points with Qhull: the 3D mesh must be "
                      "convex (a non-convex one is rejected).\n"
                      "--method colouring cuts every prism by a vertex colouring (seed 001): 4 "
                      "pentatopes per tet and slab (3 tets per triangle), consistently tagged "
                      "(marking sorted in colour order), any domain shape. The colouring is the "
                      "point array 'colour' when present, else found by propagation (see bisect "
                      "colour); --barycentric subdivides first, which always has one.\n"
                      "         bisect extrude cube.vtu --slices 0:1:4 --method colouring -o st.vtu");
  extrude_cmd->add_option("input", ex_in, "3D mesh (.vtu or .msh); 2D too with --method colouring")->required();
  extrude_cmd->add_option("--slices", ex_slices, "T0,T1,... or START:STOP:COUNT (COUNT slabs)")
      ->required();
  extrude_cmd->add_option("--method", ex_method, "delaunay (default; 3D convex meshes) or colouring")
      ->check(CLI::IsMember({"delaunay", "colouring"}));
  extrude_cmd->add_flag("--barycentric", ex_barycentric,
                        "--method colouring: extrude the barycentric subdivision (always colourable)");
  extrude_cmd->add_option("--output,-o", ex_out, "Output 4D mesh (.vtu), or 3D mesh (.vtu or .msh) from a 2D one")->required();
  extrude_cmd->add_flag("--force,-f", ex_force, "Overwrite an existing file");
  bool ex_hull = false;
  extrude_cmd->add_flag("--hull", ex_hull,
                        "delaunay: accept a non-convex 3D mesh and fill the convex hull of its "
                        "points (as seed 000 §5.2 does for a faceted sphere octant)");

  std::string colour_in, colour_out;
  bool colour_barycentric = false, colour_recompute = false, colour_force = false;
  auto *colour_cmd = app.add_subcommand(
      "colour", "Check or find a vertex colouring of a 2D/3D mesh (every cell's vertices "
                "different colours 0..dim), as extrude --method colouring needs.");
  colour_cmd->footer("Example: bisect colour cube.vtu -o cube-coloured.vtu\n"
                     "         bisect colour ball.msh --barycentric -o ball-bary.vtu\n"
                     "Checks the point array 'colour' when present; otherwise propagates colours "
                     "across facets, which either finds a colouring or proves there is none (exit 1 "
                     "with the reason, e.g. an interior edge in an odd number of tets). Colours 0, "
                     "1, 2, 3 are seed 001's labels A, B, C, D.");
  colour_cmd->add_option("input", colour_in, "2D or 3D mesh (.vtu or .msh)")->required();
  colour_cmd->add_flag("--barycentric", colour_barycentric,
                       "Subdivide barycentrically (6 triangles / 24 tets per cell), coloured by vertex kind");
  colour_cmd->add_flag("--recompute", colour_recompute, "Ignore a 'colour' array in the input");
  colour_cmd->add_option("--output,-o", colour_out, "Write the mesh with the point array 'colour'");
  colour_cmd->add_flag("--force,-f", colour_force, "Overwrite an existing file");

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
  gen_simplex->footer("Examples: bisect generate simplex --dim 3 --shape random --seed 7 -o tet.vtu\n"
                      "          bisect generate simplex --dim 4 --type A_PO -o apo.vtu");
  gen_simplex->add_option("--dim,-d", g_dim, "2, 3 or 4")->check(CLI::Range(2, 4));
  gen_simplex->add_option("--shape", g_shape, "equilateral, cartesian or random")
      ->check(CLI::IsMember({"equilateral", "cartesian", "random"}));
  gen_simplex->add_option("--seed", g_seed, "Seed for --shape random");
  std::string g_type;
  gen_simplex->add_option("--type", g_type,
                          "Force the marks to a type (seed 000 §3.2): for --dim 4 e.g. P_PP, P_AA, "
                          "A_PO (level-1 relation, then the two level-2 relations); for --dim 3 "
                          "P, A, O or M. Stored as an explicit edge order in the file");
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
  std::vector<double> k_box;
  gen_kuhn->add_option("--box", k_box, "LO,HI: the cube [LO,HI]^dim (same as --lo LO --hi HI)")
      ->delimiter(',')
      ->expected(2);
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
    // CLI11 says "A subcommand is required" for a misspelt command.
    std::string names;
    bool known = false;
    for (const CLI::App *sub : app.get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known |= argc > 1 && sub->get_name() == argv[1];
    }
    if (argc > 1 && argv[1][0] != '-' && !known) {
      std::cerr << "bisect: unknown command '" << argv[1] << "' (commands: " << names << ")\n";
      return kExitInput;
    }
    std::cerr << "bisect: " << e.what() << " (see bisect --help)\n";
    return kExitInput;
  }

  try {
    if (*refine_cmd) return run_refine(ra);
    if (*info_cmd) return run_info(info_in);
    if (*colour_cmd) return run_colour(colour_in, colour_barycentric, colour_recompute, colour_out, colour_force);
    if (*extrude_cmd) {
      std::vector<double> ts = parse_slices(ex_slices);
      if (ex_method == "colouring" && ex_hull) throw UsageError("--hull needs --method delaunay");
      if (ex_method == "colouring") return run_extrude_colouring(ex_in, ts, ex_barycentric, ex_out, ex_force);
      if (ex_barycentric) throw UsageError("--barycentric needs --method colouring");
      check_extension(ex_out);
      {
        OutputSet probe({ex_in}, ex_force); // refuse a bad output before the work
        probe.add(ex_out);
        check_output_format(ex_out, 4);
      }
      Mesh mesh = read_mesh(ex_in);
      prepare_input(mesh, ex_in);
      if (mesh.dim != 3)
        throw InputError(ex_in, "extrude needs a 3D tetrahedral mesh, this one is " +
                                    std::to_string(mesh.dim) + "D");
      Mesh m4;
      try {
        m4 = extrude_delaunay(mesh, ts, ex_hull);
      } catch (const InputError &e) {
        throw InputError(ex_in, e.what());
      }
      return write_generated(std::move(m4), ex_out, ex_force, {ex_in});
    }
    if (*slice_cmd) {
      check_extension(slice_out);
      OutputSet outputs({slice_in}, slice_force);
      const int h = outputs.add(slice_out);
      Mesh mesh = read_mesh(slice_in);
      prepare_input(mesh, slice_in);
      if (mesh.dim < 3)
        throw InputError(slice_in, "slice needs a 3D or 4D mesh, this one is 2D");
      int axis = slice_axis == "t" ? mesh.dim - 1 : int(std::string("xyz").find(slice_axis[0]));
      if (axis >= mesh.dim) throw UsageError("slice: a 3D mesh has no axis " + slice_axis);
      const std::string line = write_slice(mesh, axis, slice_value, outputs, h);
      outputs.commit();
      std::cerr << line;
      return kExitOk;
    }
    if (*check_cmd) return run_check(check_in, check_against);
    if (*quality_cmd) return run_quality(quality_in, quality_classes, quality_bins);
    if (*gen_simplex) {
      SimplexShape s = g_shape == "cartesian" ? SimplexShape::Cartesian
                       : g_shape == "random"  ? SimplexShape::Random
                                              : SimplexShape::Equilateral;
      Mesh simplex = generate_simplex(g_dim, s, g_seed);
      if (!g_type.empty()) {
        try {
          force_type(simplex, g_type);
        } catch (const std::invalid_argument &e) {
          throw UsageError(std::string("generate simplex --type: ") + e.what());
        }
      }
      return write_generated(std::move(simplex), g_out, g_force);
    }
    if (*gen_kuhn) {
      if (k_box.size() == 2) k_lo = k_box[0], k_hi = k_box[1];
      if (!(k_lo < k_hi)) throw UsageError("generate kuhn: --lo must be below --hi");
      return write_generated(generate_kuhn(g_dim, k_cells, k_lo, k_hi), g_out, g_force);
    }
  } catch (const InputError &e) {
    std::cerr << "bisect: " << one_line(e.what()) << "\n";
    return kExitInput;
  } catch (const UsageError &e) {
    std::cerr << "bisect: " << one_line(e.what()) << "\n";
    return kExitInput;
  } catch (const CheckError &e) {
    std::cerr << "bisect: internal check failed: " << one_line(e.what()) << "\n";
    return kExitCheck;
  } catch (const std::bad_alloc &) {
    std::cerr << "bisect: out of memory; no output written (try --max-elements)\n";
    return kExitInput;
  } catch (const std::exception &e) {
    std::cerr << "bisect: internal error: " << one_line(e.what()) << "\n";
    return kExitCheck;
  }
  return kExitOk;
}
