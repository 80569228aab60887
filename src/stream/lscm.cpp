// Least Squares Conformal Maps, Lévy et al. 2002 (see lscm.h).
//
// Per triangle the Cauchy-Riemann residuals of the linear map are u_x - v_y and u_y + v_x;
// LSCM minimizes their area-weighted squares. The normal equations are assembled directly
// (sum of the 6x6 blocks M_T^T M_T) and solved by a sparse LDL^T with AMD ordering, which
// on these planar-graph systems beats (preconditioned) conjugate gradients by a wide
// margin at every chart size we measured, and is deterministic.
#include "stream/lscm.h"

#include <Eigen/Sparse>

#include <cmath>

#include "core/check.h"

namespace mebake::stream {

FlatTriangle FlattenTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    FlatTriangle t;
    const Vec3d e1 = p1 - p0, e2 = p2 - p0;
    const Vec3d n = Cross(e1, e2);
    const double twice_area = Length(n);
    const double l1 = Length(e1);
    const double scale = Dot(e1, e1) + Dot(e2, e2) + Dot(p2 - p1, p2 - p1);
    // Angles below ~1e-12 rad: the gradients would be ~1e12 and swamp the solve.
    if (!(twice_area > 1e-12 * scale) || !(l1 > 0)) return t;
    const Vec3d ax = e1 / l1;
    const Vec3d ay = Cross(n / twice_area, ax);
    // Local coordinates: x0 = (0,0), x1 = (l1, 0), x2 = (e2.ax, e2.ay), counter-clockwise.
    const Vec2d x[3] = {{0, 0}, {l1, 0}, {Dot(e2, ax), Dot(e2, ay)}};
    // grad phi_j = rot90(x_{j+2} - x_{j+1}) / (2A), rot90(a, b) = (-b, a).
    for (int j = 0; j < 3; ++j) {
        const Vec2d e = x[(j + 2) % 3] - x[(j + 1) % 3];
        t.grad[j] = Vec2d(-e.y, e.x) / twice_area;
    }
    t.area = 0.5 * twice_area;
    return t;
}

std::vector<FlatTriangle> FlattenTriangles(std::span<const Vec3f> position,
                                           std::span<const std::array<uint32_t, 3>> triangles) {
    std::vector<FlatTriangle> flat(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
        const auto& f = triangles[t];
        flat[t] = FlattenTriangle(Vec3d(position[f[0]]), Vec3d(position[f[1]]),
                                  Vec3d(position[f[2]]));
    }
    return flat;
}

bool SolveLscm(std::span<const FlatTriangle> flat,
               std::span<const std::array<uint32_t, 3>> triangles, uint32_t vertex_count,
               uint32_t pin0, uint32_t pin1, double pin_distance, std::vector<Vec2d>* uv) {
    CHECK_EQ(flat.size(), triangles.size());
    CHECK_LT(pin0, vertex_count);
    CHECK_LT(pin1, vertex_count);
    CHECK_NE(pin0, pin1);
    uv->assign(vertex_count, Vec2d(0, 0));
    (*uv)[pin1] = Vec2d(pin_distance, 0);

    // Free unknowns: referenced, unpinned vertices, (u, v) interleaved.
    constexpr uint32_t kFixed = ~uint32_t(0);
    std::vector<uint32_t> index(vertex_count, kFixed);
    std::vector<char> used(vertex_count, 0);
    for (const auto& f : triangles)
        for (uint32_t v : f) used[v] = 1;
    uint32_t free_count = 0;
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (used[v] && v != pin0 && v != pin1) index[v] = free_count++;
    if (free_count == 0) return true;

    const Eigen::Index n = Eigen::Index(2) * free_count;
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(triangles.size() * 36);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
    for (size_t t = 0; t < triangles.size(); ++t) {
        const FlatTriangle& ft = flat[t];
        if (ft.area == 0) continue;
        const double w = std::sqrt(ft.area);
        // Rows of M_T over (u0 u1 u2 v0 v1 v2): sqrt(A) (u_x - v_y) and sqrt(A) (u_y + v_x).
        double m[2][6];
        for (int j = 0; j < 3; ++j) {
            m[0][j] = w * ft.grad[j].x;
            m[0][3 + j] = -w * ft.grad[j].y;
            m[1][j] = w * ft.grad[j].y;
            m[1][3 + j] = w * ft.grad[j].x;
        }
        uint32_t var[6];
        double fixed_value[6];
        for (int j = 0; j < 6; ++j) {
            const uint32_t vtx = triangles[t][j % 3];
            const int comp = j / 3;
            var[j] = index[vtx] == kFixed ? kFixed : 2 * index[vtx] + comp;
            fixed_value[j] = comp == 0 ? (*uv)[vtx].x : (*uv)[vtx].y;
        }
        for (int a = 0; a < 6; ++a) {
            if (var[a] == kFixed) continue;
            for (int b = 0; b < 6; ++b) {
                const double k = m[0][a] * m[0][b] + m[1][a] * m[1][b];
                if (var[b] == kFixed)
                    rhs[var[a]] -= k * fixed_value[b];
                else if (var[b] <= var[a])  // lower triangle is all LDL^T reads
                    triplets.emplace_back(var[a], var[b], k);
            }
        }
    }
    Eigen::SparseMatrix<double> matrix(n, n);
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    triplets = {};
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
    solver.compute(matrix);
    if (solver.info() != Eigen::Success) return false;
    const Eigen::VectorXd x = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !x.allFinite()) return false;
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (index[v] != kFixed) (*uv)[v] = Vec2d(x[2 * index[v]], x[2 * index[v] + 1]);
    return true;
}

}  // namespace mebake::stream
