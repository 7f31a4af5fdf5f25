// A box with an elongated block-shaped hole, of tetrahedra, fine near the hole
// (examples/morph_study.py turns the hole about z).
SetFactory("OpenCASCADE");
Box(1) = {-1,-1,-0.8, 2,2,1.6};
Box(2) = {-0.5,-0.08,-0.5, 1.0,0.16,1.0};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Mesh.CharacteristicLengthMin = 0.06;
Mesh.CharacteristicLengthMax = 0.2;
Field[1] = Box;
Field[1].VIn = 0.06; Field[1].VOut = 0.2;
Field[1].XMin = -0.7; Field[1].XMax = 0.7;
Field[1].YMin = -0.3; Field[1].YMax = 0.3;
Field[1].ZMin = -0.7; Field[1].ZMax = 0.7;
Field[1].Thickness = 0.3;
Background Field = 1;
