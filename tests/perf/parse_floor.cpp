// The floor under reading a text mesh (run by hand, not a test):
//   paloverde_parse_floor FILE... [--repeat R]
// Maps each file and parses every whitespace-separated number in it with std::from_chars, doing
// nothing else: no checks, no mesh, no line tracking. Prints the least seconds of R passes over
// all the files (default 5), and the count and sum of the numbers (so nothing is optimized away).
// What `paloverde improve` spends beyond this on a file is the reader's checks and the rest of
// the run (docs/benchmarks.md, "The fixed cost of a run").
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <iostream>
#include <string>
#include <vector>

namespace {

struct Parsed {
    long count = 0;
    double sum = 0.0;
};

void parse(const char* p, const char* end, Parsed& out) {
    while (p < end) {
        while (p < end && (*p == ' ' || *p == '\n' || *p == '\t' || *p == '\r')) ++p;
        if (p < end && *p == '#') {  // TetGen's comments
            while (p < end && *p != '\n') ++p;
            continue;
        }
        if (p >= end) break;
        double value = 0.0;
        const auto [next, error] = std::from_chars(p, end, value);
        if (error != std::errc()) {
            ++p;
            continue;
        }
        out.sum += value;
        ++out.count;
        p = next;
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> files;
    int repeat = 5;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--repeat" && i + 1 < argc) repeat = std::max(1, std::stoi(argv[++i]));
        else files.push_back(arg);
    }
    if (files.empty()) {
        std::cerr << "usage: paloverde_parse_floor FILE... [--repeat R]\n";
        return 2;
    }
    double least = 1e300;
    Parsed parsed;
    for (int r = 0; r < repeat; ++r) {
        parsed = Parsed{};
        const auto start = std::chrono::steady_clock::now();
        for (const std::string& file : files) {
            const int fd = open(file.c_str(), O_RDONLY);
            struct stat status {};
            if (fd < 0 || fstat(fd, &status) != 0 || status.st_size == 0) {
                std::cerr << file << ": cannot read\n";
                return 1;
            }
            const auto size = static_cast<std::size_t>(status.st_size);
            void* mapped = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
            close(fd);
            if (mapped == MAP_FAILED) {
                std::cerr << file << ": cannot map\n";
                return 1;
            }
            const char* text = static_cast<const char*>(mapped);
            parse(text, text + size, parsed);
            munmap(mapped, size);
        }
        least = std::min(least, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::cout << "parse floor " << least << " s (least of " << repeat << "), " << parsed.count << " numbers, sum "
              << parsed.sum << "\n";
}
