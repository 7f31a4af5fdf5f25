// The beam of beam.geo as 6 x 6 x 50 hexahedra (examples/morph_study.py bends it).
Point(1) = {0, -0.25, -0.25, 1};
Point(2) = {0, 0.25, -0.25, 1};
Point(3) = {0, 0.25, 0.25, 1};
Point(4) = {0, -0.25, 0.25, 1};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1:4} = 7;
Transfinite Surface{1};
Recombine Surface{1};
Extrude {4, 0, 0} { Surface{1}; Layers{50}; Recombine; }
