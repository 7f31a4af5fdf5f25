// A sphere of quadrilaterals (recombined), radius 1: the surface study's closed quadrilateral case.
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Physical Surface("sphere") = Surface{:};
Mesh.MeshSizeMin = 0.15;
Mesh.MeshSizeMax = 0.15;
Mesh.Algorithm = 6;           // frontal-Delaunay (8, meant for quads, crashes in Gmsh 4.8.4 on this sphere)
Mesh.RecombineAll = 1;
Mesh.SubdivisionAlgorithm = 1; // split what recombination leaves so that every element is a quad
