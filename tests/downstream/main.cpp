// Refines a mesh in memory with the installed library: the README's example.
// Usage: downstream OUT.vtu
#include <bisect/bisect.hpp>

#include <iostream>

int main(int argc, char **argv) try {
  bisect::Mesh mesh = bisect::generate_kuhn(3, 4); // or bisect::load_mesh("ball.msh")
  bisect::ensure_marked(mesh);                     // keeps a file's marks when it has them
  auto region = bisect::parse_region(
      R"({"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.2})", mesh.dim, "sphere");
  bisect::DriverOptions options;
  options.iterations = 4;
  auto result = bisect::run_iterations(mesh, bisect::region_selector(*region), options,
                                       [](const bisect::IterationReport &r, bisect::Mesh &) {
                                         std::cout << "iteration " << r.iteration << ": " << r.cells
                                                   << " cells, min quality " << r.quality.min
                                                   << "\n";
                                       });
  std::vector<bisect::CellId> corner{0, 1}; // a solver's marked cells, two bisections deep
  bisect::refine_marked(mesh, corner, 2);
  if (!bisect::check_conformity(mesh).ok)
    return 2;
  if (argc > 1)
    bisect::save_mesh(argv[1], mesh); // with its bisection state
  std::cout << mesh.num_cells() << " cells after " << result.iterations << " iterations\n";
  return 0;
} catch (const bisect::Error &e) {
  std::cerr << "downstream: " << e.what() << "\n";
  return 1;
}
