// A box with a torus-shaped hole about the z axis, of tetrahedra, uniform in size
// (examples/morph_study.py turns the torus about its own axis: its surface maps onto itself and
// the elements between it and the box are sheared around it).
SetFactory("OpenCASCADE");
Box(1) = {-3,-3,-1.5, 6,6,3};
Torus(2) = {0,0,0, 1.8, 0.6};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Mesh.CharacteristicLengthMax = 0.22;
