#include "paloverde/core/memory.hpp"

#include <cstdlib>  // defines __GLIBC__ under glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace paloverde {

void keep_freed_memory() noexcept {
#if defined(__GLIBC__)
    mallopt(M_MMAP_MAX, 0);        // large blocks from the heap, not a mapping of their own each
    mallopt(M_TRIM_THRESHOLD, -1);  // and the heap's free top is not given back
#endif
}

}  // namespace paloverde
