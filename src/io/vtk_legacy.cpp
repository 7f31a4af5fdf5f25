// VTK legacy files (.vtk), DATASET UNSTRUCTURED_GRID, ASCII or BINARY (big-endian).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "paloverde/core/error.hpp"
#include "raw_mesh.hpp"
#include "text_scanner.hpp"
#include "vtk_common.hpp"

namespace paloverde::io {

namespace {

using vtk::ValueType;

bool iequals(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
           });
}

// Keeps messages readable when a wrong count has put the reader inside binary data.
std::string printable(std::string_view text) {
    std::string out;
    for (char c : text.substr(0, 40)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
    return out;
}

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        const std::size_t begin = i;
        while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        if (i > begin) out.push_back(line.substr(begin, i - begin));
    }
    return out;
}

enum class Section { None, Points, Cells };

class LegacyReader {
public:
    explicit LegacyReader(const std::string& path) : s_(path) {}
    RawMesh read();

private:
    void read_header();
    void read_points();
    void read_cells();
    void read_classic_cells(std::int64_t cells, std::int64_t size);
    void read_offset_cells(std::int64_t offsets, std::int64_t connectivity);
    void read_cell_types();
    void check_early_cell_data() const {
        if (early_cell_data_ >= 0 && early_cell_data_ != cells_)
            s_.fail("CELLS declares " + std::to_string(cells_) + " cells, but the CELL_DATA section before it declares " +
                    std::to_string(early_cell_data_));
    }
    void start_section(Section section);
    void read_attribute(std::string_view keyword);
    void read_field(bool per_entity);
    // The number of values of a field with `components` per entry of the current section,
    // failing (at `line`) if they cannot fit in the rest of the file.
    std::size_t field_size(const std::string& name, std::int64_t components, ValueType type, std::size_t line) const;
    Field read_field_values(std::string name, std::int64_t components, ValueType type, std::size_t values);
    void keep(Field&& field) {
        (section_ == Section::Points ? raw_.point_fields : raw_.cell_fields).push_back(std::move(field));
    }
    void skip_metadata();

    ValueType value_type(std::string_view name);
    ValueType integer_type(std::string_view name, std::string_view what);
    // How many values could still fit in the file: a bound for declared counts, checked before
    // anything is allocated.
    std::int64_t max_values() const {
        return static_cast<std::int64_t>(binary_ ? s_.remaining() : (s_.remaining() + 1) / 2);
    }
    // In binary files the data starts right after the newline that ends its header line.
    void end_header_line() {
        if (binary_) s_.skip_one_newline();
    }
    // Reads n values of `type` (ASCII tokens or big-endian binary) and hands each to
    // consume(index, value), which may call fail_value().
    template <class T, class Consume>
    void read_values(std::size_t n, ValueType type, std::string_view what, Consume&& consume);
    // Fails at the line (ASCII) or byte (binary) of the value just read.
    [[noreturn]] void fail_value(const std::string& message) const;
    // For a header line already consumed whole.
    [[noreturn]] void fail_at_line(std::size_t line, const std::string& message) const {
        if (binary_) s_.fail(message);
        throw FileError(s_.path(), line, message);
    }

    TextScanner s_;
    bool binary_ = false;
    int major_version_ = 2;
    RawMesh raw_;
    std::int64_t points_ = -1;           // -1 until POINTS is read
    std::int64_t cells_ = -1;            // -1 until CELLS is read
    std::vector<std::int64_t> offsets_;  // cells_ + 1 entries into connectivity_
    std::vector<std::int64_t> connectivity_;
    bool have_types_ = false;
    Section section_ = Section::None;
    std::int64_t section_size_ = 0;
    // POINT_DATA / CELL_DATA sizes declared before POINTS / CELLS (-1: none), checked against them.
    std::int64_t early_point_data_ = -1;
    std::int64_t early_cell_data_ = -1;
    std::size_t value_byte_ = 0;
    // Where the text value being consumed ends, while read_values() consumes values read ahead.
    static constexpr std::size_t kNoValue = static_cast<std::size_t>(-1);
    std::size_t value_end_ = kNoValue;
};

void LegacyReader::fail_value(const std::string& message) const {
    if (binary_) throw FileError::at_byte(s_.path(), value_byte_, message);
    if (value_end_ != kNoValue) s_.fail_at(value_end_, message);
    s_.fail(message);
}

template <class T, class Consume>
void LegacyReader::read_values(std::size_t n, ValueType type, std::string_view what, Consume&& consume) {
    if (binary_ && type == ValueType::Bit) {
        const std::size_t begin = s_.offset();
        const char* data = s_.bytes((n + 7) / 8, what).data();
        for (std::size_t i = 0; i < n; ++i) {
            value_byte_ = begin + i / 8;
            consume(i, static_cast<T>((static_cast<unsigned char>(data[i / 8]) >> (7 - i % 8)) & 1));
        }
        return;
    }
    if (binary_) {
        const std::size_t size = vtk::size_of(type);
        const std::size_t begin = s_.offset();
        const char* data = s_.bytes(n * size, what).data();
        const bool swap = host_is_little_endian();
        for (std::size_t i = 0; i < n; ++i) {
            value_byte_ = begin + i * size;
            consume(i, vtk::load<T>(data + i * size, type, swap));
        }
        return;
    }
    if constexpr (std::is_integral_v<T>) {
        // Plain integers a chunk at a time; each is consumed as if just read (fail_value names
        // the line it ends on), and one that is not plain is read the usual way.
        constexpr std::size_t kChunk = 1024;
        std::int64_t values[kChunk];
        std::size_t ends[kChunk];
        for (std::size_t i = 0; i < n;) {
            const std::size_t asked = std::min(kChunk, n - i);
            const std::size_t got = s_.plain_integers(values, ends, asked);
            for (std::size_t j = 0; j < got; ++j, ++i) {
                value_end_ = ends[j];
                consume(i, values[j]);
            }
            if (got < asked) {
                const std::int64_t v = s_.integer(what);
                value_end_ = s_.offset();
                consume(i++, v);
            }
        }
        value_end_ = kNoValue;
    } else {
        for (std::size_t i = 0; i < n; ++i) consume(i, s_.real(what));
    }
}

ValueType LegacyReader::value_type(std::string_view name) {
    struct Known {
        std::string_view name;
        ValueType type;
    };
    // "long" is 8 bytes as VTK writes it on LP64 systems; vtkIdType is written as a 4-byte int.
    // Mesquite writes its `fixed` flags as "bit" (0 and 1 in ASCII files).
    static constexpr Known known[] = {
        {"bit", ValueType::Bit},
        {"unsigned_char", ValueType::UInt8},
        {"char", ValueType::Int8},
        {"signed_char", ValueType::Int8},
        {"unsigned_short", ValueType::UInt16},
        {"short", ValueType::Int16},
        {"unsigned_int", ValueType::UInt32},
        {"int", ValueType::Int32},
        {"vtkIdType", ValueType::Int32},
        {"unsigned_long", ValueType::UInt64},
        {"long", ValueType::Int64},
        {"float", ValueType::Float32},
        {"double", ValueType::Float64},
        // VTK 9's names by size (its own writer uses them for OFFSETS and CONNECTIVITY; meshio for
        // any array).
        {"vtktypeint8", ValueType::Int8},
        {"vtktypeuint8", ValueType::UInt8},
        {"vtktypeint16", ValueType::Int16},
        {"vtktypeuint16", ValueType::UInt16},
        {"vtktypeint32", ValueType::Int32},
        {"vtktypeuint32", ValueType::UInt32},
        {"vtktypeint64", ValueType::Int64},
        {"vtktypeuint64", ValueType::UInt64},
        {"vtktypefloat32", ValueType::Float32},
        {"vtktypefloat64", ValueType::Float64},
    };
    for (const Known& k : known)
        if (iequals(name, k.name)) return k.type;
    s_.fail("unsupported data type '" + printable(name) +
            "' (expected float, double, int, unsigned_int, short, unsigned_short, char, unsigned_char, long, "
            "unsigned_long, vtkIdType, bit, or vtktypeint8 to vtktypeint64, vtktypeuint8 to vtktypeuint64, "
            "vtktypefloat32 or vtktypefloat64)");
}

ValueType LegacyReader::integer_type(std::string_view name, std::string_view what) {
    const ValueType type = value_type(name);
    if (!vtk::is_integer(type))
        s_.fail(std::string(what) + " must have an integer type, not '" + printable(name) + "'");
    return type;
}

void LegacyReader::read_header() {
    if (s_.size() == 0) s_.fail("the file is empty (expected a '# vtk DataFile Version' header)");
    const std::string_view first = s_.rest_of_line();
    constexpr std::string_view magic = "# vtk DataFile Version";
    if (first.size() < magic.size() || !iequals(first.substr(0, magic.size()), magic))
        throw FileError(s_.path(), 1,
                        "not a VTK legacy file: the first line should start with '# vtk DataFile Version', found '" +
                            printable(first) + "'");
    const std::vector<std::string_view> version = split(first.substr(magic.size()));
    if (!version.empty()) {
        std::int64_t major = 0;
        const std::string_view v = version.front();
        if (parse_integer(v.substr(0, v.find('.')), major)) major_version_ = static_cast<int>(major);
    }
    // (at_end() would skip an empty title line along with the whitespace)
    if (s_.remaining() == 0) s_.fail("the file ends after its first line; expected a title line");
    s_.skip_line();  // the title, free text
    const std::string_view format = s_.expect_token("ASCII or BINARY");
    if (iequals(format, "BINARY")) {
        binary_ = true;
        s_.report_byte_offsets();
    } else if (!iequals(format, "ASCII"))
        s_.fail("expected ASCII or BINARY on the third line, found '" + printable(format) + "'");
    const std::string_view dataset = s_.expect_token("DATASET");
    if (!iequals(dataset, "DATASET"))
        s_.fail("expected 'DATASET UNSTRUCTURED_GRID', found '" + printable(dataset) + "'");
    const std::string_view kind = s_.expect_token("the dataset type");
    if (!iequals(kind, "UNSTRUCTURED_GRID"))
        s_.fail("the file holds a DATASET " + printable(kind) +
                "; Paloverde reads only DATASET UNSTRUCTURED_GRID");
}

void LegacyReader::read_points() {
    if (points_ >= 0) s_.fail("a second POINTS section");
    points_ = s_.count("the number of points", max_values() / 3);
    if (early_point_data_ >= 0 && early_point_data_ != points_)
        s_.fail("POINTS " + std::to_string(points_) + " does not match the POINT_DATA " +
                std::to_string(early_point_data_) + " declared before it");
    const ValueType type = value_type(s_.expect_token("the POINTS data type"));
    end_header_line();
    const auto n = static_cast<std::size_t>(points_);
    raw_.coordinates.reserve(3 * n);
    read_values<double>(3 * n, type, "a point coordinate", [&](std::size_t i, double x) {
        if (!std::isfinite(x)) fail_value("point " + std::to_string(i / 3) + " has a non-finite coordinate");
        raw_.coordinates.push_back(x);
    });
}

void LegacyReader::read_cells() {
    if (cells_ >= 0) s_.fail("a second CELLS section");
    if (points_ < 0) s_.fail("CELLS comes before POINTS; the points must come first");
    const std::int64_t first = s_.count("the number of cells", max_values());
    const std::int64_t second = s_.count("the CELLS size", max_values());
    if (major_version_ >= 5)
        read_offset_cells(first, second);
    else
        read_classic_cells(first, second);
}

// `CELLS n size`, then per cell its point count and the point ids: size = n + all the ids.
void LegacyReader::read_classic_cells(std::int64_t cells, std::int64_t size) {
    if (size < cells || (cells == 0 && size > 0))
        s_.fail("CELLS " + std::to_string(cells) + " " + std::to_string(size) +
                ": the size must count each cell's point count and its point ids");
    end_header_line();
    cells_ = cells;
    check_early_cell_data();
    offsets_.assign(1, 0);
    offsets_.reserve(static_cast<std::size_t>(cells) + 1);
    connectivity_.reserve(static_cast<std::size_t>(size - cells));
    std::int64_t left = 0;  // ids still to come in the current cell
    std::size_t started = 0;
    s_.set_entry([&] { return "cell " + std::to_string(left == 0 ? started : started - 1); });
    read_values<std::int64_t>(
        static_cast<std::size_t>(size), ValueType::Int32, "a cell's point count or point id",
        [&](std::size_t i, std::int64_t v) {
            const auto values_left = static_cast<std::int64_t>(static_cast<std::size_t>(size) - i - 1);
            if (left == 0) {
                if (v < 0 || v > values_left)
                    fail_value("cell " + std::to_string(started) + " claims " + std::to_string(v) + " points, but " +
                               std::to_string(values_left) + " values are left of the CELLS size " +
                               std::to_string(size));
                left = v;
                offsets_.push_back(offsets_.back() + v);
                ++started;
            } else {
                if (v < 0 || v >= points_)
                    fail_value("cell " + std::to_string(started - 1) + " refers to point " + std::to_string(v) +
                               ", outside 0.." + std::to_string(points_ - 1));
                connectivity_.push_back(v);
                --left;
            }
            if (left == 0 && started == static_cast<std::size_t>(cells) && values_left > 0)
                fail_value("cell count/size mismatch: the " + std::to_string(cells) + " cells end after " +
                           std::to_string(i + 1) + " values, but CELLS declares size " + std::to_string(size));
        });
    s_.set_entry({});
    if (started != static_cast<std::size_t>(cells))
        fail_value("cell count/size mismatch: CELLS declares " + std::to_string(cells) + " cells in " +
                   std::to_string(size) + " values, but they hold only " + std::to_string(started) + " cells");
}

// VTK 5.x: `CELLS offsets connectivity`, then `OFFSETS type` and `CONNECTIVITY type` arrays.
void LegacyReader::read_offset_cells(std::int64_t offsets, std::int64_t connectivity) {
    s_.expect_keyword("OFFSETS");
    const ValueType offset_type = integer_type(s_.expect_token("the OFFSETS data type"), "OFFSETS");
    end_header_line();
    cells_ = offsets == 0 ? 0 : offsets - 1;
    check_early_cell_data();
    offsets_.reserve(static_cast<std::size_t>(offsets));
    read_values<std::int64_t>(
        static_cast<std::size_t>(offsets), offset_type, "a cell offset", [&](std::size_t i, std::int64_t v) {
            if (i == 0 && v != 0) fail_value("the first offset must be 0, not " + std::to_string(v));
            if (i > 0 && (v < offsets_.back() || v > connectivity))
                fail_value("offset " + std::to_string(i) + " (" + std::to_string(v) +
                           ") must lie between the previous offset (" + std::to_string(offsets_.back()) +
                           ") and the connectivity size (" + std::to_string(connectivity) + ")");
            if (i + 1 == static_cast<std::size_t>(offsets) && v != connectivity)
                fail_value("cell count/size mismatch: the last offset is " + std::to_string(v) +
                           " but CELLS declares " + std::to_string(connectivity) + " connectivity entries");
            offsets_.push_back(v);
        });
    if (offsets == 0) {
        if (connectivity != 0)
            s_.fail("CELLS declares no offsets but " + std::to_string(connectivity) + " connectivity entries");
        offsets_.assign(1, 0);
    }
    s_.expect_keyword("CONNECTIVITY");
    const ValueType id_type = integer_type(s_.expect_token("the CONNECTIVITY data type"), "CONNECTIVITY");
    end_header_line();
    connectivity_.reserve(static_cast<std::size_t>(connectivity));
    auto cell_of = [&](std::size_t i) {
        return std::upper_bound(offsets_.begin(), offsets_.end(), static_cast<std::int64_t>(i)) - offsets_.begin() - 1;
    };
    s_.set_entry([&] { return "cell " + std::to_string(cell_of(connectivity_.size())); });
    read_values<std::int64_t>(
        static_cast<std::size_t>(connectivity), id_type, "a point id", [&](std::size_t i, std::int64_t v) {
            if (v < 0 || v >= points_)
                fail_value("cell " + std::to_string(cell_of(i)) + " refers to point " + std::to_string(v) +
                           ", outside 0.." + std::to_string(points_ - 1));
            connectivity_.push_back(v);
        });
    s_.set_entry({});
}

void LegacyReader::read_cell_types() {
    if (have_types_) s_.fail("a second CELL_TYPES section");
    if (cells_ < 0) s_.fail("CELL_TYPES comes before CELLS");
    const std::int64_t n = s_.count("the number of cell types", max_values());
    if (n != cells_)
        s_.fail("CELL_TYPES lists " + std::to_string(n) + " cells but CELLS declares " + std::to_string(cells_));
    end_header_line();
    have_types_ = true;
    // At most every cell, with every id: room made once, not by doubling as the cells come.
    raw_.cell_types.reserve(raw_.cell_types.size() + static_cast<std::size_t>(n));
    raw_.cell_positions.reserve(raw_.cell_positions.size() + static_cast<std::size_t>(n));
    raw_.cell_connectivity.reserve(raw_.cell_connectivity.size() + connectivity_.size());
    std::size_t typed = 0;
    s_.set_entry([&] { return "the type of cell " + std::to_string(typed); });
    read_values<std::int64_t>(static_cast<std::size_t>(n), ValueType::Int32, "a cell type",
                              [&](std::size_t i, std::int64_t type) {
                                  const std::int64_t first = offsets_[i];
                                  const std::string problem = vtk::cell_problem(i, type, offsets_[i + 1] - first);
                                  if (!problem.empty()) fail_value(problem);
                                  vtk::add_cell(raw_, i, type, connectivity_.data() + first);
                                  typed = i + 1;
                              });
    s_.set_entry({});
}

void LegacyReader::start_section(Section section) {
    const bool points = section == Section::Points;
    const char* name = points ? "POINT_DATA" : "CELL_DATA";
    const std::int64_t n = s_.count(std::string("the ") + name + " count", max_values());
    const std::int64_t expected = points ? points_ : cells_;
    if (expected >= 0 && n != expected)
        s_.fail(std::string(name) + " " + std::to_string(n) + " does not match the " + std::to_string(expected) +
                (points ? " points" : " cells"));
    if (expected < 0) (points ? early_point_data_ : early_cell_data_) = n;
    section_ = section;
    section_size_ = n;
}

void LegacyReader::read_attribute(std::string_view keyword) {
    int components = 0;  // for the kinds with a fixed count
    if (iequals(keyword, "VECTORS") || iequals(keyword, "NORMALS")) components = 3;
    if (iequals(keyword, "TENSORS")) components = 9;
    if (iequals(keyword, "TENSORS6")) components = 6;
    if (iequals(keyword, "GLOBAL_IDS") || iequals(keyword, "PEDIGREE_IDS")) components = 1;
    const bool scalars = iequals(keyword, "SCALARS");
    const bool texture = iequals(keyword, "TEXTURE_COORDINATES");
    const bool table = iequals(keyword, "LOOKUP_TABLE");
    const bool colors = iequals(keyword, "COLOR_SCALARS");
    const bool field = iequals(keyword, "FIELD");
    if (components == 0 && !scalars && !texture && !table && !colors && !field)
        s_.fail("unknown keyword '" + printable(keyword) +
                "' (expected POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, or in a data section SCALARS, "
                "VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, FIELD, GLOBAL_IDS, PEDIGREE_IDS, COLOR_SCALARS, "
                "LOOKUP_TABLE or METADATA)");
    if (section_ == Section::None) s_.fail(std::string(keyword) + " outside a POINT_DATA or CELL_DATA section");
    if (field) return read_field(true);
    if (scalars) {
        // SCALARS name type [components]: the count is optional, so the line is read whole.
        const std::size_t line = s_.line();
        const std::vector<std::string_view> words = split(s_.rest_of_line());
        if (words.size() < 2 || words.size() > 3) fail_at_line(line, "expected 'SCALARS name type [components]'");
        std::int64_t count = 1;
        if (words.size() == 3 && (!parse_integer(words[2], count) || count < 1))
            fail_at_line(line, "invalid SCALARS component count '" + printable(words[2]) + "'");
        const std::string name = vtk::decode_legacy_name(words[0]);
        const ValueType type = value_type(words[1]);
        const std::size_t values = field_size(name, count, type, line);
        const std::string_view lookup = s_.expect_token("LOOKUP_TABLE");
        if (!iequals(lookup, "LOOKUP_TABLE"))
            s_.fail("expected 'LOOKUP_TABLE name' after SCALARS " + printable(name) + ", found '" + printable(lookup) +
                    "'");
        s_.expect_token("the lookup table name");
        end_header_line();
        return keep(read_field_values(name, count, type, values));
    }
    if (table || colors) {
        // Colors: floats in ASCII files, unsigned bytes in binary ones. A table has 4 per entry.
        const std::string name = vtk::decode_legacy_name(s_.expect_token("a name"));
        const std::int64_t n = s_.count(table ? "the table size" : "the number of color components", max_values() / 4);
        end_header_line();
        const ValueType type = binary_ ? ValueType::UInt8 : ValueType::Float64;
        if (table) {
            read_values<double>(static_cast<std::size_t>(4 * n), type, "a lookup table value",
                                [](std::size_t, double) {});
            return;
        }
        if (n < 1) s_.fail("COLOR_SCALARS needs at least one component");
        Field color = read_field_values(name, n, type, field_size(name, n, type, s_.line()));
        if (binary_)
            for (double& v : color.values) v /= 255.0;
        return keep(std::move(color));
    }
    const std::string name = vtk::decode_legacy_name(s_.expect_token("a name"));
    if (texture) {
        components = static_cast<int>(s_.count("the texture dimension", 3));
        if (components < 1) s_.fail("the texture dimension must be 1, 2 or 3");
    }
    const ValueType type = value_type(s_.expect_token("a data type"));
    const std::size_t values = field_size(name, components, type, s_.line());
    end_header_line();
    keep(read_field_values(name, components, type, values));
}

// `FIELD name arrays`, then per array `name components tuples type` and its values.
void LegacyReader::read_field(bool per_entity) {
    s_.expect_token("the FIELD name");
    const std::int64_t arrays = s_.count("the number of FIELD arrays", max_values());
    for (std::int64_t a = 0; a < arrays; ++a) {
        std::string_view name = s_.expect_token("a FIELD array name");
        if (iequals(name, "METADATA")) {
            skip_metadata();
            name = s_.expect_token("a FIELD array name");
        }
        if (name == "NULL_ARRAY") continue;
        const std::string array = vtk::decode_legacy_name(name);
        const std::int64_t components = s_.count("the component count of FIELD array " + array, max_values());
        if (components < 1) s_.fail("FIELD array " + array + " has no components");
        const std::int64_t tuples = s_.count("the tuple count of FIELD array " + array, max_values() / components);
        if (per_entity && tuples != section_size_)
            s_.fail("FIELD array " + array + " has " + std::to_string(tuples) + " tuples, but its section has " +
                    std::to_string(section_size_) + " entries");
        const ValueType type = value_type(s_.expect_token("a data type"));
        if (per_entity) {
            const std::size_t values = field_size(array, components, type, s_.line());
            end_header_line();
            keep(read_field_values(array, components, type, values));
        } else {
            end_header_line();
            read_values<double>(static_cast<std::size_t>(components * tuples), type, "a FIELD value",
                                [](std::size_t, double) {});
        }
    }
}

std::size_t LegacyReader::field_size(const std::string& name, std::int64_t components, ValueType type,
                                     std::size_t line) const {
    const std::size_t n = static_cast<std::size_t>(section_size_) * static_cast<std::size_t>(components);
    const std::int64_t fits = binary_ && type == ValueType::Bit ? 8 * max_values() : max_values();
    if (static_cast<std::int64_t>(n / static_cast<std::size_t>(components)) != section_size_ ||
        static_cast<std::int64_t>(n) > fits || components > std::numeric_limits<int>::max())
        fail_at_line(line, "array " + name + " (" + std::to_string(section_size_) + " tuples of " +
                               std::to_string(components) + " components) cannot fit in the rest of the file");
    return n;
}

Field LegacyReader::read_field_values(std::string name, std::int64_t components, ValueType type, std::size_t values) {
    Field field{std::move(name), static_cast<int>(components), {}};
    field.values.reserve(values);
    read_values<double>(values, type, "a value of " + field.name,
                        [&](std::size_t, double v) { field.values.push_back(v); });
    return field;
}

// VTK 5 writers add METADATA blocks (component names, information keys) that end at an empty line.
void LegacyReader::skip_metadata() {
    s_.skip_line();
    while (s_.remaining() > 0) {
        const std::string_view line = s_.rest_of_line();
        if (std::all_of(line.begin(), line.end(), [](char c) { return std::isspace(static_cast<unsigned char>(c)); }))
            break;
    }
}

RawMesh LegacyReader::read() {
    read_header();
    while (true) {
        const std::string_view key = s_.token();
        if (key.empty()) break;
        if (iequals(key, "POINTS"))
            read_points();
        else if (iequals(key, "CELLS"))
            read_cells();
        else if (iequals(key, "CELL_TYPES"))
            read_cell_types();
        else if (iequals(key, "POINT_DATA"))
            start_section(Section::Points);
        else if (iequals(key, "CELL_DATA"))
            start_section(Section::Cells);
        else if (iequals(key, "METADATA"))
            skip_metadata();
        else if (iequals(key, "FIELD") && section_ == Section::None)
            read_field(false);  // data about the whole dataset (time, title), not per point or cell
        else
            read_attribute(key);
    }
    if (points_ < 0) throw FileError(s_.path(), 0, "the file has no POINTS section");
    if (cells_ < 0) throw FileError(s_.path(), 0, "the file has no CELLS section");
    if (!have_types_) throw FileError(s_.path(), 0, "the file has no CELL_TYPES section");
    return std::move(raw_);
}

// Writing ---------------------------------------------------------------------------------

class LegacyWriter {
public:
    LegacyWriter(std::ostream& out, bool binary) : out_(out), binary_(binary) {}

    void values(std::span<const double> v, std::size_t per_line) {
        if (binary_) {
            for (double x : v) out_.binary(x, true);
            out_.text('\n');
            return;
        }
        for (std::size_t i = 0; i < v.size(); ++i) {
            out_.real(v[i]);
            out_.text((i + 1) % per_line == 0 || i + 1 == v.size() ? '\n' : ' ');
        }
    }
    void integer(std::int32_t v, char separator) {
        if (binary_)
            out_.binary(v, true);
        else
            out_.integer(v).text(separator);
    }
    void fields(std::span<const Field> fields, std::string_view section, std::size_t count) {
        if (fields.empty()) return;
        out_.text(section).text(' ').integer(static_cast<std::int64_t>(count)).text('\n');
        std::size_t multi = 0;
        for (const Field& f : fields) {
            if (f.components != 1) {
                ++multi;
                continue;
            }
            out_.text("SCALARS ").text(vtk::legacy_name(f.name)).text(" double 1\nLOOKUP_TABLE default\n");
            values(f.values, 1);
        }
        if (multi == 0) return;
        out_.text("FIELD FieldData ").integer(static_cast<std::int64_t>(multi)).text('\n');
        for (const Field& f : fields) {
            if (f.components == 1) continue;
            out_.text(vtk::legacy_name(f.name)).text(' ').integer(f.components).text(' ');
            out_.integer(static_cast<std::int64_t>(count)).text(" double\n");
            values(f.values, static_cast<std::size_t>(f.components));
        }
    }
    vtk::Output& out() { return out_; }

private:
    vtk::Output out_;
    bool binary_;
};

}  // namespace

RawMesh read_vtk_legacy(const std::string& path) {
    LegacyReader reader(path);
    return reader.read();
}

void write_vtk_legacy(std::ostream& stream, const MeshToWrite& data, Encoding encoding) {
    vtk::check_unique_names(data.point_fields, "point", true);
    vtk::check_unique_names(data.cell_fields, "cell", true);
    const Mesh& mesh = data.mesh;
    const bool binary = encoding == Encoding::Binary;
    LegacyWriter w(stream, binary);
    vtk::Output& out = w.out();
    // Version 3.0 and the classic CELLS layout: what older readers (Mesquite among them) expect.
    out.text("# vtk DataFile Version 3.0\nWritten by Paloverde\n").text(binary ? "BINARY\n" : "ASCII\n");
    out.text("DATASET UNSTRUCTURED_GRID\n");
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const std::size_t m = data.cells();
    out.text("POINTS ").integer(static_cast<std::int64_t>(n)).text(" double\n");
    w.values(mesh.coordinates(), 3);
    out.text("CELLS ").integer(static_cast<std::int64_t>(m)).text(' ');
    out.integer(static_cast<std::int64_t>(m + data.connectivity.size())).text('\n');
    for (std::size_t c = 0; c < m; ++c) {
        const auto cell = data.cell(c);
        const auto k = static_cast<std::int32_t>(cell.size());
        w.integer(k, ' ');
        for (std::int32_t i = 0; i < k; ++i) w.integer(cell[static_cast<std::size_t>(i)], i + 1 == k ? '\n' : ' ');
    }
    if (binary) out.text('\n');
    out.text("CELL_TYPES ").integer(static_cast<std::int64_t>(m)).text('\n');
    for (std::size_t c = 0; c < m; ++c) w.integer(cell_info(data.type(c)).vtk, '\n');
    if (binary) out.text('\n');
    w.fields(data.point_fields, "POINT_DATA", n);
    w.fields(data.cell_fields, "CELL_DATA", m);
    out.flush();
}

}  // namespace paloverde::io
