#include "text_scanner.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <utility>

#include "paloverde/core/error.hpp"

namespace paloverde::io {

namespace {
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

// The plain integer at `begin`: at most 18 digits (which cannot overflow), then whitespace or the
// end of the data. Where it ends, or nullptr for anything else (which the general path reads or
// refuses).
const char* plain_integer(const char* begin, const char* data_end, std::int64_t& value) {
    const char* end = begin + std::min<std::ptrdiff_t>(data_end - begin, 18);
    const char* next = begin;
    value = 0;
    while (next < end && static_cast<unsigned char>(*next - '0') < 10) value = 10 * value + (*next++ - '0');
    return next > begin && (next == data_end || is_space(*next)) ? next : nullptr;
}
}  // namespace

TextScanner::TextScanner(std::string path, char comment) : path_(std::move(path)), comment_(comment) {
    const int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw FileError(path_, 0, "cannot open the file (missing or unreadable)");
    struct stat status {};
    if (::fstat(fd, &status) != 0 || S_ISDIR(status.st_mode)) {
        ::close(fd);
        throw FileError(path_, 0, S_ISDIR(status.st_mode) ? "is a directory, not a mesh file" : "cannot read the file");
    }
    if (S_ISREG(status.st_mode) && status.st_size > 0) {
        const auto size = static_cast<std::size_t>(status.st_size);
        void* mapped = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
        if (mapped != MAP_FAILED) {
            ::close(fd);
            mapping_ = mapped;
            data_ = std::string_view(static_cast<const char*>(mapped), size);
            return;
        }
    }
    // Not mappable (a pipe, an empty file): read it to the end.
    char buffer[1 << 16];
    for (;;) {
        const ssize_t got = ::read(fd, buffer, sizeof buffer);
        if (got == 0) break;
        if (got < 0) {
            if (errno == EINTR) continue;
            ::close(fd);
            throw FileError(path_, 0, "cannot read the file");
        }
        copy_.append(buffer, static_cast<std::size_t>(got));
    }
    ::close(fd);
    data_ = copy_;
}

TextScanner::~TextScanner() {
    if (mapping_) ::munmap(mapping_, data_.size());
}

void TextScanner::skip_space() {
    for (;;) {
        while (pos_ < data_.size() && is_space(data_[pos_])) {
            if (data_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (comment_ == '\0' || pos_ >= data_.size() || data_[pos_] != comment_) return;
        skip_line();
    }
}

bool TextScanner::at_end() {
    skip_space();
    return pos_ >= data_.size();
}

std::string_view TextScanner::token() {
    skip_space();
    const std::size_t begin = pos_;
    while (pos_ < data_.size() && !is_space(data_[pos_])) ++pos_;
    return data_.substr(begin, pos_ - begin);
}

std::string_view TextScanner::expect_token(std::string_view what) {
    const std::string_view t = token();
    if (t.empty()) fail("unexpected end of file: expected " + std::string(what) + in_entry());
    return t;
}

void TextScanner::expect_keyword(std::string_view keyword) {
    const std::string_view t = expect_token(keyword);
    if (t != keyword) fail("expected '" + std::string(keyword) + "', found '" + std::string(t.substr(0, 64)) + "'");
}

// real() and integer() read the common token (a plain number followed by whitespace or the end)
// in one pass over its characters; anything else (a sign '+', a word, a number out of range, a
// number run into other characters) goes the general way, from the same place, to its message.
// A large mesh's text is millions of such tokens, and finding a token's end before parsing it read
// each twice.
double TextScanner::real(std::string_view what) {
    skip_space();
    {
        const char* begin = data_.data() + pos_;
        const char* end = data_.data() + data_.size();
        double value = 0.0;
        const auto [next, error] = std::from_chars(begin, end, value);
        if (error == std::errc() && next > begin && (next == end || is_space(*next))) {
            pos_ += static_cast<std::size_t>(next - begin);
            return value;
        }
    }
    const std::string_view t = expect_token(what);
    double value = 0.0;
    if (!parse_real(t, value))
        fail("expected " + std::string(what) + ", found '" + std::string(t.substr(0, 64)) + "'" + in_entry());
    return value;
}

double TextScanner::finite_real(std::string_view what) {
    const double value = real(what);
    if (!std::isfinite(value)) fail(std::string(what) + " is not finite");
    return value;
}

std::int64_t TextScanner::integer(std::string_view what) {
    skip_space();
    {
        std::int64_t value = 0;
        if (const char* next = plain_integer(data_.data() + pos_, data_.data() + data_.size(), value)) {
            pos_ = static_cast<std::size_t>(next - data_.data());
            return value;
        }
    }
    const std::string_view t = expect_token(what);
    std::int64_t value = 0;
    if (!parse_integer(t, value))
        fail("expected " + std::string(what) + " (an integer), found '" + std::string(t.substr(0, 64)) + "'" +
             in_entry());
    return value;
}

std::size_t TextScanner::plain_integers(std::int64_t* out, std::size_t* ends, std::size_t count) {
    const char* data = data_.data();
    const std::size_t size = data_.size();
    std::size_t pos = pos_, line = line_, got = 0;
    for (; got < count; ++got) {
        while (pos < size && is_space(data[pos])) line += data[pos++] == '\n';
        // What follows stands where integer() takes it up (its skip of whitespace done).
        pos_ = pos, line_ = line;
        if (pos == size || data[pos] == comment_) break;  // the end, or a comment for skip_space()
        const char* next = plain_integer(data + pos, data + size, out[got]);
        if (!next) break;
        pos = static_cast<std::size_t>(next - data);
        ends[got] = pos;
    }
    pos_ = pos, line_ = line;
    return got;
}

std::int64_t TextScanner::count(std::string_view what, std::int64_t max_plausible) {
    const std::int64_t value = integer(what);
    if (value < 0) fail(std::string(what) + " is negative (" + std::to_string(value) + ")");
    if (value > max_plausible)
        fail(std::string(what) + " of " + std::to_string(value) + " cannot fit in the rest of the file (" +
             std::to_string(remaining()) + " bytes)");
    return value;
}

std::string_view TextScanner::rest_of_line() {
    const std::size_t begin = pos_;
    while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
    std::size_t end = pos_;
    if (end > begin && data_[end - 1] == '\r') --end;
    if (pos_ < data_.size()) {
        ++pos_;
        ++line_;
    }
    return data_.substr(begin, end - begin);
}

void TextScanner::skip_line() { rest_of_line(); }

std::string_view TextScanner::bytes(std::size_t n, std::string_view what) {
    if (n > remaining())
        fail_at_byte("file ends inside " + std::string(what) + " (" + std::to_string(n) + " bytes needed, " +
                     std::to_string(remaining()) + " left)");
    const std::string_view out = data_.substr(pos_, n);
    pos_ += n;
    return out;
}

void TextScanner::skip_one_newline() {
    while (pos_ < data_.size() && (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r')) ++pos_;
    if (pos_ < data_.size() && data_[pos_] == '\n') {
        ++pos_;
        ++line_;
    }
}

void TextScanner::fail(const std::string& message) const {
    if (byte_offsets_) fail_at_byte(message);
    throw FileError(path_, line_, message);
}

void TextScanner::fail_at_byte(const std::string& message) const { throw FileError::at_byte(path_, pos_, message); }

void TextScanner::fail_at(std::size_t offset, const std::string& message) const {
    if (byte_offsets_) throw FileError::at_byte(path_, offset, message);
    const auto newlines = std::count(data_.begin() + static_cast<std::ptrdiff_t>(offset),
                                     data_.begin() + static_cast<std::ptrdiff_t>(pos_), '\n');
    throw FileError(path_, line_ - static_cast<std::size_t>(newlines), message);
}

bool parse_real(std::string_view token, double& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    if (result.ec == std::errc::result_out_of_range) {
        // Underflow to a denormal or zero is fine; overflow becomes infinity (rejected by callers
        // that need finite values). The whole token must still be the number: "1e-999abc" is not.
        if (result.ptr != end) return false;
        value = std::strtod(std::string(token).c_str(), nullptr);
        return true;
    }
    return result.ec == std::errc() && result.ptr == end && !token.empty();
}

bool parse_integer(std::string_view token, std::int64_t& value) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    const char* end = token.data() + token.size();
    const auto result = std::from_chars(token.data(), end, value);
    return result.ec == std::errc() && result.ptr == end && !token.empty();
}

bool host_is_little_endian() {
    const std::uint16_t probe = 1;
    return *reinterpret_cast<const unsigned char*>(&probe) == 1;
}

namespace {
constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
int base64_value(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}
}  // namespace

std::string base64_encode(std::string_view bytes) {
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                           (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += kAlphabet[(v >> 6) & 63];
        out += kAlphabet[v & 63];
    }
    if (i < bytes.size()) {
        unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
        if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

bool base64_decode(std::string_view text, std::string& bytes) {
    bytes.clear();
    bytes.reserve(text.size() / 4 * 3);
    unsigned buffer = 0;
    int bits = 0;
    bool padding = false;
    for (char c : text) {
        if (is_space(c)) continue;
        if (c == '=') {
            padding = true;
            continue;
        }
        const int v = base64_value(c);
        // Data after padding starts a new block (VTK concatenates a base64 header and body).
        if (v < 0) return false;
        if (padding) {
            buffer = 0;
            bits = 0;
            padding = false;
        }
        buffer = (buffer << 6) | static_cast<unsigned>(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            bytes += static_cast<char>((buffer >> bits) & 0xFF);
        }
    }
    return true;
}

}  // namespace paloverde::io
