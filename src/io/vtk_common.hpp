#pragma once
// What the VTK legacy (.vtk) and XML (.vtu) formats share: cell type codes, packed binary
// values, and a buffered writer that formats numbers without iostreams.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "raw_mesh.hpp"
#include "text_scanner.hpp"

namespace paloverde::io::vtk {

// "hexahedron" for 12 and so on; "unknown" for codes VTK does not define.
std::string_view cell_type_name(std::int64_t type);

// Empty when cell `cell` (a VTK type and its corner count) can be read; otherwise the message.
// Vertices, lines and poly-lines are accepted (and later skipped), like empty cells.
std::string cell_problem(std::size_t cell, std::int64_t type, std::int64_t corners);

// Appends a cell that passed cell_problem() to the cells of `raw`, recording its position in the
// file's cell list; lower-dimensional cells are dropped. The ids must be valid point indices.
void add_cell(RawMesh& raw, std::size_t cell, std::int64_t type, const std::int64_t* ids);

// Bit: VTK legacy files only, 8 values to a byte (the first in the high bit) in binary files.
enum class ValueType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64, Bit };

std::size_t size_of(ValueType type);  // Bit: 1, the byte that holds it
bool is_integer(ValueType type);

namespace detail {
template <class Unsigned>
Unsigned swap_bytes(Unsigned v) {
    Unsigned out = 0;
    for (std::size_t i = 0; i < sizeof(Unsigned); ++i) {
        out = static_cast<Unsigned>((out << 8) | (v & 0xFF));
        v = static_cast<Unsigned>(v >> 8);
    }
    return out;
}

// Swapping happens on an unsigned integer so that a float whose swapped bytes look like a
// signalling NaN never passes through a floating-point register.
template <class Stored>
Stored load_as(const char* p, bool swap) {
    // clang-format off
    using Unsigned = std::conditional_t<sizeof(Stored) == 1, std::uint8_t,
                     std::conditional_t<sizeof(Stored) == 2, std::uint16_t,
                     std::conditional_t<sizeof(Stored) == 4, std::uint32_t, std::uint64_t>>>;
    // clang-format on
    Unsigned bits;
    std::memcpy(&bits, p, sizeof bits);
    if (swap) bits = swap_bytes(bits);
    Stored value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}
}  // namespace detail

// One packed value of `type` at `p`, converted to T. `swap` when the data's byte order is not
// the host's. Integer T requires an integer `type` (callers check is_integer first).
template <class T>
T load(const char* p, ValueType type, bool swap) {
    switch (type) {
        case ValueType::Int8: return static_cast<T>(detail::load_as<std::int8_t>(p, swap));
        case ValueType::UInt8: return static_cast<T>(detail::load_as<std::uint8_t>(p, swap));
        case ValueType::Int16: return static_cast<T>(detail::load_as<std::int16_t>(p, swap));
        case ValueType::UInt16: return static_cast<T>(detail::load_as<std::uint16_t>(p, swap));
        case ValueType::Int32: return static_cast<T>(detail::load_as<std::int32_t>(p, swap));
        case ValueType::UInt32: return static_cast<T>(detail::load_as<std::uint32_t>(p, swap));
        case ValueType::Int64: return static_cast<T>(detail::load_as<std::int64_t>(p, swap));
        // Above INT64_MAX wraps to a negative id, which every range check rejects.
        case ValueType::UInt64: return static_cast<T>(detail::load_as<std::uint64_t>(p, swap));
        case ValueType::Float32:
            if constexpr (std::is_floating_point_v<T>) return static_cast<T>(detail::load_as<float>(p, swap));
            break;
        case ValueType::Float64:
            if constexpr (std::is_floating_point_v<T>) return static_cast<T>(detail::load_as<double>(p, swap));
            break;
        case ValueType::Bit: break;  // unpacked by the legacy reader
    }
    return T{};
}

// Field names as a legacy file can hold them: no whitespace (it separates tokens), '%' escaped
// because VTK decodes %XX in names.
std::string legacy_name(std::string_view name);
// The reverse of VTK's %XX escapes in legacy names.
std::string decode_legacy_name(std::string_view name);

// Throws Error if two fields of one kind share a name once written; a reader could not tell them apart.
void check_unique_names(std::span<const Field> fields, std::string_view kind, bool legacy);

// Collects output in a large buffer and hands it to the stream in chunks, so numbers are
// formatted with std::to_chars rather than through the stream.
class Output {
public:
    explicit Output(std::ostream& out);
    Output(const Output&) = delete;
    Output& operator=(const Output&) = delete;

    Output& text(std::string_view s);
    Output& text(char c);
    Output& real(double value);  // 17 significant digits: reads back bit for bit
    Output& integer(std::int64_t value);
    // The bytes of `value`, in big-endian order or the host's.
    template <class T>
    Output& binary(T value, bool big_endian);
    void flush();  // call once at the end; the destructor does not

private:
    void reserve(std::size_t n) {
        if (buffer_.size() + n > kChunk) flush();
    }
    static constexpr std::size_t kChunk = 1 << 20;
    std::ostream& out_;
    std::string buffer_;
    bool host_little_endian_ = host_is_little_endian();
};

template <class T>
Output& Output::binary(T value, bool big_endian) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian == host_little_endian_)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    reserve(sizeof(T));
    buffer_.append(bytes, sizeof(T));
    return *this;
}

}  // namespace paloverde::io::vtk
