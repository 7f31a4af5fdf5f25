#pragma once
// How a program that runs Paloverde keeps the memory it frees.

namespace paloverde {

// Keep freed memory in the process for the next allocation instead of handing it back to the
// kernel. A run allocates and frees arrays of a value per element or vertex at every phase (the
// quality reports, the solver's copies of the mesh, each focus). By default glibc hands large
// freed blocks back (a block above its mmap threshold is a mapping of its own, and the heap's free
// top is trimmed), so the next array pays a page fault per 4 KiB page: a quarter of a 0-iteration
// run on a mesh of millions of elements (docs/benchmarks.md). The peak grows little (a freed block
// is reused when it fits: 2-12% measured); what the process once held it keeps until it exits.
//
// The heap it keeps is also grown once to 256 MiB of address space, advised for transparent huge
// pages (where the kernel grants them on request): the first touch of its pages then costs a fault
// per 2 MiB, not per 4 KiB. In a virtual machine a fault costs microseconds, and the arrays below
// 2 MiB (a mesh of 100,000 tets has many) faulted some 5,900 times in a 0-iteration run on such a
// mesh, about 700 times with the advice (docs/benchmarks.md). Only touched pages are ever backed.
//
// Call it first thing in main(); later calls do nothing. A no-op where the C library is not glibc
// (and the heap's advice only on Linux, not under a sanitizer's allocator). The command line also
// replaces operator new for arrays of 2 MiB and more, mapping them on huge pages of their own
// (src/cli/huge_pages.cpp), which go back to the kernel when freed; where the host takes freed
// memory back they come from this heap instead.
void keep_freed_memory() noexcept;

}  // namespace paloverde
