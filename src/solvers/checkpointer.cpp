#include "checkpointer.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numeric>

#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"

namespace paloverde {

void CheckpointOptions::validate() const {
    if (every_iterations < 0)
        throw OptionError("checkpoint.every_iterations must be >= 0 (0: not by iterations), got " +
                          std::to_string(every_iterations));
    if (!(every_seconds >= 0.0) || !std::isfinite(every_seconds))
        throw OptionError("checkpoint.every_seconds must be >= 0 (0: not by time)");
}

namespace detail {

namespace {

constexpr char kMagic[8] = {'P', 'A', 'L', 'O', 'V', 'C', 'K', 'P'};
constexpr std::uint64_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 32;
// After the solver's name: the kind of run (none for a single run).
constexpr std::string_view kMotionMark = "/motion", kSlidingMark = "/sliding";

std::string_view mark_of(CheckpointKind kind) {
    return kind == CheckpointKind::Motion ? kMotionMark : kind == CheckpointKind::Sliding ? kSlidingMark : "";
}

std::string_view described(CheckpointKind kind) {
    switch (kind) {
        case CheckpointKind::Motion: return "a run that followed a moved boundary in steps (morphing)";
        case CheckpointKind::Sliding: return "a run whose boundary slid (boundary: slide)";
        case CheckpointKind::SingleRun: break;
    }
    return "a single solver run";
}
// Before a text's name, in the lists that hold texts.
constexpr std::string_view kTextPrefix = "text:";

std::uint64_t fnv1a(std::string_view bytes) {
    std::uint64_t h = 14695981039346656037ull;
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

// splitmix64's finalizer: every input bit affects every output bit.
std::uint64_t mix(std::uint64_t h, std::uint64_t value) {
    std::uint64_t z = h ^ (value + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

void put_u64(std::string& out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

}  // namespace

// Little-endian 64-bit numbers, appended.
class CheckpointWriter {
public:
    void u64(std::uint64_t v) { put_u64(bytes_, v); }
    void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
    void text(const std::string& s) {
        u64(s.size());
        bytes_ += s;
    }
    void f64s(std::span<const double> values) {
        if constexpr (std::endian::native == std::endian::little) {
            if (!values.empty()) bytes_.append(reinterpret_cast<const char*>(values.data()), 8 * values.size());
        } else {
            for (double v : values) f64(v);
        }
    }
    void reserve(std::size_t n) { bytes_.reserve(n); }
    std::string& bytes() { return bytes_; }

private:
    std::string bytes_;
};

namespace {

// Reads the content; every count is checked against the bytes left before anything is
// allocated, so a damaged file cannot ask for more memory than its size.
class Reader {
public:
    Reader(std::string_view bytes, std::string path) : bytes_(bytes), path_(std::move(path)) {}

    std::uint64_t u64() {
        need(8, "a number");
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes_[at_ + i])) << (8 * i);
        at_ += 8;
        return v;
    }
    std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
    double f64() { return std::bit_cast<double>(u64()); }
    // A count of items of `item_bytes` each that must fit in what is left.
    std::size_t count(std::size_t item_bytes, const char* what) {
        const std::uint64_t n = u64();
        if (item_bytes > 0 && n > (bytes_.size() - at_) / item_bytes)
            fail(std::string("a count of ") + std::to_string(n) + " " + what + " does not fit in the rest of the file");
        return static_cast<std::size_t>(n);
    }
    std::string text() {
        const std::size_t n = count(1, "characters");
        std::string s(bytes_.substr(at_, n));
        at_ += n;
        return s;
    }
    std::vector<double> f64s(std::size_t n) {
        need(8 * n, "numbers");
        std::vector<double> v(n);
        if constexpr (std::endian::native == std::endian::little) {
            if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, 8 * n);
            at_ += 8 * n;
        } else {
            for (double& x : v) x = f64();
        }
        return v;
    }
    bool done() const { return at_ == bytes_.size(); }
    [[noreturn]] void fail(const std::string& message) const {
        throw FileError::at_byte(path_, kHeaderBytes + at_, "corrupt checkpoint: " + message);
    }

private:
    void need(std::size_t n, const char* what) const {
        if (n > bytes_.size() - at_) fail(std::string("it ends in the middle of ") + what);
    }
    std::string_view bytes_;
    std::string path_;
    std::size_t at_ = 0;
};

// The whole file, checked: header, version, length and checksum. Returns the content.
std::string read_checked(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path, 0, "cannot open the checkpoint to resume from (does it exist?)");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, 8) != 0)
        throw FileError(path, 0, "not a Paloverde checkpoint (it does not start with PALOVCKP)");
    Reader header(std::string_view(bytes).substr(8, kHeaderBytes - 8), path);
    const std::uint64_t version = header.u64(), length = header.u64(), checksum = header.u64();
    if (version != kVersion)
        throw FileError(path, 0, "checkpoint format version " + std::to_string(version) + "; this build reads version " +
                                     std::to_string(kVersion));
    if (length != bytes.size() - kHeaderBytes)
        throw FileError(path, 0, "truncated or damaged checkpoint: its header announces " + std::to_string(length) +
                                     " bytes of content, the file holds " + std::to_string(bytes.size() - kHeaderBytes));
    std::string content = bytes.substr(kHeaderBytes);
    if (fnv1a(content) != checksum) throw FileError(path, 0, "corrupt checkpoint: the checksum does not match its content");
    return content;
}

void put_record(CheckpointWriter& w, const IterationRecord& r) {
    w.i64(r.iteration);
    w.text(r.phase);
    for (double v : {r.worst_quality, r.best_worst_quality, r.mean_quality, r.mu, r.t, r.objective, r.step, r.gain, r.seconds})
        w.f64(v);
    w.i64(r.inverted);
    w.i64(r.moved);
}

IterationRecord get_record(Reader& r) {
    IterationRecord out;
    out.iteration = static_cast<int>(r.i64());
    out.phase = r.text();
    for (double* v : {&out.worst_quality, &out.best_worst_quality, &out.mean_quality, &out.mu, &out.t, &out.objective,
                      &out.step, &out.gain, &out.seconds})
        *v = r.f64();
    out.inverted = static_cast<long>(r.i64());
    out.moved = static_cast<long>(r.i64());
    return out;
}

}  // namespace

double SolverState::number(const std::string& name) const {
    const auto it = numbers.find(name);
    if (it == numbers.end()) throw FileError(source, 0, "the checkpoint has no '" + name + "' (written by another version?)");
    return it->second;
}

const std::vector<double>& SolverState::list(const std::string& name) const {
    const auto it = lists.find(name);
    if (it == lists.end()) throw FileError(source, 0, "the checkpoint has no list '" + name + "' (written by another version?)");
    return it->second;
}

const std::vector<double>& SolverState::vertex_field(const std::string& name, std::size_t local_vertices) const {
    const auto it = vertex_fields.find(name);
    if (it == vertex_fields.end())
        throw FileError(source, 0, "the checkpoint has no vertex field '" + name + "' (written by another version?)");
    if (it->second.size() != 3 * local_vertices)
        throw FileError(source, 0, "the checkpoint's vertex field '" + name + "' does not fit this mesh");
    return it->second;
}

const std::string& SolverState::text(const std::string& name) const {
    const auto it = texts.find(name);
    if (it == texts.end()) throw FileError(source, 0, "the checkpoint has no text '" + name + "' (written by another version?)");
    return it->second;
}

namespace {

using Named = std::initializer_list<std::pair<const char*, double>>;

void store_statistics(SolverState& state, const std::string& prefix, const QualityStatistics& s) {
    for (const auto& [name, value] : Named{{"count", static_cast<double>(s.count)}, {"min", s.min}, {"max", s.max},
                                           {"mean", s.mean}, {"rms", s.rms}, {"worst_element", static_cast<double>(s.worst_element)}})
        state.numbers[prefix + "." + name] = value;
    state.lists[prefix + ".histogram"].assign(s.histogram.begin(), s.histogram.end());
}

QualityStatistics restored_statistics(const SolverState& state, const std::string& prefix) {
    QualityStatistics s;
    s.count = static_cast<ElementId>(state.number(prefix + ".count"));
    s.min = state.number(prefix + ".min");
    s.max = state.number(prefix + ".max");
    s.mean = state.number(prefix + ".mean");
    s.rms = state.number(prefix + ".rms");
    s.worst_element = static_cast<ElementId>(state.number(prefix + ".worst_element"));
    for (double n : state.list(prefix + ".histogram")) s.histogram.push_back(static_cast<ElementId>(n));
    return s;
}

// The report's counts, its metrics and its cell types, each entry numbered in its order.
void store_report(SolverState& state, const std::string& prefix, const QualityReport& report) {
    for (const auto& [name, value] : Named{{"vertices", static_cast<double>(report.vertices)},
                                      {"free_vertices", static_cast<double>(report.free_vertices)},
                                      {"elements", static_cast<double>(report.elements)},
                                      {"frozen_elements", static_cast<double>(report.frozen_elements)},
                                      {"inverted", static_cast<double>(report.inverted)},
                                      {"inverted_frozen", static_cast<double>(report.inverted_frozen)},
                                      {"degenerate", static_cast<double>(report.degenerate)},
                                      {"metrics", static_cast<double>(report.metrics.size())},
                                      {"types", static_cast<double>(report.by_type.size())}})
        state.numbers[prefix + "." + name] = value;
    for (std::size_t i = 0; i < report.metrics.size(); ++i) {
        const MetricReport& m = report.metrics[i];
        const std::string at = prefix + ".metric" + std::to_string(i);
        state.texts[at] = m.name;
        store_statistics(state, at + ".all", m.all);
        store_statistics(state, at + ".movable", m.movable);
        store_statistics(state, at + ".frozen", m.frozen);
    }
    for (std::size_t i = 0; i < report.by_type.size(); ++i) {
        const QualityReport::TypeReport& t = report.by_type[i];
        const std::string at = prefix + ".type" + std::to_string(i);
        state.texts[at] = t.type;
        state.numbers[at + ".count"] = static_cast<double>(t.count);
        state.numbers[at + ".inverted"] = static_cast<double>(t.inverted);
        state.numbers[at + ".worst"] = static_cast<double>(t.worst.size());
        for (std::size_t j = 0; j < t.worst.size(); ++j) {
            state.texts[at + ".worst" + std::to_string(j)] = t.worst[j].first;
            state.numbers[at + ".worst" + std::to_string(j)] = t.worst[j].second;
        }
    }
}

// A count stored as a number, checked before it sizes anything.
std::size_t restored_count(const SolverState& state, const std::string& name) {
    const double n = state.number(name);
    if (!(n >= 0.0 && n <= 1e6 && n == std::floor(n))) throw FileError(state.source, 0, "corrupt checkpoint: a bad count '" + name + "'");
    return static_cast<std::size_t>(n);
}

QualityReport restored_report(const SolverState& state, const std::string& prefix) {
    QualityReport report;
    report.vertices = static_cast<VertexId>(state.number(prefix + ".vertices"));
    report.free_vertices = static_cast<VertexId>(state.number(prefix + ".free_vertices"));
    report.elements = static_cast<ElementId>(state.number(prefix + ".elements"));
    report.frozen_elements = static_cast<ElementId>(state.number(prefix + ".frozen_elements"));
    report.inverted = static_cast<ElementId>(state.number(prefix + ".inverted"));
    report.inverted_frozen = static_cast<ElementId>(state.number(prefix + ".inverted_frozen"));
    report.degenerate = static_cast<ElementId>(state.number(prefix + ".degenerate"));
    report.metrics.resize(restored_count(state, prefix + ".metrics"));
    for (std::size_t i = 0; i < report.metrics.size(); ++i) {
        MetricReport& m = report.metrics[i];
        const std::string at = prefix + ".metric" + std::to_string(i);
        m.name = state.text(at);
        m.all = restored_statistics(state, at + ".all");
        m.movable = restored_statistics(state, at + ".movable");
        m.frozen = restored_statistics(state, at + ".frozen");
    }
    report.by_type.resize(restored_count(state, prefix + ".types"));
    for (std::size_t i = 0; i < report.by_type.size(); ++i) {
        QualityReport::TypeReport& t = report.by_type[i];
        const std::string at = prefix + ".type" + std::to_string(i);
        t.type = state.text(at);
        t.count = static_cast<ElementId>(state.number(at + ".count"));
        t.inverted = static_cast<ElementId>(state.number(at + ".inverted"));
        t.worst.resize(restored_count(state, at + ".worst"));
        for (std::size_t j = 0; j < t.worst.size(); ++j)
            t.worst[j] = {state.text(at + ".worst" + std::to_string(j)), state.number(at + ".worst" + std::to_string(j))};
    }
    return report;
}

}  // namespace

void store_outcome(SolverState& state, const std::string& prefix, const Summary& summary) {
    state.texts[prefix + ".solver"] = summary.solver;
    state.texts[prefix + ".message"] = summary.message;
    state.texts[prefix + ".quality_metric"] = summary.quality_metric;
    state.numbers[prefix + ".reason"] = static_cast<double>(summary.reason);
    state.numbers[prefix + ".worst_before"] = summary.worst_before;
    state.numbers[prefix + ".worst_after"] = summary.worst_after;
    store_report(state, prefix + ".before", summary.before);
    store_report(state, prefix + ".after", summary.after);
    if (const auto& b = summary.boundary) {
        state.lists[prefix + ".boundary"] = {static_cast<double>(b->sliding), static_cast<double>(b->moved),
                                             b->largest_distance, b->volume_before, b->volume_after};
    }
}

void take_work(Summary& into, Summary&& from) {
    into.iterations = from.iterations;
    into.untangle_iterations = from.untangle_iterations;
    into.quality_passes = from.quality_passes;
    into.gradient_passes = from.gradient_passes;
    into.history = std::move(from.history);
}

Summary restored_outcome(const SolverState& state, const std::string& prefix) {
    Summary summary;
    summary.solver = state.text(prefix + ".solver");
    summary.message = state.text(prefix + ".message");
    summary.quality_metric = state.text(prefix + ".quality_metric");
    const double reason = state.number(prefix + ".reason");
    if (!(reason >= 0.0 && reason <= static_cast<double>(TerminationReason::NumericalFailure) && reason == std::floor(reason)))
        throw FileError(state.source, 0, "corrupt checkpoint: no termination reason is numbered " + std::to_string(reason));
    summary.reason = static_cast<TerminationReason>(static_cast<int>(reason));
    summary.worst_before = state.number(prefix + ".worst_before");
    summary.worst_after = state.number(prefix + ".worst_after");
    summary.before = restored_report(state, prefix + ".before");
    summary.after = restored_report(state, prefix + ".after");
    // (Absent for a run whose boundary did not slide, and in checkpoints written before it was kept.)
    if (state.lists.contains(prefix + ".boundary")) {
        const std::vector<double>& b = state.list(prefix + ".boundary");
        if (b.size() != 5)
            throw FileError(state.source, 0,
                            "corrupt checkpoint: " + prefix + ".boundary holds " + std::to_string(b.size()) + " numbers, not 5");
        summary.boundary = BoundaryMotion{static_cast<long>(b[0]), static_cast<long>(b[1]), b[2], b[3], b[4]};
    }
    return summary;
}

OptionsText& OptionsText::operator()(const char* key, double value) {
    // Hexadecimal floating point: every bit counts.
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%a", value);
    text_ += std::string(key) + "=" + buffer + "\n";
    return *this;
}

OptionsText& OptionsText::operator()(const char* key, const std::string& value) {
    text_ += std::string(key) + "=" + value + "\n";
    return *this;
}

OptionsText& OptionsText::operator()(const char* key, const TerminationCriterion& t) {
    const std::string k(key);
    (*this)((k + ".max_iterations").c_str(), t.max_iterations);
    if (t.target_worst_quality) (*this)((k + ".target_worst_quality").c_str(), *t.target_worst_quality);
    else (*this)((k + ".target_worst_quality").c_str(), "none");
    (*this)((k + ".min_progress").c_str(), t.min_progress);
    (*this)((k + ".progress_window").c_str(), t.progress_window);
    return (*this)((k + ".gradient_tolerance").c_str(), t.gradient_tolerance);
}

OptionsText& OptionsText::operator()(const char* key, const SurfaceOptions& s) {
    const std::string k(key);
    (*this)((k + ".feature_angle").c_str(), s.feature_angle)((k + ".domain").c_str(), s.domain.name());
    if (!s.domain.analytic()) return *this;
    for (int c = 0; c < 3; ++c) {
        (*this)((k + ".domain.point").c_str(), s.domain.point[c]);
        (*this)((k + ".domain.direction").c_str(), s.domain.direction[c]);
    }
    return (*this)((k + ".domain.radius").c_str(), s.domain.radius);
}

Checkpointer::Checkpointer(const CheckpointOptions& options, std::string solver, const std::string& options_text,
                           MeshPart whole_or_part, CheckpointKind kind)
    : options_(options), solver_(std::move(solver)), kind_(kind), part_(whole_or_part), saved_at_(Clock::now()) {
    options_.validate();
    if (!writes() && !resumes()) return;
    const Mesh& mesh = whole_or_part.mesh();
    const VertexId n = mesh.num_vertices();
    keys_.resize(static_cast<std::size_t>(n));
    vertices_ = static_cast<std::uint64_t>(whole_or_part.global_vertices());
    // A part's vertices are named by global id; the whole mesh's by their index.
    if (whole_or_part.whole()) std::iota(keys_.begin(), keys_.end(), GlobalId{0});
    else std::copy(mesh.global_ids().begin(), mesh.global_ids().end(), keys_.begin());

    options_hash_ = fnv1a(solver_ + "\n" + options_text);
    // The mesh's fingerprint: a sum of one hash per element (its sorted vertex keys) and one per
    // vertex (key, fixed flag, coordinates' bits), each counted by one process, so it does not
    // depend on the order of the elements or on the split of the mesh.
    std::array<std::uint64_t, 2> sums{0, 0};
    const int corners = mesh.corners();
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        if (!whole_or_part.counts(e)) continue;
        std::array<GlobalId, 4> key{};
        // Sorted by insertion: at most 4 keys.
        for (int i = 0; i < corners; ++i) {
            const GlobalId k = keys_[mesh.element(e)[i]];
            int j = i;
            for (; j > 0 && key[j - 1] > k; --j) key[j] = key[j - 1];
            key[j] = k;
        }
        std::uint64_t h = static_cast<std::uint64_t>(corners);
        for (int i = 0; i < corners; ++i) h = mix(h, static_cast<std::uint64_t>(key[i]));
        sums[0] += h;
    }
    const auto xyz = mesh.coordinates();
    // A motion goes from the reference to the coordinates: both are its input.
    const auto reference = kind_ == CheckpointKind::Motion ? mesh.reference_coordinates() : std::span<const double>{};
    for (VertexId v = 0; v < n; ++v) {
        if (!whole_or_part.owns(v)) continue;
        std::uint64_t h = mix(static_cast<std::uint64_t>(keys_[v]), mesh.fixed()[v]);
        for (int c = 0; c < 3; ++c) h = mix(h, std::bit_cast<std::uint64_t>(xyz[3 * static_cast<std::size_t>(v) + c]));
        if (!reference.empty())
            for (int c = 0; c < 3; ++c) h = mix(h, std::bit_cast<std::uint64_t>(reference[3 * static_cast<std::size_t>(v) + c]));
        sums[1] += h;
    }
    part_.reducer().sum_wrapping(sums);
    mesh_hash_ = mix(mix(sums[0], sums[1]), vertices_);
}

bool Checkpointer::due(int iterations) {
    if (!writes()) return false;
    const bool by_count = options_.every_iterations > 0 && iterations - saved_iterations_ >= options_.every_iterations;
    // Clocks differ between ranks: the slowest decides, as for time limits.
    const bool by_time = options_.every_seconds > 0.0 && reducer().max(seconds_since(saved_at_)) >= options_.every_seconds;
    return by_count || by_time;
}

void Checkpointer::encode(CheckpointWriter& w, const Summary& summary, const SolverState& state, double elapsed) const {
    w.text(solver_ + std::string(mark_of(kind_)));
    w.u64(mesh_hash_);
    w.u64(options_hash_);
    w.u64(static_cast<std::uint64_t>(part_.ranks()));
    w.u64(vertices_);
    w.f64(elapsed);
    w.i64(summary.iterations);
    w.i64(summary.untangle_iterations);
    w.i64(summary.quality_passes);
    w.i64(summary.gradient_passes);
    w.u64(summary.history.size());
    for (const auto& r : summary.history) put_record(w, r);
    w.u64(state.numbers.size());
    for (const auto& [name, value] : state.numbers) {
        w.text(name);
        w.f64(value);
    }
    w.u64(state.lists.size() + state.texts.size());
    for (const auto& [name, values] : state.lists) {
        w.text(name);
        w.u64(values.size());
        w.f64s(values);
    }
    for (const auto& [name, text] : state.texts) {
        w.text(std::string(kTextPrefix) + name);
        w.u64(text.size());
        for (unsigned char c : text) w.f64(c);
    }
}

void Checkpointer::save(const Summary& summary, const SolverState& state, double elapsed) {
    CheckpointWriter w;
    if (part_.root()) w.reserve(4096 + 24 * vertices_ * state.vertex_fields.size() + 128 * summary.history.size());
    encode(w, summary, state, elapsed);
    // Vertex fields are gathered (collectively) one at a time and appended on rank 0.
    w.u64(state.vertex_fields.size());
    for (const auto& [name, values] : state.vertex_fields) {
        const std::vector<double> all = part_.gather_to_root(values, 3);
        if (!part_.root()) continue;
        w.text(name);
        w.f64s(all);
    }
    part_.on_root([&] {
        const std::string& content = w.bytes();
        std::string header(kMagic, 8);
        put_u64(header, kVersion);
        put_u64(header, content.size());
        put_u64(header, fnv1a(content));
        AtomicFile file(options_.file);
        file.stream().write(header.data(), static_cast<std::streamsize>(header.size()));
        file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
        file.commit();
    });
    saved_iterations_ = summary.iterations;
    saved_at_ = Clock::now();
}

SolverState Checkpointer::resume(Summary& summary, SolverRun& run) {
    SolverState state = resume(summary);
    run.add_elapsed(state.elapsed);
    return state;
}

SolverState Checkpointer::resume(Summary& summary) {
    const std::string& path = options_.resume;
    std::string content;
    part_.on_root([&] { content = read_checked(path); });
    part_.broadcast(content);
    // Every rank parses the same bytes, so every rank fails alike.
    Reader r(content, path);
    std::string solver = r.text();
    CheckpointKind kind = CheckpointKind::SingleRun;
    for (const CheckpointKind k : {CheckpointKind::Motion, CheckpointKind::Sliding})
        if (solver.ends_with(mark_of(k))) {
            kind = k;
            solver.resize(solver.size() - mark_of(k).size());
        }
    if (solver != solver_)
        throw FileError(path, 0, "this checkpoint was written by the " + solver + " solver, not the " + solver_ + " solver");
    if (kind == CheckpointKind::Motion && kind_ != CheckpointKind::Motion)
        throw FileError(path, 0, "this checkpoint is of a run that followed a moved boundary in steps (morphing), and "
                                 "this run has no motion to follow: resume it on the moved mesh with its reference, as "
                                 "the checkpointed run was given");
    if (kind != kind_)
        throw FileError(path, 0, "this checkpoint is of " + std::string(described(kind)) + ", and this run is " +
                                     std::string(described(kind_)) + ", whose checkpoints are of their own kind: resume "
                                     "with the mesh and options of the checkpointed run, or start this one afresh");
    const std::uint64_t mesh_hash = r.u64(), options_hash = r.u64(), ranks = r.u64(), vertices = r.u64();
    if (ranks != static_cast<std::uint64_t>(part_.ranks()))
        throw FileError(path, 0, "this checkpoint was written by a run on " + std::to_string(ranks) +
                                     " rank(s); resume it on as many (this run has " + std::to_string(part_.ranks()) + ")");
    if (vertices != vertices_ || mesh_hash != mesh_hash_)
        throw FileError(path, 0, "this checkpoint belongs to another mesh: the connectivity, the fixed vertices or the "
                                 "input coordinates differ; resume from the input the checkpointed run started with");
    if (options_hash != options_hash_)
        throw FileError(path, 0, "this checkpoint was written with other " + solver_ + " solver options; resume with the "
                                 "options of the checkpointed run (only threads, time limits and checkpoint settings "
                                 "may change)");
    const double elapsed = r.f64();
    Summary restored;
    restored.iterations = static_cast<int>(r.i64());
    restored.untangle_iterations = static_cast<int>(r.i64());
    restored.quality_passes = r.i64();
    restored.gradient_passes = r.i64();
    // An iteration record takes at least 13 numbers of 8 bytes.
    restored.history.resize(r.count(13 * 8, "history records"));
    for (auto& record : restored.history) record = get_record(r);
    SolverState state;
    state.source = path;
    for (std::size_t i = 0, n = r.count(16, "numbers"); i < n; ++i) {
        std::string name = r.text();
        state.numbers[name] = r.f64();
    }
    for (std::size_t i = 0, n = r.count(16, "lists"); i < n; ++i) {
        std::string name = r.text();
        std::vector<double> values = r.f64s(r.count(8, "list entries"));
        if (!name.starts_with(kTextPrefix)) {
            state.lists[name] = std::move(values);
            continue;
        }
        std::string& text = state.texts[name.substr(kTextPrefix.size())];
        for (double c : values) {
            if (!(c >= 0.0 && c <= 255.0 && c == std::floor(c))) r.fail("a text holds something that is not a character");
            text.push_back(static_cast<char>(static_cast<unsigned char>(c)));
        }
    }
    const std::size_t local = keys_.size();
    for (std::size_t i = 0, n = r.count(8 + 24 * vertices_, "vertex fields"); i < n; ++i) {
        std::string name = r.text();
        const std::vector<double> all = r.f64s(3 * vertices_);
        std::vector<double> mine(3 * local);
        for (std::size_t v = 0; v < local; ++v)
            for (int c = 0; c < 3; ++c) mine[3 * v + c] = all[3 * static_cast<std::size_t>(keys_[v]) + c];
        state.vertex_fields[name] = std::move(mine);
    }
    if (!r.done()) r.fail("bytes left over after the last field");

    take_work(summary, std::move(restored));
    state.elapsed = elapsed;
    saved_iterations_ = summary.iterations;
    saved_at_ = Clock::now();
    return state;
}

RunCheckpoints::RunCheckpoints(MeshPart part, const CheckpointOptions& whole)
    : whole_(whole), root_(part.root()), run_pending_(!whole.resume.empty()) {
    if (whole.resume.empty()) return;
    // Rank 0's file system decides (it reads the file).
    const bool found = root_ && std::filesystem::exists(whole.resume + kSuffix);
    resumable_ = part.reducer().max(found ? 1.0 : 0.0) > 0.0;
    std::error_code ignored;
    const bool same = !whole.file.empty() && std::filesystem::weakly_canonical(whole.file, ignored) ==
                                                 std::filesystem::weakly_canonical(whole.resume, ignored);
    // Every rank must decide alike whether to write (collective).
    same_file_ = part.reducer().max(same ? 1.0 : 0.0) > 0.0;
}

CheckpointOptions RunCheckpoints::next_run() {
    CheckpointOptions run = whole_;
    run.file = whole_.file.empty() ? "" : whole_.file + kSuffix;
    run.resume = run_pending_ && resumable_ ? whole_.resume + kSuffix : "";
    run_pending_ = false;
    return run;
}

void RunCheckpoints::forget() const {
    std::error_code ignored;
    if (root_ && !whole_.file.empty()) std::filesystem::remove(whole_.file + kSuffix, ignored);
}

}  // namespace detail
}  // namespace paloverde
