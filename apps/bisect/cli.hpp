// What the commands of the `bisect` command line share: exit codes, output
// helpers, progress printing. Each command is one file (refine.cpp, info.cpp,
// ...) that parses its options, calls the library and prints; main.cpp maps
// errors to exit codes in one place.
#pragma once

#include "bisect/bisect.hpp"
#include "bisect/coarsen.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace bisect::cli {

inline constexpr int kExitOk = 0, kExitInput = 1, kExitCheck = 2, kExitLimit = 3, kExitMemory = 4,
                     kExitInterrupted = 130;

extern const char *const kExitCodesHelp;

// A subcommand: its CLI11 parser and what runs when it was given.
struct Command {
  CLI::App *app = nullptr;
  std::function<int()> run;
};

Command add_refine(CLI::App &app);
Command add_coarsen(CLI::App &app);
Command add_info(CLI::App &app);
Command add_check(CLI::App &app);
Command add_quality(CLI::App &app);
Command add_colour(CLI::App &app);
Command add_extrude(CLI::App &app);
Command add_slice(CLI::App &app);
std::vector<Command> add_generate(CLI::App &app);

// Options every command has: -q (no progress or "wrote" lines on stderr) and
// --json (a summary on stdout instead of the text report).
struct CommonFlags {
  bool quiet = false, json = false;
};
void add_common_flags(CLI::App *cmd, CommonFlags &flags);

double seconds_since(std::chrono::steady_clock::time_point t0);
double peak_rss_bytes();

// Progress lines for loading `path` on stderr ("bisect: loading big.vtu:
// matching facets (40%)"), printed as each step starts once the load has
// taken 2 s; none when `quiet`.
LoadProgress load_progress(const std::string &path, bool quiet);

// Reads, validates and marks (or restores the marks of) an input mesh; says
// so when a file's state overrides --marking.
Mesh load_for_refinement(const std::string &path, std::optional<Marking> requested, bool quiet);

// Writes `text` into `file` (an OutputSet's file for output `name`).
void write_text_file(const std::string &file, const std::string &name, const std::string &text);

// Refuses an output name that ends in neither .vtu nor .msh (any case).
void check_extension(const std::string &out);

// --origin: the cell array bisect:origin, each cell's own index (children
// inherit cell arrays, so after refining it names the input cell each cell
// descends from); a previous run's is replaced.
void add_origin_array(Mesh &mesh);

// A result made by a command other than refine and coarsen (which check
// their own), validated before it is written as any read validates a mesh
// (conforming, no degenerate, folded or overlapping cell, no duplicate
// vertex): a CheckError (exit 2) naming `out` if it fails, so that a run
// that exits 0 has written a valid mesh.
void validate_result(const Mesh &mesh, const std::string &out);

// Writes `mesh` with its bisection state into output `h` of `outputs`.
void write_output_mesh(OutputSet &outputs, int h, Mesh &mesh, const WriteOptions &options = {});

// The output mesh's file: `name`, or /dev/stdout for "-" (which needs
// `format`, and no --json: both would go to standard output).
std::string output_name(const std::string &name, const std::string &format, bool json);
// --format vtu|msh: the output's format when its name has no extension.
void add_format_option(CLI::App *cmd, std::string &format);

// "<output stem>.<axis><value>.vtu" beside the output, the value with
// `digits` significant digits.
std::string slice_path(const std::string &output, const char *axis, double value, int digits = 6);
// The fewest significant digits, at least 6, that give distinct values
// distinct names (a set of slices 1e-7 apart gets more than 6).
int slice_digits(const std::vector<double> &values);

// A section write_slice() wrote: the line to print once the outputs are
// committed, and the section's size.
struct SliceWritten {
  std::string line;
  int dim = 0;
  std::size_t cells = 0, vertices = 0;
};

// Writes the section of `mesh` at coordinate `axis` = `value` into output
// `h`. An empty section is an InputError naming the output. The line gives
// the value with `digits` significant digits, as its file name does.
SliceWritten write_slice(const Mesh &mesh, int axis, double value, OutputSet &outputs, int h,
                         int digits = 6);

// --slices of extrude and refine: "0,0.5,1" or "start:stop:count" (count
// slabs, count + 1 slices, both ends included); increasing values, at least
// `at_least` of them (extrude needs two, refine one). A UsageError otherwise.
std::vector<double> parse_slices(const std::string &text, std::size_t at_least = 2);

// Writes a made mesh to `out` (an OutputSet of one; `inputs` may not be it)
// and prints "wrote" unless quiet; with json, a summary on stdout.
int write_generated(Mesh mesh, const std::string &out, bool force, const CommonFlags &flags,
                    std::vector<std::string> inputs = {});

// Runs f(); an input error it throws about no file in particular (library
// functions that work on a mesh in memory) is rethrown naming `file`, the
// file the mesh came from.
template <class F> auto about_file(const std::string &file, F &&f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError &e) {
    if (!e.file.empty())
      throw;
    throw InputError(file, e.what());
  }
}

// colour.cpp, for extrude --method colouring too: reads a 2D or 3D mesh,
// and finds (or checks) its colouring; `how` says which (see colour.cpp).
Mesh read_colourable(const std::string &path, const char *command);
std::vector<std::uint8_t> colouring_of(Mesh &mesh, const std::string &path, bool barycentric,
                                       bool recompute, std::string &how);

// Prints `j` on stdout as one line.
void print_json(const nlohmann::json &j);

// bisect coarsen's progress (coarsen.cpp): prints one line per finished pass
// on stderr unless `quiet`, with the seconds since the one before.
std::function<void(const CoarsenPass &)> coarsen_pass_printer(int passes, bool quiet);

} // namespace bisect::cli
