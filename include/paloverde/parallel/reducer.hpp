#pragma once
// Global reductions behind one interface: a serial run uses this class as it is (every value is
// already global); a distributed run passes an MPI implementation. Solvers and objective
// functions never know which. Sums are exact (ExactSum), so a result never depends on how the
// mesh was split among processes.
#include <cstdint>
#include <span>

#include "paloverde/core/exact_sum.hpp"

namespace paloverde {

class Reducer {
public:
    virtual ~Reducer() = default;
    // In place: each sum becomes the sum of that entry over all processes.
    virtual void sum(std::span<ExactSum> sums) const { (void)sums; }
    // In place: each count becomes its sum over all processes (integers: exact in any order).
    virtual void sum_counts(std::span<std::int64_t> counts) const { (void)counts; }
    // In place: each entry becomes its sum over all processes modulo 2^64 (hashes).
    virtual void sum_wrapping(std::span<std::uint64_t> values) const { (void)values; }
    virtual double min(double value) const { return value; }
    virtual double max(double value) const { return value; }
    // The total over all processes, rounded.
    double total(ExactSum local) const {
        sum(std::span<ExactSum>(&local, 1));
        return local.value();
    }
    // A count or other small integer-valued number, summed over all processes.
    double total(double local) const {
        ExactSum s;
        s.add(local);
        return total(s);
    }
};

}  // namespace paloverde
