// Frictionless sliding across a faceted surface: a hex8 block (slave face at its bottom) is
// pressed onto an unstructured tet4 base (master face at its top, triangulated with edges in
// every direction) and slid 2.0 along x, crossing about ten facets per slave node.
//
//   gmsh sliding.geo -3 -format msh41 -o sliding.msh

SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 4, 1, 0.5};           // base
Box(2) = {0.5, 0.2, 0.5, 1, 0.6, 0.4};   // slider, 1 x 0.6 x 0.4
// OpenCASCADE numbers a box's faces xmin, xmax, ymin, ymax, zmin, zmax.
Physical Volume("base") = {1};
Physical Volume("slider") = {2};
Physical Surface("base_bottom") = {5};
Physical Surface("base_top") = {6};
Physical Surface("slider_bottom") = {11};
Physical Surface("slider_top") = {12};

MeshSize{ PointsOf{ Volume{1}; } } = 0.2;
cs() = Unique(Abs(Boundary{ Surface{7:12}; }));
Transfinite Curve{cs()} = 5;
Transfinite Surface{7:12};
Recombine Surface{7:12};
Transfinite Volume{2};
Mesh.ElementOrder = 1;
