// Hertz contact: an elastic sphere (R = 20 mm) pressed onto a rigid flat.
// Quarter model (x >= 0, y >= 0) of the lower hemisphere, centre (0, 0, R), touching the flat
// z = 0 at the origin. Linear tetrahedra, refined around the contact point.
//
// Generate the three levels with
//   gmsh hertz.geo -3 -format msh41 -setnumber level 1 -o hertz-coarse.msh
//   gmsh hertz.geo -3 -format msh41 -setnumber level 2 -o hertz-medium.msh
//   gmsh hertz.geo -3 -format msh41 -setnumber level 3 -o hertz-fine.msh
//
// Physical groups: volume "sphere"; surfaces "contact" (the curved face, slave), "sym_x" (x = 0),
// "sym_y" (y = 0), "top" (the equatorial cut z = R, where the load is applied) and "flat"
// (the rigid flat z = 0, master, fully prescribed).

SetFactory("OpenCASCADE");
R = 20;
L = 5;                               // half-width of the quarter flat (contact radius ~ 1.1 mm)
DefineConstant[ level = {1, Min 1, Max 3, Step 1} ];
hc = 0.3 / 2^(level - 1);            // element size at the contact point: 0.3, 0.15, 0.075 mm
hf = 4.0 / 2^((level - 1) / 2);      // element size far from it: 4, 2.8, 2 mm

Sphere(1) = {0, 0, R, R, -Pi/2, 0, Pi/2};
Rectangle(100) = {0, 0, 0, L, L};

e = 1e-6;
symx() = Surface In BoundingBox{-e, -e, -e, e, R + e, R + e};
symy() = Surface In BoundingBox{-e, -e, -e, R + e, e, R + e};
top() = Surface In BoundingBox{-e, -e, R - e, R + e, R + e, R + e};
all() = Boundary{ Volume{1}; };
curved() = all();
curved() -= symx();
curved() -= symy();
curved() -= top();

Physical Volume("sphere") = {1};
Physical Surface("contact") = curved();
Physical Surface("sym_x") = symx();
Physical Surface("sym_y") = symy();
Physical Surface("top") = top();
Physical Surface("flat") = {100};

Point(1000) = {0, 0, 0};
Field[1] = Distance;
Field[1].PointsList = {1000};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hc;
Field[2].SizeMax = hf;
Field[2].DistMin = 1.6;
Field[2].DistMax = 14;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.ElementOrder = 1;
