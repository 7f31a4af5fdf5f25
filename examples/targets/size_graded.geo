// A unit box meshed with tetrahedra whose size grows from 0.02 near the edge x = y = 0 to 0.15
// away from it: a graded mesh whose sizes were designed.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Field[1] = Distance;
Field[1].CurvesList = {9};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.02;
Field[2].SizeMax = 0.15;
Field[2].DistMin = 0.05;
Field[2].DistMax = 0.6;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MshFileVersion = 2.2;
