// libFuzzer target: the Gmsh (.msh 2.2 and 4.1, ASCII and binary) reader. See docs/robustness.md.
#include "fuzz_target.hpp"

PALOVERDE_FUZZ_TARGET(MeshFormat::Gmsh)
