#pragma once
// A whole run as data: the input mesh and which vertices are fixed, the instruction queue (or a
// study of several queues on the same input), and the outputs. `read_config` fills a RunSpec
// from a YAML file plus `--set` assignments, with every key checked against the registry;
// `to_yaml` writes it back with every default (`paloverde run --print-config`). The keys are
// documented in docs/config.md.
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/config/registry.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/metrics/targets.hpp"

namespace paloverde::config {

// A config that cannot be used: an unknown key, a value of the wrong type or out of range, a
// YAML syntax error. what() reads "<where>: <key>: <what to change>".
class ConfigError : public OptionError {
public:
    ConfigError(std::string where, std::string key, const std::string& message);
    // "run.yaml:12:7" (file:line:column), "--set", or the flag that set the value ("--iterations").
    const std::string& where() const noexcept { return where_; }
    // The key path, e.g. "queue[1].improve.termination.max_iterations"; empty for syntax errors.
    const std::string& key() const noexcept { return key_; }

private:
    std::string where_, key_;
};

enum class FixedVertices {
    Auto,      // the file's `fixed` point field if it has one, else the boundary
    Boundary,  // the boundary vertices, whatever the file says
    File,      // the file's `fixed` field; an error if it has none
    None       // every vertex may move
};

struct InputSpec {
    std::string mesh;                     // required (unless `pieces`)
    std::vector<std::string> pieces;      // a mesh already split in pieces (partitioned runs)
    MeshFormat format = MeshFormat::FromExtension;
    FixedVertices fixed = FixedVertices::Auto;
    std::vector<long long> fixed_vertices;  // fixed as well: 0-based vertex ids in file order
    OrientationMode orientation = OrientationMode::Auto;  // the file's convention (orientation.hpp)
    // Morphing: a point field of the mesh (three components) that moves its fixed vertices; the mesh
    // as read is then the reference (targets.reference) and the interior follows (docs/morphing.md).
    std::string displacement;
    void validate() const;                // throws OptionError naming the field
};

// What each element should look like (metrics/targets.hpp): the factors of its target kept from
// the input, those taken from a reference mesh, the rest ideal. `keep: auto` (the default) keeps
// the aspect of a mesh with cells (hexahedra, wedges, pyramids, quadrilaterals), whose cells are
// stretched by design and whose users read the scaled Jacobian, which ignores the stretch, and
// keeps nothing of a mesh of simplices; `none` keeps nothing: every element is pulled toward the
// ideal element (the regular one).
struct TargetsSpec {
    std::vector<std::string> keep{"auto"};    // size, orientation, aspect, skew, all, auto, none
    std::string reference;                    // a mesh with the input's connectivity
    std::vector<std::string> from_reference;  // with a reference; empty: every factor not kept
    std::string size_field;                   // a point field of the input: the edge length wanted at each vertex
    std::string metric_field;                 // a point field of the input: the metric wanted at each vertex
    // The targets for a mesh with cells (`cells`) or without; `input_is_reference`: the input as
    // read is the reference (input.displacement).
    TargetOptions options(bool cells, bool input_is_reference = false) const;
    void validate() const;

private:
    TargetOptions factors(bool cells, bool input_is_reference) const;  // options() without the fields
};

// Partitioned (MPI) runs; see docs/config.md. parts = 1 is a serial run.
struct PartitionSpec {
    int parts = 1;
    std::string method = "metis";
    void validate() const;
};

struct ParallelSpec {
    std::string exchange = "colored";  // colored: neighbour exchanges by edge colors; root: through rank 0
    void validate() const;
};

struct AssessSpec {
    std::vector<std::string> metrics;  // empty: the default set of QualityAssessor
    int histogram_bins = 10;
    void validate() const;
};

struct StepSpec {
    enum class Kind { Assess, Untangle, Improve, Wrapper };
    Kind kind = Kind::Improve;
    std::string label;      // shown in reports; defaults to the solver's or wrapper's name
    std::string name;       // the solver (untangle, improve) or wrapper
    SolverOptions options;  // untangle, improve, wrapper
    AssessSpec assess;      // assess
};

struct MethodSpec {
    std::string name;
    std::vector<StepSpec> queue;
};

struct OutputSpec {
    std::string mesh;     // "" for none; in a study, "{method}" in the name becomes the method's name
    bool ascii = false;
    std::string history;  // CSV, one row per iteration of every improver
    std::string summary;  // JSON
    std::string table;    // CSV, one row per method
    std::string plot;     // SVG: worst quality against iterations and time
    std::string pieces;   // partitioned output (.pvtu and one piece per part)
    std::string metric = "aspect_ratio";  // the metric of the worst/mean columns of summary and table
    void validate() const;
};

struct RunSpec {
    InputSpec input;
    TargetsSpec targets;
    int threads = 0;  // 0: OpenMP's default; results do not depend on it
    PartitionSpec partition;
    ParallelSpec parallel;
    std::vector<StepSpec> queue = default_queue();
    std::vector<MethodSpec> study;  // when set, replaces `queue`: each method runs on a copy of the input
    OutputSpec output;
    // Where each key was set: key path -> "file:line:column" or the flag. Filled by the reader.
    std::map<std::string, std::string> origins;

    // The study's methods, or the queue as one method named "run".
    std::vector<MethodSpec> methods() const;
    // Whether the run needs the partitioned (MPI) machinery: pieces in or out (input.pieces,
    // output.pieces, or a .pvtu as input.mesh or output.mesh), or partition.parts > 1.
    bool partitioned() const;
    // "<origin>: <key>" for messages (just "<key>" for a default).
    std::string where(const std::string& key) const;
    // Everything `run` needs before it starts (an input mesh, output names that fit a study);
    // throws ConfigError naming the key.
    void check_runnable() const;

    // One improve step with the global solver: what `paloverde improve` does by default.
    static std::vector<StepSpec> default_queue();
};

// A `--set key.path=value` (source "--set") or a flag standing for one (source "--iterations").
// The value is read as YAML unless `literal` (file names from flags are taken as they are).
struct Override {
    std::string assignment;
    std::string source = "--set";
    bool literal = false;
};

// Reads a config file, applies the overrides in order and checks everything. Relative paths in
// the file are used as they are, relative to the current directory (like the command line).
RunSpec read_config(const std::filesystem::path& file, std::span<const Override> overrides = {});
// The same from text; `source` names it in messages. Empty text is the all-default config.
RunSpec parse_config(std::string_view yaml, const std::string& source, std::span<const Override> overrides = {});
// The resolved config as YAML with every default; reading it back gives the same RunSpec.
// With `comments`, each key carries its help text.
std::string to_yaml(const RunSpec& spec, bool comments = true);

}  // namespace paloverde::config
