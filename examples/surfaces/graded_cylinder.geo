// An open cylinder of radius 1 of quadrilaterals graded along its axis, extruded from its bottom
// circle: 48 around, 20 rows, the first 0.01 high and each next 1.2 times the last (from a
// thirteenth of their width high to 2.4 times it). The targets-on-surfaces case (docs/surfaces.md).
n = 20;
first = 0.01;
growth = 1.2;
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {0, 1, 0};
Point(4) = {-1, 0, 0};
Point(5) = {0, -1, 0};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Transfinite Curve{1:4} = 13;  // 12 segments each
total = first * (growth^n - 1) / (growth - 1);
z = 0;
For i In {0:n-1}
  z += first * growth^i;
  counts[i] = 1;
  heights[i] = z / total;
EndFor
Extrude {0, 0, total} { Curve{1:4}; Layers{counts[], heights[]}; Recombine; }
Physical Surface("cylinder") = Surface{:};
