// Tensor-product Legendre basis of order M = 0..3 on a quadtree node of a master element
// (seed paper 000, sections 2-4: orthonormal wavelet bases in parameter space, Gauss
// quadrature, push-pull matrices that do not depend on the level; docs/method.md, Basis and fields).
//
// Conventions used by every function here:
// - A node is a square of the chart's unit square; (s,t) in [0,1]^2 are the node's local
//   coordinates. The basis is orthonormal for the node's *normalized* measure ds dt:
//   phi_ij(s,t) = P~_i(s) P~_j(t), P~_k(s) = sqrt(2k+1) P_k(2s-1). So c_00 is the mean of the
//   function over the node and the integral in chart units is 4^-level * c_00.
// - Coefficient index k = CoeffIndex(M, i, j) = j*(M+1) + i (degree in s runs fastest).
// - Coefficients come in `count` blocks (e.g. 9 = 3 colours x 3 vector components), each
//   NumCoeffs(M) floats contiguous: coeffs[b*N + k].
// - Sampled values at a tensor grid of points are point-major: values[p*count + b] with
//   p = a + n*c for the point (x[a], x[c]) (s index runs fastest).
// - Child quadrant c = qs + 2*qt (qs, qt in {0,1}): child local (u,v) maps to parent
//   ((u+qs)/2, (v+qt)/2). So 0 = low s low t, 1 = high s low t, 2 = low s high t, 3 = both high.
// All tables are built once (thread-safe static init); hot functions do not allocate.
#pragma once

#include <cstdint>

namespace mebake::solve {

inline constexpr int kMaxOrder = 3;
inline constexpr int kMaxCoeffs = (kMaxOrder + 1) * (kMaxOrder + 1);
inline constexpr int kMaxGauss = 8;  // Gauss-Legendre rules n = 1..8
inline constexpr int kMaxGrid = 16;  // control grids g = 1..16 per axis

constexpr int NumCoeffs(int order) {
    return (order + 1) * (order + 1);
}
constexpr int CoeffIndex(int order, int i, int j) {
    return j * (order + 1) + i;
}

// P~_0..P~_order at s (orthonormal shifted Legendre on [0,1]).
void Legendre(int order, double s, double* p);

// The NumCoeffs(order) basis values phi_k(s,t).
void EvalBasis(int order, double s, double t, double* phi);

// Gauss-Legendre rule with n points on [0,1], ascending; the weights sum to 1.
// Exact for polynomials of degree <= 2n-1. The 2-D rule on a node is the tensor product:
// point p = a + n*c at (x[a], x[c]) with weight w[a]*w[c] (times the node area in chart units).
struct GaussRule {
    int n = 0;
    double x[kMaxGauss] = {};
    double w[kMaxGauss] = {};
};
const GaussRule& Gauss(int n);

// Tensor Gauss point p of the n x n rule in node coordinates, and its weight.
void GaussPoint2D(int n, int p, double* s, double* t, double* weight);

// Control grid of g points per axis: a/(g-1) for a = 0..g-1 (node corners included), or
// 0.5 for g = 1. For n = M+1 Gauss collocation, DefaultControlGrid(M) = 2M+2 never hits a
// Gauss point, so the fit error measured there is not trivially zero.
double ControlPoint(int g, int a);
constexpr int DefaultControlGrid(int order) {
    return 2 * order + 2;
}

// Evaluates the `count` blocks at (s,t): out[b] = sum_k coeffs[b*N+k] phi_k(s,t).
void EvalCoeffs(int order, const float* coeffs, int count, double s, double t, float* out);

// Evaluates at all points of the tensor grid xs (ns points, along s) x ts (nt points):
// out[(a + ns*c)*count + b]. ns, nt <= kMaxGrid.
void EvalTensorGrid(int order, const float* coeffs, int count, const double* xs, int ns,
                    const double* ts, int nt, float* out);

// EvalTensorGrid at the n x n Gauss points / at the g x g control grid.
void EvalGauss(int order, int n, const float* coeffs, int count, float* out);
void EvalControlGrid(int order, int g, const float* coeffs, int count, float* out);

// Projection with the n x n Gauss rule (n >= order+1): coeffs[b*N+k] =
// sum_p w_p values[p*count+b] phi_k(x_p). Exact (= L2 projection) when the sampled function
// is a polynomial of degree <= 2n-1-order per axis. With n = order+1 it is collocation:
// the result interpolates the values at the (M+1)^2 Gauss points exactly.
void ProjectGauss(int order, int n, const float* values, int count, float* coeffs);

// Largest |fit - value| over the g x g control grid and all blocks (count <= 64); values laid
// out as EvalControlGrid writes them.
float ControlGridError(int order, int g, const float* coeffs, int count, const float* values);

// Two-scale matrix of child c: child_m = sum_k P_c[m*N+k] parent_k, the exact restriction of
// the parent polynomial to the quadrant, in the child's own basis. Same at every level.
// Returned pointer refers to a static N x N row-major table.
const double* TwoScaleMatrix(int order, int child);

// Push: child = P_c parent (or child += P_c parent), for `count` blocks.
void Push(int order, int child, const float* parent, int count, float* child_coeffs);
void PushAdd(int order, int child, const float* parent, int count, float* child_coeffs);

// Pull: the L2 projection onto the parent of the piecewise polynomial given by the four
// children, parent = (1/4) sum_c P_c^T child_c (the 1/4 is the quadrant's share of the parent's
// normalized measure). Pull(Push(x)) == x for every parent x.
void Pull(int order, const float* const children[4], int count, float* parent);

}  // namespace mebake::solve
