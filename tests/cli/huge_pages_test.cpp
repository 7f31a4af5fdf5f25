// The command line's operator new (src/cli/huge_pages.cpp, linked into this program too): arrays
// of 2 MiB and more are mappings of their own on huge pages, except where the host takes freed
// memory back: there they come from the kept heap (paloverde::keep_freed_memory, as main calls
// it), which the next array reuses without faults. The rest come from malloc, and delete hands
// each back to where it came from, in any order, also once the table of mappings is full.
#include <sys/resource.h>

#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "cli/huge_pages.hpp"
#include "paloverde/core/memory.hpp"
#include "transparent_huge_pages.hpp"

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;

bool huge_aligned(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % kHugePage == 0; }

// Whether some virtio balloon offers free page reporting (feature bit 5 of its sysfs bit string).
bool free_page_reporting() {
    const std::filesystem::path driver = "/sys/bus/virtio/drivers/virtio_balloon";
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(driver, error)) {
        if (!entry.path().filename().string().starts_with("virtio")) continue;
        std::ifstream in(entry.path() / "features");
        std::string bits;
        if (std::getline(in, bits) && bits.size() > 5 && bits[5] == '1') return true;
    }
    return false;
}

long minor_faults() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_minflt;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(huge_pages)

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
BOOST_AUTO_TEST_CASE(large_arrays_are_mapped_on_huge_pages_or_reuse_the_kept_heap) {
    paloverde::keep_freed_memory();  // as main does first
    constexpr std::size_t count = std::size_t{8} << 20;  // 64 MiB of doubles
    const bool advised = paloverde::cli::large_arrays_advised_huge();
    long first = minor_faults();
    {
        std::vector<double> big(count, 1.5);
        first = minor_faults() - first;
        BOOST_TEST(huge_aligned(big.data()) == advised);
        BOOST_TEST(std::all_of(big.begin(), big.end(), [](double x) { return x == 1.5; }));
    }
    long second = minor_faults();
    std::vector<double> again(count, 2.5);
    second = minor_faults() - second;
    BOOST_TEST(std::all_of(again.begin(), again.end(), [](double x) { return x == 2.5; }));
    // 16384 faults on 4 KiB pages each time; 32 on huge pages, where the kernel grants them and
    // they are asked for; none for the second array where the heap kept the first's memory.
    if (advised && kernel_grants_huge_pages_on_request()) {
        BOOST_TEST(first < 1000);
        BOOST_TEST(second < 1000);
    }
#if defined(__GLIBC__)
    if (!advised) BOOST_TEST(second < 1000);
#endif
}

BOOST_AUTO_TEST_CASE(no_huge_pages_where_the_host_takes_freed_memory_back) {
    BOOST_TEST(paloverde::cli::large_arrays_advised_huge() == !free_page_reporting());
}
#endif

BOOST_AUTO_TEST_CASE(blocks_of_every_size_survive_any_order_of_release) {
    std::mt19937 random(7);
    std::vector<std::unique_ptr<std::vector<std::uint32_t>>> blocks;
    for (std::uint32_t i = 0; i < 200; ++i) {
        // From a few bytes to 24 MiB, around the 2 MiB threshold too.
        const std::size_t bytes = i % 3 == 0 ? kHugePage - 4 + 4 * (i % 5) : std::size_t{1} << (2 + i % 23);
        blocks.push_back(std::make_unique<std::vector<std::uint32_t>>(bytes / 4 + 1, i));
    }
    std::shuffle(blocks.begin(), blocks.end(), random);
    for (std::size_t b = 0; b < blocks.size(); b += 2) blocks[b].reset();
    for (const auto& block : blocks)
        if (block) {
            const std::uint32_t value = block->front();
            BOOST_TEST(std::all_of(block->begin(), block->end(), [&](std::uint32_t x) { return x == value; }));
        }
}

BOOST_AUTO_TEST_CASE(more_large_arrays_than_the_table_holds_still_work) {
    // Not touched (each touched would be a huge page of memory): allocated, then freed.
    std::vector<std::unique_ptr<char[]>> blocks;
    for (int i = 0; i < 1500; ++i) blocks.emplace_back(new char[kHugePage]);
    blocks[1499][0] = 'a';
    blocks[3][kHugePage - 1] = 'b';
    BOOST_TEST(blocks[1499][0] == 'a');
    BOOST_TEST(blocks[3][kHugePage - 1] == 'b');
    blocks.clear();
    std::vector<double> after(kHugePage, 2.0);  // the table has room again
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    BOOST_TEST(huge_aligned(after.data()) == paloverde::cli::large_arrays_advised_huge());
#endif
    BOOST_TEST(after.back() == 2.0);
}

BOOST_AUTO_TEST_SUITE_END()
