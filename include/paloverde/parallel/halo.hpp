#pragma once
// Ghost vertices: a process keeps copies of the vertices its elements share with other
// processes, and refreshes them from their owners. A serial run has no ghosts, and uses this
// class as it is.
#include <span>

namespace paloverde {

class Halo {
public:
    virtual ~Halo() = default;
    // `values` holds `width` doubles per local vertex; each ghost's entries are replaced by its
    // owner's.
    virtual void update(std::span<double> values, int width) const {
        (void)values;
        (void)width;
    }
};

}  // namespace paloverde
