// Multi-emitter simplification (seed 002, section 5: light-light and light-penumbra
// simplification by an L2 test). The measures the refinement of the direct light uses when
// --multi-emitter simplify: the L2 difference between a node's polynomial and accurate values
// by Gauss-Legendre quadrature, the L2 norm of a contribution, and a code naming which lights
// are taken as known (for the probe cache). Solver::FitDirectLights (refine_direct.cpp)
// applies them; docs/method.md, "Several sources", describes the scheme.
#pragma once

#include <cstdint>
#include <span>

namespace mebake::solve {

// Largest over the `blocks` blocks of the L2 norm (normalized node measure) of
// fit - values, by the n x n Gauss-Legendre rule: coeffs of order `order`, values at the
// n x n Gauss points (point-major, values[p*blocks + b]). n <= 8, blocks <= 64.
float GaussL2Error(int order, int n, const float* coeffs, int blocks, const float* values);

// Largest |fit - values| over the n x n Gauss points and the blocks (same layout as
// GaussL2Error). It bounds GaussL2Error (the rule's weights sum to 1).
float GaussResidualMax(int order, int n, const float* coeffs, int blocks, const float* values);

// Largest over the blocks of the L2 norm of values at the n x n Gauss points.
float GaussL2Norm(int n, int blocks, const float* values);

// A code of Evaluate's `known` states (0, 2, 3 per light): exact for up to 15 lights
// (2 bits each), a hash beyond; 0 when nothing is known (the probe cache's usual keys).
uint32_t KnownCode(std::span<const uint8_t> known);

// CPU seconds of the calling thread (the debug log's timings of the extremal-boundary pass
// against the refinement, seed 002's Table 1).
double ThreadCpuSeconds();

}  // namespace mebake::solve
