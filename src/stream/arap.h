// As-rigid-as-possible parameterization by local/global iterations (Liu, Zhang, Xu,
// Gotsman, Gortler, "A Local/Global Approach to Mesh Parameterization", SGP 2008),
// started from a conformal map. Makes the map near-isometric, which is what the master
// element needs: LSCM alone lets the area scale drift across curved charts.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/vec.h"
#include "stream/cotan_laplacian.h"

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
    // Caps the authalic target's sigma1 / sigma2, so noise is not chased with shear.
    double max_target_anisotropy = 1.5;
};

struct ArapReport {
    int iterations = 0;          // accepted iterations
    double initial_energy = 0;   // sum_T A_T |J_T - R_T|^2 / sum_T A_T, at the start
    double final_energy = 0;     // same, for the returned map
    bool stopped_by_flip = false;
    bool solver_failed = false;  // a solve was not finite: uv is the last good iterate
};

// Counts triangles whose uv orientation is not strictly counter-clockwise.
uint32_t CountFlips(std::span<const Vec2d> uv, std::span<const std::array<uint32_t, 3>> triangles);

// Refines *uv in place (scale included: the result is close to 3D lengths). The global
// step solves with `laplacian`, factorized with exactly `anchor` fixed; the anchor keeps
// its position.
ArapReport RefineArap(std::span<const FlatTriangle> flat,
                      std::span<const std::array<uint32_t, 3>> triangles,
                      const CotanLaplacian& laplacian, uint32_t anchor,
                      const ArapOptions& options, std::vector<Vec2d>* uv);

}  // namespace mebake::stream
