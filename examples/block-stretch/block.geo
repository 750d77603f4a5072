// 2 x 1 x 1 block, unstructured quadratic tetrahedra (tet10, tri6 faces).
// Regenerate: gmsh block.geo -3 -order 2 -format msh41 -o block.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 1};
Mesh.MeshSizeMax = 0.35;
Physical Volume("block") = {1};
Physical Surface("left") = {1};
Physical Surface("right") = {2};
Physical Surface("top") = {6};
