#include "paloverde/core/memory.hpp"

#include <atomic>
#include <cstdint>
#include <cstdlib>  // defines __GLIBC__ under glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace paloverde {

namespace {

// The heap's first stretch, grown once and advised for huge pages. Only the pages a run touches
// are ever backed; the rest is address space.
constexpr std::size_t kHeapReserve = std::size_t{256} << 20;
constexpr std::size_t kHugePage = std::size_t{2} << 20;

}  // namespace

void keep_freed_memory() noexcept {
    static std::atomic<bool> kept{false};
    if (kept.exchange(true)) return;  // the heap is grown and advised once
#if defined(__GLIBC__)
    mallopt(M_MMAP_MAX, 0);        // large blocks from the heap, not a mapping of their own each
    mallopt(M_TRIM_THRESHOLD, -1);  // and the heap's free top is not given back
#if defined(__linux__) && defined(MADV_HUGEPAGE) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    // Grow the heap once and advise it: freed at once, the block stays as the heap's free top,
    // which the next allocations carve up from its start.
    if (void* block = std::malloc(kHeapReserve)) {
        const auto start = reinterpret_cast<std::uintptr_t>(block);
        const std::uintptr_t begin = (start + kHugePage - 1) & ~(kHugePage - 1);
        const std::uintptr_t end = (start + kHeapReserve) & ~(kHugePage - 1);
        ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice: refused, nothing changes
        std::free(block);
    }
#endif
#endif
}

}  // namespace paloverde
