// A rubber block with a slot, squeezed in a vise: a U-shaped body 2.2 wide (x), 1 deep (y) and 4
// high (z), a base 1 high and two arms 1 wide with a slot 0.2 wide between them. Its two outer
// sides are moved 0.12 towards each other (model.toml), so the slot closes and its walls press
// on each other: the slot's surface (both walls and its floor, one group) comes into contact
// with itself. Linear tetrahedra, unstructured, so that the two walls' meshes do not match.
//   gmsh -3 -format msh41 clip.geo -o clip.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2.2, 1, 4};
Box(2) = {1, -0.1, 1, 0.2, 1.2, 3.1};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Mesh.CharacteristicLengthMax = 0.2;
e = 1e-6;
Physical Volume("clip") = {3};
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -e, 2.2 + e, 1 + e, e};
Physical Surface("left") = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 4 + e};
Physical Surface("right") = Surface In BoundingBox{2.2 - e, -e, -e, 2.2 + e, 1 + e, 4 + e};
Physical Surface("slot") = Surface In BoundingBox{1 - e, -e, 1 - e, 1.2 + e, 1 + e, 4 + e};
// The slot's two walls on their own, for the comparison with a pair between two groups.
Physical Surface("left_wall") = Surface In BoundingBox{1 - e, -e, 1 - e, 1 + e, 1 + e, 4 + e};
Physical Surface("right_wall") = Surface In BoundingBox{1.2 - e, -e, 1 - e, 1.2 + e, 1 + e, 4 + e};
