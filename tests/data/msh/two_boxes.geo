// Two unit cubes sharing the face x = 1, coarse tetrahedra, for the .msh
// reader tests: the same mesh saved in the four formats bisect reads.
// Remade by (from this directory):
//   gmsh two_boxes.geo -3 -format msh22 -o two_boxes_22a.msh
//   gmsh two_boxes.geo -3 -format msh22 -bin -o two_boxes_22b.msh
//   gmsh two_boxes.geo -3 -format msh41 -o two_boxes_41a.msh
//   gmsh two_boxes.geo -3 -format msh41 -bin -o two_boxes_41b.msh
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {1, 1, 0};
Point(4) = {0, 1, 0};
Point(5) = {2, 0, 0};
Point(6) = {2, 1, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Line(5) = {2, 5};
Line(6) = {5, 6};
Line(7) = {6, 3};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, -2};
Plane Surface(2) = {2};
Extrude {0, 0, 1} { Surface{1, 2}; Layers{1}; }

Mesh.MeshSizeMin = 1;
Mesh.MeshSizeMax = 1;
Mesh.RandomSeed = 1;
General.NumThreads = 1;

Physical Volume("left", 10) = {1};
Physical Volume("right", 20) = {2};
Physical Surface("bottom", 3) = {1, 2};
