// libFuzzer target: the Medit (.mesh) reader. See docs/robustness.md.
#include "fuzz_target.hpp"

PALOVERDE_FUZZ_TARGET(MeshFormat::Medit)
