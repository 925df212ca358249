// bisect info: what a mesh is.
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
  // Validation measures the invariants and the quality on its way: not
  // measured again.
  InputFacts facts;
  facts.want_quality = true;
  Mesh mesh = load_mesh(path, load_progress(path, a.flags.quiet), &facts);
  const bool has_state = mesh.marked();
  const Invariants &inv = facts.invariants;
  const QualitySummary &q = facts.quality;
  const Box box = bounding_box(mesh);
  if (a.flags.json) {
    nlohmann::json arrays = nlohmann::json::array();
    for (const DataArray &d : mesh.cell_data)
      arrays.push_back({{"name", d.name}, {"on", "cells"}, {"components", d.components}});
    for (const DataArray &d : mesh.point_data)
      arrays.push_back({{"name", d.name}, {"on", "points"}, {"components", d.components}});
    // What the text's "tagged entities" and "physical name" lines show.
    nlohmann::json entities = nlohmann::json::array(), names = nlohmann::json::array();
    for (const Entities &b : mesh.entities)
      entities.push_back({{"dim", b.dim}, {"count", b.size()}});
    for (const PhysicalName &n : mesh.physical_names)
      names.push_back({{"dim", n.dim}, {"tag", n.tag}, {"name", n.name}});
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
         {"arrays", arrays},
         {"entities", entities},
         {"physical_names", names}});
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
  // Tagged lower-dimensional entities (README, "Files"), per dimension.
  for (const Entities &b : mesh.entities)
    std::cout << "tagged entities: " << b.size() << " of dimension " << b.dim << "\n";
  for (const PhysicalName &n : mesh.physical_names)
    std::cout << "physical name: " << n.name << " (dimension " << n.dim << ", tag " << n.tag
              << ")\n";
  return kExitOk;
}

} // namespace

Command add_info(CLI::App &app) {
  auto a = std::make_shared<InfoArgs>();
  auto *cmd = app.add_subcommand("info", "Dimension, counts, bounding box, volume, quality.");
  cmd->footer("Example: bisect info data/ball.msh");
  cmd->add_option("input", a->input, "Mesh file (.vtu or .msh; - reads standard input)")
      ->required();
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_info(*a); }};
}

} // namespace bisect::cli
