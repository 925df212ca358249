// Ball of radius 2 centred at the origin (seed 002, Section 5.2 input mesh).
// Unstructured tetrahedra, uniform target size; remade by scripts/make_data.sh:
//   gmsh data/ball.geo -3 -format msh41 -o data/ball.msh
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 2};

// Sizes live here (a command-line -clmax is ignored once MeshSizeMax is set).
Mesh.MeshSizeMin = 0.3;
Mesh.MeshSizeMax = 0.3;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 1;
Mesh.Algorithm = 6;      // Frontal-Delaunay on the surface
Mesh.Algorithm3D = 1;    // Delaunay in the volume
Mesh.RandomSeed = 1;     // fixed seed: the same file on every run
Mesh.Optimize = 1;
Mesh.OptimizeNetgen = 0;
Mesh.ElementOrder = 1;
General.NumThreads = 1;  // single thread: deterministic element order
Mesh.MaxNumThreads1D = 1;
Mesh.MaxNumThreads2D = 1;
Mesh.MaxNumThreads3D = 1;

Physical Surface("boundary", 2) = {1};
Physical Volume("ball", 1) = {1};
