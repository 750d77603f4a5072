// A small block (1 x 1 x 0.5) standing on a larger base (2 x 2 x 0.5): two separate bodies
// meshed with hexahedra, touching at z = 0.5 with non-matching meshes.
//   gmsh -3 -format msh41 blocks.geo -o blocks.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 2, 0.5};
Box(2) = {0.6, 0.6, 0.5, 1, 1, 0.5};
e = 1e-6;
Transfinite Curve{:} = 2;
base[] = Curve In BoundingBox{-e, -e, -e, 2 + e, 2 + e, 0.5 + e};
Transfinite Curve{base[]} = 9;
block[] = Curve In BoundingBox{0.6 - e, 0.6 - e, 0.5 - e, 1.6 + e, 1.6 + e, 1 + e};
Transfinite Curve{block[]} = 6;
Transfinite Surface{:};
Recombine Surface{:};
Transfinite Volume{:};
Physical Volume("base") = {1};
Physical Volume("block") = {2};
Physical Surface("base_bottom") = Surface In BoundingBox{-e, -e, -e, 2 + e, 2 + e, e};
bottom[] = Surface In BoundingBox{0.6 - e, 0.6 - e, 0.5 - e, 1.6 + e, 1.6 + e, 0.5 + e};
top[] = Surface In BoundingBox{-e, -e, 0.5 - e, 2 + e, 2 + e, 0.5 + e};
top[] -= {bottom[]};
Physical Surface("base_top") = {top[]};
Physical Surface("block_bottom") = {bottom[]};
Physical Surface("block_top") = Surface In BoundingBox{0.6 - e, 0.6 - e, 1 - e, 1.6 + e, 1.6 + e, 1 + e};
