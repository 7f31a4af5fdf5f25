// An open tube of triangles: radius 1 about the z axis, 3 long, its two rims open (the domain
// study's cylinder).
SetFactory("OpenCASCADE");
Circle(1) = {0, 0, 0, 1};
Extrude {0, 0, 3} { Curve{1}; }
Physical Surface("tube") = Surface{:};
Mesh.MeshSizeMin = 0.2;
Mesh.MeshSizeMax = 0.2;
