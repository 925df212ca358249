// bisect info, check, quality: what a mesh is, whether it conforms, how good it is.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

struct Box {
  std::vector<double> lo, hi;
};

Box bounding_box(const Mesh &mesh) {
  const int d = mesh.dim;
  Box b{std::vector<double>(std::size_t(d), 1e300), std::vector<double>(std::size_t(d), -1e300)};
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
    for (int k = 0; k < d; ++k) {
      b.lo[std::size_t(k)] = std::min(b.lo[std::size_t(k)], mesh.point(VertexId(v))[k]);
      b.hi[std::size_t(k)] = std::max(b.hi[std::size_t(k)], mesh.point(VertexId(v))[k]);
    }
  return b;
}

struct InfoArgs {
  std::string input;
  CommonFlags flags;
};

int run_info(const InfoArgs &a) {
  const std::string &path = a.input;
  Mesh mesh = load_mesh(path);
  const bool has_state = mesh.marked();
  const Invariants inv = measure_invariants(mesh);
  const QualitySummary q = quality_summary(mesh);
  const Box box = bounding_box(mesh);
  if (a.flags.json) {
    nlohmann::json arrays = nlohmann::json::array();
    for (const DataArray &d : mesh.cell_data)
      arrays.push_back({{"name", d.name}, {"on", "cells"}, {"components", d.components}});
    for (const DataArray &d : mesh.point_data)
      arrays.push_back({{"name", d.name}, {"on", "points"}, {"components", d.components}});
    print_json(
        {{"file", path},
         {"dim", mesh.dim},
         {"cells", mesh.num_cells()},
         {"vertices", mesh.num_vertices()},
         {"bounding_box", {{"min", box.lo}, {"max", box.hi}}},
         {"volume", inv.volume},
         {"boundary_facets", inv.boundary_facets},
         {"boundary_measure", inv.boundary_measure},
         {"euler_characteristic", inv.euler},
         {"min_quality", q.min},
         {"max_quality", q.max},
         {"mean_quality", q.mean},
         {"bisection_state", has_state},
         {"marking", has_state ? nlohmann::json(marking_name(mesh.marking)) : nlohmann::json()},
         {"arrays", arrays}});
    return kExitOk;
  }
  std::cout << "file: " << path << "\n"
            << "dimension: " << mesh.dim << "\n"
            << "cells: " << mesh.num_cells() << "\n"
            << "vertices: " << mesh.num_vertices() << "\n";
  std::cout << "bounding box:";
  for (int k = 0; k < mesh.dim; ++k)
    std::cout << " "
              << "xyzt"[k] << " [" << box.lo[std::size_t(k)] << ", " << box.hi[std::size_t(k)]
              << "]";
  std::cout << "\n";
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
  for (const DataArray &d : mesh.cell_data)
    std::cout << "cell array: " << d.name << " (" << d.components << " components)\n";
  for (const DataArray &d : mesh.point_data)
    std::cout << "point array: " << d.name << " (" << d.components << " components)\n";
  return kExitOk;
}

struct CheckArgs {
  std::string input, against;
  CommonFlags flags;
};

int run_check(const CheckArgs &a) {
  const std::string &path = a.input;
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  Invariants original;
  const Invariants *orig = nullptr;
  if (!a.against.empty()) {
    Mesh o = read_mesh(a.against);
    prepare_input(o, a.against);
    if (o.dim != mesh.dim)
      throw InputError(a.against, "dimension " + std::to_string(o.dim) + " differs from " + path +
                                      "'s " + std::to_string(mesh.dim));
    original = measure_invariants(o);
    orig = &original;
  }
  const CheckResult r = check_conformity(mesh, orig);
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

struct QualityArgs {
  std::string input;
  bool classes = false;
  int bins = 10;
  CommonFlags flags;
};

int run_quality(const QualityArgs &a) {
  Mesh mesh = read_mesh(a.input);
  prepare_input(mesh, a.input);
  const int bins = a.bins;
  std::vector<std::size_t> hist(std::size_t(bins), 0);
  double pts[5 * 4];
  double qmin = 1, qmax = 0, sum = 0;
  for (std::size_t c = 0; c < mesh.num_cells(); ++c) {
    cell_points(mesh, CellId(c), pts);
    const double q = mean_ratio(pts, mesh.dim);
    qmin = std::min(qmin, q);
    qmax = std::max(qmax, q);
    sum += q;
    hist[std::min<std::size_t>(std::size_t(q * bins), std::size_t(bins - 1))]++;
  }
  const double mean = mesh.num_cells() ? sum / double(mesh.num_cells()) : 0.0;
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

Command add_info(CLI::App &app) {
  auto a = std::make_shared<InfoArgs>();
  auto *cmd = app.add_subcommand("info", "Dimension, counts, bounding box, volume, quality.");
  cmd->footer("Example: bisect info data/ball.msh");
  cmd->add_option("input", a->input, "Mesh file")->required();
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_info(*a); }};
}

Command add_check(CLI::App &app) {
  auto a = std::make_shared<CheckArgs>();
  auto *cmd = app.add_subcommand(
      "check",
      "Check conformity: facets shared by at most two cells, no degenerate or inverted "
      "cell; with --against, volume, boundary measure and Euler characteristic unchanged.");
  cmd->footer("Example: bisect check ball-10.vtu --against data/ball.msh   (exit 2 names the "
              "first failure)");
  cmd->add_option("input", a->input, "Mesh file")->required();
  cmd->add_option("--against", a->against, "The original mesh it was refined from");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_check(*a); }};
}

Command add_quality(CLI::App &app) {
  auto a = std::make_shared<QualityArgs>();
  auto *cmd = app.add_subcommand("quality", "Mean-ratio quality histogram and similarity classes.");
  cmd->footer("Example: bisect quality tet-12.vtu --classes");
  cmd->add_option("input", a->input, "Mesh file")->required();
  cmd->add_flag("--classes", a->classes, "Count similarity classes");
  cmd->add_option("--bins", a->bins, "Histogram bins (default 10)")->check(CLI::Range(1, 1000));
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_quality(*a); }};
}

} // namespace bisect::cli
