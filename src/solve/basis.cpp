// Tensor-product Legendre basis on a quadtree node: Gauss rules, projection, evaluation and
// the level-independent two-scale (push/pull) matrices. See basis.h for the conventions.
#include "solve/basis.h"

#include "core/check.h"

#include <cmath>

namespace mebake::solve {
namespace {

// Legendre P_n(x) on [-1,1] and its derivative, by the three-term recurrence.
void LegendreAndDerivative(int n, double x, double* p, double* dp) {
    double p0 = 1, p1 = x;
    if (n == 0) {
        *p = 1;
        *dp = 0;
        return;
    }
    for (int k = 1; k < n; ++k) {
        double p2 = ((2 * k + 1) * x * p1 - k * p0) / (k + 1);
        p0 = p1;
        p1 = p2;
    }
    *p = p1;
    *dp = n * (x * p1 - p0) / (x * x - 1);
}

GaussRule MakeGauss(int n) {
    GaussRule r;
    r.n = n;
    if (n == 1) {
        r.x[0] = 0.5;
        r.w[0] = 1;
        return r;
    }
    // Newton on the roots of P_n from the classic cosine guess; the roots are simple and the
    // guess is within the basin, so a fixed number of steps converges to double precision.
    for (int i = 0; i < n; ++i) {
        double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
        double p = 0, dp = 1;
        for (int it = 0; it < 100; ++it) {
            LegendreAndDerivative(n, x, &p, &dp);
            double dx = p / dp;
            x -= dx;
            if (std::abs(dx) < 1e-17)
                break;
        }
        LegendreAndDerivative(n, x, &p, &dp);
        double w = 2 / ((1 - x * x) * dp * dp);
        // Roots come out descending in x; store ascending on [0,1].
        r.x[i] = 0.5 * (1 - x);
        r.w[i] = 0.5 * w;
    }
    return r;
}

struct Tables {
    GaussRule gauss[kMaxGauss + 1];
    // wp[n][a][i] = w_a P~_i(x_a) for the n-point rule (order up to kMaxOrder).
    double wp[kMaxGauss + 1][kMaxGauss][kMaxOrder + 1];
    // Two-scale matrices per order and child, N x N row-major, double and float.
    double two_scale[kMaxOrder + 1][4][kMaxCoeffs * kMaxCoeffs];
    float two_scale_f[kMaxOrder + 1][4][kMaxCoeffs * kMaxCoeffs];
    float two_scale_ft[kMaxOrder + 1][4][kMaxCoeffs * kMaxCoeffs];  // transposed (Push)

    Tables() {
        for (int n = 1; n <= kMaxGauss; ++n) {
            gauss[n] = MakeGauss(n);
            for (int a = 0; a < n; ++a) {
                double p[kMaxOrder + 1];
                Legendre(kMaxOrder, gauss[n].x[a], p);
                for (int i = 0; i <= kMaxOrder; ++i)
                    wp[n][a][i] = gauss[n].w[a] * p[i];
            }
        }
        // 1-D halves: h[half][m][k] = int_0^1 P~_k((u+half)/2) P~_m(u) du, exact with the
        // 4-point rule (integrand degree <= 6).
        double h[2][kMaxOrder + 1][kMaxOrder + 1];
        const GaussRule& g = gauss[4];
        for (int half = 0; half < 2; ++half) {
            for (int m = 0; m <= kMaxOrder; ++m) {
                for (int k = 0; k <= kMaxOrder; ++k)
                    h[half][m][k] = 0;
            }
            for (int a = 0; a < g.n; ++a) {
                double pc[kMaxOrder + 1], pp[kMaxOrder + 1];
                Legendre(kMaxOrder, g.x[a], pc);
                Legendre(kMaxOrder, 0.5 * (g.x[a] + half), pp);
                for (int m = 0; m <= kMaxOrder; ++m) {
                    for (int k = 0; k <= kMaxOrder; ++k)
                        h[half][m][k] += g.w[a] * pc[m] * pp[k];
                }
            }
        }
        // Legendre degrees are nested, so the order-M matrix is the leading block of the
        // order-3 one in 1-D; build each order's tensor product separately.
        for (int order = 0; order <= kMaxOrder; ++order) {
            const int m1 = order + 1, nn = m1 * m1;
            for (int c = 0; c < 4; ++c) {
                const int qs = c & 1, qt = c >> 1;
                for (int jm = 0; jm < m1; ++jm) {
                    for (int im = 0; im < m1; ++im) {
                        for (int jk = 0; jk < m1; ++jk) {
                            for (int ik = 0; ik < m1; ++ik) {
                                double v = h[qt][jm][jk] * h[qs][im][ik];
                                // P~_k restricted to a half has exactly zero components of
                                // degree > k; keep the zeros exact.
                                if (std::abs(v) < 1e-14)
                                    v = 0;
                                int row = CoeffIndex(order, im, jm);
                                int col = CoeffIndex(order, ik, jk);
                                two_scale[order][c][row * nn + col] = v;
                                two_scale_f[order][c][row * nn + col] = float(v);
                                two_scale_ft[order][c][col * nn + row] = float(v);
                            }
                        }
                    }
                }
            }
        }
    }
};

const Tables& T() {
    static const Tables tables;
    return tables;
}

}  // namespace

void Legendre(int order, double s, double* p) {
    DCHECK(order >= 0 && order <= kMaxOrder);
    const double x = 2 * s - 1;
    p[0] = 1;
    if (order >= 1)
        p[1] = 1.7320508075688772 * x;  // sqrt(3)
    if (order >= 2)
        p[2] = 2.23606797749979 * (1.5 * x * x - 0.5);  // sqrt(5)
    if (order >= 3)
        p[3] = 2.6457513110645907 * x * (2.5 * x * x - 1.5);  // sqrt(7)
}

void EvalBasis(int order, double s, double t, double* phi) {
    double ps[kMaxOrder + 1], pt[kMaxOrder + 1];
    Legendre(order, s, ps);
    Legendre(order, t, pt);
    for (int j = 0; j <= order; ++j) {
        for (int i = 0; i <= order; ++i)
            phi[CoeffIndex(order, i, j)] = ps[i] * pt[j];
    }
}

const GaussRule& Gauss(int n) {
    CHECK(n >= 1 && n <= kMaxGauss);
    return T().gauss[n];
}

void GaussPoint2D(int n, int p, double* s, double* t, double* weight) {
    const GaussRule& g = Gauss(n);
    DCHECK(p >= 0 && p < n * n);
    const int a = p % n, c = p / n;
    *s = g.x[a];
    *t = g.x[c];
    *weight = g.w[a] * g.w[c];
}

double ControlPoint(int g, int a) {
    DCHECK(g >= 1 && a >= 0 && a < g);
    return g == 1 ? 0.5 : double(a) / double(g - 1);
}

namespace {

// EvalCoeffs' sums with the coefficient count known at compile time (unrolled: the same
// sums in the same order, so the same bits, at a fraction of the loop's cost).
template <int N>
void SumBlocks(const float* coeffs, int count, const double* phi, float* out) {
    for (int b = 0; b < count; ++b) {
        const float* c = coeffs + b * N;
        double v = 0;
        for (int k = 0; k < N; ++k)
            v += c[k] * phi[k];
        out[b] = float(v);
    }
}

}  // namespace

void EvalCoeffs(int order, const float* coeffs, int count, double s, double t, float* out) {
    static_assert(kMaxOrder == 3);
    double phi[kMaxCoeffs];
    EvalBasis(order, s, t, phi);
    switch (NumCoeffs(order)) {
    case 1: return SumBlocks<1>(coeffs, count, phi, out);
    case 4: return SumBlocks<4>(coeffs, count, phi, out);
    case 9: return SumBlocks<9>(coeffs, count, phi, out);
    default: return SumBlocks<16>(coeffs, count, phi, out);
    }
}

void EvalTensorGrid(int order, const float* coeffs, int count, const double* xs, int ns,
                    const double* ts, int nt, float* out) {
    CHECK(order >= 0 && order <= kMaxOrder);
    CHECK(ns >= 1 && ns <= kMaxGrid && nt >= 1 && nt <= kMaxGrid);
    const int m1 = order + 1, nn = m1 * m1;
    double ps[kMaxGrid][kMaxOrder + 1], pt[kMaxGrid][kMaxOrder + 1];
    for (int a = 0; a < ns; ++a)
        Legendre(order, xs[a], ps[a]);
    for (int c = 0; c < nt; ++c)
        Legendre(order, ts[c], pt[c]);
    for (int b = 0; b < count; ++b) {
        const float* cb = coeffs + b * nn;
        for (int c = 0; c < nt; ++c) {
            // Contract along t first: row[i] = sum_j c_ij P~_j(t_c).
            double row[kMaxOrder + 1];
            for (int i = 0; i < m1; ++i) {
                double v = 0;
                for (int j = 0; j < m1; ++j)
                    v += cb[CoeffIndex(order, i, j)] * pt[c][j];
                row[i] = v;
            }
            for (int a = 0; a < ns; ++a) {
                double v = 0;
                for (int i = 0; i < m1; ++i)
                    v += row[i] * ps[a][i];
                out[(a + ns * c) * count + b] = float(v);
            }
        }
    }
}

void EvalGauss(int order, int n, const float* coeffs, int count, float* out) {
    const GaussRule& g = Gauss(n);
    EvalTensorGrid(order, coeffs, count, g.x, n, g.x, n, out);
}

void EvalControlGrid(int order, int g, const float* coeffs, int count, float* out) {
    CHECK(g >= 1 && g <= kMaxGrid);
    double x[kMaxGrid];
    for (int a = 0; a < g; ++a)
        x[a] = ControlPoint(g, a);
    EvalTensorGrid(order, coeffs, count, x, g, x, g, out);
}

void ProjectGauss(int order, int n, const float* values, int count, float* coeffs) {
    CHECK(order >= 0 && order <= kMaxOrder);
    CHECK(n >= order + 1 && n <= kMaxGauss);
    const Tables& tab = T();
    const auto& wp = tab.wp[n];
    const int m1 = order + 1, nn = m1 * m1;
    for (int b = 0; b < count; ++b) {
        double acc[kMaxCoeffs] = {};
        for (int c = 0; c < n; ++c) {
            // Reduce along s for row c, then spread along t.
            double row[kMaxOrder + 1] = {};
            for (int a = 0; a < n; ++a) {
                const double v = values[(a + n * c) * count + b];
                for (int i = 0; i < m1; ++i)
                    row[i] += wp[a][i] * v;
            }
            for (int j = 0; j < m1; ++j) {
                for (int i = 0; i < m1; ++i)
                    acc[CoeffIndex(order, i, j)] += wp[c][j] * row[i];
            }
        }
        for (int k = 0; k < nn; ++k)
            coeffs[b * nn + k] = float(acc[k]);
    }
}

float ControlGridError(int order, int g, const float* coeffs, int count, const float* values) {
    CHECK(g >= 1 && g <= kMaxGrid);
    CHECK(count >= 1 && count <= 64);
    double x[kMaxGrid];
    for (int a = 0; a < g; ++a)
        x[a] = ControlPoint(g, a);
    // One grid row at a time keeps the scratch small (TBB worker stacks).
    float fit[kMaxGrid * 64];
    float err = 0;
    for (int c = 0; c < g; ++c) {
        EvalTensorGrid(order, coeffs, count, x, g, &x[c], 1, fit);
        const float* v = values + c * g * count;
        for (int i = 0; i < g * count; ++i)
            err = std::fmax(err, std::abs(fit[i] - v[i]));
    }
    return err;
}

const double* TwoScaleMatrix(int order, int child) {
    CHECK(order >= 0 && order <= kMaxOrder && child >= 0 && child < 4);
    return T().two_scale[order][child];
}

namespace {
// Push and Pull with the matrix size a compile-time constant (one instance per order): the
// compiler unrolls the products and computes the independent outputs side by side (4x
// faster Pull at M2 than with N known at run time), each output still summed in the
// order written, so the bits are those of the plain loops.
// pt: the two-scale matrix transposed, so that every output m takes its k-th term at once.
template <int kN, bool kAdd>
void PushN(const float* pt, const float* parent, int count, float* out) {
    for (int b = 0; b < count; ++b) {
        const float* x = parent + b * kN;
        float* y = out + b * kN;
        float v[kN] = {};
        for (int k = 0; k < kN; ++k) {
            const float xk = x[k];
            for (int m = 0; m < kN; ++m)
                v[m] += pt[k * kN + m] * xk;
        }
        for (int m = 0; m < kN; ++m) {
            if constexpr (kAdd) {
                y[m] += v[m];
            } else {
                y[m] = v[m];
            }
        }
    }
}

template <int kN>
void PullN(const float* const p[4], const float* const children[4], int count, float* parent) {
    for (int b = 0; b < count; ++b) {
        float acc[kN] = {};
        for (int c = 0; c < 4; ++c) {
            const float* y = children[c] + b * kN;
            for (int m = 0; m < kN; ++m) {
                const float ym = y[m];
                for (int k = 0; k < kN; ++k)
                    acc[k] += p[c][m * kN + k] * ym;
            }
        }
        for (int k = 0; k < kN; ++k)
            parent[b * kN + k] = 0.25f * acc[k];
    }
}

template <bool kAdd>
void PushImpl(int order, int child, const float* parent, int count, float* out) {
    CHECK(order >= 0 && order <= kMaxOrder && child >= 0 && child < 4);
    const float* p = T().two_scale_ft[order][child];
    static_assert(kMaxOrder == 3);
    switch (order) {
    case 0: return PushN<1, kAdd>(p, parent, count, out);
    case 1: return PushN<4, kAdd>(p, parent, count, out);
    case 2: return PushN<9, kAdd>(p, parent, count, out);
    default: return PushN<16, kAdd>(p, parent, count, out);
    }
}
}  // namespace

void Push(int order, int child, const float* parent, int count, float* child_coeffs) {
    PushImpl<false>(order, child, parent, count, child_coeffs);
}

void PushAdd(int order, int child, const float* parent, int count, float* child_coeffs) {
    PushImpl<true>(order, child, parent, count, child_coeffs);
}

void Pull(int order, const float* const children[4], int count, float* parent) {
    CHECK(order >= 0 && order <= kMaxOrder);
    const auto& ts = T().two_scale_f[order];
    const float* const p[4] = {ts[0], ts[1], ts[2], ts[3]};
    switch (order) {
    case 0: return PullN<1>(p, children, count, parent);
    case 1: return PullN<4>(p, children, count, parent);
    case 2: return PullN<9>(p, children, count, parent);
    default: return PullN<16>(p, children, count, parent);
    }
}

}  // namespace mebake::solve
