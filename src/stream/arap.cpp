// Local/global refinement, Liu et al. 2008 (see arap.h).
//
// Energy: sum_T A_T |J_T - L_T|_F^2, J_T the 2x2 Jacobian of the uv map in the triangle's
// own isometric frame, L_T its target (see Target below). Local step: the closest target
// per triangle, in closed form. Global step: a cotangent-Laplacian solve whose matrix never
// changes, so it is factorized once and each iteration costs two back-substitutions.
// Both steps lower the energy, so the energy decrease is the stopping test.
#include "stream/arap.h"

#include "core/check.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>

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

namespace {

// The target of one triangle's Jacobian J = [[a, b], [c, d]]. Split J = C + A into its
// conformal part C = [[e, -h], [h, e]] = q Rot and anticonformal part A = [[f, g], [g, -f]]
// = r Refl: the singular values are q + r and q - r, and the matrix with J's singular
// vectors and singular values (t1, t2) is ((t1 + t2) / 2) C / q + ((t1 - t2) / 2) A / r,
// so no trigonometry is needed. ARAP: t1 = t2 = 1 (the closest rotation, also for a
// reflected J). Authalic weight w: (t1, t2) = (1 - w) (1, 1) + w (s, 1/s), with (s, 1/s)
// the closest unit-determinant pair to (q + r, q - r), s^2 capped by max_anisotropy.
std::array<double, 4> Target(double a, double b, double c, double d, double w,
                             double max_anisotropy) {
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
        const double limit = std::sqrt(max_anisotropy);
        s = std::clamp(s, 1 / limit, limit);
        t1 = (1 - w) + w * s;
        t2 = (1 - w) + w / s;
    }
    const double cw = 0.5 * (t1 + t2) / q;
    const double aw = r > 0 ? 0.5 * (t1 - t2) / r : 0;
    return {cw * e + aw * f, -cw * h + aw * g, cw * h + aw * g, cw * e - aw * f};
}

// The closest targets to the current Jacobians; returns the normalized
// energy.
double LocalStep(std::span<const FlatTriangle> flat,
                 std::span<const std::array<uint32_t, 3>> triangles, std::span<const Vec2d> uv,
                 double authalic_weight, double max_anisotropy,
                 std::vector<std::array<double, 4>>* target_out, std::vector<double>* energy) {
    ParallelForRange(
        0, int64_t(triangles.size()),
        [&](int64_t lo, int64_t hi) {
            for (int64_t t = lo; t < hi; ++t) {
                const FlatTriangle& ft = flat[t];
                const auto& f = triangles[t];
                // J = [[a, b], [c, d]]: rows u and v, columns x and y of the flat frame.
                double a = 0, b = 0, c = 0, d = 0;
                for (int j = 0; j < 3; ++j) {
                    const Vec2d& p = uv[f[j]];
                    a += p.x * ft.grad[j].x;
                    b += p.x * ft.grad[j].y;
                    c += p.y * ft.grad[j].x;
                    d += p.y * ft.grad[j].y;
                }
                const std::array<double, 4> target =
                    Target(a, b, c, d, authalic_weight, max_anisotropy);
                (*target_out)[t] = target;
                const double da = a - target[0], db = b - target[1], dc = c - target[2],
                             dd = d - target[3];
                (*energy)[t] = ft.area * (da * da + db * db + dc * dc + dd * dd);
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
            for (int i = 0; i < 3; ++i) {
                const uint32_t ri = row[triangles[t][i]];
                if (ri == kFixed)
                    continue;
                rhs[ri] += ft.area * (r[0] * ft.grad[i].x + r[1] * ft.grad[i].y);
                rhs[ri + n] += ft.area * (r[2] * ft.grad[i].x + r[3] * ft.grad[i].y);
                for (int j = 0; j < 3; ++j) {
                    if (triangles[t][j] != anchor)
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
