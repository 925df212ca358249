// bisect generate simplex|kuhn: small meshes.
#include "cli.hpp"

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>

namespace bisect::cli {
namespace {

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

std::vector<Command> add_generate(CLI::App &app) {
  auto a = std::make_shared<GenerateArgs>();
  auto *gen_cmd = app.add_subcommand("generate", "Make small meshes: one simplex, or a Kuhn cube.");
  gen_cmd->footer(
      "Examples: bisect generate kuhn --dim 3 --cells 4 -o cube.vtu\n          bisect generate "
      "simplex --dim 4 -o pentatope.vtu   (each kind's --help lists its options)");
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
