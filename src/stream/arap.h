// Local/global parameterization refinement (Liu, Zhang, Xu, Gotsman, Gortler, "A
// Local/Global Approach to Mesh Parameterization", SGP 2008), started from a conformal map.
// Each triangle's Jacobian is pulled towards a target: a rotation (ARAP, authalic_weight
// 0) or, by default, the nearest area-preserving matrix with its shear capped (the same
// framework with the target set of an authalic map). The master element wants exactly
// that: a near-constant Jacobian determinant (seed paper, "Using the master element").
// Measured on caps and bumpy/noisy height fields, 10K vertices, 16 iterations from BFF:
//   target       cap 30deg dev / shear   cap 60deg dev / shear   bumpy dev / shear
//   ARAP (w=0)   1.8% / 1.019            7.1% / 1.074            3.0% / 1.049
//   authalic     0.09% / 1.037           0.20% / 1.152           0.84% / 1.082
// (dev = jacobian_deviation_mean, shear = mean sigma1/sigma2; see parameterize.h).
#pragma once

#include "core/vec.h"
#include "stream/cotan_laplacian.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::stream {

struct ArapOptions {
    int max_iterations = 16;
    // Stop early when an iteration lowers the energy by less than this fraction.
    double relative_tolerance = 1e-5;
    // Keep the last iterate with no more flipped triangles than the start.
    bool guard_flips = true;
    // 0: ARAP (targets are rotations). In (0, 1]: targets move towards the nearest
    // area-preserving matrix, trading shear for a flatter area ratio.
    double authalic_weight = 1;
    // Caps the authalic target's sigma1 / sigma2, so scan noise is not chased with shear
    // (1.5 keeps caps up to ~60 degrees exact and halves the shear on noisy patches).
    double max_target_anisotropy = 1.5;
};

struct ArapReport {
    int iterations = 0;         // accepted iterations
    double initial_energy = 0;  // sum_T A_T |J_T - target_T|^2 / sum_T A_T, at the start
    double final_energy = 0;    // same, for the returned map
    bool stopped_by_flip = false;
    bool solver_failed = false;  // a solve was not finite: uv is the last good iterate
};

// Counts triangles whose uv orientation is not strictly counter-clockwise.
uint32_t CountFlips(std::span<const Vec2d> uv, std::span<const std::array<uint32_t, 3>> triangles);

// The local step's target for a triangle whose Jacobian (flat frame -> uv) is
// [[a, b], [c, d]], authalic weight w, the authalic stretch clamped to [lo, hi]
// (arap.cpp); the Batch form does kArapBatch triangles at once, with the same bits as
// one call each.
std::array<double, 4> ArapTarget(double a, double b, double c, double d, double w, double lo,
                                 double hi);
constexpr size_t kArapBatch = 8;
struct ArapJacobians {
    std::array<double, kArapBatch> a, b, c, d;
};
void ArapTargetBatch(const ArapJacobians& j, double w, double lo, double hi,
                     std::array<std::array<double, 4>, kArapBatch>* out);

// Refines *uv in place (scale included: the result is close to 3D lengths). The global
// step solves with `laplacian`, factorized with exactly `anchor` fixed; the anchor keeps
// its position.
ArapReport RefineArap(std::span<const FlatTriangle> flat,
                      std::span<const std::array<uint32_t, 3>> triangles,
                      const CotanLaplacian& laplacian, uint32_t anchor, const ArapOptions& options,
                      std::vector<Vec2d>* uv);

}  // namespace mebake::stream
