// The command line keeps the memory it frees (paloverde::keep_freed_memory, called first in main):
// a large block freed stays in the heap for the next one instead of going back to the kernel.
// malloc's blocks, that is: the program's operator new maps arrays of 2 MiB and more on huge pages
// of their own (huge_pages_test.cpp).
#include <boost/test/unit_test.hpp>
#include <cstdlib>
#include <cstring>

#include "paloverde/core/memory.hpp"

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

BOOST_AUTO_TEST_SUITE_END()
