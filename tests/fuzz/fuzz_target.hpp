#pragma once
// The body of every fuzz target: LLVMFuzzerTestOneInput for one format. Each process reads its
// inputs through a scratch directory of its own, made in $PALOVERDE_FUZZ_SCRATCH (the CTest runs
// and tests/fuzz/long_run.sh point it into the build directory, which they clear) or else in the
// system's temporary directory, and removed when the process ends normally. (A crash ends it
// abnormally, and leaves the directory behind with the input in it.)
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fuzz_input.hpp"

namespace paloverde::fuzz {

inline const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        const char* chosen = std::getenv("PALOVERDE_FUZZ_SCRATCH");
        const std::filesystem::path base = chosen && *chosen ? std::filesystem::path(chosen)
                                                              : std::filesystem::temp_directory_path();
        std::filesystem::create_directories(base);
        std::string pattern = (base / "paloverde_fuzz_XXXXXX").string();
        if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a scratch directory in " + base.string());
        return std::filesystem::path(pattern);
    }();
    static const bool cleanup = [] {
        std::atexit([] {
            std::error_code ignored;
            std::filesystem::remove_all(scratch_dir(), ignored);
        });
        return true;
    }();
    (void)cleanup;
    return dir;
}

inline int fuzz_one(MeshFormat format, const std::uint8_t* data, std::size_t size) {
    read_input(scratch_dir(), format, std::string_view(reinterpret_cast<const char*>(data), size));
    return 0;
}

}  // namespace paloverde::fuzz

// One line per target: PALOVERDE_FUZZ_TARGET(MeshFormat::Gmsh)
#define PALOVERDE_FUZZ_TARGET(format)                                                       \
    extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {    \
        return paloverde::fuzz::fuzz_one(paloverde::format, data, size);                   \
    }
