#pragma once
// The program's operator new (huge_pages.cpp): arrays of 2 MiB and more are mappings of their own
// on transparent huge pages, or come from the kept heap where the host takes freed memory back.

namespace paloverde::cli {

// Whether large arrays are mappings of their own advised onto huge pages: not where the host
// takes freed memory back (huge_pages.cpp says why). Decided once per process.
bool large_arrays_advised_huge() noexcept;

}  // namespace paloverde::cli
