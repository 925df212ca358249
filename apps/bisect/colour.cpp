// bisect colour: check or find a vertex colouring (and the colouring extrude uses).
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

struct ColourArgs {
  std::string input, output;
  bool barycentric = false, recompute = false, force = false;
  CommonFlags flags;
};

int run_colour(const ColourArgs &a) {
  const std::string &in = a.input, &out = a.output;
  const bool barycentric = a.barycentric, recompute = a.recompute, force = a.force;
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
  for (VertexId v : mesh.cells)
    used[v] = 1;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v])
      count[colour[v]]++;
  if (a.flags.json) {
    print_json({{"file", in},
                {"colouring", how},
                {"cells", mesh.num_cells()},
                {"vertices_per_colour", count},
                {"output", out.empty() ? nlohmann::json() : nlohmann::json(out)}});
  } else {
    std::cout << in << ": " << how << "\n"
              << "cells: " << mesh.num_cells() << "\n";
    for (int k = 0; k <= mesh.dim; ++k)
      std::cout << "colour " << k << " ("
                << "ABCD"[k] << "): " << count[std::size_t(k)] << " vertices\n";
  }
  if (!out.empty()) {
    set_colour_array(mesh, colour);
    validate_result(mesh, out);
    write_mesh_file(outputs.file(h), out, mesh);
    outputs.commit();
    if (!a.flags.quiet)
      std::cerr << "bisect: wrote " << out << " (" << mesh.num_cells() << " cells, "
                << mesh.num_vertices() << " vertices, point array " << kColourArray << ")\n";
  }
  return kExitOk;
}

} // namespace

Mesh read_colourable(const std::string &path, const char *command) {
  Mesh mesh = read_mesh(path);
  prepare_input(mesh, path);
  if (mesh.dim != 2 && mesh.dim != 3)
    throw InputError(path, std::string(command) +
                               " needs a 2D triangle or 3D tetrahedral mesh, this one is " +
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
    mesh = about_file(path, [&] { return barycentric_subdivision(mesh, &colour); });
    how = colours + " of the barycentric subdivision by vertex kind (" +
          (mesh.dim == 3 ? "A vertex, B edge centre, C face centre, D cell centre)"
                         : "A vertex, B edge centre, C cell centre)");
    return colour;
  }
  std::optional<std::vector<std::uint8_t>> given;
  if (!recompute) {
    given = about_file(path, [&] { return colour_array(mesh); });
  }
  if (given) {
    if (std::string why = check_colouring(mesh, *given); !why.empty())
      throw InputError(path, std::string("point array ") + kColourArray + " is not a proper " +
                                 colours + ": " + why);
    how = colours + " given by the point array " + kColourArray;
    return *given;
  }
  Colouring c = colour_mesh(mesh);
  const bool partial =
      !recompute && std::any_of(mesh.point_data.begin(), mesh.point_data.end(),
                                [](const DataArray &a) { return a.name == kColourArray; });
  const std::string note =
      partial ? std::string(" (the point array ") + kColourArray +
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

Command add_colour(CLI::App &app) {
  auto a = std::make_shared<ColourArgs>();
  auto *cmd = app.add_subcommand(
      "colour", "Check or find a vertex colouring of a 2D/3D mesh (every cell's vertices "
                "different colours 0..dim), as extrude --method colouring needs.");
  cmd->footer("Example: bisect colour cube.vtu -o cube-coloured.vtu\n"
              "         bisect colour ball.msh --barycentric -o ball-bary.vtu\n"
              "Checks the point array 'colour' when present; otherwise propagates colours "
              "across facets, which either finds a colouring or proves there is none (exit 1 "
              "with the reason, e.g. an interior edge in an odd number of tets). Colours 0, "
              "1, 2, 3 are seed 001's labels A, B, C, D.");
  cmd->add_option("input", a->input, "2D or 3D mesh (.vtu or .msh; - reads standard input)")
      ->required();
  cmd->add_flag(
      "--barycentric", a->barycentric,
      "Subdivide barycentrically (6 triangles / 24 tets per cell), coloured by vertex kind");
  cmd->add_flag("--recompute", a->recompute, "Ignore a 'colour' array in the input");
  cmd->add_option("--output,-o", a->output, "Write the mesh with the point array 'colour'");
  cmd->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_colour(*a); }};
}

} // namespace bisect::cli
