// A wall with a boundary layer: prisms (wedges) extruded from a triangulated wall z = 0 in
// layers graded from it, then tetrahedra above them up to z = 0.5.
SetFactory("Built-in");
lc = 0.08;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
// 12 layers: the first 1e-3 thick, each next one 1.3 times thicker.
n = 12;
h1 = 1e-3;
r = 1.3;
total = h1 * (r^n - 1) / (r - 1);
s = 0;
For i In {0 : n - 1}
  s += h1 * r^i;
  layers[i] = 1;
  heights[i] = s / total;
EndFor
layer[] = Extrude {0, 0, total} { Surface{1}; Layers{layers[], heights[]}; Recombine; };
above[] = Extrude {0, 0, 0.5 - total} { Surface{layer[0]}; };
Mesh.MshFileVersion = 2.2;
