#include "paloverde/io/atomic_file.hpp"

#include <atomic>
#include <string>
#include <system_error>
#include <unistd.h>

#include "paloverde/core/error.hpp"

namespace paloverde {

namespace {
std::filesystem::path temporary_beside(const std::filesystem::path& target) {
    static std::atomic<unsigned> counter{0};
    std::filesystem::path tmp = target;
    tmp += ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    return tmp;
}
}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target, bool binary)
    : target_(std::move(target)), temporary_(temporary_beside(target_)) {
    stream_.open(temporary_, binary ? std::ios::out | std::ios::binary | std::ios::trunc
                                    : std::ios::out | std::ios::trunc);
    if (!stream_) throw FileError(target_.string(), 0, "cannot create the file (is the directory writable?)");
}

AtomicFile::~AtomicFile() {
    if (committed_) return;
    stream_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
}

void AtomicFile::commit() {
    stream_.flush();
    const bool written = static_cast<bool>(stream_);
    stream_.close();
    if (!written || stream_.fail()) throw FileError(target_.string(), 0, "writing failed (disk full?)");
    std::error_code error;
    std::filesystem::rename(temporary_, target_, error);
    if (error) throw FileError(target_.string(), 0, "cannot rename the finished file into place: " + error.message());
    committed_ = true;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
    AtomicFile file(path, false);
    file.stream() << text;
    file.commit();
}

}  // namespace paloverde
