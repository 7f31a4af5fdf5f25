#pragma once
// A small XML reader for the VTK XML formats: elements, attributes and the positions of text,
// with line numbers for messages. No namespaces, DTDs or encodings beyond ASCII/UTF-8; text is
// not copied (it can be megabytes of numbers), only located.
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace paloverde::io {

struct XmlText {
    std::size_t begin = 0;  // byte offsets into the document
    std::size_t end = 0;
    std::size_t line = 0;  // of `begin`
};

struct XmlElement {
    std::string_view name;
    std::vector<std::pair<std::string_view, std::string>> attributes;  // values with entities decoded
    std::vector<std::size_t> children;                                 // indices into XmlDocument::elements
    std::vector<XmlText> text;                                         // the element's own text pieces, in order
    std::size_t line = 0;                                              // of the start tag
    std::size_t offset = 0;                                            // byte offset of the start tag

    const std::string* attribute(std::string_view name) const;
};

struct XmlDocument {
    static constexpr std::size_t npos = std::string_view::npos;
    std::vector<XmlElement> elements;  // elements[0] is the root
    // VTK's <AppendedData> holds bytes that are not XML after a '_' marker: parsing stops there,
    // and this is the offset just past the '_' (npos if the document has no such element).
    std::size_t opaque_data = npos;

    const XmlElement& root() const { return elements.front(); }
    // The children of `parent` named `name`, in document order.
    std::vector<const XmlElement*> children(const XmlElement& parent, std::string_view name) const;
};

// Throws FileError naming `path` and the line on malformed XML. `opaque_element` names the
// element whose content is raw data introduced by '_'.
XmlDocument parse_xml(std::string_view text, const std::string& path, std::string_view opaque_element);

// Text with XML's special characters (and newlines and tabs) as entities, for attribute values.
std::string xml_escaped(std::string_view text);

}  // namespace paloverde::io
