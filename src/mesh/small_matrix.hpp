#pragma once
// The d x d matrices (d = 2 or 3) of corner frames and targets, stored 3 x 3 with the upper-left
// d x d block in use: m[row][column].
#include <array>

namespace paloverde::detail {

using SmallMatrix = std::array<std::array<double, 3>, 3>;

inline double determinant(const SmallMatrix& m, int d) {
    if (d == 2) return m[0][0] * m[1][1] - m[0][1] * m[1][0];
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// By cofactors; the caller makes sure the determinant is not zero.
inline SmallMatrix inverse(const SmallMatrix& m, int d) {
    const double det = determinant(m, d);
    SmallMatrix out{};
    if (d == 2) {
        out[0][0] = m[1][1] / det, out[0][1] = -m[0][1] / det;
        out[1][0] = -m[1][0] / det, out[1][1] = m[0][0] / det;
        return out;
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            out[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
    return out;
}

}  // namespace paloverde::detail
