#include "paloverde/core/error.hpp"

#include <utility>

namespace paloverde {

FileError::FileError(std::string path, std::size_t line, std::string full_message, int)
    : Error(std::move(full_message)), path_(std::move(path)), line_(line) {}

FileError::FileError(std::string path, std::size_t line, const std::string& message)
    : FileError(path,
                line,
                line > 0 ? path + ":" + std::to_string(line) + ": " + message : path + ": " + message,
                0) {}

FileError FileError::at_byte(std::string path, std::size_t offset, const std::string& message) {
    std::string text = path + " (byte " + std::to_string(offset) + "): " + message;
    return FileError(std::move(path), 0, std::move(text), 0);
}

}  // namespace paloverde
