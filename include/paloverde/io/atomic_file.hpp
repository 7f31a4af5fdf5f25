#pragma once
// Write-then-rename: content goes to a temporary file in the target's directory; commit()
// flushes it and renames it over the target. Destroyed without commit(), it removes the
// temporary and leaves any existing target untouched.
#include <filesystem>
#include <fstream>

namespace paloverde {

class AtomicFile {
public:
    explicit AtomicFile(std::filesystem::path target, bool binary = true);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ofstream& stream() { return stream_; }
    void commit();  // throws FileError if writing or renaming failed

private:
    std::filesystem::path target_;
    std::filesystem::path temporary_;
    std::ofstream stream_;
    bool committed_ = false;
};

// Convenience for small text outputs (JSON, CSV).
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace paloverde
