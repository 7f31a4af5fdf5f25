// A CAD-like part with sharp edges and corners: a block with a step cut out of one end (convex and concave
// 90-degree edges) and a round hole through it. Triangles; its feature curves must stay put when smoothed.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 0.6};
Box(2) = {1.4, -0.1, 0.3, 0.7, 1.2, 0.4};
Cylinder(3) = {0.7, 0.5, -0.1, 0, 0, 0.8, 0.25};
BooleanDifference(4) = {Volume{1}; Delete;}{Volume{2, 3}; Delete;};
Physical Surface("part") = Surface{:};
Mesh.MeshSizeMin = 0.06;
Mesh.MeshSizeMax = 0.06;
