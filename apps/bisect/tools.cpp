// bisect colour, extrude, slice, generate: the tools around refinement.
#include "cli.hpp"

#include <algorithm>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

// Reads a 2D or 3D mesh for `colour` and `extrude --method colouring`.
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
    write_mesh_file(outputs.file(h), out, mesh);
    outputs.commit();
    if (!a.flags.quiet)
      std::cerr << "bisect: wrote " << out << " (" << mesh.num_cells() << " cells, "
                << mesh.num_vertices() << " vertices, point array " << kColourArray << ")\n";
  }
  return kExitOk;
}

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
  Mesh st;
  try {
    st = extrude_coloured(mesh, colour, slices);
  } catch (const InputError &e) {
    throw InputError(in, e.what());
  }
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
  prepare_input(mesh, a.input);
  if (mesh.dim != 3)
    throw InputError(a.input, "extrude needs a 3D tetrahedral mesh, this one is " +
                                  std::to_string(mesh.dim) + "D");
  Mesh m4;
  try {
    m4 = extrude_delaunay(mesh, ts, a.hull);
  } catch (const InputError &e) {
    throw InputError(a.input, e.what());
  }
  return write_generated(std::move(m4), a.output, a.force, a.flags, {a.input});
}

struct SliceArgs {
  std::string input, output, axis = "t";
  double value = 0;
  bool force = false;
  CommonFlags flags;
};

int run_slice(const SliceArgs &a) {
  check_extension(a.output);
  OutputSet outputs({a.input}, a.force);
  const int h = outputs.add(a.output);
  Mesh mesh = read_mesh(a.input);
  prepare_input(mesh, a.input);
  if (mesh.dim < 3)
    throw InputError(a.input, "slice needs a 3D or 4D mesh, this one is 2D");
  const int axis = a.axis == "t" ? mesh.dim - 1 : int(std::string("xyz").find(a.axis[0]));
  if (axis >= mesh.dim)
    throw UsageError("slice: a 3D mesh has no axis " + a.axis);
  const std::string line = write_slice(mesh, axis, a.value, outputs, h);
  outputs.commit();
  if (a.flags.json)
    print_json({{"input", a.input}, {"output", a.output}, {"axis", a.axis}, {"value", a.value}});
  if (!a.flags.quiet)
    std::cerr << line;
  return kExitOk;
}

struct GenerateArgs {
  int dim = 3;
  std::string shape = "equilateral", output, type;
  std::uint64_t seed = 1;
  bool force = false;
  int cells = 2;
  double lo = 0, hi = 1;
  std::vector<double> box;
  CommonFlags flags;
};

int run_simplex(const GenerateArgs &a) {
  const SimplexShape s = a.shape == "cartesian" ? SimplexShape::Cartesian
                         : a.shape == "random"  ? SimplexShape::Random
                                                : SimplexShape::Equilateral;
  Mesh simplex = generate_simplex(a.dim, s, a.seed);
  if (!a.type.empty()) {
    try {
      force_type(simplex, a.type);
    } catch (const UsageError &e) {
      throw UsageError(std::string("generate simplex --type: ") + e.what());
    }
  }
  return write_generated(std::move(simplex), a.output, a.force, a.flags);
}

int run_kuhn(const GenerateArgs &a) {
  double lo = a.lo, hi = a.hi;
  if (a.box.size() == 2)
    lo = a.box[0], hi = a.box[1];
  if (!(lo < hi))
    throw UsageError("generate kuhn: --lo must be below --hi");
  return write_generated(generate_kuhn(a.dim, a.cells, lo, hi), a.output, a.force, a.flags);
}

} // namespace

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
  cmd->add_option("input", a->input, "2D or 3D mesh (.vtu or .msh)")->required();
  cmd->add_flag(
      "--barycentric", a->barycentric,
      "Subdivide barycentrically (6 triangles / 24 tets per cell), coloured by vertex kind");
  cmd->add_flag("--recompute", a->recompute, "Ignore a 'colour' array in the input");
  cmd->add_option("--output,-o", a->output, "Write the mesh with the point array 'colour'");
  cmd->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_colour(*a); }};
}

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

Command add_slice(CLI::App &app) {
  auto a = std::make_shared<SliceArgs>();
  auto *cmd = app.add_subcommand(
      "slice", "Cut a 4D mesh by the hyperplane {axis = value} into a conforming 3D tetrahedral "
               "mesh for ParaView (prisms are split into three tetrahedra), or a 3D (2D+t) mesh "
               "by a plane into a conforming triangle mesh.");
  cmd->footer("Example: bisect slice hypercube-25.vtu --t 0.5 -o section.vtu");
  cmd->add_option("input", a->input, "4D mesh (.vtu), or 3D mesh")->required();
  auto *t_opt = cmd->add_option("--t", a->value, "Shorthand for --axis t --value VALUE");
  cmd->add_option("--axis", a->axis,
                  "x, y, z or t (default t: the last coordinate, z of a 3D mesh)")
      ->check(CLI::IsMember({"x", "y", "z", "t"}));
  cmd->add_option("--value", a->value, "Where the hyperplane cuts the axis")->excludes(t_opt);
  cmd->add_option("--output,-o", a->output, "Output 3D mesh (.vtu or .msh)")->required();
  cmd->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(cmd, a->flags);
  return {cmd, [a] { return run_slice(*a); }};
}

std::vector<Command> add_generate(CLI::App &app) {
  auto a = std::make_shared<GenerateArgs>();
  auto *gen_cmd = app.add_subcommand("generate", "Make small meshes: one simplex, or a Kuhn cube.");
  gen_cmd->require_subcommand(1);
  auto *simplex = gen_cmd->add_subcommand("simplex", "One simplex.");
  simplex->footer("Examples: bisect generate simplex --dim 3 --shape random --seed 7 -o tet.vtu\n"
                  "          bisect generate simplex --dim 4 --type A_PO -o apo.vtu");
  simplex->add_option("--dim,-d", a->dim, "2, 3 or 4")->check(CLI::Range(2, 4));
  simplex->add_option("--shape", a->shape, "equilateral, cartesian or random")
      ->check(CLI::IsMember({"equilateral", "cartesian", "random"}));
  simplex->add_option("--seed", a->seed, "Seed for --shape random");
  simplex->add_option("--type", a->type,
                      "Force the marks to a type (seed 000 §3.2): for --dim 4 e.g. P_PP, P_AA, "
                      "A_PO (level-1 relation, then the two level-2 relations); for --dim 3 "
                      "P, A, O or M. Stored as an explicit edge order in the file");
  simplex->add_option("--output,-o", a->output, "Output mesh")->required();
  simplex->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(simplex, a->flags);
  auto *kuhn =
      gen_cmd->add_subcommand("kuhn", "Freudenthal-Kuhn cubes: K^dim cubes of dim! simplices.");
  kuhn->footer("Example: bisect generate kuhn --dim 3 --cells 4 -o cube.vtu");
  kuhn->add_option("--dim,-d", a->dim, "2, 3 or 4")->check(CLI::Range(2, 4));
  kuhn->add_option("--cells,-k", a->cells, "Cubes per side")->check(CLI::Range(1, 1000));
  kuhn->add_option("--lo", a->lo, "Lower corner coordinate (default 0)");
  kuhn->add_option("--hi", a->hi, "Upper corner coordinate (default 1)");
  kuhn->add_option("--box", a->box, "LO,HI: the cube [LO,HI]^dim (same as --lo LO --hi HI)")
      ->delimiter(',')
      ->expected(2);
  kuhn->add_option("--output,-o", a->output, "Output mesh")->required();
  kuhn->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(kuhn, a->flags);
  return {{simplex, [a] { return run_simplex(*a); }}, {kuhn, [a] { return run_kuhn(*a); }}};
}

} // namespace bisect::cli
