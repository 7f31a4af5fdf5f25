// libFuzzer target: the VTK legacy (.vtk, ASCII and BINARY) reader. See docs/robustness.md.
#include "fuzz_target.hpp"

PALOVERDE_FUZZ_TARGET(MeshFormat::VtkLegacy)
