#pragma once
// An objective function combines the qualities of the elements being optimized into one number
// to maximize, and gives its derivative with respect to each quality; the solver chains that
// with the metric's gradient. Sums are global: they go through the Reducer.
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

class ObjectiveFunction {
public:
    virtual ~ObjectiveFunction() = default;
    virtual std::string_view name() const = 0;

    // Calls that take `counted` get the qualities this process counts in global sums (in a
    // distributed run each element is counted by exactly one process); the others take any
    // qualities, also of copies of other processes' elements.

    // At each accepted iterate: the log-barrier solves for t here, and every objective keeps
    // what weights() needs.
    virtual void update(std::span<const double> counted, const Reducer& reducer) = 0;
    // After each outer iteration: the log-barrier shrinks mu.
    virtual void advance() {}

    // A number that keeps rising while the method still makes progress, though the worst
    // quality may pause (the barrier's t, which climbs to the worst quality as mu shrinks).
    virtual double progress_measure() const { return 0.0; }
    // The objective's domain: qualities above this number (a bound, not a test per element, so
    // that solvers check whole arrays in a plain loop).
    virtual double domain_floor() const { return -1e308; }

    virtual double value(std::span<const double> counted, const Reducer& reducer) const = 0;
    // d(value)/d(quality[i]) into weight[i], at the state of the last update().
    virtual void weights(std::span<const double> quality, std::span<double> weight) const = 0;
    // -d2(value)/d(quality[i])2 of the part of the objective that is a sum over elements: how
    // sharply each element's term bends. Solvers build a preconditioner from it; 0 means none.
    virtual void curvature_weights(std::span<const double> quality, std::span<double> curvature) const;

    // What update() and advance() leave behind (the barrier's mu and t, which also seeds the next
    // t solve), for checkpoints: restore_state(state()) on a new objective of the same kind and
    // options continues bit for bit. Throws Error for a state of the wrong size.
    virtual std::vector<double> state() const { return {}; }
    virtual void restore_state(std::span<const double> state);

    // The elements that stand still while a solver moves only part of the mesh (its focus):
    // `counted`, their qualities (entries that are not finite are skipped). An objective whose own
    // parameters depend on every element (the barrier's t) goes on setting them as for the whole
    // mesh; every other call still takes the moving elements' qualities only, and value() leaves
    // out the still elements' terms, a constant while they stand still. Collective; a call with
    // no still element on any process forgets them.
    virtual void hold_still(std::span<const double> counted, const Reducer& reducer);

    // What a solver asks of an objective that is a sequence of subproblems (a continuation, like
    // the log-barrier's as mu shrinks) rather than one problem. The defaults are those of one
    // problem: no subproblems, nothing to adjust.

    // Whether advance() moves to a next subproblem whose solutions follow a central path toward
    // the max-min problem: what Newton steps need to follow.
    virtual bool is_continuation() const { return false; }
    // The current subproblem's scale in quality units (the barrier's mu): a step that gains little
    // against it has all but solved the subproblem. 0 without subproblems.
    virtual double subproblem_scale() const { return 0.0; }
    // The level every term measures its element's quality from, log(q - level), which climbs to the
    // worst quality as the subproblems go on (the barrier's t). 0 without subproblems.
    virtual double subproblem_floor() const { return 0.0; }
    // The worst element's share of the objective's pull (the weights summing to 1): how much the
    // steps still work for it. 1 where nothing else pulls.
    virtual double worst_share() const { return 1.0; }
    // Before the first update(): the solver moves only the elements within `fraction` of the way
    // from the worst quality to `ideal`, holding the rest still (a focus). An objective that would
    // choose its first subproblem from every element chooses it no looser than that band.
    virtual void focus_on_band(double /*fraction*/, double /*ideal*/) {}
    // The solver's set of terms changed (a focus over them alone moved): an objective whose pull on
    // its worst elements depends on how many terms it has keeps that pull as it was. Collective.
    virtual void keep_weighting(std::span<const double> /*counted*/, const Reducer& /*reducer*/) {}
    // The level the solver keeps its moving elements above, and how softly (an element within
    // `softness` of it weighs twice). Objectives whose domain is their own ignore it.
    virtual void set_floor(double /*floor*/, double /*softness*/) {}
};

// The log-barrier of Sastry & Shontz:  F(mu, t) = t + mu * sum_i log(q_i - t),  t < min q.
// update() sets t to the maximizer of F for the current qualities (dF/dt = 0, a 1-D root found
// by safeguarded Newton steps), so F rewards raising every quality and, as mu shrinks, t climbs
// to the worst quality and the weight mu/(q_i - t) concentrates on the worst elements.
class LogBarrier final : public ObjectiveFunction {
public:
    // mu <= 0 chooses the first mu from the qualities: t starts half the spread below the worst
    // quality, or closer when more than about `initial_active` elements would weigh as much as
    // the worst (0: 0.5% of the elements, at least 10,000), but never closer than a thousandth of
    // the qualities' size.
    explicit LogBarrier(double shrink = 0.8, double initial_mu = 0.0, double initial_active = 0.0);
    std::string_view name() const override { return "log_barrier"; }
    void update(std::span<const double> counted, const Reducer& reducer) override;
    void advance() override;
    double domain_floor() const override { return t_; }
    double progress_measure() const override { return t_; }
    double value(std::span<const double> counted, const Reducer& reducer) const override;
    void weights(std::span<const double> quality, std::span<double> weight) const override;
    void curvature_weights(std::span<const double> quality, std::span<double> curvature) const override;
    std::vector<double> state() const override { return {mu_, t_, gap_ratio_}; }
    void restore_state(std::span<const double> state) override;
    // The still elements' qualities, binned: 16,384 bins between the lowest and the highest, each
    // standing at its middle. A focus's nearest still element lies at least half its band above
    // t, and half a bin is a small fraction of that, so a bin moves each term by little.
    void hold_still(std::span<const double> counted, const Reducer& reducer) override;
    // With the automatic first mu: t starts at most `fraction` of the way from the worst quality
    // to `ideal` below the worst. A barrier that weighed the still elements outside a focus like
    // the worst would only pull t, and with it the worst element, down.
    void focus_on_band(double fraction, double ideal) override;
    // Sets mu so that t stays where it stands for these terms (before an automatic first mu:
    // nothing). A barrier over a focus alone keeps its t, and the weight on its worst elements,
    // when the focus changes: with mu kept, ten times the terms would put t ten times farther
    // below the worst (the gap is about mu times the terms near it). Where a term lies at or
    // below t, t keeps its gap below the worst instead. Collective.
    void keep_weighting(std::span<const double> counted, const Reducer& reducer) override;
    bool is_continuation() const override { return true; }
    double subproblem_scale() const override { return mu_; }
    double subproblem_floor() const override { return t_; }
    // The worst element's weight mu / (worst - t) at the last t solve. 1 before the first solve.
    double worst_share() const override { return gap_ratio_ > 0.0 ? 1.0 / gap_ratio_ : 1.0; }

    double mu() const { return mu_; }
    double t() const { return t_; }

private:
    double automatic_active(double elements) const;
    // The lowest quality the barrier weighs: of these terms and the still elements. Collective.
    double worst(std::span<const double> counted, const Reducer& reducer) const;

    double shrink_;
    double initial_active_;
    double mu_;
    double t_ = 0.0;
    double gap_ratio_ = 0.0;  // (worst quality - t) / mu at the last t solve; 0 before the first
    // The still elements (hold_still), the same on every process: bin middles, ascending, and
    // how many elements each stands for.
    std::vector<double> still_quality_, still_count_;
    double still_total_ = 0.0;
    double first_gap_fraction_ = 0.0, ideal_ = 0.0;  // focus_on_band; 0: no limit
};

// The p-mean of the qualities, (1/n sum q_i^p)^(1/p) (Mesquite's LPtoP, normalized). A negative
// p stresses the worst elements. Defined for positive qualities only.
class PMean final : public ObjectiveFunction {
public:
    explicit PMean(double p = -2.0);
    std::string_view name() const override { return "p_mean"; }
    double domain_floor() const override { return 0.0; }
    void update(std::span<const double> counted, const Reducer& reducer) override;
    double value(std::span<const double> counted, const Reducer& reducer) const override;
    void weights(std::span<const double> quality, std::span<double> weight) const override;
    std::vector<double> state() const override { return {mean_, count_}; }
    void restore_state(std::span<const double> state) override;

private:
    double p_;
    double mean_ = 0.0, count_ = 0.0;  // at the last update()
};

// The worst quality (Mesquite's LInf on the minimum). Its gradient is that of the worst
// element(s): a nonsmooth objective, here for comparison.
class MinQuality final : public ObjectiveFunction {
public:
    std::string_view name() const override { return "min_quality"; }
    void update(std::span<const double> counted, const Reducer& reducer) override;
    double value(std::span<const double> counted, const Reducer& reducer) const override;
    void weights(std::span<const double> quality, std::span<double> weight) const override;
    std::vector<double> state() const override { return {worst_}; }
    void restore_state(std::span<const double> state) override;

private:
    double worst_ = 0.0;  // at the last update()
};

// The qualities' sum with a barrier at a floor: F = sum_i q_i + mu * sum_i log(q_i - floor). Raises
// the mean quality while every element stays above the floor; the barrier keeps them off it
// smoothly (an element within mu of the floor weighs twice), and its curvature gives a solver's
// preconditioner the elements' scale (the sum alone has none). Both are set by the solver
// (set_floor) and kept in its state. Not among make_objective's names: without a floor it is
// not defined.
class MeanAboveFloor final : public ObjectiveFunction {
public:
    std::string_view name() const override { return "mean_above_floor"; }
    // floor: finite; mu > 0. Throws OptionError otherwise.
    void set_floor(double floor, double mu) override;
    double domain_floor() const override { return floor_; }
    void update(std::span<const double>, const Reducer&) override {}
    double value(std::span<const double> counted, const Reducer& reducer) const override;
    void weights(std::span<const double> quality, std::span<double> weight) const override;
    void curvature_weights(std::span<const double> quality, std::span<double> curvature) const override;
    std::vector<double> state() const override { return {floor_, mu_}; }
    void restore_state(std::span<const double> state) override;

private:
    double floor_ = 0.0, mu_ = 0.0;
};

struct ObjectiveOptions {
    double barrier_shrink = 0.8;  // mu <- shrink * mu after steps_per_mu steps, in (0, 1]
    double initial_mu = 0.0;      // 0: chosen from the qualities
    double barrier_initial_active = 0.0;  // with automatic mu: elements the barrier first weighs
                                          // like the worst; 0: 0.5% of them, at least 10,000
    double p = -2.0;              // p_mean exponent, nonzero
    void validate() const;        // throws OptionError
};

// Names: log_barrier, p_mean, min_quality.
std::unique_ptr<ObjectiveFunction> make_objective(std::string_view name, const ObjectiveOptions& options = {});

}  // namespace paloverde
