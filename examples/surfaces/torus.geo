// A closed, smooth, doubly curved surface with no features: the basic test for sliding vertices on a surface.
// Triangles; ring radius R = 1, tube radius r = 0.35 (surface_study.py snaps to this exact torus).
SetFactory("OpenCASCADE");
Torus(1) = {0, 0, 0, 1, 0.35};
Physical Surface("torus") = Surface{:};
Mesh.MeshSizeMin = 0.08;
Mesh.MeshSizeMax = 0.08;
