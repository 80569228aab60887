// ARAP parameterization by local/global iterations, Liu et al. 2008 (see arap.h).
//
// Energy: sum_T A_T |J_T - R_T|_F^2, J_T the 2x2 Jacobian of the uv map in the triangle's
// own isometric frame, R_T a rotation. Local step: R_T = closest rotation to J_T, in closed
// form for 2x2 (angle atan2(c - b, a + d)). Global step: a cotangent-Laplacian solve
// whose matrix never changes, so it is factorized once and each iteration costs two
// back-substitutions.
#include "stream/arap.h"

#include <Eigen/Sparse>

#include <cmath>

#include "core/check.h"
#include "core/parallel.h"

namespace mebake::stream {

uint32_t CountFlips(std::span<const Vec2d> uv, std::span<const std::array<uint32_t, 3>> triangles) {
    uint32_t flips = 0;
    for (const auto& f : triangles) {
        const double a = Cross(uv[f[1]] - uv[f[0]], uv[f[2]] - uv[f[0]]);
        if (!(a > 0)) ++flips;
    }
    return flips;
}

namespace {

// J = Rot(phi) diag(s1, s2) Rot(theta) (closed-form 2x2 SVD); the target keeps the
// rotations and moves the singular values to (1 - w) (1, 1) + w (s, 1/s), (s, 1/s) the
// closest unit-determinant pair: w = 0 is ARAP, w = 1 the closest area-preserving map.
std::array<double, 4> BlendedTarget(double a, double b, double c, double d, double w) {
    const double e = 0.5 * (a + d), f = 0.5 * (a - d), g = 0.5 * (c + b), h = 0.5 * (c - b);
    const double q = std::hypot(e, h), r = std::hypot(f, g);
    const double s1 = q + r, s2 = q - r;
    const double a1 = std::atan2(g, f), a2 = std::atan2(h, e);
    const double theta = 0.5 * (a2 - a1), phi = 0.5 * (a2 + a1);
    double t1 = 1, t2 = 1;
    if (s2 > 0) {
        // minimize (s1 - s)^2 + (s2 - 1/s)^2: s^4 - s1 s^3 + s2 s - 1 = 0, Newton from
        // sqrt(s1 / s2) (exact when s1 s2 = 1).
        double s = std::sqrt(s1 / s2);
        for (int it = 0; it < 20; ++it) {
            const double fv = ((s - s1) * s * s) * s + s2 * s - 1;
            const double df = 4 * s * s * s - 3 * s1 * s * s + s2;
            if (!(df > 0)) break;
            const double step = fv / df;
            s = std::max(s - step, 0.5 * s);
            if (std::abs(step) < 1e-14 * s) break;
        }
        t1 = (1 - w) + w * s;
        t2 = (1 - w) + w / s;
    }
    const double cp = std::cos(phi), sp = std::sin(phi), ct = std::cos(theta),
                 st = std::sin(theta);
    // Rot(phi) diag(t1, t2) Rot(theta), Rot(x) = [[cos, -sin], [sin, cos]].
    const double m00 = t1 * ct, m01 = -t1 * st, m10 = t2 * st, m11 = t2 * ct;
    return {cp * m00 - sp * m10, cp * m01 - sp * m11, sp * m00 + cp * m10,
            sp * m01 + cp * m11};
}

// Closest targets (rotations for ARAP) to the current Jacobians; returns the normalized
// energy.
double LocalStep(std::span<const FlatTriangle> flat,
                 std::span<const std::array<uint32_t, 3>> triangles, std::span<const Vec2d> uv,
                 double authalic_weight, std::vector<std::array<double, 4>>* rotation,
                 std::vector<double>* energy) {
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
                std::array<double, 4> target;
                if (authalic_weight == 0) {
                    const double theta = std::atan2(c - b, a + d);
                    const double cs = std::cos(theta), sn = std::sin(theta);
                    target = {cs, -sn, sn, cs};
                } else {
                    target = BlendedTarget(a, b, c, d, authalic_weight);
                }
                (*rotation)[t] = target;
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
                      std::span<const std::array<uint32_t, 3>> triangles, uint32_t anchor,
                      const ArapOptions& options, std::vector<Vec2d>* uv) {
    CHECK_EQ(flat.size(), triangles.size());
    CHECK_LT(anchor, uv->size());
    ArapReport report;
    const uint32_t vertex_count = uint32_t(uv->size());

    constexpr uint32_t kFixed = ~uint32_t(0);
    std::vector<uint32_t> index(vertex_count, kFixed);
    std::vector<char> used(vertex_count, 0);
    for (const auto& f : triangles)
        for (uint32_t v : f) used[v] = 1;
    uint32_t free_count = 0;
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (used[v] && v != anchor) index[v] = free_count++;

    std::vector<std::array<double, 4>> rotation(triangles.size());
    std::vector<double> tri_energy(triangles.size());
    report.initial_energy = LocalStep(flat, triangles, *uv, options.authalic_weight, &rotation, &tri_energy);
    report.final_energy = report.initial_energy;
    if (free_count == 0 || options.max_iterations <= 0) return report;

    // L = sum_T A_T G_T G_T^T over free vertices (the cotangent Laplacian).
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(triangles.size() * 6);
    for (size_t t = 0; t < triangles.size(); ++t) {
        const FlatTriangle& ft = flat[t];
        if (ft.area == 0) continue;
        for (int i = 0; i < 3; ++i) {
            const uint32_t vi = index[triangles[t][i]];
            if (vi == kFixed) continue;
            for (int j = 0; j < 3; ++j) {
                const uint32_t vj = index[triangles[t][j]];
                if (vj == kFixed || vj > vi) continue;
                triplets.emplace_back(vi, vj, ft.area * Dot(ft.grad[i], ft.grad[j]));
            }
        }
    }
    Eigen::SparseMatrix<double> laplacian(free_count, free_count);
    laplacian.setFromTriplets(triplets.begin(), triplets.end());
    triplets = {};
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
    solver.compute(laplacian);
    if (solver.info() != Eigen::Success) {
        report.solver_failed = true;
        return report;
    }

    const uint32_t start_flips = CountFlips(*uv, triangles);
    const Vec2d fixed = (*uv)[anchor];
    std::vector<Vec2d> next(*uv);
    Eigen::MatrixX2d rhs(free_count, 2);
    for (int it = 0; it < options.max_iterations; ++it) {
        // Global step: L x_c = sum_T A_T (row c of R_T) . grad_i, minus the anchor's column.
        rhs.setZero();
        for (size_t t = 0; t < triangles.size(); ++t) {
            const FlatTriangle& ft = flat[t];
            if (ft.area == 0) continue;
            const auto& r = rotation[t];
            for (int i = 0; i < 3; ++i) {
                const uint32_t vi = index[triangles[t][i]];
                if (vi == kFixed) continue;
                rhs(vi, 0) += ft.area * (r[0] * ft.grad[i].x + r[1] * ft.grad[i].y);
                rhs(vi, 1) += ft.area * (r[2] * ft.grad[i].x + r[3] * ft.grad[i].y);
                for (int j = 0; j < 3; ++j) {
                    if (triangles[t][j] != anchor) continue;
                    const double k = ft.area * Dot(ft.grad[i], ft.grad[j]);
                    rhs(vi, 0) -= k * fixed.x;
                    rhs(vi, 1) -= k * fixed.y;
                }
            }
        }
        const Eigen::MatrixX2d x = solver.solve(rhs);
        if (solver.info() != Eigen::Success || !x.allFinite()) {
            report.solver_failed = true;
            break;
        }
        for (uint32_t v = 0; v < vertex_count; ++v)
            if (index[v] != kFixed) next[v] = Vec2d(x(index[v], 0), x(index[v], 1));
        if (options.guard_flips && CountFlips(next, triangles) > start_flips) {
            report.stopped_by_flip = true;
            break;
        }
        const double energy = LocalStep(flat, triangles, next, options.authalic_weight, &rotation, &tri_energy);
        uv->swap(next);
        ++report.iterations;
        const double previous = report.final_energy;
        report.final_energy = energy;
        if (previous - energy <= options.relative_tolerance * previous) break;
    }
    return report;
}

}  // namespace mebake::stream
