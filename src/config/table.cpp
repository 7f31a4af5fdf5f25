#include "config/table.hpp"

namespace paloverde::config::detail {

void fail_at(const OptionError& error, const Location& where, const std::string& path, const std::string& key) {
    std::string message = error.what();
    // "max_iterations must be >= 0" at key max_iterations: the path already names it. The C++
    // field may have a longer name than the key ("shape_metric 'x' has no gradient" at `metric`).
    const std::size_t space = message.find(' ');
    const std::string first = message.substr(0, space);
    if (space != std::string::npos && (first == key || first.ends_with("_" + key))) message = message.substr(space + 1);
    fail(where, path, message);
}

std::string inline_yaml(const Node& node) {
    switch (node.kind) {
        case Node::Kind::Null: return "~";
        case Node::Kind::Scalar: return node.scalar.empty() ? "\"\"" : node.scalar;
        case Node::Kind::Sequence: {
            std::string out = "[";
            for (std::size_t i = 0; i < node.items.size(); ++i) out += (i ? ", " : "") + inline_yaml(node.items[i]);
            return out + "]";
        }
        case Node::Kind::Map: {
            std::string out = "{";
            for (std::size_t i = 0; i < node.entries.size(); ++i)
                out += (i ? ", " : "") + node.entries[i].key + ": " + inline_yaml(node.entries[i].value);
            return out + "}";
        }
    }
    return "";
}

std::string one_of(const Node& node, const std::string& path, const std::vector<std::string>& names,
                   const std::string& kind) {
    if (node.kind != Node::Kind::Scalar)
        fail(node.where, path, "expected the name of a " + kind + " (" + join(names) + "), got " + node.describe());
    for (const auto& n : names)
        if (n == node.scalar) return n;
    std::string message = "unknown " + kind + " '" + node.scalar + "'";
    if (const std::string near = closest(node.scalar, names); !near.empty()) message += "; did you mean '" + near + "'?";
    fail(node.where, path, message + " (known: " + join(names) + ")");
}

}  // namespace paloverde::config::detail
