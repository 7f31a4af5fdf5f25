#pragma once
// An objective function combines the qualities of the elements being optimized into one number
// to maximize, and gives its derivative with respect to each quality; the solver chains that
// with the metric's gradient. Sums are global: they go through the Reducer.
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

class ObjectiveFunction {
public:
    virtual ~ObjectiveFunction() = default;
    virtual std::string_view name() const = 0;

    // Once per outer iteration, at the accepted qualities: the log-barrier solves for t here.
    virtual void update(std::span<const double> quality, const Reducer& reducer) {
        (void)quality;
        (void)reducer;
    }
    // After each outer iteration: the log-barrier shrinks mu.
    virtual void advance() {}

    // A number that keeps rising while the method still makes progress, though the worst
    // quality may pause (the barrier's t, which climbs to the worst quality as mu shrinks).
    virtual double progress_measure() const { return 0.0; }
    // Whether element `element` with quality `quality` lies in the objective's domain.
    virtual bool admissible(double quality, std::size_t element) const {
        (void)element;
        return quality > -1e308;
    }

    virtual double value(std::span<const double> quality, const Reducer& reducer) const = 0;
    // Also writes d(value)/d(quality[i]) into weight[i].
    virtual double value_and_weights(std::span<const double> quality, std::span<double> weight,
                                     const Reducer& reducer) const = 0;
    // -d2(value)/d(quality[i])2 of the part of the objective that is a sum over elements: how
    // sharply each element's term bends. Solvers build a preconditioner from it; 0 means none.
    virtual void curvature_weights(std::span<const double> quality, std::span<double> curvature) const;
};

// The log-barrier of Sastry & Shontz:  F(mu, t) = t + mu * sum_i log(q_i - t),  t < min q.
// update() sets t to the maximizer of F for the current qualities (dF/dt = 0, a 1-D root found
// by safeguarded Newton steps), so F rewards raising every quality and, as mu shrinks, t climbs
// to the worst quality and the weight mu/(q_i - t) concentrates on the worst elements.
class LogBarrier final : public ObjectiveFunction {
public:
    // mu <= 0 chooses the first mu from the qualities: t starts half the spread below the worst
    // quality, or closer when more than about `initial_active` elements would weigh as much as
    // the worst.
    explicit LogBarrier(double shrink = 0.8, double initial_mu = 0.0, double initial_active = 1e4);
    std::string_view name() const override { return "log_barrier"; }
    void update(std::span<const double> quality, const Reducer& reducer) override;
    void advance() override;
    bool admissible(double quality, std::size_t) const override { return quality > t_; }
    double progress_measure() const override { return t_; }
    double value(std::span<const double> quality, const Reducer& reducer) const override;
    double value_and_weights(std::span<const double> quality, std::span<double> weight,
                             const Reducer& reducer) const override;
    void curvature_weights(std::span<const double> quality, std::span<double> curvature) const override;

    double mu() const { return mu_; }
    double t() const { return t_; }


private:

    double shrink_;
    double initial_active_;
    double mu_;
    double t_ = 0.0;
};

// The p-mean of the qualities, (1/n sum q_i^p)^(1/p) (Mesquite's LPtoP, normalized). A negative
// p stresses the worst elements. Defined for positive qualities only.
class PMean final : public ObjectiveFunction {
public:
    explicit PMean(double p = -2.0);
    std::string_view name() const override { return "p_mean"; }
    bool admissible(double quality, std::size_t) const override { return quality > 0.0; }
    double value(std::span<const double> quality, const Reducer& reducer) const override;
    double value_and_weights(std::span<const double> quality, std::span<double> weight,
                             const Reducer& reducer) const override;

private:
    double p_;
};

// The worst quality (Mesquite's LInf on the minimum). Its gradient is that of the worst
// element(s): a nonsmooth objective, here for comparison.
class MinQuality final : public ObjectiveFunction {
public:
    std::string_view name() const override { return "min_quality"; }
    double value(std::span<const double> quality, const Reducer& reducer) const override;
    double value_and_weights(std::span<const double> quality, std::span<double> weight,
                             const Reducer& reducer) const override;
};

struct ObjectiveOptions {
    double barrier_shrink = 0.8;  // mu <- shrink * mu after steps_per_mu steps, in (0, 1]
    double initial_mu = 0.0;      // 0: chosen from the qualities
    double barrier_initial_active = 1e4;  // with automatic mu: elements the barrier first weighs
    double p = -2.0;              // p_mean exponent, nonzero
    void validate() const;        // throws OptionError
};

// Names: log_barrier, p_mean, min_quality.
std::unique_ptr<ObjectiveFunction> make_objective(std::string_view name, const ObjectiveOptions& options = {});

}  // namespace paloverde
