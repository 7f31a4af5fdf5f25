// The run config: its sections, the instruction queue and the study, read from the tree with
// the registry's tables and written back with every default.
#include <algorithm>
#include <fstream>
#include <sstream>

#include "config/registry_internal.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"

namespace paloverde::config {

ConfigError::ConfigError(std::string where, std::string key, const std::string& message)
    : OptionError((where.empty() ? std::string() : where + ": ") + (key.empty() ? std::string() : key + ": ") + message),
      where_(std::move(where)),
      key_(std::move(key)) {}

void InputSpec::validate() const {
    for (long long v : fixed_vertices)
        if (v < 0) throw OptionError("fixed_vertices must be vertex ids >= 0 (got " + std::to_string(v) + ")");
}

TargetOptions TargetsSpec::options(bool cells, bool input_is_reference) const {
    if (!metric_field.empty()) {
        const bool keeps = std::any_of(keep.begin(), keep.end(), [](const std::string& w) { return w != "auto" && w != "none"; });
        if (keeps || !from_reference.empty() || !reference.empty() || !size_field.empty() || input_is_reference)
            throw OptionError("metric_field gives each element its size, aspect and orientation (the skew is ideal in the "
                              "metric): leave keep (auto or none), from_reference, reference, size_field and "
                              "input.displacement out");
        TargetOptions o;
        o.size = o.aspect = o.orientation = TargetSource::Metric;
        return o;
    }
    TargetOptions o = factors(cells, input_is_reference);
    if (size_field.empty()) return o;
    auto names_size = [](const std::vector<std::string>& words) {
        return std::find(words.begin(), words.end(), "size") != words.end() ||
               std::find(words.begin(), words.end(), "all") != words.end();
    };
    if (names_size(keep) || names_size(from_reference))
        throw OptionError("size_field gives each element its size: leave size (and all) out of keep and from_reference");
    o.size = TargetSource::Field;
    return o;
}

TargetOptions TargetsSpec::factors(bool cells, bool input_is_reference) const {
    auto joined = [](const std::vector<std::string>& words) {
        std::string out;
        for (const auto& w : words) {
            if (w == "none" || w == "auto") continue;
            out += (out.empty() ? "" : ",") + w;
        }
        return out;
    };
    const bool automatic = std::find(keep.begin(), keep.end(), "auto") != keep.end();
    TargetOptions o = TargetOptions::from(joined(keep), TargetSource::Input);
    // auto keeps a cell's aspect unless the reference is asked for it.
    const bool aspect_from_reference =
        std::find(from_reference.begin(), from_reference.end(), "aspect") != from_reference.end() ||
        std::find(from_reference.begin(), from_reference.end(), "all") != from_reference.end();
    if (automatic && cells && !aspect_from_reference) o.aspect = TargetSource::Input;
    if (reference.empty() && !input_is_reference) return o;
    // The input as read is the reference: what it keeps, it keeps from there (not from the moved mesh).
    const auto kept_from_reference = [&] {
        if (input_is_reference)
            for (TargetSource* f : {&o.size, &o.orientation, &o.aspect, &o.skew})
                if (*f == TargetSource::Input) *f = TargetSource::Reference;
        return o;
    };
    if (from_reference.empty()) {  // every factor not kept
        for (TargetSource* f : {&o.size, &o.orientation, &o.aspect, &o.skew})
            if (*f == TargetSource::Ideal) *f = TargetSource::Reference;
        return kept_from_reference();
    }
    const TargetOptions r = TargetOptions::from(joined(from_reference), TargetSource::Reference);
    const TargetSource* from[] = {&r.size, &r.orientation, &r.aspect, &r.skew};
    TargetSource* to[] = {&o.size, &o.orientation, &o.aspect, &o.skew};
    for (int i = 0; i < 4; ++i) {
        if (*from[i] != TargetSource::Reference) continue;
        if (*to[i] == TargetSource::Input && !input_is_reference)
            throw OptionError("a factor cannot be both kept and taken from the reference (keep: " + joined(keep) +
                              "; from_reference: " + joined(from_reference) + ")");
        *to[i] = TargetSource::Reference;
    }
    return kept_from_reference();
}

void TargetsSpec::validate() const {
    const bool alone = std::none_of(keep.begin(), keep.end(), [](const std::string& w) { return w == "none" || w == "auto"; });
    if (!alone && keep.size() > 1)
        throw OptionError("keep: auto and none stand alone (got " + std::to_string(keep.size()) + " words)");
    options(true);
}

void PartitionSpec::validate() const {
    if (parts < 1) throw OptionError("parts must be >= 1 (1: a serial run; got " + std::to_string(parts) + ")");
    if (method != "metis") throw OptionError("method must be metis (got '" + method + "')");
}

void ParallelSpec::validate() const {
    if (exchange != "colored" && exchange != "root")
        throw OptionError("exchange must be colored or root (got '" + exchange + "')");
}

void AssessSpec::validate() const {
    if (metrics.empty()) QualityAssessor({"aspect_ratio"}, histogram_bins);  // checks the bins
    else QualityAssessor(metrics, histogram_bins);
}

void OutputSpec::validate() const {
    make_metric(metric);
    const auto extension = [](const std::string& path) { return std::filesystem::path(path).extension().string(); };
    if (!plot.empty() && extension(plot) != ".svg")
        throw OptionError("plot must be an .svg file name (got '" + plot + "'); plots are written as SVG");
    // A .pvtu is a partitioned output (RunSpec::partitioned()); anything else must be a format
    // the writers know, checked now rather than after the solvers ran.
    const std::string mesh_extension = extension(mesh);
    if (!mesh.empty() && mesh_extension != ".pvtu" && mesh_extension != ".vtk" && mesh_extension != ".vtu" &&
        mesh_extension != ".msh" && mesh_extension != ".mesh")
        throw OptionError("mesh must name a .vtk, .vtu, .msh or .mesh file, the format to write (got '" + mesh + "')");
    if (!pieces.empty() && extension(pieces) != ".pvtu")
        throw OptionError("pieces must be a .pvtu file name (got '" + pieces + "')");
}

std::vector<StepSpec> RunSpec::default_queue() {
    StepSpec step;
    step.kind = StepSpec::Kind::Improve;
    step.name = "global";
    step.label = "global";
    step.options = default_options("global");
    return {step};
}

std::vector<MethodSpec> RunSpec::methods() const {
    if (!study.empty()) return study;
    return {MethodSpec{"run", queue}};
}

bool RunSpec::partitioned() const {
    auto pvtu = [](const std::string& path) { return std::filesystem::path(path).extension() == ".pvtu"; };
    return !input.pieces.empty() || pvtu(input.mesh) || partition.parts > 1 || !output.pieces.empty() || pvtu(output.mesh);
}

std::string RunSpec::where(const std::string& key) const {
    const auto it = origins.find(key);
    return it == origins.end() ? key : it->second + ": " + key;
}

namespace {
std::string origin_of(const RunSpec& spec, const std::string& key) {
    const auto it = spec.origins.find(key);
    return it == spec.origins.end() ? std::string() : it->second;
}
}  // namespace

void RunSpec::check_runnable() const {
    if (input.mesh.empty() && input.pieces.empty())
        throw ConfigError(origin_of(*this, "input.mesh"), "input.mesh",
                          "no input mesh: set input.mesh in the config (or --set input.mesh=FILE)");
    if (!input.mesh.empty() && !input.pieces.empty())
        throw ConfigError(origin_of(*this, "input.pieces"), "input.pieces",
                          "give input.mesh (one file) or input.pieces (a mesh in pieces), not both");
    if (study.size() > 1 && !output.mesh.empty() && output.mesh.find("{method}") == std::string::npos)
        throw ConfigError(origin_of(*this, "output.mesh"), "output.mesh",
                          "a study writes one mesh per method: put {method} in the name (e.g. out_{method}.vtu)");
    if (!input.displacement.empty() && !targets.reference.empty())
        throw ConfigError(origin_of(*this, "targets.reference"), "targets.reference",
                          "input.displacement makes the input its own reference: leave targets.reference empty");
    // A reference and a size field travel from the whole mesh to the parts; pieces read as they
    // are carry neither.
    const bool from_pieces = !input.pieces.empty() || std::filesystem::path(input.mesh).extension() == ".pvtu";
    auto refuse_with_pieces = [&](const std::string& value, const std::string& key, const std::string& what) {
        if (from_pieces && !value.empty())
            throw ConfigError(origin_of(*this, key), key,
                              "a mesh read in pieces carries no " + what +
                                  " for the parts: give the whole mesh as input.mesh (partition.parts splits it)");
    };
    refuse_with_pieces(input.displacement, "input.displacement", "reference");
    refuse_with_pieces(targets.reference, "targets.reference", "reference");
    refuse_with_pieces(targets.size_field, "targets.size_field", "size field");
    refuse_with_pieces(targets.metric_field, "targets.metric_field", "metric field");
}

namespace detail {
namespace {

const Table<InputSpec>& input_table() {
    static const Table<InputSpec> t = [] {
        Table<InputSpec> t("input", [](const InputSpec& s) { s.validate(); });
        t.path("mesh", &InputSpec::mesh, "The mesh to improve (.vtk .vtu .msh .mesh .node/.ele). Required.")
            .paths("pieces", &InputSpec::pieces,
                   "A mesh already split in pieces, one file per part (partitioned runs), instead of mesh.")
            .choice("format", &InputSpec::format,
                    {{"auto", MeshFormat::FromExtension}, {"vtk", MeshFormat::VtkLegacy}, {"vtu", MeshFormat::Vtu},
                     {"gmsh", MeshFormat::Gmsh}, {"medit", MeshFormat::Medit}, {"tetgen", MeshFormat::TetGen}},
                    "File format; auto: from the extension.")
            .choice("fixed", &InputSpec::fixed,
                    {{"auto", FixedVertices::Auto}, {"boundary", FixedVertices::Boundary},
                     {"file", FixedVertices::File}, {"none", FixedVertices::None}},
                    "Which vertices stay put. auto: the file's `fixed` point field if it has one, else the boundary; "
                    "boundary: the boundary; file: the `fixed` field (an error without one); none: every vertex moves.")
            .integers("fixed_vertices", &InputSpec::fixed_vertices,
                      "Vertices fixed as well: 0-based ids in the file's order.")
            .choice("orientation", &InputSpec::orientation,
                    {{"auto", OrientationMode::Auto}, {"as_is", OrientationMode::AsIs},
                     {"flipped", OrientationMode::Flipped}},
                    "The file's element orientation convention. auto: flip every element (two corners swapped) "
                    "when the elements' total signed volume is negative (the mirror convention); as_is: the file's "
                    "order; flipped: flip every element. Outputs keep the file's order. Pieces decide together.")
            .text("displacement", &InputSpec::displacement,
                  "Morphing: the name of a point field of the mesh, three components, that moves its fixed (boundary) "
                  "vertices; the mesh as read is the reference (targets), and the interior follows it "
                  "(docs/morphing.md). Empty: none.");
        return t;
    }();
    return t;
}

const Table<TargetsSpec>& targets_table() {
    static const Table<TargetsSpec> t = [] {
        const auto factors = [] { return std::vector<std::string>{"size", "orientation", "aspect", "skew", "all"}; };
        const auto kept = [] {
            return std::vector<std::string>{"size", "orientation", "aspect", "skew", "all", "auto", "none"};
        };
        Table<TargetsSpec> t("targets", [](const TargetsSpec& s) { s.validate(); });
        t.names("keep", &TargetsSpec::keep, kept, "factor",
                "Factors of each element's target kept from the input: size, orientation, aspect (the edges' "
                "relative lengths), skew (the angles), all; the rest are ideal (or from the reference). auto: aspect "
                "for a mesh with cells (hexahedra, wedges, pyramids, quadrilaterals), nothing for tetrahedra and "
                "triangles; none: nothing, every element is pulled toward the ideal element. With size or "
                "orientation kept, solver steps whose metric is not set rate with shape_size or "
                "shape_size_orient (docs/targets.md).")
            .path("reference", &TargetsSpec::reference,
                  "A mesh with the input's connectivity (any format) whose elements give the factors of "
                  "from_reference; empty: none.")
            .names("from_reference", &TargetsSpec::from_reference, factors, "factor",
                   "Factors taken from the reference mesh; empty: every factor not kept.")
            .text("size_field", &TargetsSpec::size_field,
                  "A point field of the input mesh, one value per vertex: the edge length wanted there (a size "
                  "field). Each element's target size is the regular element's with edges of the mean of its "
                  "vertices' lengths; shape factors as keep and from_reference say. Empty: none.")
            .text("metric_field", &TargetsSpec::metric_field,
                  "A point field of the input mesh: the metric wanted at each vertex, a symmetric positive definite "
                  "matrix M in which the wanted edges have unit length (e^T M e = 1; edges of length h: I / h^2), as 6 "
                  "values (xx, yy, zz, xy, yz, xz) or 9 (the full matrix). Each element's target is the ideal element "
                  "in the mean of its vertices' metrics: size, aspect and orientation from the field, with keep "
                  "auto or none and no reference. Empty: none.");
        return t;
    }();
    return t;
}

const Table<PartitionSpec>& partition_table() {
    static const Table<PartitionSpec> t = [] {
        Table<PartitionSpec> t("partition", [](const PartitionSpec& s) { s.validate(); });
        t.integer("parts", &PartitionSpec::parts, "Parts (MPI ranks) to split the mesh into; 1: a serial run.")
            .name("method", &PartitionSpec::method, [] { return std::vector<std::string>{"metis"}; }, "partitioner",
                  "How to split: metis (the vertex graph, minimizing the edge cut).");
        return t;
    }();
    return t;
}

const Table<ParallelSpec>& parallel_table() {
    static const Table<ParallelSpec> t = [] {
        Table<ParallelSpec> t("parallel", [](const ParallelSpec& s) { s.validate(); });
        t.name("exchange", &ParallelSpec::exchange, [] { return std::vector<std::string>{"colored", "root"}; },
               "exchange",
               "How ranks exchange boundary values: colored (neighbours pairwise, by the colors of the process "
               "graph's edges) or root (everything through rank 0; for checking).");
        return t;
    }();
    return t;
}

const Table<OutputSpec>& output_table() {
    static const Table<OutputSpec> t = [] {
        Table<OutputSpec> t("output", [](const OutputSpec& s) { s.validate(); });
        t.path("mesh", &OutputSpec::mesh,
               "Where to write the improved mesh (format from the extension); in a study, {method} in the name "
               "becomes the method's name.")
            .flag("ascii", &OutputSpec::ascii, "Write the mesh as text where the format has a binary form.")
            .path("history", &OutputSpec::history, "CSV: one row per iteration of every improver (method, improver, then the solver's columns).")
            .path("summary", &OutputSpec::summary, "JSON: the run's outcome, each method's steps, reports and histories.")
            .path("table", &OutputSpec::table, "CSV: one row per method (time, iterations, worst/mean/inverted before and after).")
            .path("plot", &OutputSpec::plot, "SVG: the worst quality against iterations and against time, one line per method.")
            .path("pieces", &OutputSpec::pieces, "Partitioned output: a .pvtu file and one .vtu piece per part.")
            .name("metric", &OutputSpec::metric, [] { return metric_names(); }, "metric",
                  "The metric of the worst and mean columns of summary and table.");
        return t;
    }();
    return t;
}

const std::vector<std::string> kStepKinds{"assess", "untangle", "improve", "wrapper"};

// Shorthands to maps, so that --set can reach inside them: `improve: local` -> `{name: local}`,
// `assess: before` -> `{label: before}`, `objective: p_mean` -> `{name: p_mean}`, `queue: NAME` ->
// `[{wrapper: {name: NAME}}]`. Leaves anything malformed for the reader to report.
void normalize_body(Node& body, const std::string& kind) {
    if (body.kind == Node::Kind::Scalar) {
        Node map = Node::map(body.where);
        map.entries.push_back({kind == "assess" ? "label" : "name", body.where, body});
        body = std::move(map);
    } else if (body.is_null()) {
        const Location where = body.where;
        body = Node::map(where);
    }
    if (!body.is_map() || kind == "assess") return;
    for (const char* key : {"objective", "metric"}) {
        Node* sub = body.find(key);
        if (sub && sub->kind == Node::Kind::Scalar) {
            Node map = Node::map(sub->where);
            map.entries.push_back({"name", sub->where, *sub});
            *sub = std::move(map);
        }
    }
}

void normalize_queue(Node* queue) {
    if (!queue) return;
    if (queue->kind == Node::Kind::Scalar) {
        Node body = Node::map(queue->where);
        body.entries.push_back({"name", queue->where, *queue});
        Node step = Node::map(queue->where);
        step.entries.push_back({"wrapper", queue->where, std::move(body)});
        Node list;
        list.kind = Node::Kind::Sequence;
        list.where = queue->where;
        list.items.push_back(std::move(step));
        *queue = std::move(list);
    }
    if (queue->kind != Node::Kind::Sequence) return;
    for (Node& step : queue->items)
        if (step.is_map() && step.entries.size() == 1) normalize_body(step.entries[0].value, step.entries[0].key);
}

void normalize(Node& root) {
    if (!root.is_map()) return;
    normalize_queue(root.find("queue"));
    if (Node* study = root.find("study"); study && study->kind == Node::Kind::Sequence)
        for (Node& method : study->items)
            if (method.is_map()) normalize_queue(method.find("queue"));
}

std::string optional_text(const Node& body, const std::string& key, const std::string& path, const Reader& r,
                          const std::string& otherwise) {
    const Node* n = body.find(key);
    if (!n || n->is_null()) return otherwise;
    r.record(child_path(path, key), n->where);
    return to_text(*n, child_path(path, key));
}

StepSpec read_step(const Node& node, const std::string& path, const Reader& r) {
    const std::string usage = "a step is one of: assess: LABEL, untangle: SOLVER, improve: SOLVER, wrapper: NAME "
                              "(each also as a map with its options)";
    if (!node.is_map()) fail(node.where, path, "expected a step, got " + node.describe() + "; " + usage);
    if (node.entries.size() != 1) {
        std::vector<std::string> keys;
        for (const auto& e : node.entries) keys.push_back(e.key);
        fail(node.where, path, "a step has exactly one key, this one has " + std::to_string(keys.size()) + " (" +
                                   join(keys) + "); " + usage + ". Options go inside, indented under the step's key");
    }
    const auto& entry = node.entries[0];
    const std::string p = child_path(path, entry.key);
    const Node& body = entry.value;
    StepSpec step;
    if (std::find(kStepKinds.begin(), kStepKinds.end(), entry.key) == kStepKinds.end()) {
        std::string message = "unknown step '" + entry.key + "'";
        if (const auto near = closest(entry.key, kStepKinds); !near.empty()) message += "; did you mean '" + near + "'?";
        if (find_wrapper(entry.key)) message += "; a wrapper is written `wrapper: " + entry.key + "`";
        if (find_solver(entry.key)) message += "; a solver is written `improve: " + entry.key + "`";
        fail(entry.key_where, p, message + " (" + usage + ")");
    }
    if (!body.is_map()) fail(body.where, p, "expected a name or a map of options, got " + body.describe());
    r.record(p, body.where);

    if (entry.key == "assess") {
        step.kind = StepSpec::Kind::Assess;
        step.label = optional_text(body, "label", p, r, "assess");
        assess_table().read(step.assess, body, p, r, {}, {"label"});
        return step;
    }
    const std::string np = child_path(p, "name");
    const Node* name = body.find("name");
    if (name) r.record(np, name->where);
    if (entry.key == "wrapper") {
        step.kind = StepSpec::Kind::Wrapper;
        if (!name || name->is_null())
            fail(body.where, np, "a wrapper step needs a name: " + join(wrapper_names()));
        step.name = one_of(*name, np, wrapper_names(), "wrapper");
        const WrapperKind& w = *find_wrapper(step.name);
        step.options = w.defaults();
        w.options->read(step.options, body, p, r, w.skip, {"name", "label"});
        step.label = optional_text(body, "label", p, r, step.name);
        return step;
    }
    step.kind = entry.key == "untangle" ? StepSpec::Kind::Untangle : StepSpec::Kind::Improve;
    step.name = name && !name->is_null() ? one_of(*name, np, solver_names(), "solver") : "global";
    const SolverKind& s = *find_solver(step.name);
    if (step.kind == StepSpec::Kind::Untangle) {
        if (!s.options->untangles) {
            std::vector<std::string> untanglers;
            for (const auto& other : solver_kinds())
                if (other.options->untangles) untanglers.push_back(other.name);
            fail(name->where, np, "solver " + step.name + " does not untangle; these do: " + join(untanglers));
        }
        step.options = s.defaults();
        s.options->untangle_only(step.options);
        s.options->read(step.options, body, p, r, untangle_skip(), {"name", "label"});
        step.label = optional_text(body, "label", p, r, "untangle");
        return step;
    }
    step.options = s.defaults();
    s.options->read(step.options, body, p, r, s.skip, {"name", "label"});
    step.label = optional_text(body, "label", p, r, step.name);
    return step;
}

std::vector<StepSpec> read_queue(const Node& node, const std::string& path, const Reader& r) {
    if (node.is_null()) return {};
    if (node.kind != Node::Kind::Sequence)
        fail(node.where, path, "expected a list of steps (- assess: ..., - improve: ...) or a wrapper's name (" +
                                   join(wrapper_names()) + "), got " + node.describe());
    std::vector<StepSpec> steps;
    for (std::size_t i = 0; i < node.items.size(); ++i) steps.push_back(read_step(node.items[i], item_path(path, i), r));
    return steps;
}

Node text_node(const std::string& s, const std::string& comment, bool comments) {
    Node n = Node::text(s, {});
    n.quote_text = true;
    if (comments) n.comment = comment;
    return n;
}

Node write_step(const StepSpec& step, bool comments) {
    Node body = Node::map({});
    std::string key;
    switch (step.kind) {
        case StepSpec::Kind::Assess: {
            key = "assess";
            body.add("label", text_node(step.label, "shown in reports", comments));
            for (auto& e : assess_table().write(step.assess, {}, comments).entries) body.entries.push_back(std::move(e));
            break;
        }
        case StepSpec::Kind::Wrapper: {
            key = "wrapper";
            const WrapperKind* w = find_wrapper(step.name);
            if (!w) throw OptionError("unknown wrapper '" + step.name + "' (known: " + join(wrapper_names()) + ")");
            body.add("name", text_node(step.name, join(wrapper_names()), comments));
            body.add("label", text_node(step.label, "shown in reports", comments));
            for (auto& e : w->options->write(step.options, w->skip, comments).entries) body.entries.push_back(std::move(e));
            break;
        }
        case StepSpec::Kind::Untangle:
        case StepSpec::Kind::Improve: {
            const bool untangle = step.kind == StepSpec::Kind::Untangle;
            key = untangle ? "untangle" : "improve";
            const SolverKind* s = find_solver(step.name);
            if (!s) throw OptionError("unknown solver '" + step.name + "' (known: " + join(solver_names()) + ")");
            body.add("name", text_node(step.name, untangle ? "global" : join(solver_names()), comments));
            body.add("label", text_node(step.label, "shown in reports", comments));
            for (auto& e : s->options->write(step.options, untangle ? untangle_skip() : s->skip, comments).entries)
                body.entries.push_back(std::move(e));
            break;
        }
    }
    Node n = Node::map({});
    n.add(key, std::move(body));
    return n;
}

Node write_queue(const std::vector<StepSpec>& queue, bool comments) {
    Node list;
    list.kind = Node::Kind::Sequence;
    for (const auto& step : queue) list.items.push_back(write_step(step, comments));
    return list;
}

std::vector<MethodSpec> read_study(const Node& node, const std::string& path, const Reader& r) {
    if (node.is_null()) return {};
    if (node.kind != Node::Kind::Sequence)
        fail(node.where, path, "expected a list of methods (- name: NAME, queue: ...), got " + node.describe());
    std::vector<MethodSpec> methods;
    for (std::size_t i = 0; i < node.items.size(); ++i) {
        const Node& item = node.items[i];
        const std::string p = item_path(path, i);
        if (!item.is_map()) fail(item.where, p, "expected a method (name: NAME, queue: STEPS), got " + item.describe());
        MethodSpec method;
        for (const auto& e : item.entries)
            if (e.key != "name" && e.key != "queue") {
                std::string message = "unknown key '" + e.key + "' in a study method";
                if (const auto near = closest(e.key, {"name", "queue"}); !near.empty()) message += "; did you mean '" + near + "'?";
                fail(e.key_where, child_path(p, e.key), message + " (known: name, queue)");
            }
        const Node* name = item.find("name");
        if (!name || name->is_null()) fail(item.where, child_path(p, "name"), "each study method needs a name (used in the table and file names)");
        method.name = to_text(*name, child_path(p, "name"));
        r.record(child_path(p, "name"), name->where);
        if (method.name.empty() || method.name.find_first_of("/\\{}") != std::string::npos)
            fail(name->where, child_path(p, "name"), "a method's name must be non-empty, without / \\ { }");
        for (const auto& other : methods)
            if (other.name == method.name) fail(name->where, child_path(p, "name"), "two methods are named '" + method.name + "'; names must differ");
        const Node* queue = item.find("queue");
        if (!queue || queue->is_null()) fail(item.where, child_path(p, "queue"), "each study method needs a queue (steps, or a wrapper's name)");
        method.queue = read_queue(*queue, child_path(p, "queue"), r);
        methods.push_back(std::move(method));
    }
    return methods;
}

const Table<RunSpec>& run_table() {
    static const Table<RunSpec> t = [] {
        Table<RunSpec> t("a run config", [](const RunSpec& s) {
            if (s.threads < 0) throw OptionError("threads must be >= 0 (0: OpenMP's default; got " + std::to_string(s.threads) + ")");
        });
        t.object("input", &RunSpec::input, input_table(), "The mesh, which of its vertices stay put, and its orientation convention.")
            .object("targets", &RunSpec::targets, targets_table(),
                    "What each element should look like: its size, orientation, aspect and skew kept from the input, "
                    "taken from a reference mesh, or ideal (docs/targets.md).")
            .integer("threads", &RunSpec::threads, "Threads of every solver; 0: OpenMP's default. Results do not depend on it.")
            .object("partition", &RunSpec::partition, partition_table(), "Splitting the mesh across MPI ranks.")
            .object("parallel", &RunSpec::parallel, parallel_table(), "How the ranks of a partitioned run talk.")
            .add({"queue", "list of steps, or a wrapper's name",
                  "The instruction queue: assess, untangle, improve and wrapper steps, in order. Default: one improve "
                  "step with the global solver.",
                  [](RunSpec& s, const Node& n, const std::string& p, const Reader& r) { s.queue = read_queue(n, p, r); },
                  [](const RunSpec& s, bool comments) { return write_queue(s.queue, comments); }})
            .add({"study", "list of methods (name, queue)",
                  "Methods to compare, each run on its own copy of the input; replaces queue.",
                  [](RunSpec& s, const Node& n, const std::string& p, const Reader& r) { s.study = read_study(n, p, r); },
                  [](const RunSpec& s, bool comments) {
                      Node list;
                      list.kind = Node::Kind::Sequence;
                      for (const auto& m : s.study) {
                          Node method = Node::map({});
                          method.add("name", text_node(m.name, "", false));
                          method.add("queue", write_queue(m.queue, comments));
                          list.items.push_back(std::move(method));
                      }
                      return list;
                  }})
            .object("output", &RunSpec::output, output_table(), "What to write; every file goes through a temporary and a rename.");
        return t;
    }();
    return t;
}

struct KeyInfo {
    std::string key, type, default_value, help;
};
std::vector<OptionInfo> keys_info(const std::vector<KeyInfo>& keys) {
    std::vector<OptionInfo> out;
    for (const auto& k : keys) out.push_back({k.key, k.type, k.default_value, k.help});
    return out;
}

}  // namespace

std::vector<ObjectInfo> section_infos() {
    std::vector<ObjectInfo> out;
    RunSpec defaults;
    auto run_options = run_table().describe(defaults);
    for (auto& o : run_options)
        if (o.key == "queue") o.default_value = "[improve: global]";
    out.push_back({"section", "run", "The top level of a config file.", run_options});
    out.push_back({"section", "input", "", input_table().describe(defaults.input)});
    out.push_back({"section", "partition", "Partitioned (MPI) runs; docs/parallel.md, \"From a config file\".", partition_table().describe(defaults.partition)});
    out.push_back({"section", "parallel", "Partitioned (MPI) runs; docs/parallel.md, \"From a config file\".", parallel_table().describe(defaults.parallel)});
    out.push_back({"section", "output", "", output_table().describe(defaults.output)});
    out.push_back({"section", "study method", "One entry of `study`.",
                   keys_info({{"name", "text", "(required)", "Unique: the method's name in the table, the summary and {method}."},
                              {"queue", "list of steps, or a wrapper's name", "(required)", "Its steps, as the top-level queue."}})});
    auto assess = assess_table().describe({});
    assess.insert(assess.begin(), {"label", "text", "assess", "Shown in reports and the summary."});
    out.push_back({"section", "assess step", "`- assess: LABEL` or `- assess: {label: ..., metrics: [...], histogram_bins: N}`.", assess});
    out.push_back({"section", "improve step",
                   "`- improve: SOLVER` or a map: `name`, `label` and any option of that solver (see Solvers).",
                   keys_info({{"name", "one of: " + join(solver_names()), "global", "The solver."},
                              {"label", "text", "the name", "Shown in reports, the history and the progress line."}})});
    out.push_back({"section", "untangle step",
                   "`- untangle: global` (or `local`) or a map: `name`, `label` and the solver's options except "
                   "untangle, improve_shape and termination. Stops once no element is inverted.",
                   keys_info({{"name", "global or local", "global", "The solver that untangles (Laplace smoothing does not)."},
                              {"label", "text", "untangle", "Shown in reports, the history and the progress line."}})});
    out.push_back({"section", "wrapper step",
                   "`- wrapper: NAME` or a map: `name`, `label` and the options of the wrapper's solver (see Wrappers). "
                   "`queue: NAME` is short for a queue of this one step.",
                   keys_info({{"name", "one of: " + join(wrapper_names()), "(required)", "The wrapper."},
                              {"label", "text", "the name", "Its name in the summary."}})});
    return out;
}

}  // namespace detail

namespace {
// With size or orientation kept, a solver step whose metric was not set rates with the metric
// that measures them (TargetOptions::metric): a shape metric alone would let them drift.
void choose_target_metrics(RunSpec& spec) {
    if (!spec.targets.from_reference.empty() && spec.targets.reference.empty() && spec.input.displacement.empty())
        throw ConfigError(origin_of(spec, "targets.from_reference"), "targets.from_reference",
                          "from_reference needs a reference mesh (targets.reference: FILE, or input.displacement)");
    // auto keeps no size
    const TargetOptions targets = spec.targets.options(false, !spec.input.displacement.empty());
    if (!targets.any()) return;
    auto choose = [&](std::vector<StepSpec>& queue, const std::string& path) {
        for (std::size_t i = 0; i < queue.size(); ++i) {
            const std::string prefix = path + "[" + std::to_string(i) + "].";
            const bool set = std::any_of(spec.origins.begin(), spec.origins.end(), [&](const auto& origin) {
                return origin.first.starts_with(prefix) && origin.first.find(".metric", prefix.size() - 1) != std::string::npos;
            });
            if (set) continue;
            if (auto* global = queue[i].options.get_if<GlobalSolverOptions>())
                global->shape_metric = targets.metric(global->shape_metric);
            else if (auto* local = queue[i].options.get_if<LocalSolverOptions>())
                local->metric = targets.metric(local->metric);
        }
    };
    choose(spec.queue, "queue");
    for (std::size_t m = 0; m < spec.study.size(); ++m) choose(spec.study[m].queue, "study[" + std::to_string(m) + "].queue");
}
}  // namespace

RunSpec parse_config(std::string_view yaml, const std::string& source, std::span<const Override> overrides) {
    using namespace detail;
    Node root = parse_yaml(yaml, source);
    if (root.is_null()) root = Node::map({source});
    if (!root.is_map())
        fail(root.where, "", "a config is a map of sections (input:, queue:, output:, ...), got " + root.describe());
    normalize(root);
    for (const Override& o : overrides) {
        apply(root, parse_assignment(o.assignment, o.source, o.literal));
        normalize(root);
    }
    if (const Node* study = root.find("study"); study && study->kind == Node::Kind::Sequence && !study->items.empty())
        for (const auto& e : root.entries)
            if (e.key == "queue")
                fail(e.key_where, "queue", "give either queue (one job) or study (methods compared on the same input), not both");
    RunSpec spec;
    spec.queue = RunSpec::default_queue();
    run_table().read(spec, root, "", Reader{&spec.origins});
    choose_target_metrics(spec);
    return spec;
}

RunSpec read_config(const std::filesystem::path& file, std::span<const Override> overrides) {
    std::ifstream in(file, std::ios::binary);
    if (!in) {
        const std::string why = std::filesystem::exists(file) ? "cannot be read" : "no such file";
        throw ConfigError(file.string(), "", "cannot read the config: " + why);
    }
    std::ostringstream text;
    text << in.rdbuf();
    return parse_config(text.str(), file.string(), overrides);
}

std::string to_yaml(const RunSpec& spec, bool comments) {
    using namespace detail;
    Node root = run_table().write(spec, {}, comments);
    if (!spec.study.empty()) root.erase("queue");
    std::string header = "# Paloverde run config, every key resolved (docs/config.md). Run it with: paloverde run FILE\n";
    return header + emit_yaml(root);
}

}  // namespace paloverde::config
