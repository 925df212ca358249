// bisect slice: sections of 4D and 3D meshes.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

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
  prepare_input(mesh, a.input, load_progress(a.input, a.flags.quiet));
  if (mesh.dim < 3)
    throw InputError(a.input, "slice needs a 3D or 4D mesh, this one is 2D");
  // x, y, z or t: below the dimension of a 3D or 4D mesh (z is t in 3D).
  const int axis = a.axis == "t" ? mesh.dim - 1 : int(std::string("xyz").find(a.axis[0]));
  const SliceWritten s = write_slice(mesh, axis, a.value, outputs, h);
  outputs.commit();
  if (a.flags.json)
    print_json({{"input", a.input},
                {"output", a.output},
                {"axis", a.axis},
                {"value", a.value},
                {"dim", s.dim},
                {"cells", s.cells},
                {"vertices", s.vertices}});
  if (!a.flags.quiet)
    std::cerr << s.line;
  return kExitOk;
}

} // namespace

Command add_slice(CLI::App &app) {
  auto a = std::make_shared<SliceArgs>();
  auto *cmd = app.add_subcommand(
      "slice", "Cut a 4D mesh by the hyperplane {axis = value} into a conforming 3D tetrahedral "
               "mesh for ParaView (prisms are split into three tetrahedra), or a 3D (2D+t) mesh "
               "by a plane into a conforming triangle mesh.");
  cmd->footer("Example: bisect slice hypercube-25.vtu --t 0.5 -o section.vtu\n"
              "The cut coordinate is dropped, the others kept in order as x, y(, z): a 4D "
              "mesh cut at t keeps (x, y, z), at --axis x gives (y, z, t) as (x, y, z); a 3D "
              "mesh cut at t (its z) gives (x, y) in the plane z = VALUE, at --axis x gives "
              "(y, z) as (x, y) in the plane z = 0.");
  cmd->add_option("input", a->input, "4D mesh (.vtu), or 3D mesh (- reads standard input)")
      ->required();
  auto *t_opt = cmd->add_option("--t", a->value, "Shorthand for --axis t --value VALUE");
  cmd->add_option("--axis", a->axis,
                  "x, y, z or t (default t: the last coordinate, z of a 3D mesh)")
      ->check(CLI::IsMember({"x", "y", "z", "t"}))
      ->excludes(t_opt);
  auto *value_opt =
      cmd->add_option("--value", a->value, "Where the hyperplane cuts the axis")->excludes(t_opt);
  cmd->add_option("--output,-o", a->output, "Output 3D mesh (.vtu or .msh)")->required();
  cmd->add_flag("--force,-f", a->force, "Overwrite an existing file");
  add_common_flags(cmd, a->flags);
  return {cmd, [a, t_opt, value_opt] {
            // No default cut: a forgotten value is not silently 0.
            if (t_opt->count() == 0 && value_opt->count() == 0)
              throw UsageError("slice: give where to cut: --t VALUE, or --axis AXIS --value VALUE");
            return run_slice(*a);
          }};
}

} // namespace bisect::cli
