#pragma once
// An options table: each field of an options struct declared once, with its key, type and help.
// From the declaration come reading (with type checks), validation, writing back as YAML and the
// reference documentation.
//
// Ranges are not repeated here: after each key is read the struct's own validate() runs, and an
// OptionError it throws is reported at that key. The defaults are valid and each earlier key
// passed, so the key just read is the one to change.
#include <climits>
#include <limits>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/node.hpp"
#include "paloverde/config/config.hpp"
#include "paloverde/config/registry.hpp"

namespace paloverde::config::detail {

using Origins = std::map<std::string, std::string>;

inline std::string child_path(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
}
inline std::string item_path(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

// Records where each key was set (RunSpec::origins).
struct Reader {
    Origins* origins = nullptr;
    void record(const std::string& path, const Location& where) const {
        if (origins && !where.source.empty()) (*origins)[path] = where.str();
    }
};

// Keys of a table that a context does not accept (an untangle step sets `improve_shape` itself),
// and why.
struct Skip {
    std::vector<std::string> keys;
    std::string why;
    bool has(const std::string& key) const {
        for (const auto& k : keys)
            if (k == key) return true;
        return false;
    }
};

// An OptionError from validate() reported at the key just read. Its message usually starts with
// the field's name, which the key path already gives.
[[noreturn]] void fail_at(const OptionError& error, const Location& where, const std::string& path,
                          const std::string& key);

// One line of YAML for a value (flow style), for the reference tables.
std::string inline_yaml(const Node& node);

// The text of `node`, which must be one of `names` ("unknown metric 'x' (known: ...)").
std::string one_of(const Node& node, const std::string& path, const std::vector<std::string>& names,
                   const std::string& kind);

template <class T>
class Table {
public:
    using Validate = std::function<void(const T&)>;
    struct Field {
        std::string key, type, help;
        std::function<void(T&, const Node&, const std::string& path, const Reader&)> read;
        std::function<Node(const T&, bool comments)> write;
    };

    // `what` names the object in messages ("solver global", "termination", "input").
    Table(std::string what, Validate validate = {}) : what_(std::move(what)), validate_(std::move(validate)) {}

    const std::string& what() const { return what_; }
    const std::vector<Field>& fields() const { return fields_; }
    std::vector<std::string> keys(const Skip& skip = {}, const std::vector<std::string>& also_known = {}) const {
        std::vector<std::string> out(also_known);
        for (const auto& f : fields_)
            if (!skip.has(f.key)) out.push_back(f.key);
        return out;
    }
    const Field* field(const std::string& key) const {
        for (const auto& f : fields_)
            if (f.key == key) return &f;
        return nullptr;
    }
    // Extra words for an unknown key (e.g. which other object has it).
    Table& hint(std::function<std::string(const std::string& key)> h) {
        hint_ = std::move(h);
        return *this;
    }

    Table& add(Field f) {
        fields_.push_back(std::move(f));
        return *this;
    }

    Table& flag(std::string key, bool T::*m, std::string help) {
        return add({std::move(key), "true/false", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) { t.*m = to_bool(n, p); },
                    [m](const T& t, bool) { return Node::text(t.*m ? "true" : "false", {}); }});
    }

    template <class Int>
    Table& integer(std::string key, Int T::*m, std::string help) {
        return add({std::move(key), "whole number", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        t.*m = static_cast<Int>(to_integer(n, p, std::numeric_limits<Int>::min(),
                                                           std::numeric_limits<Int>::max()));
                    },
                    [m](const T& t, bool) { return Node::text(std::to_string(t.*m), {}); }});
    }

    Table& real(std::string key, double T::*m, std::string help) {
        return add({std::move(key), "number", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) { t.*m = to_real(n, p); },
                    [m](const T& t, bool) { return Node::text(format_real(t.*m), {}); }});
    }

    Table& maybe_real(std::string key, std::optional<double> T::*m, std::string help) {
        return add({std::move(key), "number or ~ (none)", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        if (n.is_null()) t.*m = std::nullopt;
                        else t.*m = to_real(n, p);
                    },
                    [m](const T& t, bool) { return t.*m ? Node::text(format_real(*(t.*m)), {}) : Node(); }});
    }

    // A file name, or ~ / "" for none.
    Table& path(std::string key, std::string T::*m, std::string help) {
        return add({std::move(key), "file name or ~ (none)", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        t.*m = n.is_null() ? std::string() : to_text(n, p);
                    },
                    [m](const T& t, bool) { return (t.*m).empty() ? Node() : quoted(t.*m); }});
    }

    Table& text(std::string key, std::string T::*m, std::string help) {
        return add({std::move(key), "text", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) { t.*m = to_text(n, p); },
                    [m](const T& t, bool) { return quoted(t.*m); }});
    }

    // One of a list of names (`kind` names them in messages: "metric", "objective").
    Table& name(std::string key, std::string T::*m, std::function<std::vector<std::string>()> names,
                std::string kind, std::string help) {
        const auto known = names();
        std::string type = known.size() <= 4 ? "one of: " + join(known, ", ")
                                              : std::string("name of a") + (std::string("aeiou").find(kind[0]) != std::string::npos ? "n " : " ") + kind;
        return add({std::move(key), std::move(type), std::move(help),
                    [m, names, kind](T& t, const Node& n, const std::string& p, const Reader&) {
                        t.*m = one_of(n, p, names(), kind);
                    },
                    [m](const T& t, bool) { return quoted(t.*m); }});
    }

    template <class E>
    Table& choice(std::string key, E T::*m, std::vector<std::pair<std::string, E>> names, std::string help) {
        std::vector<std::string> words;
        for (const auto& [w, e] : names) words.push_back(w);
        return add({std::move(key), "one of: " + join(words, ", "), std::move(help),
                    [m, names, words](T& t, const Node& n, const std::string& p, const Reader&) {
                        const std::string w = one_of(n, p, words, "value");
                        for (const auto& [word, e] : names)
                            if (word == w) t.*m = e;
                    },
                    [m, names](const T& t, bool) {
                        for (const auto& [word, e] : names)
                            if (e == t.*m) return Node::text(word, {});
                        return Node();
                    }});
    }

    // A list of names; a single name is a list of one.
    Table& names(std::string key, std::vector<std::string> T::*m, std::function<std::vector<std::string>()> known,
                 std::string kind, std::string help) {
        return add({std::move(key), "list of " + kind + " names", std::move(help),
                    [m, known, kind](T& t, const Node& n, const std::string& p, const Reader&) {
                        (t.*m).clear();
                        for_each_item(n, p, [&](const Node& item, const std::string& ip) {
                            (t.*m).push_back(one_of(item, ip, known(), kind));
                        });
                    },
                    [m](const T& t, bool) { return list_of_text(t.*m); }});
    }

    Table& paths(std::string key, std::vector<std::string> T::*m, std::string help) {
        return add({std::move(key), "list of file names", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        (t.*m).clear();
                        for_each_item(n, p, [&](const Node& item, const std::string& ip) {
                            (t.*m).push_back(to_text(item, ip));
                        });
                    },
                    [m](const T& t, bool) { return list_of_text(t.*m); }});
    }

    Table& integers(std::string key, std::vector<long long> T::*m, std::string help) {
        return add({std::move(key), "list of whole numbers", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        (t.*m).clear();
                        for_each_item(n, p, [&](const Node& item, const std::string& ip) {
                            (t.*m).push_back(to_integer(item, ip, LLONG_MIN, LLONG_MAX));
                        });
                    },
                    [m](const T& t, bool) {
                        Node list;
                        list.kind = Node::Kind::Sequence;
                        for (long long v : t.*m) list.items.push_back(Node::text(std::to_string(v), {}));
                        return list;
                    }});
    }

    // A point or vector: a list of three numbers.
    Table& vector3(std::string key, Vec3 T::*m, std::string help) {
        return add({std::move(key), "list of 3 numbers", std::move(help),
                    [m](T& t, const Node& n, const std::string& p, const Reader&) {
                        Vec3 v{};
                        std::size_t count = 0;
                        for_each_item(n, p, [&](const Node& item, const std::string& ip) {
                            if (count < 3) v[count] = to_real(item, ip);
                            ++count;
                        });
                        if (count != 3) fail(n.where, p, "expected a list of 3 numbers, got " + std::to_string(count));
                        t.*m = v;
                    },
                    [m](const T& t, bool) {
                        Node list;
                        list.kind = Node::Kind::Sequence;
                        for (double c : t.*m) list.items.push_back(Node::text(format_real(c), {}));
                        return list;
                    }});
    }

    // A nested options struct with a table of its own.
    template <class U>
    Table& object(std::string key, U T::*m, const Table<U>& sub, std::string help) {
        return add({std::move(key), "map (" + sub.what() + ")", std::move(help),
                    [m, &sub](T& t, const Node& n, const std::string& p, const Reader& r) { sub.read(t.*m, n, p, r); },
                    [m, &sub](const T& t, bool comments) { return sub.write(t.*m, {}, comments); }});
    }

    // Reads a map onto `target` (which holds the defaults), key by key in file order.
    // `also_known`: keys the caller reads itself (a step's `name` and `label`), for messages.
    void read(T& target, const Node& node, const std::string& path, const Reader& reader, const Skip& skip = {},
              const std::vector<std::string>& also_known = {}) const {
        if (node.is_null()) return;
        if (!node.is_map())
            fail(node.where, path, "expected a map of " + what_ + " options (key: value lines), got " + node.describe());
        for (const auto& e : node.entries) {
            const std::string p = child_path(path, e.key);
            bool caller_reads = false;
            for (const auto& k : also_known) caller_reads = caller_reads || k == e.key;
            if (caller_reads) continue;
            const Field* f = field(e.key);
            if (!f || skip.has(e.key)) fail(e.key_where, p, unknown_key(e.key, skip, also_known));
            reader.record(p, e.value.where);
            f->read(target, e.value, p, reader);
            check(target, e.value.where, p, e.key);
        }
    }

    // Runs validate() on `target`, reporting an error at `where` / `path`.
    void check(const T& target, const Location& where, const std::string& path, const std::string& key) const {
        if (!validate_) return;
        try {
            validate_(target);
        } catch (const ConfigError&) {
            throw;
        } catch (const OptionError& e) {
            fail_at(e, where, path, key);
        }
    }

    Node write(const T& value, const Skip& skip = {}, bool comments = false) const {
        Node n = Node::map({});
        for (const auto& f : fields_) {
            if (skip.has(f.key)) continue;
            Node v = f.write(value, comments);
            if (comments) v.comment = f.help;
            n.add(f.key, std::move(v));
        }
        return n;
    }

    std::vector<OptionInfo> describe(const T& defaults, const Skip& skip = {}) const {
        std::vector<OptionInfo> out;
        for (const auto& f : fields_)
            if (!skip.has(f.key)) out.push_back({f.key, f.type, inline_yaml(f.write(defaults, false)), f.help});
        return out;
    }

    std::string unknown_key(const std::string& key, const Skip& skip, const std::vector<std::string>& also_known = {}) const {
        if (skip.has(key)) return "'" + key + "' cannot be set here: " + skip.why;
        const auto known = keys(skip, also_known);
        std::string message = "unknown key '" + key + "' in " + what_;
        if (const std::string near = closest(key, known); !near.empty()) message += "; did you mean '" + near + "'?";
        if (hint_)
            if (const std::string h = hint_(key); !h.empty()) message += " (" + h + ")";
        message += known.empty() ? std::string(" (it takes no options)") : " (known: " + join(known) + ")";
        return message;
    }

private:
    static Node quoted(const std::string& s) {
        Node n = Node::text(s, {});
        n.quote_text = true;
        return n;
    }
    static Node list_of_text(const std::vector<std::string>& words) {
        Node list;
        list.kind = Node::Kind::Sequence;
        for (const auto& w : words) list.items.push_back(quoted(w));
        return list;
    }
    template <class F>
    static void for_each_item(const Node& n, const std::string& p, F&& f) {
        if (n.is_null()) return;
        if (n.kind == Node::Kind::Scalar) return f(n, p);
        if (n.kind != Node::Kind::Sequence) fail(n.where, p, "expected a list ([a, b] or - lines), got " + n.describe());
        for (std::size_t i = 0; i < n.items.size(); ++i) f(n.items[i], item_path(p, i));
    }

    std::string what_;
    Validate validate_;
    std::vector<Field> fields_;
    std::function<std::string(const std::string&)> hint_;
};

}  // namespace paloverde::config::detail
