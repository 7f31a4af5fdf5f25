// VTK XML unstructured grids (.vtu): DataArrays in ascii, inline base64 ("binary") or appended
// (raw or base64) form, optionally zlib-compressed as ParaView writes them by default.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <zlib.h>

#include "paloverde/core/error.hpp"
#include "raw_mesh.hpp"
#include "text_scanner.hpp"
#include "vtk_common.hpp"
#include "xml_reader.hpp"

namespace paloverde::io {

namespace {

using vtk::ValueType;
constexpr std::size_t npos = std::string_view::npos;

bool parse_value_type(std::string_view name, ValueType& type) {
    struct Known {
        std::string_view name;
        ValueType type;
    };
    static constexpr Known known[] = {
        {"Int8", ValueType::Int8},       {"UInt8", ValueType::UInt8},   {"Int16", ValueType::Int16},
        {"UInt16", ValueType::UInt16},   {"Int32", ValueType::Int32},   {"UInt32", ValueType::UInt32},
        {"Int64", ValueType::Int64},     {"UInt64", ValueType::UInt64}, {"Float32", ValueType::Float32},
        {"Float64", ValueType::Float64},
    };
    for (const Known& k : known)
        if (name == k.name) {
            type = k.type;
            return true;
        }
    return false;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// The whitespace-separated tokens of an element's text pieces, with the line of each.
class TokenCursor {
public:
    TokenCursor(std::string_view document, const std::vector<XmlText>& pieces) : doc_(document), pieces_(pieces) {
        if (!pieces_.empty()) start_piece();
    }
    bool next(std::string_view& token) {
        while (piece_ < pieces_.size()) {
            const std::size_t end = pieces_[piece_].end;
            while (pos_ < end && is_space(doc_[pos_])) {
                if (doc_[pos_] == '\n') ++line_;
                ++pos_;
            }
            if (pos_ < end) {
                const std::size_t begin = pos_;
                while (pos_ < end && !is_space(doc_[pos_])) ++pos_;
                token = doc_.substr(begin, pos_ - begin);
                return true;
            }
            if (++piece_ < pieces_.size()) start_piece();
        }
        return false;
    }
    std::size_t line() const { return line_; }

private:
    void start_piece() {
        pos_ = pieces_[piece_].begin;
        line_ = pieces_[piece_].line;
    }
    std::string_view doc_;
    const std::vector<XmlText>& pieces_;
    std::size_t piece_ = 0;
    std::size_t pos_ = 0;
    std::size_t line_ = 0;
};

// One DataArray, located and decoded down to packed values (or left as text for ascii).
struct ArrayData {
    const XmlElement* element = nullptr;
    std::string name;
    ValueType type = ValueType::Float64;
    std::int64_t components = 1;
    bool ascii = false;
    std::vector<char> owned;       // decoded or decompressed bytes; a vector so that moves keep `packed` valid
    std::string_view packed;       // the values in the file's byte order
    std::size_t file_byte = npos;  // where `packed` starts in the file, when it is stored there as is
    std::size_t data_byte = 0;     // where the array's encoded data starts in the file
};

class VtuReader {
public:
    explicit VtuReader(const std::string& path) : scanner_(path), path_(path) {}
    RawMesh read();

private:
    [[noreturn]] void fail_at(const XmlElement& e, const std::string& message) const {
        throw FileError(path_, e.line, message);
    }
    [[noreturn]] void fail_at_byte(std::size_t byte, const std::string& message) const {
        throw FileError::at_byte(path_, byte, message);
    }
    [[noreturn]] void fail_value(const ArrayData& a, std::size_t index, const std::string& message) const;
    void read_header();
    std::int64_t integer_attribute(const XmlElement& e, std::string_view name, std::int64_t fallback,
                                   bool required) const;
    const XmlElement& only_child(const XmlElement& parent, std::string_view name) const;
    ArrayData load_array(const XmlElement& e) const;
    void unpack_payload(ArrayData& a, std::string_view data, std::size_t byte, bool in_file) const;
    std::uint64_t header_word(const char* p) const;
    template <class T>
    std::vector<T> values(const ArrayData& a) const;
    std::vector<std::int64_t> integers(const ArrayData& a) const;
    void read_points(const XmlElement& piece, std::int64_t points);
    void read_cells(const XmlElement& piece, std::int64_t points, std::int64_t cells);
    void read_fields(const XmlElement& piece, std::string_view section, std::int64_t count,
                     std::vector<Field>& out) const;

    TextScanner scanner_;
    std::string path_;
    std::string_view text_;
    XmlDocument doc_;
    bool swap_ = false;
    bool header64_ = false;
    bool zlib_ = false;
    bool appended_base64_ = false;
    std::size_t appended_end_ = 0;
    std::vector<std::int64_t> appended_offsets_;  // sorted, to find where a base64 array ends
    RawMesh raw_;
};

void VtuReader::fail_value(const ArrayData& a, std::size_t index, const std::string& message) const {
    if (a.ascii) {
        TokenCursor cursor(text_, a.element->text);
        std::string_view token;
        for (std::size_t i = 0; i <= index && cursor.next(token); ++i) {
        }
        throw FileError(path_, cursor.line(), message);
    }
    if (a.file_byte != npos) fail_at_byte(a.file_byte + index * vtk::size_of(a.type), message);
    fail_at_byte(a.data_byte, message + " (value " + std::to_string(index) + " of DataArray '" + a.name +
                                  "', encoded from this byte on)");
}

std::int64_t VtuReader::integer_attribute(const XmlElement& e, std::string_view name, std::int64_t fallback,
                                          bool required) const {
    const std::string* text = e.attribute(name);
    if (!text) {
        if (required) fail_at(e, "<" + std::string(e.name) + "> has no " + std::string(name) + " attribute");
        return fallback;
    }
    std::int64_t value = 0;
    if (!parse_integer(*text, value) || value < 0)
        fail_at(e, "attribute " + std::string(name) + "=\"" + text->substr(0, 40) + "\" of <" + std::string(e.name) +
                       "> is not a non-negative integer");
    return value;
}

const XmlElement& VtuReader::only_child(const XmlElement& parent, std::string_view name) const {
    const std::vector<const XmlElement*> found = doc_.children(parent, name);
    if (found.empty()) fail_at(parent, "<" + std::string(parent.name) + "> has no <" + std::string(name) + "> element");
    if (found.size() > 1)
        fail_at(*found[1], "<" + std::string(parent.name) + "> has more than one <" + std::string(name) + "> element");
    return *found.front();
}

void VtuReader::read_header() {
    const XmlElement& root = doc_.root();
    if (root.name != "VTKFile") fail_at(root, "the root element is <" + std::string(root.name) + ">, not <VTKFile>");
    const std::string* type = root.attribute("type");
    if (!type) fail_at(root, "<VTKFile> has no type attribute");
    if (*type != "UnstructuredGrid")
        fail_at(root, "this is a VTK XML " + *type + " file; Paloverde reads UnstructuredGrid (.vtu) files");
    const std::string* order = root.attribute("byte_order");
    bool big = false;
    if (order && *order == "BigEndian")
        big = true;
    else if (order && *order != "LittleEndian")
        fail_at(root, "byte_order \"" + *order + "\" is neither LittleEndian nor BigEndian");
    swap_ = big == host_is_little_endian();
    // Files of format version 0.1 have no header_type: their headers are UInt32.
    if (const std::string* header = root.attribute("header_type")) {
        if (*header == "UInt64")
            header64_ = true;
        else if (*header != "UInt32")
            fail_at(root, "header_type \"" + *header + "\" is neither UInt32 nor UInt64");
    }
    if (const std::string* compressor = root.attribute("compressor"); compressor && !compressor->empty()) {
        if (*compressor != "vtkZLibDataCompressor")
            fail_at(root, "compressor \"" + *compressor +
                              "\" is not supported; Paloverde reads uncompressed and vtkZLibDataCompressor data "
                              "(in ParaView, save with the ZLib compressor or none)");
        zlib_ = true;
    }
    if (doc_.opaque_data == XmlDocument::npos) return;
    const XmlElement& appended = doc_.elements.back();
    const std::string* encoding = appended.attribute("encoding");
    if (!encoding) fail_at(appended, "<AppendedData> has no encoding attribute (raw or base64)");
    if (*encoding == "base64")
        appended_base64_ = true;
    else if (*encoding != "raw")
        fail_at(appended, "<AppendedData> encoding \"" + *encoding + "\" is neither raw nor base64");
    appended_end_ = text_.rfind("</AppendedData>");
    if (appended_end_ == npos || appended_end_ < doc_.opaque_data)
        fail_at_byte(doc_.opaque_data, "the appended data has no closing </AppendedData> (truncated file?)");
    for (const XmlElement& e : doc_.elements)
        if (e.name == "DataArray")
            if (const std::string* format = e.attribute("format"); format && *format == "appended")
                appended_offsets_.push_back(integer_attribute(e, "offset", 0, true));
    std::sort(appended_offsets_.begin(), appended_offsets_.end());
}

std::uint64_t VtuReader::header_word(const char* p) const {
    return header64_ ? vtk::load<std::uint64_t>(p, ValueType::UInt64, swap_)
                     : vtk::load<std::uint64_t>(p, ValueType::UInt32, swap_);
}

ArrayData VtuReader::load_array(const XmlElement& e) const {
    ArrayData a;
    a.element = &e;
    if (const std::string* name = e.attribute("Name")) a.name = *name;
    const std::string* type = e.attribute("type");
    if (!type) fail_at(e, "DataArray '" + a.name + "' has no type attribute");
    if (!parse_value_type(*type, a.type))
        fail_at(e, "DataArray '" + a.name + "' has unknown type \"" + type->substr(0, 40) +
                       "\" (expected Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32 or Float64)");
    a.components = integer_attribute(e, "NumberOfComponents", 1, false);
    if (a.components < 1 || a.components > std::numeric_limits<int>::max())
        fail_at(e, "DataArray '" + a.name + "' has NumberOfComponents=" + std::to_string(a.components));
    const std::string* format = e.attribute("format");
    if (!format) fail_at(e, "DataArray '" + a.name + "' has no format attribute (ascii, binary or appended)");
    if (*format == "ascii") {
        a.ascii = true;
    } else if (*format == "binary") {
        // Inline base64: VTK encodes the header and the data as separate base64 runs; the decoder
        // joins them.
        std::string encoded;
        for (const XmlText& piece : e.text) encoded.append(text_.substr(piece.begin, piece.end - piece.begin));
        a.data_byte = e.text.empty() ? e.offset : e.text.front().begin;
        std::string decoded;
        if (!base64_decode(encoded, decoded)) fail_at(e, "DataArray '" + a.name + "' holds invalid base64 data");
        a.owned.assign(decoded.begin(), decoded.end());
        unpack_payload(a, std::string_view(a.owned.data(), a.owned.size()), a.data_byte, false);
    } else if (*format == "appended") {
        if (doc_.opaque_data == XmlDocument::npos)
            fail_at(e, "DataArray '" + a.name + "' is in appended format but the file has no <AppendedData>");
        const std::int64_t offset = integer_attribute(e, "offset", 0, true);
        const std::size_t available = appended_end_ - doc_.opaque_data;
        if (static_cast<std::uint64_t>(offset) >= available)
            fail_at(e, "DataArray '" + a.name + "' has offset " + std::to_string(offset) +
                           ", past the end of the appended data (" + std::to_string(available) + " bytes)");
        const std::size_t begin = doc_.opaque_data + static_cast<std::size_t>(offset);
        a.data_byte = begin;
        if (!appended_base64_) {
            unpack_payload(a, text_.substr(begin, appended_end_ - begin), begin, true);
        } else {
            // A base64 array runs up to where the next one starts.
            const auto next = std::upper_bound(appended_offsets_.begin(), appended_offsets_.end(), offset);
            const std::size_t end =
                next == appended_offsets_.end() ? appended_end_ : doc_.opaque_data + static_cast<std::size_t>(*next);
            std::string decoded;
            if (!base64_decode(text_.substr(begin, end - begin), decoded))
                fail_at_byte(begin, "DataArray '" + a.name + "': invalid base64 in the appended data");
            a.owned.assign(decoded.begin(), decoded.end());
            unpack_payload(a, std::string_view(a.owned.data(), a.owned.size()), begin, false);
        }
    } else {
        fail_at(e, "DataArray '" + a.name + "' has format \"" + format->substr(0, 40) +
                       "\" (expected ascii, binary or appended)");
    }
    if (!a.ascii && a.packed.size() % vtk::size_of(a.type) != 0)
        fail_at_byte(a.data_byte, "DataArray '" + a.name + "' holds " + std::to_string(a.packed.size()) +
                                      " bytes, not a whole number of " + *type + " values");
    return a;
}

// `data` starts with the array's header: its byte count, or the zlib block table.
void VtuReader::unpack_payload(ArrayData& a, std::string_view data, std::size_t byte, bool in_file) const {
    const std::size_t word = header64_ ? 8 : 4;
    const std::string array = "DataArray '" + a.name + "'";
    if (!zlib_) {
        if (data.size() < word) fail_at_byte(byte, array + ": the file ends inside its byte-count header");
        const std::uint64_t n = header_word(data.data());
        if (n > data.size() - word)
            fail_at_byte(byte, array + " declares " + std::to_string(n) + " bytes, but only " +
                                   std::to_string(data.size() - word) + " follow (truncated file or bad offset?)");
        a.packed = data.substr(word, static_cast<std::size_t>(n));
        if (in_file) a.file_byte = byte + word;
        return;
    }
    // [blocks, block size, size of the last block (0 if full), compressed size of each block]
    if (data.size() < 3 * word) fail_at_byte(byte, array + ": the file ends inside its compression header");
    const std::uint64_t blocks = header_word(data.data());
    const std::uint64_t block_size = header_word(data.data() + word);
    const std::uint64_t last_size = header_word(data.data() + 2 * word);
    if (blocks > (data.size() - 3 * word) / word)
        fail_at_byte(byte, array + ": the compression header lists " + std::to_string(blocks) +
                               " blocks, more than the data can hold");
    const std::size_t header = (3 + static_cast<std::size_t>(blocks)) * word;
    std::uint64_t compressed_total = 0;
    std::uint64_t total = 0;
    for (std::uint64_t b = 0; b < blocks; ++b) {
        const std::uint64_t compressed = header_word(data.data() + (3 + b) * word);
        const std::uint64_t size = b + 1 == blocks && last_size != 0 ? last_size : block_size;
        if (compressed > data.size() - header - compressed_total)
            fail_at_byte(byte, array + ": compressed block " + std::to_string(b) + " runs past the end of the data");
        // Deflate cannot shrink data more than about 1032:1, so a larger claim is corrupt, and
        // refusing it avoids a giant allocation.
        if (size > compressed * 1032 + 64)
            fail_at_byte(byte, array + ": block " + std::to_string(b) + " claims " + std::to_string(size) +
                                   " bytes from " + std::to_string(compressed) + " compressed bytes");
        compressed_total += compressed;
        total += size;
    }
    // `data` may live in a.owned, so the output goes to a buffer of its own.
    std::vector<char> inflated(static_cast<std::size_t>(total));
    std::size_t in = header;
    std::size_t out = 0;
    for (std::uint64_t b = 0; b < blocks; ++b) {
        const std::uint64_t compressed = header_word(data.data() + (3 + b) * word);
        const std::uint64_t size = b + 1 == blocks && last_size != 0 ? last_size : block_size;
        uLongf produced = static_cast<uLongf>(size);
        const int status = uncompress(reinterpret_cast<Bytef*>(inflated.data() + out), &produced,
                                      reinterpret_cast<const Bytef*>(data.data() + in), static_cast<uLong>(compressed));
        if (status != Z_OK || produced != size)
            fail_at_byte(in_file ? byte + in : byte, array + ": zlib block " + std::to_string(b) + " is corrupt (" +
                                                         (status == Z_OK ? "wrong size" : zError(status)) + ")");
        in += static_cast<std::size_t>(compressed);
        out += static_cast<std::size_t>(size);
    }
    a.owned = std::move(inflated);
    a.packed = std::string_view(a.owned.data(), a.owned.size());
}

template <class T>
std::vector<T> VtuReader::values(const ArrayData& a) const {
    std::vector<T> out;
    if (!a.ascii) {
        const std::size_t size = vtk::size_of(a.type);
        const std::size_t n = a.packed.size() / size;
        out.resize(n);
        for (std::size_t i = 0; i < n; ++i) out[i] = vtk::load<T>(a.packed.data() + i * size, a.type, swap_);
        return out;
    }
    TokenCursor cursor(text_, a.element->text);
    std::string_view token;
    const bool integral = vtk::is_integer(a.type);
    while (cursor.next(token)) {
        bool ok = false;
        if (integral) {
            std::int64_t v = 0;
            ok = parse_integer(token, v);
            out.push_back(static_cast<T>(v));
        } else {
            double v = 0.0;
            ok = parse_real(token, v);
            out.push_back(static_cast<T>(v));
        }
        if (!ok)
            throw FileError(path_, cursor.line(),
                            "DataArray '" + a.name + "': expected " + (integral ? "an integer" : "a number") +
                                ", found '" + std::string(token.substr(0, 40)) + "'");
    }
    return out;
}

std::vector<std::int64_t> VtuReader::integers(const ArrayData& a) const {
    if (!vtk::is_integer(a.type)) fail_at(*a.element, "DataArray '" + a.name + "' must have an integer type");
    return values<std::int64_t>(a);
}

void VtuReader::read_points(const XmlElement& piece, std::int64_t points) {
    const XmlElement& element = only_child(piece, "Points");
    const std::vector<const XmlElement*> arrays = doc_.children(element, "DataArray");
    if (arrays.empty()) fail_at(element, "<Points> has no DataArray");
    const ArrayData a = load_array(*arrays.front());
    if (a.components != 3)
        fail_at(*a.element, "the Points DataArray has " + std::to_string(a.components) + " components, not 3");
    raw_.coordinates = values<double>(a);
    if (raw_.coordinates.size() % 3 != 0 || raw_.coordinates.size() / 3 != static_cast<std::size_t>(points))
        fail_at(*a.element, "the Points DataArray holds " + std::to_string(raw_.coordinates.size()) +
                                " values, but NumberOfPoints=" + std::to_string(points) + " needs 3 per point");
    for (std::size_t i = 0; i < raw_.coordinates.size(); ++i)
        if (!std::isfinite(raw_.coordinates[i]))
            fail_value(a, i, "point " + std::to_string(i / 3) + " has a non-finite coordinate");
}

void VtuReader::read_cells(const XmlElement& piece, std::int64_t points, std::int64_t cells) {
    const XmlElement& element = only_child(piece, "Cells");
    auto find = [&](std::string_view name) {
        for (const XmlElement* e : doc_.children(element, "DataArray"))
            if (const std::string* n = e->attribute("Name"); n && *n == name) return load_array(*e);
        fail_at(element, "<Cells> has no DataArray named '" + std::string(name) + "'");
    };
    const ArrayData connectivity_array = find("connectivity");
    const ArrayData offsets_array = find("offsets");
    const ArrayData types_array = find("types");
    const std::vector<std::int64_t> connectivity = integers(connectivity_array);
    const std::vector<std::int64_t> offsets = integers(offsets_array);
    const std::vector<std::int64_t> types = integers(types_array);
    const auto n = static_cast<std::size_t>(cells);
    if (offsets.size() != n)
        fail_at(*offsets_array.element, "the offsets DataArray has " + std::to_string(offsets.size()) +
                                            " values, but NumberOfCells=" + std::to_string(cells));
    if (types.size() != n)
        fail_at(*types_array.element, "the types DataArray has " + std::to_string(types.size()) +
                                          " values, but NumberOfCells=" + std::to_string(cells));
    // Each offset is where a cell ends in the connectivity.
    const auto size = static_cast<std::int64_t>(connectivity.size());
    std::int64_t previous = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (offsets[i] < previous || offsets[i] > size)
            fail_value(offsets_array, i,
                       "offset " + std::to_string(offsets[i]) + " of cell " + std::to_string(i) +
                           " must lie between the previous offset (" + std::to_string(previous) +
                           ") and the connectivity size (" + std::to_string(size) + ")");
        previous = offsets[i];
    }
    if (previous != size)
        fail_at(*offsets_array.element, "the cells use " + std::to_string(previous) +
                                            " connectivity entries, but the connectivity DataArray has " +
                                            std::to_string(size));
    for (std::size_t j = 0; j < connectivity.size(); ++j)
        if (connectivity[j] < 0 || connectivity[j] >= points) {
            const auto cell =
                std::upper_bound(offsets.begin(), offsets.end(), static_cast<std::int64_t>(j)) - offsets.begin();
            fail_value(connectivity_array, j,
                       "cell " + std::to_string(cell) + " refers to point " + std::to_string(connectivity[j]) +
                           ", outside 0.." + std::to_string(points - 1));
        }
    for (std::size_t i = 0; i < n; ++i) {
        const std::int64_t begin = i == 0 ? 0 : offsets[i - 1];
        const std::string problem = vtk::cell_problem(i, types[i], offsets[i] - begin);
        if (!problem.empty()) fail_value(types_array, i, problem);
        vtk::add_cell(raw_, i, types[i], connectivity.data() + begin);
    }
}

void VtuReader::read_fields(const XmlElement& piece, std::string_view section, std::int64_t count,
                            std::vector<Field>& out) const {
    for (const XmlElement* element : doc_.children(piece, section)) {
        for (const XmlElement* e : doc_.children(*element, "DataArray")) {
            const ArrayData a = load_array(*e);
            Field field{a.name, static_cast<int>(a.components), values<double>(a)};
            const auto components = static_cast<std::size_t>(a.components);
            if (field.values.size() % components != 0 ||
                field.values.size() / components != static_cast<std::size_t>(count))
                fail_at(*e, "DataArray '" + a.name + "' holds " + std::to_string(field.values.size()) + " values; " +
                                std::to_string(count) + " tuples of " + std::to_string(a.components) +
                                " were expected");
            out.push_back(std::move(field));
        }
    }
}

RawMesh VtuReader::read() {
    text_ = scanner_.bytes(scanner_.size(), "the file");
    if (text_.empty()) throw FileError(path_, 0, "the file is empty (expected a VTK XML UnstructuredGrid)");
    doc_ = parse_xml(text_, path_, "AppendedData");
    read_header();
    const XmlElement& grid = only_child(doc_.root(), "UnstructuredGrid");
    const std::vector<const XmlElement*> pieces = doc_.children(grid, "Piece");
    if (pieces.empty()) fail_at(grid, "<UnstructuredGrid> has no <Piece>");
    if (pieces.size() > 1)
        fail_at(*pieces[1], "the file holds " + std::to_string(pieces.size()) +
                                " pieces; Paloverde reads single-piece .vtu files (merge the pieces first)");
    const XmlElement& piece = *pieces.front();
    const std::int64_t points = integer_attribute(piece, "NumberOfPoints", 0, true);
    const std::int64_t cells = integer_attribute(piece, "NumberOfCells", 0, true);
    read_points(piece, points);
    read_cells(piece, points, cells);
    read_fields(piece, "PointData", points, raw_.point_fields);
    read_fields(piece, "CellData", cells, raw_.cell_fields);
    return std::move(raw_);
}

// Writing ---------------------------------------------------------------------------------


enum class Content { Field, Points, Connectivity, Offsets, Types };

struct ArrayToWrite {
    Content content;
    const Field* field = nullptr;
};

class VtuWriter {
public:
    VtuWriter(std::ostream& out, const MeshToWrite& data, bool binary)
        : out_(out), data_(data), mesh_(data.mesh), binary_(binary) {}
    void write();

private:
    std::string_view type(const ArrayToWrite& a) const {
        if (a.content == Content::Types) return "UInt8";
        if (a.content == Content::Connectivity || a.content == Content::Offsets) return "Int64";
        return "Float64";
    }
    std::uint64_t values(const ArrayToWrite& a) const {
        const auto m = static_cast<std::uint64_t>(data_.cells());
        switch (a.content) {
            case Content::Field: return a.field->values.size();
            case Content::Points: return mesh_.coordinates().size();
            case Content::Connectivity: return data_.connectivity.size();
            case Content::Offsets:
            case Content::Types: return m;
        }
        return 0;
    }
    std::uint64_t bytes(const ArrayToWrite& a) const { return values(a) * (a.content == Content::Types ? 1 : 8); }
    void element(const ArrayToWrite& a, std::string_view name, int components, std::uint64_t& offset);
    void ascii_values(const ArrayToWrite& a);
    void binary_values(const ArrayToWrite& a);

    vtk::Output out_;
    const MeshToWrite& data_;
    const Mesh& mesh_;
    bool binary_;
    std::vector<ArrayToWrite> appended_;
};

void VtuWriter::element(const ArrayToWrite& a, std::string_view name, int components, std::uint64_t& offset) {
    out_.text("        <DataArray type=\"").text(type(a)).text('"');
    if (!name.empty()) out_.text(" Name=\"").text(xml_escaped(name)).text('"');
    if (components != 1) out_.text(" NumberOfComponents=\"").integer(components).text('"');
    if (binary_) {
        out_.text(" format=\"appended\" offset=\"").integer(static_cast<std::int64_t>(offset)).text("\"/>\n");
        offset += 8 + bytes(a);
        appended_.push_back(a);
        return;
    }
    out_.text(" format=\"ascii\">\n");
    ascii_values(a);
    out_.text("        </DataArray>\n");
}

void VtuWriter::ascii_values(const ArrayToWrite& a) {
    // One tuple (or cell) per line, or rows of 6 single values as ParaView writes them.
    if (a.content == Content::Connectivity) {
        for (std::size_t c = 0; c < data_.cells(); ++c) {
            out_.text("          ");
            const auto cell = data_.cell(c);
            for (std::size_t i = 0; i < cell.size(); ++i) out_.integer(cell[i]).text(i + 1 == cell.size() ? '\n' : ' ');
        }
        return;
    }
    const std::uint64_t n = values(a);
    std::uint64_t per_line = 6;
    if (a.content == Content::Points) per_line = 3;
    if (a.content == Content::Field && a.field->components > 1)
        per_line = static_cast<std::uint64_t>(a.field->components);
    for (std::uint64_t i = 0; i < n; ++i) {
        if (i % per_line == 0) out_.text("          ");
        switch (a.content) {
            case Content::Field: out_.real(a.field->values[i]); break;
            case Content::Points: out_.real(mesh_.coordinates()[i]); break;
            case Content::Connectivity: break;
            case Content::Offsets: out_.integer(data_.end_of(i)); break;
            case Content::Types: out_.integer(cell_info(data_.type(i)).vtk); break;
        }
        out_.text((i + 1) % per_line == 0 || i + 1 == n ? '\n' : ' ');
    }
}

void VtuWriter::binary_values(const ArrayToWrite& a) {
    const bool big = !host_is_little_endian();
    const std::size_t m = data_.cells();
    out_.binary(bytes(a), big);
    switch (a.content) {
        case Content::Field:
            for (double v : a.field->values) out_.binary(v, big);
            break;
        case Content::Points:
            for (double v : mesh_.coordinates()) out_.binary(v, big);
            break;
        case Content::Connectivity:
            for (VertexId v : data_.connectivity) out_.binary(static_cast<std::int64_t>(v), big);
            break;
        case Content::Offsets:
            for (std::size_t c = 0; c < m; ++c) out_.binary(data_.end_of(c), big);
            break;
        case Content::Types:
            for (std::size_t c = 0; c < m; ++c) out_.binary(static_cast<std::uint8_t>(cell_info(data_.type(c)).vtk), big);
            break;
    }
}

void VtuWriter::write() {
    out_.text("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"");
    out_.text(host_is_little_endian() ? "LittleEndian" : "BigEndian").text("\" header_type=\"UInt64\">\n");
    out_.text("  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"").integer(mesh_.num_vertices());
    out_.text("\" NumberOfCells=\"").integer(static_cast<std::int64_t>(data_.cells())).text("\">\n");
    std::uint64_t offset = 0;
    if (!data_.point_fields.empty()) {
        out_.text("      <PointData>\n");
        for (const Field& f : data_.point_fields) element({Content::Field, &f}, f.name, f.components, offset);
        out_.text("      </PointData>\n");
    }
    if (!data_.cell_fields.empty()) {
        out_.text("      <CellData>\n");
        for (const Field& f : data_.cell_fields) element({Content::Field, &f}, f.name, f.components, offset);
        out_.text("      </CellData>\n");
    }
    out_.text("      <Points>\n");
    element({Content::Points}, "Points", 3, offset);
    out_.text("      </Points>\n      <Cells>\n");
    element({Content::Connectivity}, "connectivity", 1, offset);
    element({Content::Offsets}, "offsets", 1, offset);
    element({Content::Types}, "types", 1, offset);
    out_.text("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    if (binary_) {
        out_.text("  <AppendedData encoding=\"raw\">\n   _");
        for (const ArrayToWrite& a : appended_) binary_values(a);
        out_.text("\n  </AppendedData>\n");
    }
    out_.text("</VTKFile>\n");
    out_.flush();
}

}  // namespace

RawMesh read_vtu(const std::string& path) {
    VtuReader reader(path);
    return reader.read();
}

void write_vtu(std::ostream& out, const MeshToWrite& data, Encoding encoding) {
    vtk::check_unique_names(data.point_fields, "point", false);
    vtk::check_unique_names(data.cell_fields, "cell", false);
    VtuWriter writer(out, data, encoding == Encoding::Binary);
    writer.write();
}

}  // namespace paloverde::io
