#pragma once
// How a program that runs Paloverde keeps the memory it frees.

namespace paloverde {

// Keep freed memory in the process for the next allocation instead of handing it back to the
// kernel. A run allocates and frees arrays of a value per element or vertex at every phase (the
// quality reports, the solver's copies of the mesh, each focus). By default glibc hands large
// freed blocks back (a block above its mmap threshold is a mapping of its own, and the heap's free
// top is trimmed), so the next array pays a page fault per 4 KiB page: a quarter of a 0-iteration
// run on fandisk-2M (docs/benchmarks.md). The peak grows little (a freed block is reused when it
// fits: 2-12% on fandisk-9M); what the process once held it keeps until it exits. Call it first
// thing in main(); a no-op where the C library is not glibc. (The command line also replaces
// operator new for arrays of 2 MiB and more, mapping them on huge pages: src/cli/huge_pages.cpp.
// Those go back to the kernel when freed; this keeps the smaller ones.)
void keep_freed_memory() noexcept;

}  // namespace paloverde
