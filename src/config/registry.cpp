// The registry: every metric, objective, termination criterion, solver, assessor and wrapper by
// name, each option declared once here.
#include <algorithm>
#include <sstream>

#include "config/registry_internal.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/wrappers.hpp"

namespace paloverde::config {
namespace detail {
namespace {

const std::vector<std::pair<std::string, std::string>>& objective_help() {
    static const std::vector<std::pair<std::string, std::string>> help{
        {"log_barrier", "F(mu, t) = t + mu sum_i log(q_i - t), t < min q (Sastry & Shontz): t climbs to the worst "
                        "quality as mu shrinks."},
        {"p_mean", "(1/n sum_i q_i^p)^(1/p) (Mesquite's LPtoP, normalized); p < 0 stresses the worst elements; "
                   "positive qualities only."},
        {"min_quality", "The worst quality (Mesquite's LInf): nonsmooth, for comparison."},
    };
    return help;
}

std::vector<std::string> names_in(const std::vector<std::pair<std::string, std::string>>& list) {
    std::vector<std::string> out;
    for (const auto& [n, h] : list) out.push_back(n);
    return out;
}

// A sub-object chosen by name with options that depend on the name: `objective: log_barrier` or
// `objective: {name: p_mean, p: -4}`. The name and the options live in two fields of T.
template <class T, class O>
typename Table<T>::Field named_field(std::string key, std::string kind, std::string help, std::string T::*name_member,
                                     O T::*options_member, std::function<std::vector<std::string>()> names,
                                     std::function<const Table<O>&(const std::string&)> table_of,
                                     std::function<void(const std::string&, const O&)> validate) {
    typename Table<T>::Field f;
    f.key = key;
    f.type = std::string("name of a") + (kind == "objective" ? "n " : " ") + kind + ", or a map: name and the " + kind + "'s options";
    f.help = std::move(help);
    f.read = [=](T& t, const Node& n, const std::string& p, const Reader& r) {
        auto check = [&](const Location& where, const std::string& path, const std::string& k) {
            try {
                validate(t.*name_member, t.*options_member);
            } catch (const ConfigError&) {
                throw;
            } catch (const OptionError& e) {
                fail_at(e, where, path, k);
            }
        };
        if (n.is_null()) return;
        if (n.kind == Node::Kind::Scalar) {
            t.*name_member = one_of(n, p, names(), kind);
            return check(n.where, p, key);
        }
        if (!n.is_map())
            fail(n.where, p, "expected the name of a " + kind + " or a map (name: ... and its options), got " +
                                 n.describe());
        if (const Node* name = n.find("name")) {
            const std::string np = child_path(p, "name");
            t.*name_member = one_of(*name, np, names(), kind);
            r.record(np, name->where);
            check(name->where, np, "name");
        }
        const Table<O>& table = table_of(t.*name_member);
        for (const auto& e : n.entries) {
            if (e.key == "name") continue;
            const std::string ep = child_path(p, e.key);
            const auto* field = table.field(e.key);
            if (!field) {
                std::vector<std::string> owners;
                for (const auto& other : names())
                    if (other != t.*name_member && table_of(other).field(e.key)) owners.push_back(other);
                std::string message = table.unknown_key(e.key, {}, {"name"});
                if (!owners.empty())
                    message = "'" + e.key + "' is an option of " + kind + " " + join(owners, " and ") + ", not of " +
                              t.*name_member + " (" + kind + " " + t.*name_member + " takes: " +
                              (table.keys().empty() ? std::string("no options") : join(table.keys())) + ")";
                fail(e.key_where, ep, message);
            }
            r.record(ep, e.value.where);
            field->read(t.*options_member, e.value, ep, r);
            check(e.value.where, ep, e.key);
        }
    };
    f.write = [=](const T& t, bool comments) {
        Node out = Node::map({});
        Node name = Node::text(t.*name_member, {});
        name.quote_text = true;
        if (comments) name.comment = join(names(), ", ");
        out.add("name", std::move(name));
        for (auto& e : table_of(t.*name_member).write(t.*options_member, {}, comments).entries)
            out.entries.push_back(std::move(e));
        return out;
    };
    return f;
}

template <class O>
OptionsKind options_kind(const Table<O>& table) {
    OptionsKind k;
    k.what = table.what();
    k.untangles = requires(O o) {
        o.untangle = true;
        o.improve_shape = false;
    };
    k.untangle_only = [](SolverOptions& options) {
        if constexpr (requires(O o) { o.improve_shape = false; }) {
            O& o = options.get<O>();
            o.untangle = true;
            o.improve_shape = false;
        }
    };
    k.set_threads = [](SolverOptions& options, int threads) { options.get<O>().threads = threads; };
    k.read = [&table](SolverOptions& o, const Node& n, const std::string& p, const Reader& r, const Skip& s,
                      const std::vector<std::string>& also) { table.read(o.get<O>(), n, p, r, s, also); };
    k.write = [&table](const SolverOptions& o, const Skip& s, bool c) { return table.write(o.get<O>(), s, c); };
    k.describe = [&table](const SolverOptions& o, const Skip& s) { return table.describe(o.get<O>(), s); };
    k.keys = [&table](const Skip& s) { return table.keys(s); };
    k.has = [&table](const std::string& key) { return table.field(key) != nullptr; };
    return k;
}

template <class O>
const O& options_as(const SolverOptions& options, const std::string& name) {
    if (const O* o = options.get_if<O>()) return *o;
    throw OptionError("solver or wrapper '" + name + "' was given the options of another solver");
}

// The target_worst_quality a solver with options O aims at, if any (none while only untangling).
template <class O>
std::optional<double> shape_target(const O& o) {
    if constexpr (requires { o.improve_shape; })
        if (!o.improve_shape) return std::nullopt;
    return o.termination.target_worst_quality;
}

// A solver's registry entry: S built from options O, which `kind` reads and writes.
template <class S, class O>
SolverKind solver_kind(std::string name, std::string help, const OptionsKind& kind, bool distributed = true) {
    SolverKind s;
    s.name = name;
    s.help = std::move(help);
    s.options = &kind;
    s.defaults = [] { return SolverOptions(O{}); };
    s.make = [name](const SolverOptions& o) { return std::make_unique<S>(options_as<O>(o, name)); };
    s.target = [name](const SolverOptions& o) { return shape_target(options_as<O>(o, name)); };
    s.distributed = distributed;
    return s;
}

struct Tables {
    Table<TerminationCriterion> termination{"termination", [](const TerminationCriterion& t) { t.validate(); }};
    Table<MetricOptions> metric{"metric", [](const MetricOptions& m) { m.validate(); }};
    Table<ObjectiveOptions> log_barrier{"objective log_barrier", [](const ObjectiveOptions& o) { o.validate(); }};
    Table<ObjectiveOptions> p_mean{"objective p_mean", [](const ObjectiveOptions& o) { o.validate(); }};
    Table<ObjectiveOptions> min_quality{"objective min_quality", [](const ObjectiveOptions& o) { o.validate(); }};
    Table<GlobalSolverOptions> global{"the global solver", [](const GlobalSolverOptions& o) { o.validate(); }};
    Table<LocalSolverOptions> local{"the local solver", [](const LocalSolverOptions& o) { o.validate(); }};
    Table<LaplaceSolverOptions> laplace{"a Laplace solver", [](const LaplaceSolverOptions& o) { o.validate(); }};
    Table<AssessSpec> assess{"an assess step", [](const AssessSpec& a) { a.validate(); }};
    Table<CheckpointOptions> checkpoint{"checkpoint", [](const CheckpointOptions& c) { c.validate(); }};
    Table<SurfaceDomain> domain{"domain", [](const SurfaceDomain& d) { d.validate(); }};
    Table<SurfaceOptions> surface{"surface", [](const SurfaceOptions& s) { s.validate(); }};
    OptionsKind global_kind, local_kind, laplace_kind;
    std::vector<SolverKind> solvers;
    std::vector<WrapperKind> wrappers;
    Skip untangle{{"untangle", "improve_shape", "termination"},
                  "an untangle step only untangles (its limits are untangle_termination); use an improve step to "
                  "raise the shape"};

    Tables();

    const Table<ObjectiveOptions>& objective_table(const std::string& name) const {
        if (name == "p_mean") return p_mean;
        if (name == "min_quality") return min_quality;
        return log_barrier;
    }

    template <class T>
    typename Table<T>::Field metric_field(std::string T::*name, MetricOptions T::*options, std::string help) const {
        return named_field<T, MetricOptions>(
            "metric", "metric", std::move(help), name, options, [] { return metric_names(); },
            [this](const std::string&) -> const Table<MetricOptions>& { return metric; },
            [](const std::string& n, const MetricOptions& o) { make_metric(n, o); });
    }
};

Tables::Tables() {
    termination.integer("max_iterations", &TerminationCriterion::max_iterations, "Most iterations (sweeps for the local and Laplace solvers), >= 0.")
        .real("max_seconds", &TerminationCriterion::max_seconds, "Stop after this many seconds; 0: no limit.")
        .maybe_real("target_worst_quality", &TerminationCriterion::target_worst_quality,
                    "Stop once the worst quality reaches this; ~: no target. Missing it ends a run with exit code 3.")
        .real("min_progress", &TerminationCriterion::min_progress,
              "Converged when the worst quality rose by less than this (relative) over progress_window iterations, >= 0. "
              "Laplace reads it as a distance instead: it stops once no vertex moved more than this many mean edge lengths in a sweep.")
        .integer("progress_window", &TerminationCriterion::progress_window,
                 "Iterations that min_progress looks back over, >= 1 (Laplace looks at one sweep and does not read it).")
        .real("gradient_tolerance", &TerminationCriterion::gradient_tolerance,
              "Global solver only (the local and Laplace sweeps have no whole gradient): stop when the gradient "
              "norm falls below this fraction of its first value, in [0, 1).");

    metric.real("hybrid_sharpness", &MetricOptions::hybrid_sharpness,
                "Steepness alpha of the untangling metric's logistic blend, per unit of scale-free volume, > 0.");

    log_barrier.real("barrier_shrink", &ObjectiveOptions::barrier_shrink, "mu is multiplied by this after steps_per_mu steps, in (0, 1].")
        .real("initial_mu", &ObjectiveOptions::initial_mu, "First mu; 0: chosen from the qualities.")
        .real("barrier_initial_active", &ObjectiveOptions::barrier_initial_active,
              "With the automatic first mu: about how many elements the barrier first weighs like the worst, >= 1; 0: 0.5% of the elements, at least 10,000.");
    p_mean.real("p", &ObjectiveOptions::p, "Exponent, nonzero; negative stresses the worst elements.");

    domain.choice("shape", &SurfaceDomain::shape,
                  {{"mesh", SurfaceDomain::Shape::Mesh},
                   {"plane", SurfaceDomain::Shape::Plane},
                   {"sphere", SurfaceDomain::Shape::Sphere},
                   {"cylinder", SurfaceDomain::Shape::Cylinder}},
                  "What vertices on the surface's patches stay on: mesh (the input's own triangles), or a plane, "
                  "sphere or cylinder every such vertex of the input lies on (to 1e-6 of the bounding-box diagonal).")
        .vector3("point", &SurfaceDomain::point, "A point of the plane, the sphere's centre, a point on the cylinder's axis.")
        .vector3("direction", &SurfaceDomain::direction, "The plane's normal, the cylinder's axis (any non-zero length).")
        .real("radius", &SurfaceDomain::radius, "The sphere's or cylinder's radius, > 0.");
    surface.real("feature_angle", &SurfaceOptions::feature_angle,
                 "Boundary faces meeting at more than this angle (degrees, in (0, 180)) make a feature curve that "
                 "stays; curves turning more sharply make corners, which stay put.")
        .object("domain", &SurfaceOptions::domain, domain,
                "An analytic shape for the vertices to stay on instead of the input's triangles: surface meshes, "
                "the sliding boundary of tetrahedral meshes (boundary: slide), a planar mesh's plane (checked).");

    checkpoint.path("file", &CheckpointOptions::file,
                    "Write the solver's state here (a temporary, then a rename) to resume from; ~: no checkpoints.")
        .integer("every_iterations", &CheckpointOptions::every_iterations,
                 "Write a checkpoint every this many iterations (sweeps), >= 0; 0: not by count.")
        .real("every_seconds", &CheckpointOptions::every_seconds,
              "And every this many seconds, >= 0; 0: not by time. A stop request (Ctrl-C, SIGTERM) also writes one.")
        .path("resume", &CheckpointOptions::resume,
              "Continue from this checkpoint (same mesh and options) to the result the uninterrupted run gives; ~: start afresh.");

    const char* surface_help =
        "The boundary surface slid on (boundary: slide): feature_angle, in degrees in (0, 180): boundary faces "
        "meeting at a sharper angle make a feature curve, which stays; curves turning more sharply make corners, "
        "which stay put; domain: an analytic shape (plane, sphere, cylinder) the vertices stay on instead of the "
        "input's triangles.";
    const auto objective_field = named_field<GlobalSolverOptions, ObjectiveOptions>(
        "objective", "objective", "What the global solver maximizes: log_barrier, p_mean or min_quality.",
        &GlobalSolverOptions::objective, &GlobalSolverOptions::objective_options,
        [] { return names_in(objective_help()); },
        [this](const std::string& n) -> const Table<ObjectiveOptions>& { return objective_table(n); },
        [](const std::string& n, const ObjectiveOptions& o) { make_objective(n, o); });

    global.add(metric_field(&GlobalSolverOptions::shape_metric, &GlobalSolverOptions::metric_options,
                            "Shape metric to raise (one with a gradient: aspect_ratio, mean_ratio, inverse_condition, edge_ratio, dihedral_sine)."))
        .add(objective_field)
        .choice("direction", &GlobalSolverOptions::direction,
                {{"conjugate_gradient", GlobalSolverOptions::Direction::ConjugateGradient},
                 {"steepest_ascent", GlobalSolverOptions::Direction::SteepestAscent},
                 {"newton", GlobalSolverOptions::Direction::Newton}},
                "Search direction of each step; newton: truncated Newton steps in the shape phase (log_barrier only), "
                "mu shrinking once each barrier subproblem is solved.")
        .flag("untangle", &GlobalSolverOptions::untangle, "Untangle first when movable elements are inverted.")
        .flag("improve_shape", &GlobalSolverOptions::improve_shape, "Run the shape phase (false: stop once untangled).")
        .choice("untangling", &GlobalSolverOptions::untangling,
                {{"energy", GlobalSolverOptions::Untangling::Energy}, {"barrier", GlobalSolverOptions::Untangling::Barrier}},
                "How to untangle: energy (the regularized energy, then the barrier ascent where elements stay inverted) "
                "or barrier (the barrier ascent on the hybrid metric alone).")
        .object("termination", &GlobalSolverOptions::termination, termination, "When the shape phase stops.")
        .object("untangle_termination", &GlobalSolverOptions::untangle_termination, termination, "When untangling stops.")
        .flag("precondition_untangling", &GlobalSolverOptions::precondition_untangling,
              "While untangling, scale each vertex's move by its block of the objective's curvature.")
        .integer("local_untangle_rounds", &GlobalSolverOptions::local_untangle_rounds,
                 "Rounds of local vertex untangling when the global ascent stalls with elements inverted, >= 0.")
        .integer("steps_per_mu", &GlobalSolverOptions::steps_per_mu,
                 "Steps at one mu before it shrinks while untangling (and in the shape phase with gain_tolerance 0); "
                 "in the shape phase the fewest steps at one mu, >= 1 (conjugate_gradient and steepest_ascent).")
        .real("gain_tolerance", &GlobalSolverOptions::gain_tolerance,
              "Shape phase (conjugate_gradient and steepest_ascent, log_barrier): mu shrinks once a step gains less "
              "than this times mu (after at least steps_per_mu steps), >= 0; 0: after steps_per_mu steps.")
        .real("focus_band", &GlobalSolverOptions::focus_band,
              "Shape phase: move the vertices of the elements in this lowest fraction of worst..ideal quality and "
              "their neighbours, chosen anew as the worst climbs (finish none: widened where it stalls), in (0, 1]; 1: the "
              "whole mesh every iteration (direction newton: always the whole mesh; the newton finish focuses too). "
              "Focused, the barrier's t still weighs the elements held still, and its automatic start lies no more "
              "than the band below the worst quality.")
        .real("finish_band", &GlobalSolverOptions::finish_band,
              "The newton finish's focus band, as a fraction of focus_band, in (0, 1]; 1: the shape phase's band. A "
              "third makes the finish of a large mesh many times faster, to the same result (docs/global_solver.md, "
              "\"The Newton finish\").")
        .real("newton_tolerance", &GlobalSolverOptions::newton_tolerance,
              "direction newton and the newton finish: mu shrinks once the Newton decrement (gradient . direction) is below this times mu, > 0.")
        .integer("newton_cg_iterations", &GlobalSolverOptions::newton_cg_iterations,
                 "direction newton and the newton finish: at most this many conjugate-gradient iterations (Hessian products) per step, >= 1.")
        .choice("finish", &GlobalSolverOptions::finish,
                {{"none", GlobalSolverOptions::Finish::None}, {"newton", GlobalSolverOptions::Finish::Newton}},
                "Shape phase (conjugate_gradient and steepest_ascent, log_barrier; not while the boundary slides): newton: "
                "where it stalls, truncated Newton steps go on from its best iterate on a new focus, with its barrier, or "
                "a fresh one where 50 steps cannot solve that barrier's subproblem or the budget leaves no room for them "
                "(and again from the best iterate where the worst quality rose far above a barrier's t), until they "
                "stall too (judged per gradient pass; mu shrinks faster while Newton solves each subproblem in one "
                "step); none: stop there.")
        .choice("polish", &GlobalSolverOptions::polish,
                {{"off", GlobalSolverOptions::Polish::Off},
                 {"auto", GlobalSolverOptions::Polish::Auto},
                 {"always", GlobalSolverOptions::Polish::Always}},
                "After the shape phases (within what is left of the budget): the vertices of the elements in the lowest "
                "3% of worst..ideal quality stand still and the others raise the sum of their qualities, each kept "
                "above that line; the worst element keeps its quality bit for bit. auto: where the shape phases left "
                "the mean quality below the input's, until it is above it again; always: until the mean stops rising; "
                "off.")
        .flag("damped_vertex_ascent", &GlobalSolverOptions::damped_vertex_ascent,
              "Shape phase (log_barrier, not the newton finish): a vertex the line search damped so that no element "
              "blocks is damped further while its own elements' barrier terms are lower than at the iterate.")
        .integer("max_failed_searches", &GlobalSolverOptions::max_failed_searches,
                 "Line searches in a row without a step before giving up, >= 1.")
        .flag("renumber", &GlobalSolverOptions::renumber, "Reverse Cuthill-McKee order while solving (the output keeps the input's order).")
        .choice("boundary", &GlobalSolverOptions::boundary,
                {{"fixed", GlobalSolverOptions::Boundary::Fixed}, {"slide", GlobalSolverOptions::Boundary::Slide}},
                "Boundary vertices: fixed (the fixed flags decide), or slide on the input's boundary in a shape phase "
                "after the run with them fixed (feature curves kept, corners fixed; not with direction newton).")
        .object("surface", &GlobalSolverOptions::surface, surface, surface_help)
        .real("smallest_motion_step", &GlobalSolverOptions::smallest_motion_step,
              "Morphing (a mesh with reference coordinates: --reference, or morph): when the mesh does not untangle as it "
              "is, the boundary's motion is followed from the reference in steps, halved down to this fraction of "
              "the whole motion, in (0, 1].")
        .object("checkpoint", &GlobalSolverOptions::checkpoint, checkpoint,
                "Checkpoints of a long run: file, every_iterations, every_seconds; and resume (docs/robustness.md).");

    local.add(metric_field(&LocalSolverOptions::metric, &LocalSolverOptions::metric_options,
                           "Shape metric whose minimum over each vertex's elements is raised (one with a gradient)."))
        .flag("untangle", &LocalSolverOptions::untangle, "Untangle first when movable elements are inverted.")
        .flag("improve_shape", &LocalSolverOptions::improve_shape, "Run the shape sweeps (false: stop once untangled).")
        .choice("untangling", &LocalSolverOptions::untangling,
                {{"energy", LocalSolverOptions::Untangling::Energy}, {"volume", LocalSolverOptions::Untangling::Volume}},
                "How a vertex moves while untangling: energy (to the minimum of its elements' regularized energy) "
                "or volume (to where its elements' smallest signed volume is largest).")
        .object("termination", &LocalSolverOptions::termination, termination, "When the shape sweeps stop.")
        .object("untangle_termination", &LocalSolverOptions::untangle_termination, termination, "When untangling stops.")
        .choice("coloring", &LocalSolverOptions::coloring,
                {{"smallest_last", ColoringOrder::SmallestLast}, {"greedy", ColoringOrder::Greedy}},
                "Vertex coloring order (smallest_last usually needs fewer colors).")
        .integer("ascent_steps", &LocalSolverOptions::ascent_steps, "Ascent steps per vertex visit, >= 1.")
        .real("active_tolerance", &LocalSolverOptions::active_tolerance,
              "Elements within this fraction of the patch minimum are active, in [0, 1).")
        .real("improve_below", &LocalSolverOptions::improve_below,
              "Move only vertices whose worst element lies in this lowest fraction of worst..ideal, > 0 (1: all).")
        .choice("boundary", &LocalSolverOptions::boundary,
                {{"fixed", LocalSolverOptions::Boundary::Fixed}, {"slide", LocalSolverOptions::Boundary::Slide}},
                "Boundary vertices: fixed (the fixed flags decide), or slide on the input's boundary in the shape "
                "sweeps (feature curves kept, corners fixed).")
        .object("surface", &LocalSolverOptions::surface, surface, surface_help)
        .real("smallest_motion_step", &LocalSolverOptions::smallest_motion_step,
              "Morphing (a mesh with reference coordinates: --reference, or morph): when the mesh does not untangle as it "
              "is, the boundary's motion is followed from the reference in steps, halved down to this fraction of "
              "the whole motion, in (0, 1].")
        .object("checkpoint", &LocalSolverOptions::checkpoint, checkpoint,
                "Checkpoints of a long run, at sweep boundaries: file, every_iterations, every_seconds; and resume (docs/robustness.md).");

    laplace.flag("smart", &LaplaceSolverOptions::smart,
                 "Smart Laplace: keep a move only if the vertex's worst element does not get worse and nothing inverts. "
                 "false: plain Laplace, which may invert elements.")
        .add(metric_field(&LaplaceSolverOptions::metric, &LaplaceSolverOptions::metric_options,
                          "Metric that smart Laplace protects and the summary reports (any metric)."))
        .object("termination", &LaplaceSolverOptions::termination, termination,
                "When the sweeps stop; min_progress here is a distance: the sweeps stop once no vertex moved more than "
                "min_progress mean edge lengths in one.")
        .choice("coloring", &LaplaceSolverOptions::coloring,
                {{"smallest_last", ColoringOrder::SmallestLast}, {"greedy", ColoringOrder::Greedy}},
                "Vertex coloring order; smart Laplace moves one color at a time.");

    assess.names("metrics", &AssessSpec::metrics, [] { return metric_names(); }, "metric",
                 "Metrics to report; [] (empty): the shape metrics, scaled volume and the smallest angle.")
        .integer("histogram_bins", &AssessSpec::histogram_bins, "Bins of each histogram, 1 to 10000.");

    global_kind = options_kind(global);
    local_kind = options_kind(local);
    laplace_kind = options_kind(laplace);

    solvers.push_back(solver_kind<GlobalSolver, GlobalSolverOptions>(
        "global",
        "The log-barrier solver of Sastry & Shontz: every free vertex moves at once; untangles first (hybrid metric), "
        "then raises the worst element.",
        global_kind));
    solvers.push_back(solver_kind<LocalSolver, LocalSolverOptions>(
        "local",
        "The Freitag-Plassmann local smoother: one vertex at a time, by colors, raises the smallest quality of its "
        "elements; untangles first.",
        local_kind));
    // Two names for one solver: the name decides `smart`.
    const Skip smart_by_name{{"smart"}, "the name decides it: smart_laplace is smart Laplace, laplace is plain Laplace"};
    for (const bool smart : {true, false}) {
        SolverKind s = solver_kind<LaplaceSolver, LaplaceSolverOptions>(
            smart ? "smart_laplace" : "laplace",
            smart ? "Smart Laplace: each vertex moves to the mean of its neighbours only if its worst element does not "
                    "get worse and nothing inverts. Does not untangle."
                  : "Plain Laplace (Jacobi): every free vertex moves to the mean of its neighbours; may invert "
                    "elements. Does not untangle.",
            laplace_kind, false);
        s.skip = smart_by_name;
        s.defaults = [smart] {
            LaplaceSolverOptions o;
            o.smart = smart;
            return SolverOptions(o);
        };
        s.make = [smart, name = s.name](const SolverOptions& o) {
            LaplaceSolverOptions l = options_as<LaplaceSolverOptions>(o, name);
            l.smart = smart;
            return std::make_unique<LaplaceSolver>(l);
        };
        solvers.push_back(std::move(s));
    }

    using Targets = std::vector<std::optional<double>>;
    wrappers.push_back({"untangle", "Assess, untangle with the global solver (stops once no element is inverted), assess.",
                        "global", &global_kind, untangle,
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::untangle(options_as<GlobalSolverOptions>(o, "untangle")); },
                        [](const SolverOptions&) { return Targets{std::nullopt}; }});
    wrappers.push_back({"shape_improvement",
                        "Assess, raise the worst element of a valid mesh with the global log-barrier solver, assess.",
                        "global", &global_kind,
                        {{"untangle", "improve_shape", "untangling", "untangle_termination", "precondition_untangling", "local_untangle_rounds"},
                         "shape_improvement does not untangle (untangle_then_improve does)"},
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::shape_improvement(options_as<GlobalSolverOptions>(o, "shape_improvement")); },
                        [](const SolverOptions& o) { return Targets{o.get<GlobalSolverOptions>().termination.target_worst_quality}; }});
    wrappers.push_back({"local_shape_improvement", "Assess, improve with the local smoother (which untangles first), assess.",
                        "local", &local_kind,
                        {{"improve_shape"},
                         "local_shape_improvement improves the shape; to stop once untangled, use an improve step "
                         "(name: local, improve_shape: false)"},
                        [] { return SolverOptions(LocalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::local_shape_improvement(options_as<LocalSolverOptions>(o, "local_shape_improvement")); },
                        [](const SolverOptions& o) { return Targets{o.get<LocalSolverOptions>().termination.target_worst_quality}; }});
    wrappers.push_back({"laplace", "Assess, smart Laplace (plain Laplace with `smart: false`, which may invert elements), assess.",
                        "smart_laplace", &laplace_kind, {},
                        [] { return SolverOptions(LaplaceSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::laplace(options_as<LaplaceSolverOptions>(o, "laplace")); },
                        [](const SolverOptions& o) { return Targets{o.get<LaplaceSolverOptions>().termination.target_worst_quality}; }});
    const auto global_target = [](const SolverOptions& o) {
        return Targets{o.get<GlobalSolverOptions>().termination.target_worst_quality};
    };
    wrappers.push_back({"size_adapt_shape",
                        "Every element keeps its size (its target's size is the input's), its shape is made ideal: "
                        "assess, untangle if needed and improve with the global solver rating shape_size, assess",
                        "global", &global_kind, {{"metric"}, "size_adapt_shape rates with shape_size"},
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::size_adapt_shape(options_as<GlobalSolverOptions>(o, "size_adapt_shape")); },
                        global_target});
    wrappers.push_back({"boundary_layer_shape",
                        "Every element keeps its size, aspect and orientation, its angles are made ideal (layers keep "
                        "their heights): assess, untangle if needed and improve with the global solver rating "
                        "shape_size_orient, assess",
                        "global", &global_kind, {{"metric"}, "boundary_layer_shape rates with shape_size_orient"},
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::boundary_layer_shape(options_as<GlobalSolverOptions>(o, "boundary_layer_shape")); },
                        global_target});
    wrappers.push_back({"deforming_domain",
                        "Morphing: a mesh whose boundary moved from its reference (input.displacement or "
                        "targets.reference); every element pulled toward its size, aspect and skew in the reference: "
                        "assess, untangle (following the motion in steps where needed) and improve with the global "
                        "solver rating shape_size, assess",
                        "global", &global_kind, {{"metric"}, "deforming_domain rates with shape_size"},
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::deforming_domain(options_as<GlobalSolverOptions>(o, "deforming_domain")); },
                        global_target});
    wrappers.push_back({"untangle_then_improve",
                        "Assess, untangle, then improve the shape, each with the global solver, assess: the default job.",
                        "global", &global_kind,
                        {{"untangle", "improve_shape", "checkpoint"},
                         "untangle_then_improve untangles, then improves: it sets both; its two solvers cannot share one "
                         "checkpoint (use an untangle step and an improve step, each with its own)"},
                        [] { return SolverOptions(GlobalSolverOptions{}); },
                        [](const SolverOptions& o) { return wrappers::untangle_then_improve(options_as<GlobalSolverOptions>(o, "untangle_then_improve")); },
                        [](const SolverOptions& o) {
                            return Targets{std::nullopt, o.get<GlobalSolverOptions>().termination.target_worst_quality};
                        }});

    // An option of another solver, misplaced: say whose it is.
    const auto owner_hint = [this](const std::string& key) {
        std::vector<std::string> owners;
        for (const auto& s : solvers)
            if (s.options->has(key) && !s.skip.has(key)) owners.push_back(s.name);
        return owners.empty() ? std::string() : "'" + key + "' is an option of solver " + join(owners, ", ");
    };
    global.hint(owner_hint);
    local.hint(owner_hint);
    laplace.hint([owner_hint](const std::string& key) {
        std::string hint = owner_hint(key);
        if (key == "untangle" || key == "improve_shape" || key == "untangle_termination")
            hint += std::string(hint.empty() ? "" : "; ") + "Laplace smoothing does not untangle: untangle with global or local";
        return hint;
    });
}

const Tables& tables() {
    static const Tables t;
    return t;
}

}  // namespace

const std::vector<SolverKind>& solver_kinds() { return tables().solvers; }

std::vector<std::string> solver_names() {
    std::vector<std::string> out;
    for (const auto& s : solver_kinds()) out.push_back(s.name);
    return out;
}

std::vector<std::string> wrapper_names() {
    std::vector<std::string> out;
    for (const auto& w : wrapper_kinds()) out.push_back(w.name);
    return out;
}

const SolverKind* find_solver(const std::string& name) {
    for (const auto& s : solver_kinds())
        if (s.name == name) return &s;
    return nullptr;
}

const std::vector<WrapperKind>& wrapper_kinds() { return tables().wrappers; }

const WrapperKind* find_wrapper(const std::string& name) {
    for (const auto& w : wrapper_kinds())
        if (w.name == name) return &w;
    return nullptr;
}

const Skip& untangle_skip() { return tables().untangle; }

const Table<AssessSpec>& assess_table() { return tables().assess; }

std::string solvers_with(const std::string& key, const std::string& except) {
    std::vector<std::string> owners;
    for (const auto& s : solver_kinds())
        if (s.name != except && s.options->has(key) && !s.skip.has(key)) owners.push_back(s.name);
    if (owners.empty()) return "";
    return (owners.size() == 1 ? "solver " : "solvers ") + join(owners);
}

std::vector<ObjectInfo> object_infos() {
    const Tables& t = tables();
    std::vector<ObjectInfo> out;
    for (const auto& m : metric_catalogue()) out.push_back({"metric", m.name, m.help, t.metric.describe({})});
    for (const auto& [name, help] : objective_help())
        out.push_back({"objective", name, help, t.objective_table(name).describe({})});
    out.push_back({"termination", "termination",
                   "When a solver (or one of its phases) stops. Every test is relative, so a mesh scaled by 1e-4 or 1e4 "
                   "stops at the same iteration.",
                   t.termination.describe({})});
    out.push_back({"checkpoint", "checkpoint",
                   "The `checkpoint` option of the global and local solvers: periodic checkpoints of a long run, written "
                   "through a temporary and a rename, and resuming from one to the result the uninterrupted run gives "
                   "(docs/robustness.md). A checkpoint is refused for another mesh or other options.",
                   t.checkpoint.describe({})});
    for (const auto& s : t.solvers) out.push_back({"solver", s.name, s.help, s.options->describe(s.defaults(), s.skip)});
    out.push_back({"assessor", "quality",
                   "Quality statistics (min / max / mean / rms / histogram) of metrics over the mesh, split between "
                   "elements with a free vertex and the rest, and the exact count of inverted elements.",
                   t.assess.describe({})});
    for (const auto& w : t.wrappers) {
        const SolverKind& solver = *find_solver(w.solver);
        const auto theirs = solver.options->keys(solver.skip), ours = w.options->keys(w.skip);
        std::vector<std::string> without, extra;
        for (const auto& k : theirs)
            if (std::find(ours.begin(), ours.end(), k) == ours.end()) without.push_back("`" + k + "`");
        for (const auto& k : ours)
            if (std::find(theirs.begin(), theirs.end(), k) == theirs.end()) extra.push_back("`" + k + "`");
        std::string help = w.help + " Options: those of solver `" + w.solver + "`";
        if (!without.empty()) help += " except " + join(without);
        if (!extra.empty()) help += ", and " + join(extra);
        out.push_back({"wrapper", w.name, help + ".", w.options->describe(w.defaults(), w.skip)});
    }
    return out;
}

}  // namespace detail

const std::vector<ObjectInfo>& registry() {
    // Built on first use, and again when a program has registered a metric since.
    static std::vector<ObjectInfo> all;
    static std::size_t metrics_seen = 0;
    if (all.empty() || metrics_seen != metric_catalogue().size()) {
        all = detail::object_infos();
        for (auto& s : detail::section_infos()) all.push_back(std::move(s));
        metrics_seen = metric_catalogue().size();
    }
    return all;
}

std::vector<std::string> names_of(std::string_view kind) {
    std::vector<std::string> out;
    for (const auto& o : registry())
        if (o.kind == kind) out.push_back(o.name);
    return out;
}

const ObjectInfo& describe(std::string_view kind, std::string_view name) {
    for (const auto& o : registry())
        if (o.kind == kind && o.name == name) return o;
    const auto known = names_of(kind);
    if (known.empty()) throw OptionError("no kind of object is called '" + std::string(kind) + "'");
    std::string message = "unknown " + std::string(kind) + " '" + std::string(name) + "'";
    if (const auto near = detail::closest(name, known); !near.empty()) message += "; did you mean '" + near + "'?";
    throw OptionError(message + " (known: " + detail::join(known) + ")");
}

std::string registry_markdown() {
    std::ostringstream out;
    auto escape = [](const std::string& s) {
        std::string r;
        for (char c : s) r += c == '|' ? std::string("\\|") : std::string(1, c);
        return r;
    };
    auto table = [&](const std::vector<OptionInfo>& options) {
        out << "\n| key | type | default | meaning |\n|---|---|---|---|\n";
        for (const auto& o : options) {
            out << "| `" << o.key << "` | " << escape(o.type) << " | ";
            if (!o.default_value.empty()) out << '`' << escape(o.default_value) << '`';
            out << " | " << escape(o.help) << " |\n";
        }
    };
    const auto& all = registry();
    auto of_kind = [&](std::string_view kind) {
        std::vector<const ObjectInfo*> list;
        for (const auto& o : all)
            if (o.kind == kind) list.push_back(&o);
        return list;
    };

    out << "\n### Metrics\n\nV is the signed volume (A the signed area), L the sum of the squared edge lengths; "
           "docs/metrics.md has the details.\n\n| name | formula, range, ideal value |\n|---|---|\n";
    const auto metrics = of_kind("metric");
    for (const auto* m : metrics) out << "| `" << m->name << "` | " << escape(m->help) << " |\n";
    out << "\nEvery metric takes the same option; write `metric: NAME` or `metric: {name: NAME, hybrid_sharpness: 10}`.\n";
    if (!metrics.empty()) table(metrics.front()->options);

    const std::pair<const char*, const char*> kinds[] = {{"objective", "Objective functions (global solver)"},
                                                          {"termination", "Termination criterion"},
                                                          {"checkpoint", "Checkpoints (global and local solvers)"},
                                                          {"solver", "Solvers (improve and untangle steps)"},
                                                          {"assessor", "Assessor (assess steps)"}};
    for (const auto& [kind, title] : kinds) {
        out << "\n### " << title << "\n";
        for (const auto* o : of_kind(kind)) {
            out << "\n#### `" << o->name << "`\n\n" << o->help << "\n";
            if (!o->options.empty()) table(o->options);
        }
    }
    out << "\n### Wrappers (wrapper steps, `queue: NAME`)\n\nReady-made queues (`paloverde/wrappers.hpp`, same names). "
           "Each takes the options of its solver, listed above, except those it sets itself.\n\n"
           "| name | what it runs |\n|---|---|\n";
    for (const auto* o : of_kind("wrapper")) out << "| `" << o->name << "` | " << escape(o->help) << " |\n";
    out << "\n### Sections of a run config\n";
    for (const auto* o : of_kind("section")) {
        out << "\n#### `" << o->name << "`\n";
        if (!o->help.empty()) out << "\n" << o->help << "\n";
        if (!o->options.empty()) table(o->options);
    }
    return out.str();
}

SolverOptions default_options(std::string_view name) {
    if (const auto* s = detail::find_solver(std::string(name))) return s->defaults();
    if (const auto* w = detail::find_wrapper(std::string(name))) return w->defaults();
    auto known = names_of("solver");
    for (const auto& w : names_of("wrapper")) known.push_back(w);
    throw OptionError("unknown solver or wrapper '" + std::string(name) + "' (known: " + detail::join(known) + ")");
}

std::unique_ptr<Solver> make_solver(std::string_view name, const SolverOptions& options) {
    if (const auto* s = detail::find_solver(std::string(name))) return s->make(options);
    describe("solver", name);  // throws, naming the known solvers
    return nullptr;
}

InstructionQueue make_wrapper(std::string_view name, const SolverOptions& options) {
    if (const auto* w = detail::find_wrapper(std::string(name))) return w->make(options);
    describe("wrapper", name);
    return {};
}

}  // namespace paloverde::config
