// bisect check: whether a mesh conforms.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

struct CheckArgs {
  std::string input, against;
  CommonFlags flags;
};

int run_check(const CheckArgs &a) {
  const std::string &path = a.input;
  // Validation checks all that check_conformity does (and more, each
  // failure an input error) and measures the invariants on its way.
  const LoadProgress progress = load_progress(path, a.flags.quiet);
  if (progress)
    progress("reading", 0.0);
  // The file's bisection state is checked too, as every command that reads
  // it does (an altered one is an input error, exit 1): a file that passes
  // here refines and coarsens.
  StoredState stored;
  Mesh mesh = read_mesh(path, stored);
  InputFacts facts;
  prepare_read_mesh(mesh, path, progress, facts, &stored);
  stored = {};
  InputFacts original;
  const Invariants *orig = nullptr;
  if (!a.against.empty()) {
    Mesh o = read_mesh(a.against, stored);
    stored = {};
    prepare_input(o, a.against, load_progress(a.against, a.flags.quiet), &original);
    if (o.dim != mesh.dim)
      throw InputError(a.against, "dimension " + std::to_string(o.dim) + " differs from " + path +
                                      "'s " + std::to_string(mesh.dim));
    orig = &original.invariants;
  }
  const CheckResult r = orig ? compare_invariants(*orig, facts.invariants) : CheckResult{};
  if (a.flags.json)
    print_json({{"file", path},
                {"against", orig ? nlohmann::json(a.against) : nlohmann::json()},
                {"cells", mesh.num_cells()},
                {"conforming", r.ok},
                {"failure", r.ok ? nlohmann::json() : nlohmann::json(r.failure)}});
  if (!r.ok) {
    if (!a.flags.quiet)
      std::cerr << "bisect: " << path << ": check failed: " << r.failure << "\n";
    return kExitCheck;
  }
  if (!a.flags.json && !a.flags.quiet)
    std::cout << path << ": conforming (" << mesh.num_cells() << " cells"
              << (orig ? ", volume, boundary and Euler characteristic match " + a.against
                       : std::string())
              << ")\n";
  return kExitOk;
}

} // namespace

Command add_check(CLI::App &app) {
  auto a = std::make_shared<CheckArgs>();
  auto *cmd = app.add_subcommand(
      "check",
      "Check conformity: facets shared by at most two cells, no degenerate or inverted "
      "cell, and a consistent bisection state (bisect:* arrays) where the file has one; with "
      "--against, volume, boundary measure and Euler characteristic unchanged.");
  cmd->footer("Example: bisect check ball-10.vtu --against data/ball.msh   (exit 2 names the "
              "first failure)");
  cmd->add_option("input", a->input, "Mesh file (.vtu or .msh; - reads standard input)")
      ->required();
  cmd->add_option("--against", a->against, "The original mesh it was refined from");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_check(*a); }};
}

} // namespace bisect::cli
