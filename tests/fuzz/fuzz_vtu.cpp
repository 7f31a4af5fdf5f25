// libFuzzer target: the VTK XML (.vtu: ascii, base64, appended raw or base64, zlib) reader. See docs/robustness.md.
#include "fuzz_target.hpp"

PALOVERDE_FUZZ_TARGET(MeshFormat::Vtu)
