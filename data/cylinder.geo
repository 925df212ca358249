// The "hyper-cylinder" of seed 002, Section 5.3, as a 2D+t space-time domain:
// the disk (x - 1/2)^2 + (y - 1/2)^2 <= 1 times 0 <= t <= 1, with t stored as
// the third coordinate (z). Unstructured tetrahedra sized to match the
// paper's initial mesh (3,781 tets, 712 vertices): size 0.32 on the boundary,
// 0.118 from 0.28 inwards (a finer interior gives the paper's ratio of about
// 5.3 tets per vertex; a uniform size gives about 4). Remade by
// scripts/make_data.sh:
//   gmsh data/cylinder.geo -3 -format msh41 -o data/cylinder.msh
SetFactory("OpenCASCADE");
Cylinder(1) = {0.5, 0.5, 0, 0, 0, 1, 1};

// Sizes come from the background field only.
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Field[1] = Distance;
Field[1].SurfacesList = {1, 2, 3};
Field[2] = Threshold;      // 0.32 at the boundary, 0.118 beyond distance 0.28
Field[2].InField = 1;
Field[2].SizeMin = 0.32;
Field[2].SizeMax = 0.118;
Field[2].DistMin = 0;
Field[2].DistMax = 0.28;
Background Field = 2;

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

Physical Surface("boundary", 2) = {1, 2, 3};
Physical Volume("cylinder", 1) = {1};
