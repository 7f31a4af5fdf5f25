// Gmsh MSH files: reads versions 2.2 and 4.1 (ASCII and binary), writes 2.2.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "paloverde/core/error.hpp"
#include "raw_mesh.hpp"
#include "text_scanner.hpp"

namespace paloverde::io {

namespace {

// Gmsh element types that can be read: the cells of cell_types.hpp, and points (15) and lines
// (1), lower-dimensional decorations (geometry vertices, feature curves) whose nodes are checked
// before they are skipped.
//
// Second-order elements are refused rather than cut to their corners: moving the corners would
// leave the mid-edge nodes where they were, and writing the mesh back would drop the curved
// geometry without a word.
struct ElementType {
    int nodes = 0;                   // 0: a type that cannot be read
    const CellInfo* cell = nullptr;  // nullptr for skipped points and lines
};

ElementType element_type(std::int64_t type) {
    if (type == 15) return {1, nullptr};
    if (type == 1) return {2, nullptr};
    if (const CellInfo* cell = find_cell([&](const CellInfo& c) { return c.gmsh == type; })) return {cell->corners, cell};
    return {};
}

std::string unsupported_element(std::int64_t tag, std::int64_t type) {
    std::string name;
    switch (type) {
        case 8: name = " (3-node second-order line)"; break;
        case 9: name = " (6-node second-order triangle)"; break;
        case 10: name = " (9-node second-order quadrangle)"; break;
        case 11: name = " (10-node second-order tetrahedron)"; break;
        case 12: name = " (27-node second-order hexahedron)"; break;
        case 13: name = " (18-node second-order prism)"; break;
        case 14: name = " (14-node second-order pyramid)"; break;
        case 16: name = " (8-node second-order quadrangle)"; break;
        case 17: name = " (20-node second-order hexahedron)"; break;
        case 18: name = " (15-node second-order prism)"; break;
        case 19: name = " (13-node second-order pyramid)"; break;
        default: break;
    }
    std::string message = "element " + std::to_string(tag) + " has type " + std::to_string(type) + name + "; only " +
                          handled_cells(&CellInfo::gmsh) + " can be read, with points (15) and lines (1) skipped";
    if (!name.empty()) message += "; save a first-order mesh (gmsh -order 1)";
    return message;
}

// Gmsh tags are positive but may be sparse and in any order. Maps each tag to its position in
// the file (0, 1, 2, ...): a dense table when the tags are compact, a sorted list otherwise.
class TagIndex {
public:
    void add(std::int64_t tag) { tags_.push_back(tag); }
    std::size_t size() const { return tags_.size(); }
    std::int64_t tag_at(std::size_t position) const { return tags_[position]; }
    std::vector<std::int64_t> release() { return std::move(tags_); }

    // Returns a tag that appears more than once, or 0 if all are distinct.
    std::int64_t build() {
        const std::size_t n = tags_.size();
        const std::int64_t max_tag = n == 0 ? 0 : *std::max_element(tags_.begin(), tags_.end());
        if (static_cast<std::uint64_t>(max_tag) <= 2 * static_cast<std::uint64_t>(n) + 64) {
            dense_.assign(static_cast<std::size_t>(max_tag) + 1, -1);
            for (std::size_t i = 0; i < n; ++i) {
                std::int64_t& slot = dense_[static_cast<std::size_t>(tags_[i])];
                if (slot >= 0) return tags_[i];
                slot = static_cast<std::int64_t>(i);
            }
            return 0;
        }
        sorted_.resize(n);
        for (std::size_t i = 0; i < n; ++i) sorted_[i] = {tags_[i], static_cast<std::int64_t>(i)};
        std::sort(sorted_.begin(), sorted_.end());
        for (std::size_t i = 1; i < n; ++i)
            if (sorted_[i].first == sorted_[i - 1].first) return sorted_[i].first;
        return 0;
    }

    // The position of `tag`, or -1 if the file has no such tag.
    std::int64_t find(std::int64_t tag) const {
        if (!dense_.empty() || sorted_.empty()) {
            if (tag < 0 || static_cast<std::uint64_t>(tag) >= dense_.size()) return -1;
            return dense_[static_cast<std::size_t>(tag)];
        }
        const auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::pair<std::int64_t, std::int64_t>{tag, -1});
        return it != sorted_.end() && it->first == tag ? it->second : -1;
    }

private:
    std::vector<std::int64_t> tags_;
    std::vector<std::int64_t> dense_;
    std::vector<std::pair<std::int64_t, std::int64_t>> sorted_;
};

// One $NodeData or $ElementData view. Several sections of the same view are either later time
// steps (the last one read wins) or partitions of the same step (merged).
struct View {
    std::int64_t step = 0;
    Field field;
};

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

std::string quoted_or_bare(std::string_view s) {
    s = trim(s);
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
    return std::string(s);
}

class GmshReader {
public:
    explicit GmshReader(const std::string& path) : s_(path) {}
    RawMesh read();

private:
    // Text errors name the line. In a binary file, line numbers mean nothing past the first
    // binary block, so errors name a byte offset: the current record's, or the scanner's.
    [[noreturn]] void fail(const std::string& message) const {
        if (!binary_) s_.fail(message);
        if (record_offset_ != kNoRecord) throw FileError::at_byte(s_.path(), record_offset_, message);
        s_.fail_at_byte(message);
    }

    std::string_view token(std::string_view what) {
        const std::string_view t = s_.token();
        if (t.empty()) fail("unexpected end of file: expected " + std::string(what) + s_.in_entry());
        return t;
    }
    std::int64_t integer(std::string_view what) {
        const std::string_view t = token(what);
        std::int64_t value = 0;
        if (!parse_integer(t, value))
            fail("expected " + std::string(what) + " (an integer), found '" + std::string(t.substr(0, 64)) + "'" +
                 s_.in_entry());
        return value;
    }
    double real(std::string_view what) {
        const std::string_view t = token(what);
        double value = 0.0;
        if (!parse_real(t, value))
            fail("expected " + std::string(what) + " (a number), found '" + std::string(t.substr(0, 64)) + "'" +
                 s_.in_entry());
        return value;
    }
    // A count of items that each take at least `min_bytes` of the rest of the file, so that a
    // corrupt count fails here instead of causing a huge allocation.
    std::int64_t count(std::string_view what, std::size_t min_bytes) {
        const std::int64_t value = integer(what);
        check_count(value, what, min_bytes);
        return value;
    }
    void check_count(std::int64_t value, std::string_view what, std::size_t min_bytes) const {
        if (value < 0) fail(std::string(what) + " is negative (" + std::to_string(value) + ")");
        if (static_cast<std::uint64_t>(value) > s_.remaining() / min_bytes)
            fail(std::string(what) + " of " + std::to_string(value) + " cannot fit in the rest of the file (" +
                 std::to_string(s_.remaining()) + " bytes)");
    }
    void end_section(std::string_view keyword) {
        const std::string_view t = s_.token();
        if (t.empty()) fail("unexpected end of file: expected " + std::string(keyword));
        if (t != keyword) fail("expected " + std::string(keyword) + ", found '" + std::string(t.substr(0, 64)) + "'");
    }

    template <class T>
    T load(const char* p) const {
        T value;
        std::memcpy(&value, p, sizeof value);
        return swap_ ? byte_swapped(value) : value;
    }
    // MSH 4.1 writes tags and counts as size_t, whose width the header gives.
    std::int64_t load_size(const char* p) const {
        if (size_bytes_ == 4) return load<std::uint32_t>(p);
        const std::uint64_t value = load<std::uint64_t>(p);
        if (value > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
            fail("a size_t value " + std::to_string(value) + " is out of range");
        return static_cast<std::int64_t>(value);
    }
    template <class T>
    T next(std::string_view what) {
        return load<T>(s_.bytes(sizeof(T), what).data());
    }
    std::int64_t next_size(std::string_view what) { return load_size(s_.bytes(size_bytes_, what).data()); }
    // `count` records of `record` bytes each; checked by division so that no product can overflow.
    const char* block(std::size_t count, std::size_t record, std::string_view what) {
        if (count > s_.remaining() / record)
            s_.fail_at_byte("file ends inside " + std::string(what) + " (" + std::to_string(count) + " records of " +
                            std::to_string(record) + " bytes, " + std::to_string(s_.remaining()) + " bytes left)");
        return s_.bytes(count * record, what).data();
    }
    std::int64_t next_count(std::string_view what, std::size_t min_bytes) {
        const std::int64_t value = next_size(what);
        check_count(value, what, min_bytes);
        return value;
    }

    void read_format();
    void read_nodes_v2();
    void read_nodes_v4();
    void read_elements_v2();
    void read_elements_v4();
    void read_data(bool on_nodes);
    void skip_section(std::string_view name);
    void finish_nodes();
    void finish_elements();

    void add_node_tag(std::int64_t tag) {
        if (tag < 1) fail("node tag " + std::to_string(tag) + " is not positive");
        node_tags_.add(tag);
    }
    void add_point(std::int64_t tag, double x, double y, double z) {
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
            fail("node " + std::to_string(tag) + " has a non-finite coordinate");
        raw_.coordinates.insert(raw_.coordinates.end(), {x, y, z});
    }
    void add_element(std::int64_t tag, const ElementType& type, const std::int64_t* nodes);
    // Names the element being read in the messages of a list cut short: by its tag once read.
    void name_elements(const std::int64_t& tag, const std::int64_t& number) {
        s_.set_entry([&] {
            return tag != 0 ? "element " + std::to_string(tag) : "element number " + std::to_string(number + 1) + " of the list";
        });
    }

    static constexpr std::size_t kNoRecord = static_cast<std::size_t>(-1);

    TextScanner s_;
    int version_ = 2;
    bool binary_ = false;
    bool swap_ = false;
    std::size_t size_bytes_ = 8;
    std::size_t record_offset_ = kNoRecord;
    bool have_nodes_ = false;
    bool have_elements_ = false;
    TagIndex node_tags_;
    TagIndex element_tags_;
    std::vector<View> point_views_;
    std::vector<View> cell_views_;
    std::size_t view_bytes_ = 0;  // of all views' values
    RawMesh raw_;
};

RawMesh GmshReader::read() {
    const std::string_view first = s_.token();
    if (first.empty()) s_.fail("empty file: expected $MeshFormat");
    if (first != "$MeshFormat")
        s_.fail("expected $MeshFormat at the start of a Gmsh file, found '" + std::string(first.substr(0, 64)) + "'");
    read_format();

    for (std::string_view name = s_.token(); !name.empty(); name = s_.token()) {
        if (name == "$Nodes") {
            if (have_nodes_) fail("a second $Nodes section");
            version_ == 2 ? read_nodes_v2() : read_nodes_v4();
            finish_nodes();
        } else if (name == "$Elements") {
            if (!have_nodes_) fail("$Elements comes before $Nodes");
            if (have_elements_) fail("a second $Elements section");
            version_ == 2 ? read_elements_v2() : read_elements_v4();
            finish_elements();
        } else if (name == "$NodeData") {
            read_data(true);
        } else if (name == "$ElementData") {
            read_data(false);
        } else if (name.size() > 1 && name.front() == '$' && name.substr(0, 4) != "$End") {
            skip_section(name);
        } else {
            fail("expected a section such as $Nodes or $Elements, found '" + std::string(name.substr(0, 64)) + "'");
        }
    }
    if (!have_nodes_) fail("the file has no $Nodes section");
    if (!have_elements_) fail("the file has no $Elements section");

    for (View& view : point_views_) raw_.point_fields.push_back(std::move(view.field));
    for (View& view : cell_views_) raw_.cell_fields.push_back(std::move(view.field));
    raw_.cell_name = [tags = element_tags_.release()](std::size_t position, CellType type) {
        return "element " + std::to_string(tags[position]) + " (" + std::string(cell_info(type).name) + ")";
    };
    return std::move(raw_);
}

void GmshReader::read_format() {
    const std::string_view version = token("the MSH version");
    double number = 0.0;
    if (version == "4.1") {
        version_ = 4;
    } else if (parse_real(version, number) && number >= 2.0 && number < 3.0) {
        version_ = 2;
    } else {
        fail("MSH version " + std::string(version.substr(0, 16)) +
             " cannot be read (versions 2.x and 4.1 can); save the mesh as version 4.1 or 2.2");
    }
    const std::int64_t file_type = integer("the file type (0 for ASCII, 1 for binary)");
    if (file_type != 0 && file_type != 1) fail("file type " + std::to_string(file_type) + " is neither 0 (ASCII) nor 1 (binary)");
    const std::int64_t data_size = integer("the data size");
    if (version_ == 2 && data_size != 8) fail("data size " + std::to_string(data_size) + " is not 8 (the size of a double)");
    if (version_ == 4 && data_size != 4 && data_size != 8)
        fail("data size " + std::to_string(data_size) + " is neither 4 nor 8 (the size of size_t)");
    size_bytes_ = static_cast<std::size_t>(data_size);
    if (file_type == 1) {
        binary_ = true;
        s_.skip_one_newline();
        const std::int32_t one = next<std::int32_t>("the endianness marker");
        if (one != 1) {
            if (byte_swapped(one) != 1)
                fail("the binary endianness marker is " + std::to_string(one) + ", expected 1");
            swap_ = true;
        }
    }
    end_section("$EndMeshFormat");
}

void GmshReader::skip_section(std::string_view name) {
    const std::string section(name);
    const std::string end = "$End" + section.substr(1);
    for (;;) {
        const std::string_view t = s_.token();
        if (t.empty()) fail("unexpected end of file inside " + section + " (no " + end + ")");
        if (t == end) return;
    }
}

void GmshReader::read_nodes_v2() {
    if (!binary_) {
        // "tag x y z" takes at least 8 bytes.
        const std::int64_t n = count("the number of nodes", 8);
        raw_.coordinates.reserve(3 * static_cast<std::size_t>(n));
        for (std::int64_t i = 0; i < n; ++i) {
            const std::int64_t tag = integer("a node tag");
            add_node_tag(tag);
            const double x = real("an x coordinate");
            const double y = real("a y coordinate");
            const double z = real("a z coordinate");
            add_point(tag, x, y, z);
        }
    } else {
        constexpr std::size_t record = sizeof(std::int32_t) + 3 * sizeof(double);
        const std::int64_t n = count("the number of nodes", record);
        raw_.coordinates.reserve(3 * static_cast<std::size_t>(n));
        s_.skip_one_newline();
        const std::size_t start = s_.offset();
        const char* p = block(static_cast<std::size_t>(n), record, "the binary node records");
        for (std::int64_t i = 0; i < n; ++i, p += record) {
            record_offset_ = start + static_cast<std::size_t>(i) * record;
            const std::int64_t tag = load<std::int32_t>(p);
            add_node_tag(tag);
            add_point(tag, load<double>(p + 4), load<double>(p + 12), load<double>(p + 20));
        }
        record_offset_ = kNoRecord;
    }
    end_section("$EndNodes");
}

void GmshReader::read_nodes_v4() {
    std::int64_t blocks = 0;
    std::int64_t total = 0;
    if (!binary_) {
        blocks = count("the number of node blocks", 8);
        total = count("the number of nodes", 8);
        integer("the smallest node tag");
        integer("the largest node tag");
    } else {
        s_.skip_one_newline();
        blocks = next_count("the number of node blocks", 3 * sizeof(std::int32_t) + size_bytes_);
        total = next_count("the number of nodes", size_bytes_ + 3 * sizeof(double));
        next_size("the smallest node tag");
        next_size("the largest node tag");
    }
    raw_.coordinates.reserve(3 * static_cast<std::size_t>(total));
    std::int64_t read = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
        std::int64_t dim = 0;
        std::int64_t parametric = 0;
        std::int64_t k = 0;
        if (!binary_) {
            dim = integer("the entity dimension of a node block");
            integer("the entity tag of a node block");
            parametric = integer("the parametric flag of a node block");
            k = integer("the number of nodes in a node block");
        } else {
            dim = next<std::int32_t>("the entity dimension of a node block");
            next<std::int32_t>("the entity tag of a node block");
            parametric = next<std::int32_t>("the parametric flag of a node block");
            k = next_size("the number of nodes in a node block");
        }
        if (dim < 0 || dim > 3) fail("node block " + std::to_string(b + 1) + " has entity dimension " + std::to_string(dim));
        if (parametric != 0 && parametric != 1)
            fail("node block " + std::to_string(b + 1) + " has parametric flag " + std::to_string(parametric));
        if (k < 0 || k > total - read)
            fail("node block " + std::to_string(b + 1) + " holds " + std::to_string(k) + " nodes, more than the " +
                 std::to_string(total) + " the $Nodes header declares");
        const std::size_t values = 3 + static_cast<std::size_t>(parametric ? dim : 0);
        const std::size_t first = node_tags_.size();
        const auto kn = static_cast<std::size_t>(k);
        if (!binary_) {
            for (std::size_t i = 0; i < kn; ++i) add_node_tag(integer("a node tag"));
            for (std::size_t i = 0; i < kn; ++i) {
                const double x = real("an x coordinate");
                const double y = real("a y coordinate");
                const double z = real("a z coordinate");
                for (std::size_t extra = 3; extra < values; ++extra) real("a parametric coordinate");
                add_point(node_tags_.tag_at(first + i), x, y, z);
            }
        } else {
            std::size_t start = s_.offset();
            const char* p = block(kn, size_bytes_, "the node tags");
            for (std::size_t i = 0; i < kn; ++i) {
                record_offset_ = start + i * size_bytes_;
                add_node_tag(load_size(p + i * size_bytes_));
            }
            const std::size_t record = values * sizeof(double);
            start = s_.offset();
            p = block(kn, record, "the node coordinates");
            for (std::size_t i = 0; i < kn; ++i, p += record) {
                record_offset_ = start + i * record;
                add_point(node_tags_.tag_at(first + i), load<double>(p), load<double>(p + 8), load<double>(p + 16));
            }
            record_offset_ = kNoRecord;
        }
        read += k;
    }
    if (read != total)
        fail("the node blocks hold " + std::to_string(read) + " nodes, but the $Nodes header declares " + std::to_string(total));
    end_section("$EndNodes");
}

void GmshReader::finish_nodes() {
    if (node_tags_.size() > static_cast<std::size_t>(std::numeric_limits<VertexId>::max()))
        fail("too many nodes for one process (" + std::to_string(node_tags_.size()) + ")");
    if (const std::int64_t repeated = node_tags_.build())
        fail("node tag " + std::to_string(repeated) + " appears more than once in $Nodes");
    have_nodes_ = true;
}

void GmshReader::add_element(std::int64_t tag, const ElementType& type, const std::int64_t* nodes) {
    if (tag < 1) fail("element tag " + std::to_string(tag) + " is not positive");
    const std::size_t position = element_tags_.size();
    element_tags_.add(tag);
    VertexId vertices[kMaxCellCorners] = {};
    for (int c = 0; c < type.nodes; ++c) {
        const std::int64_t index = node_tags_.find(nodes[c]);
        if (index < 0)
            fail("element " + std::to_string(tag) + " refers to node " + std::to_string(nodes[c]) +
                 ", which is not in $Nodes");
        vertices[c] = static_cast<VertexId>(index);
    }
    if (type.cell) raw_.add_file_cell(type.cell->type, vertices, position);
}

void GmshReader::read_elements_v2() {
    std::int64_t nodes[kMaxCellCorners] = {};
    if (!binary_) {
        // "tag type ntags node" takes at least 8 bytes.
        const std::int64_t n = count("the number of elements", 8);
        std::int64_t tag = 0;
        std::int64_t e = 0;
        name_elements(tag, e);
        for (; e < n; ++e) {
            tag = 0;  // until read: a list cut before the tag names the element by its number
            tag = integer("an element tag");
            const std::int64_t type_number = integer("an element type");
            const ElementType type = element_type(type_number);
            if (type.nodes == 0) fail(unsupported_element(tag, type_number));
            const std::int64_t tags = count("the number of element tags", 2);
            for (std::int64_t t = 0; t < tags; ++t) integer("an element tag value");
            for (int c = 0; c < type.nodes; ++c) nodes[c] = integer("a node tag");
            add_element(tag, type, nodes);
        }
        s_.set_entry({});
    } else {
        // An element takes at least its tag and one node: 8 bytes.
        const std::int64_t n = count("the number of elements", 2 * sizeof(std::int32_t));
        s_.skip_one_newline();
        std::int64_t read = 0;
        while (read < n) {
            const std::size_t header_offset = s_.offset();
            const std::int64_t type_number = next<std::int32_t>("an element block header");
            const std::int64_t follow = next<std::int32_t>("an element block header");
            const std::int64_t tags = next<std::int32_t>("an element block header");
            record_offset_ = header_offset;
            if (follow < 1 || follow > n - read)
                fail("an element block declares " + std::to_string(follow) + " elements, but " + std::to_string(n - read) +
                     " of the declared " + std::to_string(n) + " remain");
            if (tags < 0 || static_cast<std::size_t>(tags) > s_.remaining() / sizeof(std::int32_t))
                fail("an element block declares " + std::to_string(tags) + " tags per element");
            const ElementType type = element_type(type_number);
            if (type.nodes == 0) {
                const std::int64_t first_tag =
                    s_.remaining() >= 4 ? next<std::int32_t>("the first element tag of a block") : 0;
                fail(unsupported_element(first_tag, type_number));
            }
            record_offset_ = kNoRecord;
            const std::size_t record = (1 + static_cast<std::size_t>(tags) + static_cast<std::size_t>(type.nodes)) * 4;
            const std::size_t start = s_.offset();
            const char* p = block(static_cast<std::size_t>(follow), record, "the binary element records");
            for (std::int64_t e = 0; e < follow; ++e, p += record) {
                record_offset_ = start + static_cast<std::size_t>(e) * record;
                const char* q = p + 4 * (1 + tags);
                for (int c = 0; c < type.nodes; ++c) nodes[c] = load<std::int32_t>(q + 4 * c);
                add_element(load<std::int32_t>(p), type, nodes);
            }
            record_offset_ = kNoRecord;
            read += follow;
        }
    }
    end_section("$EndElements");
}

void GmshReader::read_elements_v4() {
    std::int64_t blocks = 0;
    std::int64_t total = 0;
    if (!binary_) {
        blocks = count("the number of element blocks", 8);
        total = count("the number of elements", 4);
        integer("the smallest element tag");
        integer("the largest element tag");
    } else {
        s_.skip_one_newline();
        blocks = next_count("the number of element blocks", 3 * sizeof(std::int32_t) + size_bytes_);
        total = next_count("the number of elements", 2 * size_bytes_);
        next_size("the smallest element tag");
        next_size("the largest element tag");
    }
    std::int64_t nodes[kMaxCellCorners] = {};
    std::int64_t read = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
        std::int64_t type_number = 0;
        std::int64_t k = 0;
        if (!binary_) {
            integer("the entity dimension of an element block");
            integer("the entity tag of an element block");
            type_number = integer("the element type of an element block");
            k = integer("the number of elements in an element block");
        } else {
            next<std::int32_t>("the entity dimension of an element block");
            next<std::int32_t>("the entity tag of an element block");
            type_number = next<std::int32_t>("the element type of an element block");
            k = next_size("the number of elements in an element block");
        }
        if (k < 0 || k > total - read)
            fail("element block " + std::to_string(b + 1) + " holds " + std::to_string(k) + " elements, more than the " +
                 std::to_string(total) + " the $Elements header declares");
        const ElementType type = element_type(type_number);
        if (type.nodes == 0) {
            std::int64_t first_tag = 0;
            if (k > 0) first_tag = binary_ ? next_size("the first element tag of a block") : integer("an element tag");
            fail(unsupported_element(first_tag, type_number));
        }
        if (!binary_) {
            std::int64_t tag = 0;
            std::int64_t e = read;
            name_elements(tag, e);
            for (; e < read + k; ++e) {
                tag = 0;  // until read, as in read_elements_v2
                tag = integer("an element tag");
                for (int c = 0; c < type.nodes; ++c) nodes[c] = integer("a node tag");
                add_element(tag, type, nodes);
            }
            s_.set_entry({});
        } else {
            const std::size_t record = (1 + static_cast<std::size_t>(type.nodes)) * size_bytes_;
            const std::size_t start = s_.offset();
            const char* p = block(static_cast<std::size_t>(k), record, "the element records");
            for (std::int64_t e = 0; e < k; ++e, p += record) {
                record_offset_ = start + static_cast<std::size_t>(e) * record;
                for (int c = 0; c < type.nodes; ++c) nodes[c] = load_size(p + (1 + c) * size_bytes_);
                add_element(load_size(p), type, nodes);
            }
            record_offset_ = kNoRecord;
        }
        read += k;
    }
    if (read != total)
        fail("the element blocks hold " + std::to_string(read) + " elements, but the $Elements header declares " +
             std::to_string(total));
    end_section("$EndElements");
}

void GmshReader::finish_elements() {
    if (const std::int64_t repeated = element_tags_.build())
        fail("element tag " + std::to_string(repeated) + " appears more than once in $Elements");
    have_elements_ = true;
}

// $NodeData / $ElementData: string tags (the first is the view's name), real tags (the first is
// the time), integer tags (time step, components, number of values, [partition]), then one
// "tag value..." record per entity. Binary records start with an int tag: the 4.1 manual says
// size_t, but Gmsh itself reads and writes int there in every version.
void GmshReader::read_data(bool on_nodes) {
    const std::string section = on_nodes ? "$NodeData" : "$ElementData";
    if (on_nodes ? !have_nodes_ : !have_elements_)
        fail(section + " comes before " + (on_nodes ? "$Nodes" : "$Elements"));
    const std::int64_t strings = count("the number of string tags", 2);
    s_.skip_line();
    std::string name;
    for (std::int64_t i = 0; i < strings; ++i) {
        const std::string_view line = s_.rest_of_line();
        if (i == 0) name = quoted_or_bare(line);
    }
    if (strings == 0) name = on_nodes ? "node_data" : "element_data";
    const std::int64_t reals = count("the number of real tags", 2);
    for (std::int64_t i = 0; i < reals; ++i) real("a real tag");
    const std::int64_t integers = count("the number of integer tags", 2);
    if (integers < 3)
        fail(section + " '" + name + "' has " + std::to_string(integers) +
             " integer tags; it needs 3 (time step, components, number of values)");
    const std::int64_t step = integer("the time step");
    const std::int64_t components = integer("the number of components");
    const std::size_t entities = on_nodes ? node_tags_.size() : element_tags_.size();
    const std::size_t value_bytes = binary_ ? sizeof(double) : 2;
    // Gmsh's views have 1, 3 or 9 components; more are accepted only if the whole field fits in
    // the file, so that a corrupt value cannot cause a huge allocation.
    if (components < 1 ||
        (components > 9 && static_cast<std::uint64_t>(components) >
                               s_.remaining() / (value_bytes * std::max<std::size_t>(entities, 1))))
        fail(section + " '" + name + "' has an impossible number of components (" + std::to_string(components) + ")");
    const auto width = static_cast<std::size_t>(components);
    const std::size_t record = binary_ ? sizeof(std::int32_t) + width * sizeof(double) : 2 * (1 + width);
    const std::int64_t n = count("the number of values", record);
    for (std::int64_t i = 3; i < integers; ++i) integer("an integer tag");

    std::vector<View>& views = on_nodes ? point_views_ : cell_views_;
    auto view = std::find_if(views.begin(), views.end(), [&](const View& v) { return v.field.name == name; });
    // Every view is filled out to every entity, whatever few values it gives; so that many views
    // in a small file cannot add up to a giant allocation, all views together may take at most
    // 16 times the file's size (a view of 9 components over every node fits in 9 times).
    auto reserve_view = [&](std::size_t released) {
        const std::size_t bytes = entities * width * sizeof(double);
        if (view_bytes_ - released + bytes > 16 * s_.size() + (1u << 20))
            fail(section + " '" + name + "' would bring the views to " + std::to_string(view_bytes_ - released + bytes) +
                 " bytes in memory, more than 16 times the file's size: too many views (each is filled out to every " +
                 (on_nodes ? "node" : "element") + ") for a file this small");
        view_bytes_ = view_bytes_ - released + bytes;
    };
    if (view == views.end()) {
        reserve_view(0);
        views.push_back({step, Field{name, static_cast<int>(components), {}}});
        view = views.end() - 1;
        view->field.values.assign(entities * width, std::numeric_limits<double>::quiet_NaN());
    } else if (view->step != step || view->field.components != components) {
        reserve_view(view->field.values.size() * sizeof(double));
        view->step = step;
        view->field.components = static_cast<int>(components);
        view->field.values.assign(entities * width, std::numeric_limits<double>::quiet_NaN());
    }
    // Gmsh views may cover part of the mesh; entities without a value keep NaN.
    double* values = view->field.values.data();
    const TagIndex& index = on_nodes ? node_tags_ : element_tags_;
    const char* what = on_nodes ? "node" : "element";
    auto position_of = [&](std::int64_t tag) {
        const std::int64_t position = index.find(tag);
        if (position < 0)
            fail(section + " '" + name + "' refers to " + what + " " + std::to_string(tag) + ", which is not in " +
                 (on_nodes ? "$Nodes" : "$Elements"));
        return static_cast<std::size_t>(position);
    };
    if (!binary_) {
        for (std::int64_t i = 0; i < n; ++i) {
            const std::size_t position = position_of(integer(on_nodes ? "a node tag" : "an element tag"));
            for (std::size_t c = 0; c < width; ++c) values[position * width + c] = real("a field value");
        }
    } else {
        s_.skip_one_newline();
        const std::size_t start = s_.offset();
        const char* p = block(static_cast<std::size_t>(n), record, "the binary field records");
        for (std::int64_t i = 0; i < n; ++i, p += record) {
            record_offset_ = start + static_cast<std::size_t>(i) * record;
            const std::size_t position = position_of(load<std::int32_t>(p));
            for (std::size_t c = 0; c < width; ++c) values[position * width + c] = load<double>(p + 4 + 8 * c);
        }
        record_offset_ = kNoRecord;
    }
    end_section(on_nodes ? "$EndNodeData" : "$EndElementData");
}

// Formats into one string and hands it to the stream in large pieces: std::to_chars is exact
// and an order of magnitude faster than stream formatting.
class Output {
public:
    explicit Output(std::ostream& out) : out_(out) { buffer_.reserve(kChunk + 4096); }
    void text(std::string_view s) {
        buffer_.append(s);
        if (buffer_.size() >= kChunk) flush();
    }
    void integer(std::int64_t value) {
        char digits[24];
        buffer_.append(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
    }
    // The shortest decimal form that reads back as the same double (at most 17 significant
    // digits), so ASCII round trips are exact.
    void real(double value) {
        char digits[32];
        buffer_.append(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
    }
    template <class T>
    void binary(T value) {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof value);
        buffer_.append(bytes, sizeof bytes);
        if (buffer_.size() >= kChunk) flush();
    }
    void flush() {
        out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
        buffer_.clear();
    }

private:
    static constexpr std::size_t kChunk = 1 << 20;
    std::ostream& out_;
    std::string buffer_;
};

void write_view(Output& out, const Field& field, bool on_nodes, std::size_t entities, bool binary) {
    if (field.name.find_first_of("\"\r\n") != std::string::npos)
        throw Error("field name '" + field.name + "' cannot be written to a Gmsh file (it holds a quote or a line break)");
    const auto width = static_cast<std::size_t>(field.components);
    out.text(on_nodes ? "$NodeData\n1\n\"" : "$ElementData\n1\n\"");
    out.text(field.name);
    out.text("\"\n1\n0\n3\n0\n");
    out.integer(field.components);
    out.text("\n");
    out.integer(static_cast<std::int64_t>(entities));
    out.text("\n");
    for (std::size_t i = 0; i < entities; ++i) {
        const double* values = field.values.data() + i * width;
        if (binary) {
            out.binary(static_cast<std::int32_t>(i + 1));
            for (std::size_t c = 0; c < width; ++c) out.binary(values[c]);
        } else {
            out.integer(static_cast<std::int64_t>(i + 1));
            for (std::size_t c = 0; c < width; ++c) {
                out.text(" ");
                out.real(values[c]);
            }
            out.text("\n");
        }
    }
    out.text(binary ? "\n" : "");
    out.text(on_nodes ? "$EndNodeData\n" : "$EndElementData\n");
}

}  // namespace

RawMesh read_gmsh(const std::string& path) { return GmshReader(path).read(); }

// MSH 2.2. Nodes and elements are numbered from 1 in mesh order; every element gets physical
// tag 0 (no physical group) and elementary tag 1. Binary data is written in the host's byte
// order, which the endianness marker records.
void write_gmsh(std::ostream& stream, const MeshToWrite& data, Encoding encoding) {
    const Mesh& mesh = data.mesh;
    const bool binary = encoding == Encoding::Binary;
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const std::size_t m = data.cells();
    const std::span<const double> xyz = mesh.coordinates();

    Output out(stream);
    out.text(binary ? "$MeshFormat\n2.2 1 8\n" : "$MeshFormat\n2.2 0 8\n");
    if (binary) {
        out.binary(std::int32_t{1});
        out.text("\n");
    }
    out.text("$EndMeshFormat\n$Nodes\n");
    out.integer(static_cast<std::int64_t>(n));
    out.text("\n");
    for (std::size_t v = 0; v < n; ++v) {
        if (binary) {
            out.binary(static_cast<std::int32_t>(v + 1));
            for (int c = 0; c < 3; ++c) out.binary(xyz[3 * v + c]);
        } else {
            out.integer(static_cast<std::int64_t>(v + 1));
            for (int c = 0; c < 3; ++c) {
                out.text(" ");
                out.real(xyz[3 * v + c]);
            }
            out.text("\n");
        }
    }
    out.text(binary ? "\n$EndNodes\n$Elements\n" : "$EndNodes\n$Elements\n");
    out.integer(static_cast<std::int64_t>(m));
    out.text("\n");
    VertexId element[kMaxCellCorners];
    for (std::size_t e = 0; e < m; ++e) {
        const CellInfo& info = cell_info(data.type(e));
        to_file_order(info.type, data.cell(e), element);
        if (binary) {
            // A block header before each run of one type: its type, length and tag count.
            if (e == 0 || data.type(e - 1) != info.type) {
                std::size_t run = e + 1;
                while (run < m && data.type(run) == info.type) ++run;
                out.binary(static_cast<std::int32_t>(info.gmsh));
                out.binary(static_cast<std::int32_t>(run - e));
                out.binary(std::int32_t{2});
            }
            out.binary(static_cast<std::int32_t>(e + 1));
            out.binary(std::int32_t{0});
            out.binary(std::int32_t{1});
            for (int c = 0; c < info.corners; ++c) out.binary(static_cast<std::int32_t>(element[c] + 1));
        } else {
            out.integer(static_cast<std::int64_t>(e + 1));
            out.text(" ");
            out.integer(info.gmsh);
            out.text(" 2 0 1");
            for (int c = 0; c < info.corners; ++c) {
                out.text(" ");
                out.integer(static_cast<std::int64_t>(element[c]) + 1);
            }
            out.text("\n");
        }
    }
    out.text(binary ? "\n$EndElements\n" : "$EndElements\n");
    for (const Field& field : data.point_fields) write_view(out, field, true, n, binary);
    for (const Field& field : data.cell_fields) write_view(out, field, false, m, binary);
    out.flush();
}

}  // namespace paloverde::io
