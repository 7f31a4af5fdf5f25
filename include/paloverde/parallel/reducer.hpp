#pragma once
// Global reductions behind one interface: a serial run uses this class as it is (every value is
// already global); a distributed run passes an MPI implementation. Solvers and objective
// functions never know which.
#include <span>

namespace paloverde {

class Reducer {
public:
    virtual ~Reducer() = default;
    // In place: each entry becomes the sum of that entry over all processes.
    virtual void sum(std::span<double> values) const { (void)values; }
    virtual double min(double value) const { return value; }
    virtual double max(double value) const { return value; }
    double sum(double value) const {
        sum(std::span<double>(&value, 1));
        return value;
    }
};

}  // namespace paloverde
