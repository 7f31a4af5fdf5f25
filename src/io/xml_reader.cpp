#include "xml_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <unordered_set>

#include "paloverde/core/error.hpp"

namespace paloverde::io {

const std::string* XmlElement::attribute(std::string_view wanted) const {
    for (const auto& [name, value] : attributes)
        if (name == wanted) return &value;
    return nullptr;
}

std::vector<const XmlElement*> XmlDocument::children(const XmlElement& parent, std::string_view name) const {
    std::vector<const XmlElement*> out;
    for (std::size_t child : parent.children)
        if (elements[child].name == name) out.push_back(&elements[child]);
    return out;
}

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
bool ends_name(char c) { return is_space(c) || c == '>' || c == '/' || c == '=' || c == '<'; }

std::string shorten(std::string_view text) {
    std::string out;
    for (char c : text.substr(0, 40)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
    return out;
}

class XmlParser {
public:
    XmlParser(std::string_view text, const std::string& path, std::string_view opaque)
        : t_(text), path_(path), opaque_(opaque) {}
    XmlDocument parse();

private:
    [[noreturn]] void fail(const std::string& message) const { throw FileError(path_, line_, message); }
    void move_to(std::size_t p) {
        line_ += static_cast<std::size_t>(std::count(t_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                                     t_.begin() + static_cast<std::ptrdiff_t>(p), '\n'));
        pos_ = p;
    }
    void skip_space() {
        while (pos_ < t_.size() && is_space(t_[pos_])) {
            if (t_[pos_] == '\n') ++line_;
            ++pos_;
        }
    }
    // Moves past `close`, which must come before the end of the document.
    void skip_past(std::string_view close, std::string_view what) {
        const std::size_t end = t_.find(close, pos_);
        if (end == std::string_view::npos)
            fail("unterminated " + std::string(what) + " (no '" + std::string(close) + "')");
        move_to(end + close.size());
    }
    std::string_view name(std::string_view what) {
        const std::size_t begin = pos_;
        while (pos_ < t_.size() && !ends_name(t_[pos_])) ++pos_;
        if (pos_ == begin) fail("expected " + std::string(what) + ", found '" + shorten(t_.substr(pos_, 10)) + "'");
        return t_.substr(begin, pos_ - begin);
    }
    std::string decode(std::string_view value) const;
    void start_tag(std::vector<std::size_t>& open);
    void end_tag(std::vector<std::size_t>& open);
    void add_text(std::size_t begin, std::size_t end, std::size_t line, const std::vector<std::size_t>& open);

    std::string_view t_;
    const std::string& path_;
    std::string_view opaque_;
    std::size_t pos_ = 0;
    std::size_t line_ = 1;
    XmlDocument doc_;
    bool done_ = false;
};

std::string XmlParser::decode(std::string_view value) const {
    std::string out;
    out.reserve(value.size());
    for (std::size_t i = 0; i < value.size(); ++i) {
        if (value[i] != '&') {
            out += value[i];
            continue;
        }
        const std::size_t semicolon = value.find(';', i);
        if (semicolon == std::string_view::npos) fail("'&' without ';' in an attribute value");
        const std::string_view entity = value.substr(i + 1, semicolon - i - 1);
        if (entity == "lt")
            out += '<';
        else if (entity == "gt")
            out += '>';
        else if (entity == "amp")
            out += '&';
        else if (entity == "quot")
            out += '"';
        else if (entity == "apos")
            out += '\'';
        else if (entity.size() > 1 && entity[0] == '#') {
            const bool hex = entity[1] == 'x' || entity[1] == 'X';
            const std::string_view digits = entity.substr(hex ? 2 : 1);
            unsigned code = 0;
            const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), code, hex ? 16 : 10);
            if (r.ec != std::errc() || r.ptr != digits.data() + digits.size() || code == 0 || code > 0x10FFFF)
                fail("invalid character reference '&" + shorten(entity) + ";'");
            // UTF-8, so that names survive whatever characters they hold.
            if (code < 0x80) {
                out += static_cast<char>(code);
            } else if (code < 0x800) {
                out += static_cast<char>(0xC0 | (code >> 6));
                out += static_cast<char>(0x80 | (code & 0x3F));
            } else if (code < 0x10000) {
                out += static_cast<char>(0xE0 | (code >> 12));
                out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
                out += static_cast<char>(0x80 | (code & 0x3F));
            } else {
                out += static_cast<char>(0xF0 | (code >> 18));
                out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
                out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
                out += static_cast<char>(0x80 | (code & 0x3F));
            }
        } else {
            fail("unknown entity '&" + shorten(entity) + ";'");
        }
        i = semicolon;
    }
    return out;
}

void XmlParser::add_text(std::size_t begin, std::size_t end, std::size_t line, const std::vector<std::size_t>& open) {
    const auto first = std::find_if_not(t_.begin() + static_cast<std::ptrdiff_t>(begin),
                                        t_.begin() + static_cast<std::ptrdiff_t>(end), is_space);
    if (first == t_.begin() + static_cast<std::ptrdiff_t>(end)) return;
    if (open.empty()) {
        line_ =
            line + static_cast<std::size_t>(std::count(t_.begin() + static_cast<std::ptrdiff_t>(begin), first, '\n'));
        fail("text outside the root element: '" + shorten(t_.substr(static_cast<std::size_t>(first - t_.begin()))) +
             "'");
    }
    doc_.elements[open.back()].text.push_back({begin, end, line});
}

void XmlParser::start_tag(std::vector<std::size_t>& open) {
    const std::size_t tag_line = line_;
    const std::size_t tag_offset = pos_;
    ++pos_;  // '<'
    XmlElement element;
    element.name = name("an element name");
    element.line = tag_line;
    element.offset = tag_offset;
    // A set rather than a search of the attributes so far, which takes quadratic time on a tag
    // with very many of them.
    std::unordered_set<std::string_view> names;
    bool closed = false;
    while (true) {
        skip_space();
        if (pos_ >= t_.size()) fail("the file ends inside the <" + std::string(element.name) + "> tag");
        if (t_[pos_] == '>') {
            ++pos_;
            break;
        }
        if (t_.compare(pos_, 2, "/>") == 0) {
            pos_ += 2;
            closed = true;
            break;
        }
        const std::string_view attribute = name("an attribute name or '>'");
        skip_space();
        if (pos_ >= t_.size() || t_[pos_] != '=') fail("expected '=' after attribute " + std::string(attribute));
        ++pos_;
        skip_space();
        if (pos_ >= t_.size() || (t_[pos_] != '"' && t_[pos_] != '\''))
            fail("expected a quoted value for attribute " + std::string(attribute));
        const char quote = t_[pos_];
        const std::size_t end = t_.find(quote, pos_ + 1);
        if (end == std::string_view::npos) fail("unterminated value of attribute " + std::string(attribute));
        const std::string_view raw = t_.substr(pos_ + 1, end - pos_ - 1);
        if (raw.find('<') != std::string_view::npos) fail("'<' in the value of attribute " + std::string(attribute));
        if (!names.insert(attribute).second) fail("attribute " + std::string(attribute) + " appears twice");
        element.attributes.emplace_back(attribute, decode(raw));
        move_to(end + 1);
    }
    const std::size_t index = doc_.elements.size();
    if (open.empty()) {
        if (index > 0) fail("a second root element <" + std::string(element.name) + ">");
    } else {
        doc_.elements[open.back()].children.push_back(index);
    }
    const bool opaque = !closed && element.name == opaque_;
    doc_.elements.push_back(std::move(element));
    if (opaque) {
        skip_space();
        if (pos_ >= t_.size() || t_[pos_] != '_')
            fail("expected '_' at the start of the <" + std::string(opaque_) + "> data");
        doc_.opaque_data = pos_ + 1;
        done_ = true;
        return;
    }
    if (!closed)
        open.push_back(index);
    else if (open.empty())
        done_ = true;
}

void XmlParser::end_tag(std::vector<std::size_t>& open) {
    pos_ += 2;  // "</"
    const std::string_view closing = name("an element name after '</'");
    skip_space();
    if (pos_ >= t_.size() || t_[pos_] != '>') fail("expected '>' to end </" + std::string(closing));
    ++pos_;
    if (open.empty()) fail("</" + std::string(closing) + "> closes no open element");
    const std::string_view expected = doc_.elements[open.back()].name;
    if (closing != expected)
        fail("</" + std::string(closing) + "> does not match <" + std::string(expected) + "> opened at line " +
             std::to_string(doc_.elements[open.back()].line));
    open.pop_back();
    if (open.empty()) done_ = true;
}

XmlDocument XmlParser::parse() {
    std::vector<std::size_t> open;
    if (t_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte order mark
    while (!done_) {
        const std::size_t lt = t_.find('<', pos_);
        const std::size_t text_line = line_;
        const std::size_t text_end = lt == std::string_view::npos ? t_.size() : lt;
        add_text(pos_, text_end, text_line, open);
        move_to(text_end);
        if (lt == std::string_view::npos) {
            if (doc_.elements.empty()) fail("no XML element found (is this a VTK XML file?)");
            fail("the file ends inside the <" + std::string(doc_.elements[open.back()].name) +
                 "> element opened at line " + std::to_string(doc_.elements[open.back()].line) + " (truncated file?)");
        }
        const std::string_view rest = t_.substr(pos_);
        if (rest.starts_with("<?")) {
            skip_past("?>", "processing instruction");
        } else if (rest.starts_with("<!--")) {
            skip_past("-->", "comment");
        } else if (rest.starts_with("<![CDATA[")) {
            const std::size_t line = line_;
            const std::size_t begin = pos_ + 9;
            skip_past("]]>", "CDATA section");
            if (open.empty()) fail("CDATA outside the root element");
            doc_.elements[open.back()].text.push_back({begin, pos_ - 3, line});
        } else if (rest.starts_with("<!")) {
            skip_past(">", "declaration");
        } else if (rest.starts_with("</")) {
            end_tag(open);
        } else {
            start_tag(open);
        }
    }
    return std::move(doc_);
}

}  // namespace

XmlDocument parse_xml(std::string_view text, const std::string& path, std::string_view opaque_element) {
    XmlParser parser(text, path, opaque_element);
    return parser.parse();
}

std::string xml_escaped(std::string_view text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            case '\n': out += "&#10;"; break;
            case '\t': out += "&#9;"; break;
            default: out += c;
        }
    }
    return out;
}

}  // namespace paloverde::io
