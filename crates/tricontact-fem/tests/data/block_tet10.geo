// Unstructured quadratic tetrahedra in a 2 x 1 x 1 block.
// Regenerate: gmsh block_tet10.geo -3 -order 2 -format msh41 -o block_tet10.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 1};
Mesh.MeshSizeMax = 0.5;
Physical Volume("block") = {1};
Physical Surface("left") = {1};
Physical Surface("right") = {2};
Physical Point("corner") = {2};
