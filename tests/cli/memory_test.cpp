// The command line keeps the memory it frees (paloverde::keep_freed_memory, called first in main):
// a large block freed stays in the heap for the next one instead of going back to the kernel.
// malloc's blocks, that is: the program's operator new maps arrays of 2 MiB and more on huge pages
// of their own, except where the host takes freed memory back (huge_pages_test.cpp).
#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "paloverde/core/memory.hpp"
#include "transparent_huge_pages.hpp"

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#include <malloc.h>
#define PALOVERDE_GLIBC_MALLOC 1
#endif

BOOST_AUTO_TEST_SUITE(memory)

BOOST_AUTO_TEST_CASE(a_freed_large_array_stays_in_the_heap) {
#ifdef PALOVERDE_GLIBC_MALLOC
    paloverde::keep_freed_memory();
    constexpr std::size_t bytes = std::size_t{64} << 20;  // twice glibc's largest dynamic mmap threshold
    const auto before = mallinfo2();
    auto held = before;
    {
        char* big = static_cast<char*>(std::malloc(bytes));
        BOOST_TEST_REQUIRE(big != nullptr);
        std::memset(big, 1, bytes);
        asm volatile("" : : "r"(big) : "memory");  // the block is used: not elided
        held = mallinfo2();
        std::free(big);
    }
    const auto after = mallinfo2();
    BOOST_TEST(held.hblkhd == before.hblkhd);  // not a mapping of its own: in the heap
    BOOST_TEST(held.arena >= bytes);
    BOOST_TEST(after.arena == held.arena);  // freed, and not handed back
    BOOST_TEST(after.fordblks >= bytes);
#else
    BOOST_TEST_MESSAGE("not glibc's allocator (a sanitizer's, or another C library): nothing to check");
#endif
}

namespace {

// The VmFlags of each part of the heap (/proc/self/smaps: the mappings named [heap]).
std::vector<std::string> heap_flags() {
    std::vector<std::string> flags;
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool heap = false;
    while (std::getline(smaps, line)) {
        std::uintptr_t low = 0, high = 0;
        char dash = 0;
        std::istringstream head(line);
        if (head >> std::hex >> low >> dash >> high && dash == '-') heap = line.ends_with("[heap]");
        else if (heap && line.rfind("VmFlags:", 0) == 0) flags.push_back(line);
    }
    return flags;
}

}  // namespace

BOOST_AUTO_TEST_CASE(the_kept_heap_is_advised_for_huge_pages) {
#if defined(PALOVERDE_GLIBC_MALLOC) && !defined(__SANITIZE_THREAD__) && defined(__linux__)
    if (!kernel_grants_huge_pages_on_request()) {
        BOOST_TEST_MESSAGE("this kernel has no transparent huge pages: nothing to check");
        return;
    }
    // The first call grew the heap and advised the stretch it grew (the kernel keeps an advised
    // stretch a part of its own), whatever this program allocated and freed since.
    paloverde::keep_freed_memory();
    const std::vector<std::string> flags = heap_flags();
    BOOST_TEST_REQUIRE(!flags.empty());
    BOOST_TEST(std::any_of(flags.begin(), flags.end(), [](const std::string& f) { return f.find(" hg") != std::string::npos; }));
#else
    BOOST_TEST_MESSAGE("not glibc's allocator on Linux: nothing to check");
#endif
}

BOOST_AUTO_TEST_SUITE_END()
