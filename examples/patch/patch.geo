// Contact patch test: an upper block (slave face at its bottom) pressed by a uniform pressure
// onto a lower block (master face at its top); both 1 x 1 x 0.5, on lateral rollers, so the
// stress is uniform and every slave node must carry the applied pressure exactly.
//
//   gmsh patch.geo -3 -format msh41 -setnumber tets 0 -setnumber nl 4 -setnumber nu 4 -o matching-hex.msh
//   gmsh patch.geo -3 -format msh41 -setnumber tets 0 -setnumber nl 3 -setnumber nu 5 -o nonmatching-hex.msh
//   gmsh patch.geo -3 -format msh41 -setnumber tets 1 -setnumber nl 3 -setnumber nu 5 -o nonmatching-tet.msh
//
// nl, nu: divisions per side of the lower and upper blocks (structured, so the two contact
// faces do not match when nl != nu); tets = 1 splits each structured cell into tet4 instead of
// one hex8.

SetFactory("OpenCASCADE");
DefineConstant[ nl = {3, Min 1, Max 50, Step 1}, nu = {5, Min 1, Max 50, Step 1}, tets = {0, Choices{0, 1}} ];

Box(1) = {0, 0, 0, 1, 1, 0.5};
Box(2) = {0, 0, 0.5, 1, 1, 0.5};
// OpenCASCADE numbers a box's faces xmin, xmax, ymin, ymax, zmin, zmax.
Physical Volume("lower_solid") = {1};
Physical Volume("upper_solid") = {2};
Physical Surface("lower_xmin") = {1};
Physical Surface("lower_xmax") = {2};
Physical Surface("lower_ymin") = {3};
Physical Surface("lower_ymax") = {4};
Physical Surface("lower_zmin") = {5};
Physical Surface("lower_zmax") = {6};
Physical Surface("upper_xmin") = {7};
Physical Surface("upper_xmax") = {8};
Physical Surface("upper_ymin") = {9};
Physical Surface("upper_ymax") = {10};
Physical Surface("upper_zmin") = {11};
Physical Surface("upper_zmax") = {12};

cl() = Unique(Abs(Boundary{ Surface{1:6}; }));
cu() = Unique(Abs(Boundary{ Surface{7:12}; }));
Transfinite Curve{cl()} = nl + 1;
Transfinite Curve{cu()} = nu + 1;
Transfinite Surface{1:12};
If (tets == 0)
  Recombine Surface{1:12};
EndIf
Transfinite Volume{1, 2};
Mesh.ElementOrder = 1;
