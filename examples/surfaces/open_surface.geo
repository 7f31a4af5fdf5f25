// An open surface with a boundary curve: the saddle z = 0.6 x y over [-1, 1]^2 (OpenCASCADE fills its four straight
// edges with exactly this bilinear patch). Triangles; its boundary vertices must stay put; no sharp feature inside.
SetFactory("OpenCASCADE");
Point(1) = {-1, -1,  0.6};
Point(2) = { 1, -1, -0.6};
Point(3) = { 1,  1,  0.6};
Point(4) = {-1,  1, -0.6};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Surface(1) = {1};
Physical Surface("saddle") = Surface{:};
Mesh.MeshSizeMin = 0.05;
Mesh.MeshSizeMax = 0.05;
