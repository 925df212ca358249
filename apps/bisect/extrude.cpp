// bisect extrude: space-time meshes from a 3D mesh (Delaunay) or a coloured 2D/3D one.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

// extrude --method colouring: prisms cut and tagged by the colouring (seed 001).
int run_extrude_colouring(const std::string &in, const std::vector<double> &slices,
                          bool barycentric, const std::string &out, bool force,
                          const CommonFlags &flags) {
  check_extension(out);
  OutputSet outputs({in}, force);
  const int h = outputs.add(out);
  Mesh mesh = read_colourable(in, "extrude --method colouring");
  check_output_format(out, mesh.dim + 1);
  std::string how;
  std::vector<std::uint8_t> colour = colouring_of(mesh, in, barycentric, false, how);
  Mesh st = about_file(in, [&] { return extrude_coloured(mesh, colour, slices); });
  validate_result(st, out);
  write_output_mesh(outputs, h, st);
  outputs.commit();
  if (flags.json)
    print_json({{"output", out},
                {"dim", st.dim},
                {"cells", st.num_cells()},
                {"vertices", st.num_vertices()},
                {"colouring", how}});
  if (!flags.quiet)
    std::cerr << "bisect: wrote " << out << " (" << st.num_cells()
              << (st.dim == 4 ? " pentatopes, " : " tetrahedra, ") << st.num_vertices()
              << " vertices; tagged by the " << how << ")\n";
  return kExitOk;
}

struct ExtrudeArgs {
  std::string input, output, slices, method = "delaunay";
  bool force = false, barycentric = false, hull = false;
  CommonFlags flags;
};

int run_extrude(const ExtrudeArgs &a) {
  const std::vector<double> ts = parse_slices(a.slices);
  if (a.method == "colouring" && a.hull)
    throw UsageError("--hull needs --method delaunay");
  if (a.method == "colouring")
    return run_extrude_colouring(a.input, ts, a.barycentric, a.output, a.force, a.flags);
  if (a.barycentric)
    throw UsageError("--barycentric needs --method colouring");
  check_extension(a.output);
  {
    OutputSet probe({a.input}, a.force); // refuse a bad output before the work
    probe.add(a.output);
    check_output_format(a.output, 4);
  }
  Mesh mesh = read_mesh(a.input);
  prepare_input(mesh, a.input, load_progress(a.input, a.flags.quiet));
  if (mesh.dim != 3)
    throw InputError(a.input, "extrude needs a 3D tetrahedral mesh, this one is " +
                                  std::to_string(mesh.dim) + "D");
  Mesh m4 = about_file(a.input, [&] { return extrude_delaunay(mesh, ts, a.hull); });
  try {
    return write_generated(std::move(m4), a.output, a.force, a.flags, {a.input});
  } catch (const CheckError &e) {
    // Qhull's triangulation of nearly degenerate points (a slab far thinner
    // than the mesh, a mesh barely non-convex) can fail the validation.
    throw CheckError(std::string(e.what()) +
                     "; Delaunay could not triangulate these points robustly (slabs much "
                     "thinner than the mesh, or a mesh not quite convex): --method colouring "
                     "extrudes without Delaunay");
  }
}

} // namespace

Command add_extrude(CLI::App &app) {
  auto a = std::make_shared<ExtrudeArgs>();
  auto *cmd = app.add_subcommand(
      "extrude",
      "Extrude a 3D tetrahedral mesh over time slices into a 4D pentatope mesh (or, with "
      "--method colouring, a 2D triangle mesh into a 3D tetrahedral one).");
  cmd->footer("Example: bisect extrude cube.vtu --slices 0,0.5,1 -o spacetime.vtu\n"
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
  cmd->add_option("input", a->input, "3D mesh (.vtu or .msh); 2D too with --method colouring")
      ->required();
  cmd->add_option("--slices", a->slices, "T0,T1,... or START:STOP:COUNT (COUNT slabs)")->required();
  cmd->add_option("--method", a->method, "delaunay (default; 3D convex meshes) or colouring")
      ->check(CLI::IsMember({"delaunay", "colouring"}));
  cmd->add_flag("--barycentric", a->barycentric,
                "--method colouring: extrude the barycentric subdivision (always colourable)");
  cmd->add_option("--output,-o", a->output,
                  "Output 4D mesh (.vtu), or 3D mesh (.vtu or .msh) from a 2D one")
      ->required();
  cmd->add_flag("--force,-f", a->force, "Overwrite an existing file");
  cmd->add_flag("--hull", a->hull,
                "delaunay: accept a non-convex 3D mesh and fill the convex hull of its "
                "points (as seed 000 §5.2 does for a faceted sphere octant)");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_extrude(*a); }};
}

} // namespace bisect::cli
