// libFuzzer target: the TetGen (.node + .ele, split at the line "-- .ele --") reader. See docs/robustness.md.
#include "fuzz_target.hpp"

PALOVERDE_FUZZ_TARGET(MeshFormat::TetGen)
