// Helpers the commands share (cli.hpp).
#include "cli.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <sys/resource.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace bisect::cli {

const char *const kExitCodesHelp =
    "Exit codes: 0 success; 1 usage or input error (one line on stderr names the file and the "
    "problem), or a system failure (disk full, permission); 2 an internal check failed; 3 a limit "
    "(--max-elements, --max-memory, 32-bit ids, the precision limit) was reached, the output is "
    "still written and conforming; 4 out of memory (no output written); 130 interrupted (no output "
    "written).";

void add_common_flags(CLI::App *cmd, CommonFlags &flags) {
  cmd->add_flag("--quiet,-q", flags.quiet, "No progress or \"wrote\" lines on stderr");
  cmd->add_flag("--json", flags.json, "Print a JSON summary on stdout");
  cmd->add_option_function<int>(
         "--threads", [](int n) { set_threads(n); },
         "Threads for the parallel steps (default 0: one per core); the output is the same for "
         "every count")
      ->check(CLI::Range(0, 4096))
      ->type_name("N");
}

void print_json(const nlohmann::json &j) {
  std::cout << j.dump() << std::endl;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Peak resident memory of this process so far, in bytes.
double peak_rss_bytes() {
  struct rusage u {};
  ::getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) * 1024.0;
}

LoadProgress load_progress(const std::string &path, bool quiet) {
  if (quiet)
    return {};
  const auto t0 = std::chrono::steady_clock::now();
  return [path, t0](const char *step, double done) {
    if (seconds_since(t0) >= 2.0)
      std::cerr << "bisect: loading " << path << ": " << step << " (" << int(done * 100 + 0.5)
                << "%)\n";
  };
}

// Reads, validates and marks (or restores the marks of) an input mesh.
Mesh load_for_refinement(const std::string &path, std::optional<Marking> requested, bool quiet) {
  Mesh mesh = load_mesh(path, load_progress(path, quiet));
  if (mesh.marked()) {
    if (requested && *requested != mesh.marking && !quiet)
      std::cerr << "bisect: " << path << " carries bisection state with --marking "
                << marking_name(mesh.marking) << "; continuing it (--marking "
                << marking_name(*requested) << " ignored)\n";
  } else {
    mark_mesh(mesh, requested.value_or(Marking::Index));
  }
  return mesh;
}

// Writes `text` into `file` (an OutputSet's file for output `name`).
void write_text_file(const std::string &file, const std::string &name, const std::string &text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
    throw InputError(name, "cannot write: " + write_failure(errno));
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      throw InputError(name, "cannot write: " + write_failure(err));
    }
    done += std::size_t(n);
  }
  if (::close(fd) != 0)
    throw InputError(name, "cannot write: " + write_failure(errno));
}

// One output file, checked before any work (see output.hpp for the rules).
void check_extension(const std::string &out) {
  const std::string ext = [&] {
    std::string e = fs::path(out).extension().string();
    for (char &c : e)
      c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
  }();
#ifndef BISECT_MPI
  if (ext == ".pvtu")
    throw UsageError(out + ": a .pvtu output is the distributed run's, and this bisect was built "
                           "without MPI: use the MPI build (cmake -DBISECT_MPI=ON; "
                           "scripts/test.sh makes build-mpi/bisect), or end the output in .vtu "
                           "or .msh");
#endif
  if (ext != ".vtu" && ext != ".msh")
    throw UsageError(out + ": output must end in .vtu or .msh");
}

// Writes `mesh` with its bisection state into output `h` of `outputs`.
std::string output_name(const std::string &name, const std::string &format, bool json) {
  if (name != "-")
    return name;
  if (format.empty())
    throw UsageError("-o -: give the format with --format vtu or --format msh");
  if (json)
    throw UsageError("--json and -o - both write to standard output; choose one");
  return "/dev/stdout";
}

void add_format_option(CLI::App *cmd, std::string &format) {
  cmd->add_option("--format", format,
                  "Output format when the output's name has no .vtu/.msh extension "
                  "(-o - for standard output, -o /dev/stdout, a FIFO)")
      ->check(CLI::IsMember({"vtu", "msh"}));
}

void add_origin_array(Mesh &mesh) {
  std::erase_if(mesh.cell_data, [](const DataArray &d) { return d.name == kOriginArray; });
  DataArray origin{kOriginArray, 1, std::vector<double>(mesh.num_cells()), ValueType::Int32};
  for (std::size_t c = 0; c < mesh.num_cells(); ++c)
    origin.values[c] = double(c);
  mesh.cell_data.push_back(std::move(origin));
}

void validate_result(const Mesh &mesh, const std::string &out) {
  Mesh copy = mesh; // validation orients the cells: the result is written as made
  try {
    prepare_input(copy, out, nullptr);
  } catch (const InputError &e) {
    throw CheckError(std::string(e.what()) + " (the result fails the validation every read makes; "
                                             "nothing written)");
  }
}

void write_output_mesh(OutputSet &outputs, int h, Mesh &mesh, const WriteOptions &options) {
  write_mesh_file_with_state(outputs.file(h), outputs.name(h), mesh, options);
}

// "<output stem>.t<value>.vtu" beside the output.
std::string slice_path(const std::string &output, const char *axis, double value, int digits) {
  fs::path p(output);
  std::ostringstream name;
  name << p.stem().string() << "." << axis << std::setprecision(digits) << value << ".vtu";
  return (p.parent_path() / name.str()).string();
}

int slice_digits(const std::vector<double> &values) {
  for (int digits = 6;; ++digits) {
    std::vector<std::string> shown;
    for (double v : values) {
      std::ostringstream s;
      s << std::setprecision(digits) << v;
      shown.push_back(s.str());
    }
    std::sort(shown.begin(), shown.end());
    // 17 significant digits tell every two doubles apart.
    if (digits == 17 || std::adjacent_find(shown.begin(), shown.end()) == shown.end())
      return digits;
  }
}

// Writes the section of `mesh` at coordinate `axis` = `value` into output
// `h`; returns the line to print once the outputs are committed (the value
// with `digits` significant digits, as in its file name).
SliceWritten write_slice(const Mesh &mesh, int axis, double value, OutputSet &outputs, int h,
                         int digits) {
  Mesh s = slice_mesh(mesh, axis, value);
  // The 4D bisection state means nothing on a 3D section.
  std::erase_if(s.cell_data, [](const DataArray &d) { return d.name.rfind("bisect:", 0) == 0; });
  strip_tree(s); // the tree arrays encode_state added to the mesh are not the section's
  if (s.num_cells() == 0)
    throw InputError(outputs.name(h), std::string("the section ") +
                                          (axis == mesh.dim - 1 ? 't' : "xyz"[axis]) + " = " +
                                          std::to_string(value) + " is empty (it misses the mesh)");
  validate_result(s, outputs.name(h));
  write_mesh_file(outputs.file(h), outputs.name(h), s);
  std::ostringstream line;
  line << "bisect: wrote " << outputs.name(h) << " (" << with_commas(s.num_cells())
       << (s.dim == 3 ? " tetrahedra" : " triangles") << ": the section "
       << (axis == mesh.dim - 1 ? 't' : "xyz"[axis]) << " = " << std::setprecision(digits) << value
       << ")\n";
  return {line.str(), s.dim, s.num_cells(), s.num_vertices()};
}

// "0,0.5,1" or "start:stop:count" (count slabs, count + 1 slices).
std::vector<double> parse_slices(const std::string &text, std::size_t at_least) {
  auto number = [&](const std::string &t) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(t, &used);
    } catch (const std::exception &) {
      used = 0;
    }
    if (used != t.size() || t.empty() || !std::isfinite(v))
      throw UsageError("--slices: \"" + t +
                       "\" is not a number (expected T0,T1,... or START:STOP:COUNT)");
    return v;
  };
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream in(text);
    for (std::string p; std::getline(in, p, ':');)
      parts.push_back(p);
    if (parts.size() != 3)
      throw UsageError("--slices: expected START:STOP:COUNT, got \"" + text + "\"");
    double a = number(parts[0]), b = number(parts[1]), n = number(parts[2]);
    if (!(n >= 1 && n <= 10000 && n == std::floor(n)))
      throw UsageError("--slices: COUNT must be a whole number from 1 to 10000");
    for (int i = 0; i <= int(n); ++i)
      out.push_back(a + (b - a) * i / n);
  } else {
    std::stringstream in(text);
    for (std::string p; std::getline(in, p, ',');)
      out.push_back(number(p));
  }
  if (out.size() < at_least)
    throw UsageError(at_least == 1 ? std::string("--slices: need at least one slice")
                     : at_least == 2
                         ? std::string("--slices: need at least two slices")
                         : "--slices: need at least " + std::to_string(at_least) + " slices");
  for (std::size_t i = 1; i < out.size(); ++i)
    if (!(out[i] > out[i - 1]))
      throw UsageError("--slices: values must increase");
  return out;
}

// Writes a made mesh to `out` (an OutputSet of one; `inputs` may not be it).
int write_generated(Mesh mesh, const std::string &out, bool force, const CommonFlags &flags,
                    std::vector<std::string> inputs) {
  check_extension(out);
  OutputSet outputs(std::move(inputs), force);
  const int h = outputs.add(out);
  check_output_format(out, mesh.dim);
  validate_result(mesh, out);
  if (mesh.marked())
    encode_state(mesh);
  write_mesh_file(outputs.file(h), out, mesh);
  outputs.commit();
  if (flags.json)
    print_json({{"output", out},
                {"dim", mesh.dim},
                {"cells", mesh.num_cells()},
                {"vertices", mesh.num_vertices()}});
  if (!flags.quiet)
    std::cerr << "bisect: wrote " << out << " (" << mesh.num_cells() << " cells, "
              << mesh.num_vertices() << " vertices)\n";
  return kExitOk;
}

} // namespace bisect::cli
