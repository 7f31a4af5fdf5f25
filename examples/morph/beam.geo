// A beam 4 x 0.5 x 0.5 of tetrahedra (examples/morph_study.py bends it).
SetFactory("OpenCASCADE");
Box(1) = {0, -0.25, -0.25, 4, 0.5, 0.5};
Mesh.CharacteristicLengthMin = 0.08;
Mesh.CharacteristicLengthMax = 0.08;
