#pragma once
// A whole file in memory, read as whitespace-separated tokens with line tracking, or as raw
// bytes for the binary blocks some formats embed. Every failure is a FileError that names the
// file and the line (text) or byte offset (binary).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace paloverde::io {

class TextScanner {
public:
    // Reads the file; throws FileError if it cannot. With a `comment` character other than '\0',
    // a token that starts with it begins a comment running to the end of its line, which
    // token() and at_end() skip like whitespace. A regular file is mapped, not copied (a large
    // mesh's text is read once, from the page cache; another process that truncates the file
    // meanwhile ends this one); anything else (a pipe) is read to its end.
    explicit TextScanner(std::string path, char comment = '\0');
    TextScanner(const TextScanner&) = delete;
    TextScanner& operator=(const TextScanner&) = delete;
    ~TextScanner();

    const std::string& path() const noexcept { return path_; }
    std::size_t line() const noexcept { return line_; }
    std::size_t offset() const noexcept { return pos_; }
    std::size_t size() const noexcept { return data_.size(); }
    std::size_t remaining() const noexcept { return data_.size() - pos_; }
    bool at_end();  // skips whitespace first

    // Next whitespace-separated token; empty at end of file.
    std::string_view token();
    // Next token, failing with "expected <what>" at end of file.
    std::string_view expect_token(std::string_view what);
    // Next token must equal `keyword` (case-sensitive).
    void expect_keyword(std::string_view keyword);
    double real(std::string_view what);              // finite or not: see finite_real
    double finite_real(std::string_view what);       // rejects NaN and infinity
    std::int64_t integer(std::string_view what);
    // Up to `count` plain integers (digits only, at most 18 of them, then whitespace or the end of
    // the file) into out, each one's end offset into ends: integer() on each, in one loop. Stops
    // before the first value that is not plain, which integer() then reads or refuses as usual.
    // Returns how many it read.
    std::size_t plain_integers(std::int64_t* out, std::size_t* ends, std::size_t count);
    // A count: non-negative, and at most `max_plausible` (e.g. bounded by the remaining bytes).
    std::int64_t count(std::string_view what, std::int64_t max_plausible);
    // The rest of the current line (without the newline), then moves to the next line.
    std::string_view rest_of_line();
    void skip_line();

    // Binary access: the next n bytes, failing if the file is shorter.
    std::string_view bytes(std::size_t n, std::string_view what);
    // Moves past exactly one newline (after a text header that precedes binary data).
    void skip_one_newline();

    // The entry being read ("cell 7"), which the messages of a file that ends too soon or holds a
    // word where a number should be then name: a list cut short names the entry it was cut in.
    // Set around such a list (and cleared after it); it costs nothing until a message needs it.
    void set_entry(std::function<std::string()> entry) { entry_ = std::move(entry); }
    // " (in cell 7)", or empty without an entry.
    std::string in_entry() const { return entry_ ? " (in " + entry_() + ")" : std::string(); }

    [[noreturn]] void fail(const std::string& message) const;          // at the current line
    // As fail(), as if the scanner stood at `offset`, a place already read past (the end of a
    // value plain_integers() read, found wrong after it).
    [[noreturn]] void fail_at(std::size_t offset, const std::string& message) const;
    [[noreturn]] void fail_at_byte(const std::string& message) const;  // at the current offset
    // For files that mix text headers with binary blocks, where line numbers stop meaning
    // anything after the first block: from now on fail() reports the byte offset instead.
    void report_byte_offsets() noexcept { byte_offsets_ = true; }

private:
    void skip_space();
    std::string path_;
    std::string_view data_;  // the mapping, or copy_ where the file cannot be mapped
    void* mapping_ = nullptr;
    std::string copy_;
    std::size_t pos_ = 0;
    std::size_t line_ = 1;
    bool byte_offsets_ = false;
    char comment_ = '\0';
    std::function<std::string()> entry_;
};

// Parses a whole token as a number; false if it is not one.
bool parse_real(std::string_view token, double& value);
bool parse_integer(std::string_view token, std::int64_t& value);

// Byte order: binary VTK legacy is big-endian; everything else is read as written.
bool host_is_little_endian();
template <class T>
T byte_swapped(T value) {
    auto* bytes = reinterpret_cast<unsigned char*>(&value);
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    return value;
}

// Base64 (RFC 4648) without line breaks; decode ignores whitespace and fails on other characters.
std::string base64_encode(std::string_view bytes);
bool base64_decode(std::string_view text, std::string& bytes);

}  // namespace paloverde::io
