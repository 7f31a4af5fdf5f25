// A coarse sphere of triangles, radius 1: the domain study's case whose facets are far from the
// sphere (about 0.6% of the radius at their centres).
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Physical Surface("sphere") = Surface{:};
Mesh.MeshSizeMin = 0.25;
Mesh.MeshSizeMax = 0.25;
