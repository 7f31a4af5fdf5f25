// A planar box with an elongated elliptic hole (an airfoil-like obstacle) of triangles, fine
// near the hole (examples/morph_study.py pitches the hole).
SetFactory("OpenCASCADE");
Rectangle(1) = {-2, -1.5, 0, 4, 3};
Disk(2) = {0, 0, 0, 0.6, 0.08};
BooleanDifference(3) = { Surface{1}; Delete; }{ Surface{2}; Delete; };
Field[1] = Distance;
Field[1].CurvesList = {5};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.02; Field[2].SizeMax = 0.15;
Field[2].DistMin = 0.02; Field[2].DistMax = 1.0;
Background Field = 2;
Mesh.CharacteristicLengthExtendFromBoundary = 0;
