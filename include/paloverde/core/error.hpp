#pragma once
// Every failure a user can cause is reported as an exception derived from paloverde::Error,
// with a message that names what to change (file, line or byte, element, option).
#include <cstddef>
#include <stdexcept>
#include <string>

namespace paloverde {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// A file that cannot be read or written, or whose content is malformed.
class FileError : public Error {
public:
    // `line` is 1-based; 0 means "no line" (binary data or the whole file).
    FileError(std::string path, std::size_t line, const std::string& message);
    // For binary content: the byte offset where the problem was found.
    static FileError at_byte(std::string path, std::size_t offset, const std::string& message);

    const std::string& path() const noexcept { return path_; }
    std::size_t line() const noexcept { return line_; }

private:
    FileError(std::string path, std::size_t line, std::string full_message, int);
    std::string path_;
    std::size_t line_ = 0;
};

// A mesh that is structurally unusable (out-of-range index, repeated vertex in an element,
// non-finite coordinate, no elements) regardless of where it came from.
class MeshError : public Error {
public:
    using Error::Error;
};

// An option with an impossible value; the message names the option.
class OptionError : public Error {
public:
    using Error::Error;
};

}  // namespace paloverde
