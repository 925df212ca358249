// The unit sphere's octant x, y, z >= 0 (seed 000, Section 5.2 input mesh:
// the paper's has 40 nodes and 95 tets; this one has 38 and 77). Extruded one
// unit in t and re-triangulated by 4D Delaunay (`bisect extrude --hull`).
// Remade by scripts/make_data.sh:
//   gmsh data/octant.geo -3 -format msh41 -o data/octant.msh
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1, 0, Pi/2, Pi/2}; // polar angle 0..pi/2, azimuth 0..pi/2

Mesh.MeshSizeMin = 0.4;
Mesh.MeshSizeMax = 0.4;
Mesh.MeshSizeFromCurvature = 0;
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

Physical Volume("octant", 1) = {1};
