// Cantilever beam 10 x 1 x 1 meshed with 20 x 2 x 2 hexahedra (hex8).
// Regenerate: gmsh beam.geo -3 -format msh41 -o beam.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 10, 1, 1};
Transfinite Curve{:} = 3;
Transfinite Curve{9, 10, 11, 12} = 21;
Transfinite Surface{:};
Recombine Surface{:};
Transfinite Volume{1};
Physical Volume("beam") = {1};
Physical Surface("clamp") = {1};
Physical Surface("tip") = {2};
Physical Surface("top") = {4};
Mesh.MshFileVersion = 4.1;
