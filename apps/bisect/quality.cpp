// bisect quality: mean-ratio histogram and similarity classes.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

struct QualityArgs {
  std::string input;
  bool classes = false;
  int bins = 10;
  CommonFlags flags;
};

int run_quality(const QualityArgs &a) {
  StoredState stored; // a .vtu's bisection state, not needed here: kept small
  Mesh mesh = read_mesh(a.input, stored);
  stored = {};
  prepare_input(mesh, a.input, load_progress(a.input, a.flags.quiet));
  const int bins = a.bins;
  const QualityHistogram h = quality_histogram(mesh, bins);
  const std::vector<std::size_t> &hist = h.counts;
  const double qmin = h.summary.min, qmax = h.summary.max, mean = h.summary.mean;
  if (a.flags.json) {
    nlohmann::json j{{"file", a.input},     {"cells", mesh.num_cells()}, {"min_quality", qmin},
                     {"max_quality", qmax}, {"mean_quality", mean},      {"histogram", hist}};
    if (a.classes)
      j["classes"] = count_similarity_classes(mesh);
    print_json(j);
    return kExitOk;
  }
  std::cout << "cells: " << mesh.num_cells() << "\n"
            << "quality: min " << qmin << " max " << qmax << " mean " << mean << "\n"
            << "histogram (mean ratio):\n";
  for (int b = 0; b < bins; ++b) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "  [%.2f, %.2f%c %zu\n", double(b) / bins, double(b + 1) / bins,
                  b + 1 == bins ? ']' : ')', hist[std::size_t(b)]);
    std::cout << buf;
  }
  if (a.classes)
    std::cout << "classes: " << count_similarity_classes(mesh) << "\n";
  return kExitOk;
}

} // namespace

Command add_quality(CLI::App &app) {
  auto a = std::make_shared<QualityArgs>();
  auto *cmd = app.add_subcommand("quality", "Mean-ratio quality histogram and similarity classes.");
  cmd->footer("Example: bisect quality tet-12.vtu --classes");
  cmd->add_option("input", a->input, "Mesh file (.vtu or .msh; - reads standard input)")
      ->required();
  cmd->add_flag("--classes", a->classes, "Count similarity classes");
  cmd->add_option("--bins", a->bins, "Histogram bins (default 10)")->check(CLI::Range(1, 1000));
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_quality(*a); }};
}

} // namespace bisect::cli
