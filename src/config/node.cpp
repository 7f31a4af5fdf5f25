#include "config/node.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <yaml-cpp/yaml.h>

#include "paloverde/config/config.hpp"

namespace paloverde::config::detail {

std::string Location::str() const {
    if (line <= 0) return source;
    return source + ":" + std::to_string(line) + ":" + std::to_string(column);
}

Node Node::map(Location where) {
    Node n;
    n.kind = Kind::Map;
    n.where = std::move(where);
    return n;
}

Node Node::text(std::string value, Location where) {
    Node n;
    n.kind = Kind::Scalar;
    n.scalar = std::move(value);
    n.where = std::move(where);
    return n;
}

const Node* Node::find(std::string_view key) const {
    for (const Entry& e : entries)
        if (e.key == key) return &e.value;
    return nullptr;
}

Node* Node::find(std::string_view key) {
    for (Entry& e : entries)
        if (e.key == key) return &e.value;
    return nullptr;
}

Node& Node::at(const std::string& key) {
    if (Node* n = find(key)) return *n;
    Node value;
    value.where = where;
    entries.push_back({key, where, std::move(value)});
    return entries.back().value;
}

void Node::erase(std::string_view key) {
    std::erase_if(entries, [&](const Entry& e) { return e.key == key; });
}

void Node::add(std::string key, Node value) {
    Location key_where = value.where;
    entries.push_back(Entry{std::move(key), std::move(key_where), std::move(value)});
}

std::string Node::describe() const {
    switch (kind) {
        case Kind::Null: return "nothing";
        case Kind::Scalar: return "'" + scalar + "'";
        case Kind::Sequence: return "a list";
        case Kind::Map: return "a map";
    }
    return "?";
}

namespace {

Location location_of(const YAML::Mark& mark, const std::string& source) {
    if (mark.is_null()) return {source, 0, 0};
    return {source, mark.line + 1, mark.column + 1};
}

// No configuration nests more than a few levels; a deeper document is refused before the
// recursion below could run out of stack.
constexpr int max_nesting = 64;

Node convert(const YAML::Node& y, const std::string& source, int depth = 0) {
    Node n;
    n.where = location_of(y.Mark(), source);
    if (depth > max_nesting)
        fail(n.where, "", "lists and maps are nested more than " + std::to_string(max_nesting) +
                              " levels deep; a configuration needs only a few");
    switch (y.Type()) {
        case YAML::NodeType::Undefined:
        case YAML::NodeType::Null: n.kind = Node::Kind::Null; break;
        case YAML::NodeType::Scalar:
            n.kind = Node::Kind::Scalar;
            n.scalar = y.Scalar();
            break;
        case YAML::NodeType::Sequence:
            n.kind = Node::Kind::Sequence;
            for (const auto& item : y) n.items.push_back(convert(item, source, depth + 1));
            break;
        case YAML::NodeType::Map:
            n.kind = Node::Kind::Map;
            for (auto it = y.begin(); it != y.end(); ++it) {
                const Location key_where = location_of(it->first.Mark(), source);
                if (!it->first.IsScalar())
                    fail(key_where, "", "a key must be a plain name, not " +
                                            std::string(it->first.IsSequence() ? "a list" : "a map"));
                const std::string key = it->first.Scalar();
                for (const auto& e : n.entries)
                    if (e.key == key)
                        fail(key_where, key, "the key appears twice in this map (first at line " +
                                                 std::to_string(e.key_where.line) + "); keep one");
                n.entries.push_back({key, key_where, convert(it->second, source, depth + 1)});
            }
            break;
    }
    return n;
}

// Scalars that a YAML reader would not read back as text.
bool needs_quotes(const std::string& s) {
    if (s.empty()) return true;
    std::string lower(s);
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* word : {"~", "null", "true", "false", "yes", "no", "on", "off", "y", "n"})
        if (lower == word) return true;
    double d;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
    return ec == std::errc() && end == s.data() + s.size();
}

bool is_scalar_list(const Node& n) {
    return std::all_of(n.items.begin(), n.items.end(), [](const Node& i) { return i.kind != Node::Kind::Map &&
                                                                                 i.kind != Node::Kind::Sequence; });
}

void emit(YAML::Emitter& out, const Node& n, bool quote_text) {
    switch (n.kind) {
        case Node::Kind::Null: out << YAML::Null; break;
        case Node::Kind::Scalar:
            if (quote_text && needs_quotes(n.scalar)) out << YAML::DoubleQuoted << n.scalar;
            else out << n.scalar;
            break;
        case Node::Kind::Sequence:
            if (n.items.empty() || is_scalar_list(n)) out << YAML::Flow;
            out << YAML::BeginSeq;
            for (const Node& item : n.items) emit(out, item, true);
            out << YAML::EndSeq;
            break;
        case Node::Kind::Map:
            if (n.entries.empty()) out << YAML::Flow;
            out << YAML::BeginMap;
            for (const auto& e : n.entries) {
                out << YAML::Key << e.key << YAML::Value;
                emit(out, e.value, e.value.quote_text);
                if (!e.value.comment.empty() && (e.value.kind == Node::Kind::Scalar || e.value.kind == Node::Kind::Null ||
                                                 (e.value.kind == Node::Kind::Sequence && is_scalar_list(e.value)) ||
                                                 (e.value.kind == Node::Kind::Map && e.value.entries.empty())))
                    out << YAML::Comment(e.value.comment);
            }
            out << YAML::EndMap;
            break;
    }
}

bool all_digits(std::string_view s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = up;
        }
    }
    return row[b.size()];
}

}  // namespace

Node parse_yaml(std::string_view text, const std::string& source) {
    YAML::Node root;
    try {
        root = YAML::Load(std::string(text));
    } catch (const YAML::Exception& e) {
        fail(location_of(e.mark, source), "", "not valid YAML: " + e.msg);
    }
    return convert(root, source);
}

std::string emit_yaml(const Node& root) {
    YAML::Emitter out;
    out.SetIndent(2);
    emit(out, root, root.quote_text);
    if (!out.good()) throw Error("cannot write the config as YAML: " + out.GetLastError());
    return std::string(out.c_str()) + "\n";
}

std::vector<std::string> split_path(std::string_view path, const std::string& source) {
    std::vector<std::string> parts;
    std::string current;
    auto finish = [&] {
        if (current.empty()) fail({source}, std::string(path), "empty key in the path (write keys as a.b[1].c)");
        parts.push_back(current);
        current.clear();
    };
    for (std::size_t i = 0; i < path.size(); ++i) {
        const char c = path[i];
        if (c == '.') {
            if (i > 0 && path[i - 1] == ']') continue;
            finish();
        } else if (c == '[') {
            if (!current.empty()) finish();
            const std::size_t close = path.find(']', i);
            if (close == std::string_view::npos || !all_digits(path.substr(i + 1, close - i - 1)))
                fail({source}, std::string(path), "a list index is written [N] with N a number from 0");
            parts.emplace_back(path.substr(i + 1, close - i - 1));
            i = close;
            if (i + 1 < path.size() && path[i + 1] != '.' && path[i + 1] != '[')
                fail({source}, std::string(path), "expected '.' or '[' after ']'");
        } else {
            current += c;
        }
    }
    if (!current.empty()) parts.push_back(current);
    else if (path.empty() || path.back() == '.') finish();
    return parts;
}

Assignment parse_assignment(std::string_view text, const std::string& source, bool literal) {
    const std::size_t eq = text.find('=');
    if (eq == std::string_view::npos || eq == 0)
        fail({source}, std::string(text), "expected key.path=value, e.g. queue[0].improve.termination.max_iterations=50");
    Assignment a;
    a.path_text = std::string(text.substr(0, eq));
    a.path = split_path(a.path_text, source);
    const std::string value(text.substr(eq + 1));
    const Location where{source};
    if (literal) {
        a.value = Node::text(value, where);
    } else {
        a.value = parse_yaml(value, source);
        // Positions inside the value text mean nothing to the user: report the assignment.
        struct Relocate {
            const Location& where;
            void operator()(Node& n) const {
                n.where = where;
                for (Node& item : n.items) (*this)(item);
                for (auto& e : n.entries) e.key_where = where, (*this)(e.value);
            }
        };
        Relocate{where}(a.value);
    }
    return a;
}

void apply(Node& root, const Assignment& a) {
    const Location where = a.value.where;
    Node* at = &root;
    std::string walked;
    for (std::size_t i = 0; i < a.path.size(); ++i) {
        const std::string& part = a.path[i];
        const bool index = all_digits(part);
        if (at->kind == Node::Kind::Null) {
            at->kind = index ? Node::Kind::Sequence : Node::Kind::Map;
            at->where = where;
        }
        Node* next = nullptr;
        if (index) {
            if (at->kind != Node::Kind::Sequence)
                fail(where, walked, "is " + at->describe() + ", not a list: [" + part + "] does not apply");
            std::size_t k = 0;
            const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), k);
            if (error != std::errc() || end != part.data() + part.size() || k > at->items.size())
                fail(where, walked, "has " + std::to_string(at->items.size()) + " entries; [" + part +
                                        "] can name one of them or append one at [" +
                                        std::to_string(at->items.size()) + "]");
            if (k == at->items.size()) {
                Node fresh;
                fresh.where = where;
                at->items.push_back(fresh);
            }
            next = &at->items[k];
            walked += "[" + part + "]";
        } else {
            if (at->kind != Node::Kind::Map)
                fail(where, walked, "is " + at->describe() + ", not a map: ." + part + " does not apply");
            next = at->find(part);
            if (!next) {
                Node fresh;
                fresh.where = where;
                at->entries.push_back({part, where, fresh});
                next = &at->entries.back().value;
            }
            walked += (walked.empty() ? "" : ".") + part;
        }
        at = next;
    }
    *at = a.value;
}

std::string closest(std::string_view word, const std::vector<std::string>& known) {
    std::string best;
    std::size_t best_distance = std::numeric_limits<std::size_t>::max();
    for (const auto& k : known) {
        const std::size_t d = edit_distance(word, k);
        if (d < best_distance) best_distance = d, best = k;
    }
    const std::size_t allowed = std::max<std::size_t>(2, word.size() / 3);
    return best_distance <= allowed ? best : std::string();
}

std::string join(const std::vector<std::string>& words, std::string_view separator) {
    std::string out;
    for (const auto& w : words) out += (out.empty() ? "" : std::string(separator)) + w;
    return out;
}

void fail(const Location& where, const std::string& path, const std::string& message) {
    throw ConfigError(where.str(), path, message);
}

namespace {
const std::string& scalar_of(const Node& node, const std::string& path, const char* expected) {
    if (node.kind != Node::Kind::Scalar) fail(node.where, path, std::string("expected ") + expected + ", got " + node.describe());
    return node.scalar;
}
}  // namespace

bool to_bool(const Node& node, const std::string& path) {
    std::string s = scalar_of(node, path, "true or false");
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    fail(node.where, path, "expected true or false, got '" + node.scalar + "'");
}

long long to_integer(const Node& node, const std::string& path, long long min, long long max) {
    const std::string& s = scalar_of(node, path, "a whole number");
    std::string_view digits(s);
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    long long value = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range || (ec == std::errc() && end == digits.data() + digits.size() &&
                                                 (value < min || value > max)))
        fail(node.where, path, "'" + s + "' is out of range: must lie in [" + std::to_string(min) + ", " +
                                   std::to_string(max) + "]");
    if (ec != std::errc() || end != digits.data() + digits.size())
        fail(node.where, path, "expected a whole number, got '" + s + "'");
    return value;
}

double to_real(const Node& node, const std::string& path) {
    const std::string& s = scalar_of(node, path, "a number");
    std::string_view digits(s);
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range) fail(node.where, path, "'" + s + "' is out of the range of a double");
    if (ec != std::errc() || end != digits.data() + digits.size())
        fail(node.where, path, "expected a number, got '" + s + "'");
    return value;
}

const std::string& to_text(const Node& node, const std::string& path) { return scalar_of(node, path, "text"); }

std::string format_real(double value) {
    char buffer[64];
    const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
    (void)ec;
    return std::string(buffer, end);
}

}  // namespace paloverde::config::detail
