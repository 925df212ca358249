// Unit square [0,1]^2 in the plane z = 0: unstructured triangles, uniform size.
// Remade by scripts/make_data.sh:
//   gmsh data/square.geo -2 -format msh41 -o data/square.msh
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {1, 1, 0};
Point(4) = {0, 1, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Mesh.MeshSizeMin = 0.08;
Mesh.MeshSizeMax = 0.08;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;      // Frontal-Delaunay
Mesh.RandomSeed = 1;     // fixed seed: the same file on every run
Mesh.ElementOrder = 1;
General.NumThreads = 1;
Mesh.MaxNumThreads1D = 1;
Mesh.MaxNumThreads2D = 1;

Physical Curve("boundary", 2) = {1, 2, 3, 4};
Physical Surface("square", 1) = {1};
