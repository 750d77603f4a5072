// A wedge pressed into a V-groove. The base, 2 x 1 x 1, has a groove along y in its top: flanks
// from x = 0.5 and x = 1.5 down to the valley line x = 1, z = 0.75 (slopes of 26.6 degrees, a
// concave kink of 53 degrees between them). The wedge fills the groove between x = 0.6 and 1.4,
// y = 0.1 and 0.9, its bottom lying on the flanks, its top at z = 1.3. Hexahedra throughout; the
// wedge has four elements on each side of the valley line, so a row of its bottom nodes lies on
// it (the case one constraint per node cannot hold).
//   gmsh -3 -format msh41 v-groove.geo -o v-groove.msh

// A column of the cross-section in the plane y = y0: the quadrilateral from (x0, zb0), (x1, zb1)
// at the bottom to (x1, zt1), (x0, zt0) at the top, nx x nz transfinite quadrangles, extruded by
// dy along y in ny layers of hexahedra. Appends its volume, bottom face and top face to vols[],
// bottoms[] and tops[].
Macro Column
  p1 = newp; Point(p1) = {x0, y0, zb0};
  p2 = newp; Point(p2) = {x1, y0, zb1};
  p3 = newp; Point(p3) = {x1, y0, zt1};
  p4 = newp; Point(p4) = {x0, y0, zt0};
  l1 = newl; Line(l1) = {p1, p2};
  l2 = newl; Line(l2) = {p2, p3};
  l3 = newl; Line(l3) = {p3, p4};
  l4 = newl; Line(l4) = {p4, p1};
  Transfinite Curve{l1, l3} = nx + 1;
  Transfinite Curve{l2, l4} = nz + 1;
  c = newcl; Curve Loop(c) = {l1, l2, l3, l4};
  s = news; Plane Surface(s) = {c};
  Transfinite Surface{s};
  Recombine Surface{s};
  // out[1]: the volume; out[2], out[4]: the faces swept by l1 (bottom) and l3 (top).
  out[] = Extrude {0, dy, 0} { Surface{s}; Layers{ny}; Recombine; };
  vols[] += {out[1]};
  bottoms[] += {out[2]};
  tops[] += {out[4]};
Return

// The base: four columns (flat, left flank, right flank, flat) of 4 x 4 x 4 elements.
vols[] = {}; bottoms[] = {}; tops[] = {};
y0 = 0; dy = 1; nx = 4; ny = 4; nz = 4;
xs[] = {0, 0.5, 1, 1.5, 2};
floor[] = {1, 1, 0.75, 1, 1};
For k In {0:3}
  x0 = xs[k]; x1 = xs[k + 1];
  zb0 = 0; zb1 = 0; zt0 = floor[k]; zt1 = floor[k + 1];
  Call Column;
EndFor
base[] = vols[]; base_bottom[] = bottoms[]; base_top[] = tops[];

// The wedge: two columns, 4 x 3 x 3 elements each, its bottom on the flanks (z = 0.95 at
// x = 0.6 and 1.4, 0.75 at the valley line).
vols[] = {}; bottoms[] = {}; tops[] = {};
y0 = 0.1; dy = 0.8; nx = 4; ny = 3; nz = 3;
xs[] = {0.6, 1, 1.4};
floor[] = {0.95, 0.75, 0.95};
For k In {0:1}
  x0 = xs[k]; x1 = xs[k + 1];
  zb0 = floor[k]; zb1 = floor[k + 1]; zt0 = 1.3; zt1 = 1.3;
  Call Column;
EndFor


Physical Volume("base") = {base[]};
Physical Volume("wedge") = {vols[]};
Physical Surface("base_bottom") = {base_bottom[]};
Physical Surface("base_top") = {base_top[]};
Physical Surface("wedge_bottom") = {bottoms[]};
Physical Surface("wedge_top") = {tops[]};
