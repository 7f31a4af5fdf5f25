#pragma once
// The config as a tree that remembers where each value came from (file, line and column, or the
// command-line flag that set it), so that every error can name the key and the place to change.
// yaml-cpp only parses and emits; everything else works on this tree.
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace paloverde::config::detail {

struct Location {
    std::string source;  // the config file, "--set", or the flag that set the value ("--iterations")
    int line = 0;        // 1-based; 0 when the value did not come from a file
    int column = 0;
    std::string str() const;  // "run.yaml:12:7", or the source alone
};

struct Node {
    enum class Kind { Null, Scalar, Sequence, Map };
    struct Entry;

    Kind kind = Kind::Null;
    std::string scalar;        // Kind::Scalar
    std::vector<Node> items;   // Kind::Sequence
    std::vector<Entry> entries;  // Kind::Map, in file order
    Location where;
    std::string comment;       // printed after the value by emit_yaml (help text); not parsed
    bool quote_text = false;   // a text value: emit_yaml quotes it where YAML would read a number

    static Node map(Location where);
    static Node text(std::string value, Location where);
    bool is_map() const { return kind == Kind::Map; }
    bool is_null() const { return kind == Kind::Null; }
    const Node* find(std::string_view key) const;
    Node* find(std::string_view key);
    // The entry `key`, added (null, at this node's location) if missing. Only on maps.
    Node& at(const std::string& key);
    void erase(std::string_view key);
    // Appends an entry (maps only).
    void add(std::string key, Node value);
    std::string describe() const;  // "a list", "a map", "'text'", "nothing"
};

struct Node::Entry {
    std::string key;
    Location key_where;
    Node value;
};

// Parses YAML text; a syntax error or a duplicate key is a ConfigError naming the line.
Node parse_yaml(std::string_view text, const std::string& source);

// YAML text of the tree, with each node's comment.
std::string emit_yaml(const Node& root);

// A "key.path[1].x=value" assignment from the command line: the value is parsed as YAML (so
// `~` is null and `[a, b]` a list) unless `literal`.
struct Assignment {
    std::vector<std::string> path;  // list indexes as decimal strings
    std::string path_text;
    Node value;
};
Assignment parse_assignment(std::string_view text, const std::string& source, bool literal);
std::vector<std::string> split_path(std::string_view path, const std::string& source);
// Sets the value at the path, creating maps on the way; a list index may be one past the end
// (appends). Errors name the assignment's source.
void apply(Node& root, const Assignment& assignment);

// A "did you mean" hint: the closest of `known` to `word`, if close enough, else "".
std::string closest(std::string_view word, const std::vector<std::string>& known);
std::string join(const std::vector<std::string>& words, std::string_view separator = ", ");

// Throws ConfigError: "<where>: <path>: <message>".
[[noreturn]] void fail(const Location& where, const std::string& path, const std::string& message);

// Scalar conversions; each fails naming the path and the value.
bool to_bool(const Node& node, const std::string& path);
long long to_integer(const Node& node, const std::string& path, long long min, long long max);
double to_real(const Node& node, const std::string& path);
const std::string& to_text(const Node& node, const std::string& path);
std::string format_real(double value);  // shortest text that reads back to the same double

}  // namespace paloverde::config::detail
