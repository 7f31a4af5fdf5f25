#!/usr/bin/env bash
# Sets up Paloverde on Debian bookworm and runs the main job or every test.
#   bash scripts/setup.sh run     install the packages the program needs, build the library and the
#                                 `paloverde` program only, untangle + improve the bundled example
#   bash scripts/setup.sh test    install every package, build everything, run every test
#   bash scripts/setup.sh build   install every package and build everything
#   bash scripts/setup.sh sanitize   build with AddressSanitizer + UBSan (build-sanitize/) and run
#                                    the tests there (all but the install check, which links a
#                                    downstream program without the sanitizers)
#   bash scripts/setup.sh fuzz       build the libFuzzer targets of the mesh readers and the
#                                    config reader with clang (build-fuzz/) and run each for a
#                                    short fixed number of inputs (docs/robustness.md)
# Run as root (or with sudo available). Set PALOVERDE_BUILD_DIR to build elsewhere than ./build,
# and PALOVERDE_MPI=OFF for `run`, `test` and `build` without MPI (serial only: docs/parallel.md).
set -euo pipefail
cd "$(dirname "$0")/.."

# Every Debian package the library, the program and the tests need, in one place.
PACKAGES=(
  build-essential cmake
  ccache                              # rebuilds (three builds in CI) compile only what changed
  libopenmpi-dev openmpi-bin          # MPI
  libmetis-dev                        # partitioning
  libcgal-dev                         # exact predicates
  libopenmesh-dev                     # the OpenMesh adapter
  libboost-test-dev                   # tests
  libcli11-dev nlohmann-json3-dev     # command line, JSON
  libyaml-cpp-dev                     # config files (paloverde run)
  zlib1g-dev                          # compressed .vtu
)
# For the example scripts and the benchmark meshes only (`run` leaves them out: matplotlib alone brings
# numpy, fonts and image libraries).
EXAMPLE_PACKAGES=(
  python3-matplotlib                  # plots of examples/compare_methods.py, solver_race.py, study.py
  tetgen                              # benchmark meshes (docs/global_solver.md)
)
# The Python package and its tests (wrappers/python, tests/python): `run` leaves them out too.
PYTHON_PACKAGES=(
  python3-dev pybind11-dev            # the extension module
  python3-numpy python3-meshio python3-pytest
)
# For `fuzz` only: clang, its libFuzzer runtime and its OpenMP (the config target links the
# whole library).
FUZZ_PACKAGES=(clang libclang-rt-dev libomp-dev)

install_packages() {  # also installs the packages given as arguments
  local missing=()
  for p in "${PACKAGES[@]}" "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "Installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# Compiles go through ccache where it is installed. Paths are taken relative to the checkout and
# the build directory is left out of the hash, so that another clone (CI's) reuses the objects.
# (Called once the packages are installed.)
LAUNCHER=()
use_compiler_cache() {
  command -v ccache >/dev/null || return 0
  LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=true
}

BUILD_DIR=${PALOVERDE_BUILD_DIR:-build}
build() {  # PYTHON=ON|OFF, then the targets given as arguments (--target NAME), or everything
  local python=$1
  shift
  use_compiler_cache
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DPALOVERDE_PYTHON="$python" \
    -DPALOVERDE_MPI="${PALOVERDE_MPI:-ON}" "${LAUNCHER[@]}"
  cmake --build "$BUILD_DIR" -j "$(nproc)" "$@"
}

case "${1:-}" in
  run)
    install_packages
    # The program and the library it links, not the tests, examples and benchmarks.
    build OFF --target paloverde_cli
    "$BUILD_DIR/bin/paloverde" improve examples/data/tangled_cube.vtk -o "$BUILD_DIR/tangled_cube_improved.vtk"
    echo "Improved mesh written to $BUILD_DIR/tangled_cube_improved.vtk"
    ;;
  test)
    install_packages "${EXAMPLE_PACKAGES[@]}" "${PYTHON_PACKAGES[@]}"
    build ON
    ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)"
    ;;
  build)
    install_packages "${EXAMPLE_PACKAGES[@]}" "${PYTHON_PACKAGES[@]}"
    build ON
    ;;
  sanitize)
    install_packages
    use_compiler_cache
    cmake --preset sanitize "${LAUNCHER[@]}"
    cmake --build --preset sanitize -j "$(nproc)"
    ctest --preset sanitize
    ;;
  fuzz)
    install_packages "${FUZZ_PACKAGES[@]}"
    use_compiler_cache
    cmake --preset fuzz "${LAUNCHER[@]}"
    cmake --build --preset fuzz -j "$(nproc)"
    ctest --preset fuzz
    ;;
  *)
    echo "usage: bash scripts/setup.sh run|test|build|sanitize|fuzz" >&2
    exit 2
    ;;
esac
