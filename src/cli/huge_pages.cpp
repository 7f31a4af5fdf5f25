// The program's large arrays on transparent huge pages.
//
// A run on a large mesh fills several hundred megabytes of freshly allocated arrays (the mesh,
// its copies in working order, per-element qualities for every metric assessed). On 4 KiB pages
// each first touch is a page fault, and in a virtual machine a fault costs microseconds: on a
// 2M-tet mesh with --iterations 0 they were 97 thousand faults and about a sixth of the run.
// Mapped on huge pages (2 MiB), where the kernel grants them on request
// (/sys/kernel/mm/transparent_hugepage/enabled: madvise, Debian's default), the large arrays take
// a few hundred, and that run 16 thousand in all (docs/benchmarks.md). glibc
// can do much the same (GLIBC_TUNABLES=glibc.malloc.hugetlb=1), but only when set
// before the process starts; this does it from inside, for the program alone (the library's users
// keep their own allocator).
//
// Only operator new is replaced, and only allocations of at least kLarge bytes change: each is a
// mapping of its own, aligned to a huge page and advised, listed in a small table that delete
// looks in for pointers aligned like them (malloc's pointers hardly ever are). When the table is
// full, allocations go to malloc as before. libstdc++'s other forms (arrays, nothrow) forward here.
//
// Where the kernel reports free memory to a hypervisor (a virtio balloon with free page
// reporting, as in Firecracker) large arrays come from malloc instead. The balloon reports free
// blocks of a huge page or more (2 MiB on one such guest, 8 MiB on another) and the host takes
// them back, so a mapping unmapped when freed is memory the host must back afresh at the next
// phase's arrays: 2.8 ms a megabyte as huge pages, 0.4 as small pages, measured on such a guest
// (docs/benchmarks.md). The program's heap keeps what is freed (keep_freed_memory), so the next
// arrays reuse it without a fault: a 0-iteration run on a 2M-tet mesh took 186 thousand faults
// and 4.5 s as mappings, 24 thousand and 2.8 s from the heap, peak memory about the same.
#include <dirent.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <new>
#include <string_view>

#include "huge_pages.hpp"

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kLarge = kHugePage;  // smaller ones cannot hold a huge page
constexpr std::size_t kPage = 4096;

struct Mapping {
    void* start = nullptr;
    std::size_t length = 0;
};
// A few hundred large arrays are alive at once at most; a full table only means malloc.
constexpr int kMappings = 1024;
Mapping mappings[kMappings];
std::mutex mappings_mutex;

bool huge_aligned(const void* p) { return (reinterpret_cast<std::uintptr_t>(p) & (kHugePage - 1)) == 0; }

// Whether a virtio balloon device offers free page reporting (feature bit 5,
// VIRTIO_BALLOON_F_REPORTING: the sysfs "features" file is a string of bits, bit 0 first). Plain
// system calls only: this runs inside operator new.
bool host_takes_free_memory_back() noexcept {
    constexpr const char* kDriver = "/sys/bus/virtio/drivers/virtio_balloon";
    constexpr int kReporting = 5;
    DIR* driver = ::opendir(kDriver);
    if (!driver) return false;
    bool reporting = false;
    while (const dirent* entry = ::readdir(driver)) {
        char path[512];
        const std::string_view name = entry->d_name;
        if (!name.starts_with("virtio") || name.size() > 200) continue;
        const int length = std::snprintf(path, sizeof path, "%s/%s/features", kDriver, entry->d_name);
        if (length <= 0 || length >= static_cast<int>(sizeof path)) continue;
        const int file = ::open(path, O_RDONLY | O_CLOEXEC);
        if (file < 0) continue;
        char bits[64];
        const ssize_t read = ::read(file, bits, sizeof bits);
        ::close(file);
        if (read > kReporting && bits[kReporting] == '1') reporting = true;
    }
    ::closedir(driver);
    return reporting;
}

void* map_large(std::size_t size) noexcept {
    const std::size_t length = (size + kPage - 1) / kPage * kPage;
    void* raw = ::mmap(nullptr, length + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) return nullptr;
    // Keep the aligned stretch; hand the slack on either side back.
    const auto address = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = (address + kHugePage - 1) & ~(kHugePage - 1);
    if (aligned > address) ::munmap(raw, aligned - address);
    const std::uintptr_t end = address + length + kHugePage;
    if (end > aligned + length) ::munmap(reinterpret_cast<void*>(aligned + length), end - (aligned + length));
    void* p = reinterpret_cast<void*>(aligned);
    ::madvise(p, length, MADV_HUGEPAGE);  // refused: ordinary pages
    {
        const std::lock_guard lock(mappings_mutex);
        for (Mapping& m : mappings)
            if (!m.start) {
                m = {p, length};
                return p;
            }
    }
    ::munmap(p, length);
    return std::malloc(size);
}

// Whether p was mapped here; unmaps it if so.
bool unmap_large(void* p) noexcept {
    if (!p || !huge_aligned(p)) return false;
    const std::lock_guard lock(mappings_mutex);
    for (Mapping& m : mappings)
        if (m.start == p) {
            ::munmap(m.start, m.length);
            m = {};
            return true;
        }
    return false;
}

void* allocate(std::size_t size) {
    for (;;) {
        const bool large = size >= kLarge && paloverde::cli::large_arrays_advised_huge();
        if (void* p = large ? map_large(size) : std::malloc(size == 0 ? 1 : size)) return p;
        const std::new_handler handler = std::get_new_handler();
        if (!handler) throw std::bad_alloc();
        handler();
    }
}

void release(void* p) noexcept {
    if (!unmap_large(p)) std::free(p);
}

}  // namespace

bool paloverde::cli::large_arrays_advised_huge() noexcept {
    static const bool advised = !host_takes_free_memory_back();
    return advised;
}

// The sanitizers bring their own operator new, which checks what they are there to check.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
#endif
