// Local/global refinement, Liu et al. 2008 (see arap.h).
//
// Energy: sum_T A_T |J_T - L_T|_F^2, J_T the 2x2 Jacobian of the uv map in the triangle's
// own isometric frame, L_T its target (see ArapTarget below). Local step: the closest target
// per triangle, in closed form. Global step: a cotangent-Laplacian solve whose matrix never
// changes, so it is factorized once and each iteration costs two back-substitutions.
// Both steps lower the energy, so the energy decrease is the stopping test.
#include "stream/arap.h"

#include "core/check.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mebake::stream {

uint32_t CountFlips(std::span<const Vec2d> uv, std::span<const std::array<uint32_t, 3>> triangles) {
    uint32_t flips = 0;
    for (const auto& f : triangles) {
        const double a = Cross(uv[f[1]] - uv[f[0]], uv[f[2]] - uv[f[0]]);
        if (!(a > 0))
            ++flips;
    }
    return flips;
}

// The target of one triangle's Jacobian J = [[a, b], [c, d]]. Split J = C + A into its
// conformal part C = [[e, -h], [h, e]] = q Rot and anticonformal part A = [[f, g], [g, -f]]
// = r Refl: the singular values are q + r and q - r, and the matrix with J's singular
// vectors and singular values (t1, t2) is ((t1 + t2) / 2) C / q + ((t1 - t2) / 2) A / r,
// so no trigonometry is needed. ARAP: t1 = t2 = 1 (the closest rotation, also for a
// reflected J). Authalic weight w: (t1, t2) = (1 - w) (1, 1) + w (s, 1/s), with (s, 1/s)
// the closest unit-determinant pair to (q + r, q - r), s clamped to [lo, hi] (hi^2 the
// largest anisotropy).
std::array<double, 4> ArapTarget(double a, double b, double c, double d, double w, double lo,
                                 double hi) {
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    const double q = std::sqrt(e * e + h * h), r = std::sqrt(f * f + g * g);
    if (!(q > 0))
        return {1, 0, 0, 1};
    const double s1 = q + r, s2 = q - r;
    double t1 = 1, t2 = 1;
    if (w > 0 && s2 > 0) {
        // minimize (s1 - s)^2 + (s2 - 1/s)^2: s^4 - s1 s^3 + s2 s - 1 = 0. Newton from
        // sqrt(s1 / s2), the root when s1 s2 = 1; the polynomial is convex beyond it.
        double s = std::sqrt(s1 / s2);
        for (int it = 0; it < 20; ++it) {
            const double fv = ((s - s1) * s * s) * s + s2 * s - 1;
            const double df = (4 * s - 3 * s1) * s * s + s2;
            if (!(df > 0))
                break;
            const double step = fv / df;
            s = std::max(s - step, 0.5 * s);
            if (std::abs(step) < 1e-12 * s)
                break;
        }
        s = std::clamp(s, lo, hi);
        t1 = (1 - w) + w * s;
        t2 = (1 - w) + w / s;
    }
    const double cw = 0.5 * (t1 + t2) / q;
    const double aw = r > 0 ? 0.5 * (t1 - t2) / r : 0;
    return {cw * e + aw * f, -cw * h + aw * g, cw * h + aw * g, cw * e - aw * f};
}

#if defined(__SSE2__)
namespace {
using V = __m128d;  // two lanes: two triangles
V Select(V mask, V yes, V no) {
    return _mm_or_pd(_mm_and_pd(mask, yes), _mm_andnot_pd(mask, no));
}
V Add(V x, V y) { return _mm_add_pd(x, y); }
V Sub(V x, V y) { return _mm_sub_pd(x, y); }
V Mul(V x, V y) { return _mm_mul_pd(x, y); }
V Div(V x, V y) { return _mm_div_pd(x, y); }
V Less(V x, V y) { return _mm_cmplt_pd(x, y); }
V Splat(double x) { return _mm_set1_pd(x); }
}  // namespace
#endif

// ArapTarget of kArapBatch triangles, lane by lane the same operations in the same order
// (SSE2's packed add, multiply, divide and square root round as the scalar ones do; both
// sides of a branch are computed and the lane's own is kept). The Newton steps of the
// batch run side by side: one triangle's steps wait on their divisions, four overlap.
void ArapTargetBatch(const ArapJacobians& j, double w, double lo, double hi,
                     std::array<std::array<double, 4>, kArapBatch>* out) {
#if defined(__SSE2__)
    constexpr int K = kArapBatch / 2;  // vectors
    const V half = Splat(0.5), one = Splat(1), zero = Splat(0), sign = Splat(-0.0);
    V e[K], f[K], g[K], h[K], q[K], r[K], q_pos[K], s1[K], s2[K], newton[K], t1[K], t2[K];
    int any = 0;
    for (int k = 0; k < K; ++k) {
        const V A = _mm_loadu_pd(&j.a[2 * k]), B = _mm_loadu_pd(&j.b[2 * k]),
                C = _mm_loadu_pd(&j.c[2 * k]), D = _mm_loadu_pd(&j.d[2 * k]);
        e[k] = Mul(half, Add(A, D));
        f[k] = Mul(half, Sub(A, D));
        g[k] = Mul(half, Add(C, B));
        h[k] = Mul(half, Sub(C, B));
        q[k] = _mm_sqrt_pd(Add(Mul(e[k], e[k]), Mul(h[k], h[k])));
        r[k] = _mm_sqrt_pd(Add(Mul(f[k], f[k]), Mul(g[k], g[k])));
        q_pos[k] = Less(zero, q[k]);
        s1[k] = Add(q[k], r[k]);
        s2[k] = Sub(q[k], r[k]);
        newton[k] = w > 0 ? _mm_and_pd(q_pos[k], Less(zero, s2[k])) : zero;
        t1[k] = t2[k] = one;
        any |= _mm_movemask_pd(newton[k]);
    }
    if (any) {
        const V four = Splat(4), three = Splat(3), tiny = Splat(1e-12);
        V s[K], run[K];  // run: lanes still stepping
        for (int k = 0; k < K; ++k) {
            s[k] = _mm_sqrt_pd(Div(s1[k], s2[k]));
            run[k] = newton[k];
        }
        for (int it = 0; it < 20 && any; ++it) {
            any = 0;
            for (int k = 0; k < K; ++k) {
                const V fv = Sub(Add(Mul(Mul(Mul(Sub(s[k], s1[k]), s[k]), s[k]), s[k]),
                                     Mul(s2[k], s[k])),
                                 one);
                const V df =
                    Add(Mul(Mul(Sub(Mul(four, s[k]), Mul(three, s1[k])), s[k]), s[k]), s2[k]);
                run[k] = _mm_and_pd(run[k], Less(zero, df));
                const V step = Div(fv, df);
                const V x = Sub(s[k], step), y = Mul(half, s[k]);
                s[k] = Select(run[k], Select(Less(x, y), y, x), s[k]);  // std::max(x, y)
                run[k] = _mm_andnot_pd(Less(_mm_andnot_pd(sign, step), Mul(tiny, s[k])), run[k]);
                any |= _mm_movemask_pd(run[k]);
            }
        }
        const V L = Splat(lo), H = Splat(hi), keep = Splat(1 - w), W = Splat(w);
        for (int k = 0; k < K; ++k) {
            const V m = Select(Less(s[k], L), L, s[k]);  // std::clamp: min(max(s, lo), hi)
            s[k] = Select(Less(H, m), H, m);
            t1[k] = Select(newton[k], Add(keep, Mul(W, s[k])), one);
            t2[k] = Select(newton[k], Add(keep, Div(W, s[k])), one);
        }
    }
    for (int k = 0; k < K; ++k) {
        const V cw = Div(Mul(half, Add(t1[k], t2[k])), q[k]);
        const V aw = Select(Less(zero, r[k]), Div(Mul(half, Sub(t1[k], t2[k])), r[k]), zero);
        const V neg_cw = _mm_xor_pd(cw, sign);
        alignas(16) double v[4][2];
        _mm_store_pd(v[0], Select(q_pos[k], Add(Mul(cw, e[k]), Mul(aw, f[k])), one));
        _mm_store_pd(v[1], Select(q_pos[k], Add(Mul(neg_cw, h[k]), Mul(aw, g[k])), zero));
        _mm_store_pd(v[2], Select(q_pos[k], Add(Mul(cw, h[k]), Mul(aw, g[k])), zero));
        _mm_store_pd(v[3], Select(q_pos[k], Sub(Mul(cw, e[k]), Mul(aw, f[k])), one));
        for (int l = 0; l < 2; ++l)
            (*out)[size_t(2 * k + l)] = {v[0][l], v[1][l], v[2][l], v[3][l]};
    }
#else
    for (size_t l = 0; l < kArapBatch; ++l)
        (*out)[l] = ArapTarget(j.a[l], j.b[l], j.c[l], j.d[l], w, lo, hi);
#endif
}

namespace {

// The closest targets to the current Jacobians, kArapBatch triangles at a time; returns the
// normalized energy.
double LocalStep(std::span<const FlatTriangle> flat,
                 std::span<const std::array<uint32_t, 3>> triangles, std::span<const Vec2d> uv,
                 double authalic_weight, double max_anisotropy,
                 std::vector<std::array<double, 4>>* target_out, std::vector<double>* energy) {
    const double hi = std::sqrt(max_anisotropy), lo = 1 / hi;
    ParallelForRange(
        0, int64_t(triangles.size()),
        [&](int64_t begin, int64_t end) {
            for (int64_t t = begin; t < end; t += kArapBatch) {
                const int lanes = int(std::min<int64_t>(kArapBatch, end - t));
                // J = [[a, b], [c, d]]: rows u and v, columns x and y of the flat frame
                // (lanes past the end stay 0: their target is the identity, unused).
                ArapJacobians jac{};
                for (int l = 0; l < lanes; ++l) {
                    const FlatTriangle& ft = flat[size_t(t + l)];
                    const auto& f = triangles[size_t(t + l)];
                    for (int k = 0; k < 3; ++k) {
                        const Vec2d& p = uv[f[k]];
                        jac.a[l] += p.x * ft.grad[k].x;
                        jac.b[l] += p.x * ft.grad[k].y;
                        jac.c[l] += p.y * ft.grad[k].x;
                        jac.d[l] += p.y * ft.grad[k].y;
                    }
                }
                std::array<std::array<double, 4>, kArapBatch> target;
                ArapTargetBatch(jac, authalic_weight, lo, hi, &target);
                for (int l = 0; l < lanes; ++l) {
                    const size_t i = size_t(t + l);
                    const std::array<double, 4>& tg = target[size_t(l)];
                    (*target_out)[i] = tg;
                    const double da = jac.a[l] - tg[0], db = jac.b[l] - tg[1],
                                 dc = jac.c[l] - tg[2], dd = jac.d[l] - tg[3];
                    (*energy)[i] = flat[i].area * (da * da + db * db + dc * dc + dd * dd);
                }
            }
        },
        1024);
    double sum = 0, area = 0;
    for (size_t t = 0; t < triangles.size(); ++t) {  // fixed order: deterministic
        sum += (*energy)[t];
        area += flat[t].area;
    }
    return area > 0 ? sum / area : 0;
}

}  // namespace

ArapReport RefineArap(std::span<const FlatTriangle> flat,
                      std::span<const std::array<uint32_t, 3>> triangles,
                      const CotanLaplacian& laplacian, uint32_t anchor, const ArapOptions& options,
                      std::vector<Vec2d>* uv) {
    CHECK_EQ(flat.size(), triangles.size());
    CHECK_EQ(laplacian.row().size(), uv->size());
    CHECK_LT(anchor, uv->size());
    CHECK_EQ(laplacian.row()[anchor], CotanLaplacian::kFixed);
    ArapReport report;
    const std::vector<uint32_t>& row = laplacian.row();
    const size_t n = laplacian.size();
    constexpr uint32_t kFixed = CotanLaplacian::kFixed;

    std::vector<std::array<double, 4>> target(triangles.size());
    std::vector<double> tri_energy(triangles.size());
    auto local_step = [&](std::span<const Vec2d> at) {
        return LocalStep(flat, triangles, at, options.authalic_weight,
                         options.max_target_anisotropy, &target, &tri_energy);
    };
    report.initial_energy = local_step(*uv);
    report.final_energy = report.initial_energy;
    if (n == 0 || options.max_iterations <= 0)
        return report;

    const uint32_t start_flips = CountFlips(*uv, triangles);
    const Vec2d fixed = (*uv)[anchor];
    std::vector<Vec2d> next(*uv);
    std::vector<double> rhs(2 * n);  // u column, then v column
    for (int it = 0; it < options.max_iterations; ++it) {
        // Global step: L x_c = sum_T A_T (row c of the target) . grad_i, minus the
        // anchor's column.
        std::fill(rhs.begin(), rhs.end(), 0.0);
        for (size_t t = 0; t < triangles.size(); ++t) {
            const FlatTriangle& ft = flat[t];
            if (ft.area == 0)
                continue;
            const auto& r = target[t];
            const auto& f = triangles[t];
            const bool at_anchor = f[0] == anchor || f[1] == anchor || f[2] == anchor;
            for (int i = 0; i < 3; ++i) {
                const uint32_t ri = row[f[i]];
                if (ri == kFixed)
                    continue;
                rhs[ri] += ft.area * (r[0] * ft.grad[i].x + r[1] * ft.grad[i].y);
                rhs[ri + n] += ft.area * (r[2] * ft.grad[i].x + r[3] * ft.grad[i].y);
                for (int j = 0; at_anchor && j < 3; ++j) {
                    if (f[j] != anchor)
                        continue;
                    const double k = CotanWeight(ft, i, j);
                    rhs[ri] -= k * fixed.x;
                    rhs[ri + n] -= k * fixed.y;
                }
            }
        }
        if (!laplacian.Solve(&rhs, 2)) {
            report.solver_failed = true;
            break;
        }
        for (size_t v = 0; v < row.size(); ++v)
            if (row[v] != kFixed)
                next[v] = Vec2d(rhs[row[v]], rhs[row[v] + n]);
        if (options.guard_flips && CountFlips(next, triangles) > start_flips) {
            report.stopped_by_flip = true;
            break;
        }
        const double energy = local_step(next);
        uv->swap(next);
        ++report.iterations;
        const double previous = report.final_energy;
        report.final_energy = energy;
        if (previous - energy <= options.relative_tolerance * previous)
            break;
    }
    return report;
}

}  // namespace mebake::stream
