// bisect: conformal local refinement of triangle, tetrahedral and 4D
// simplicial meshes by edge bisection. The umbrella header of the library
// (README, "Library"): link bisect::bisect and include this.
//
//   bisect::Mesh mesh = bisect::load_mesh("ball.msh");  // validated, state restored
//   bisect::ensure_marked(mesh);                          // marks unless the file had marks
//   auto region = bisect::read_region("sphere.json", mesh.dim);
//   bisect::DriverOptions options;
//   options.iterations = 5;
//   bisect::run_iterations(mesh, bisect::region_selector(*region), options);
//   bisect::save_mesh("ball-5.vtu", mesh);                // with its bisection state
#pragma once

#include "bisect/check.hpp"     // conformity checks, input validation
#include "bisect/coarsen.hpp"   // coarsening along the bisection tree
#include "bisect/colour.hpp"    // vertex colourings (tools)
#include "bisect/driver.hpp"    // the iteration driver, refine by marked cells
#include "bisect/error.hpp"     // bisect::Error and its kinds
#include "bisect/extrude.hpp"   // space-time extrusion (tools)
#include "bisect/generate.hpp"  // simplices and Kuhn cubes (tools)
#include "bisect/indicator.hpp" // marking by an error indicator
#include "bisect/io.hpp"        // .vtu and .msh, load_mesh / save_mesh
#include "bisect/mark.hpp"      // marking: global edge orders, ensure_marked
#include "bisect/measure.hpp"   // volumes, quality, similarity classes
#include "bisect/mesh.hpp"      // the mesh: flat arrays
#include "bisect/output.hpp"    // outputs written as one transaction
#include "bisect/refine.hpp"    // bisection and refine to conformity
#include "bisect/region.hpp"    // region specs and selection
#include "bisect/slice.hpp"     // sections of 3D and 4D meshes (tools)
#include "bisect/state.hpp"     // the bisection state in files
#include "bisect/text.hpp"      // one_line, with_commas
#include "bisect/threads.hpp"   // how many threads the parallel loops use
