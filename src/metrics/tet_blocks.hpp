#pragma once
// Tetrahedron metrics over blocks of elements, for the batch passes: the corners of kTetBlock
// elements are gathered into structure-of-arrays buffers and one branch-free loop rates them
// all, which the compiler turns into SIMD code. The results are bit for bit those of the scalar
// kernels in kernels.hpp: the same operations in the same order, and no contraction into FMA.
#include "paloverde/core/types.hpp"
#include "paloverde/mesh/cell_types.hpp"

namespace paloverde::metrics {

inline constexpr int kTetBlock = 16;

// Coordinate d of corner i of the block's element j is at[3 * i + d][j]; also used for the
// gradient with respect to that coordinate.
struct TetBlock {
    alignas(64) double at[12][kTetBlock];
};

// The baseline build is SSE2 (2 doubles per instruction); CPUs with AVX2 or AVX-512 run a copy
// of the loops compiled for it (4 or 8 doubles). All give the same bits.
enum class BlockPath { baseline, avx2, avx512 };
bool block_path_supported(BlockPath path);
BlockPath best_block_path();  // the widest supported

// Copies the corners of `count` (at most kTetBlock) tetrahedra, given by their 4 vertex ids each
// in `connectivity`, from `coordinates` (3 per vertex) into x; pads the rest of the block with a
// degenerate element at the origin (quality 0, no NaN).
void gather_tets(const VertexId* connectivity, const double* coordinates, int count, TetBlock& x);

// Carries each lane's corners by its map, maps[j] (a target's, cell_types.hpp: M[k - 1][i - 1]),
// bit for bit as one element's are carried before a scalar kernel rates it: y_0 = x_0,
// y_i = x_0 + sum_k (x_k - x_0) M[k][i], the sum from 0 in the order k = 1, 2, 3; then, when
// `roots` is not null, every corner by the lane's metric root: z = N y.
void map_tets(BlockPath path, const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x);
// The chain rule back through map_tets() for the lanes' gradients, bit for bit as one element's
// gradient is carried back after a scalar kernel: through the metric root (transposed) first,
// then g_xk = sum_i g_yi M[k][i] for k = 1, 2, 3, and g_x0 what makes both sums equal.
void unmap_tets(BlockPath path, const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& gradient);

// quality[j] for the block's elements, and when `gradient` is not null their gradients.
// As tet_aspect(): 0 with a zero gradient for an element without edge length.
void tet_aspect_block(BlockPath path, const TetBlock& corners, double* quality, TetBlock* gradient);
// As UntangleHybrid::tet() with the reference volume reference_volume[j] for element j.
void tet_hybrid_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double alpha,
                      double* quality, TetBlock* gradient);

// As MeanRatio::tet(): 0 with a zero gradient for an element without edge length.
void tet_mean_ratio_block(BlockPath path, const TetBlock& corners, double* quality, TetBlock* gradient);
// As ShapeSize::tet() (the mean ratio times the size term) with the reference volume
// reference_volume[j] for element j.
void tet_shape_size_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double* quality,
                          TetBlock* gradient);

// As RegularizedEnergy::tet() with epsilon, theta and the reference volume reference_volume[j].
void tet_energy_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double epsilon,
                      double theta, double* quality, TetBlock* gradient);

// The metrics a quality report rates besides the aspect ratio, values only (a report needs no
// gradient): quality[j] is bit for bit the scalar tet() of that metric without a gradient.
// reference_volume[j] is read by scaled_volume alone (the others may be given null).
enum class TetValueMetric { inverse_condition, edge_ratio, scaled_volume, min_dihedral, scaled_jacobian };
void tet_values_block(BlockPath path, TetValueMetric metric, const TetBlock& corners, const double* reference_volume,
                      double* quality);

}  // namespace paloverde::metrics
