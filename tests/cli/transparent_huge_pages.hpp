#pragma once
// Whether the kernel grants transparent huge pages to a mapping advised MADV_HUGEPAGE
// (/sys/kernel/mm/transparent_hugepage/enabled: madvise or always).
#include <fstream>
#include <string>

inline bool kernel_grants_huge_pages_on_request() {
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string modes;
    std::getline(in, modes);
    return modes.find("[madvise]") != std::string::npos || modes.find("[always]") != std::string::npos;
}
