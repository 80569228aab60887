// Least Squares Conformal Maps, Lévy et al. 2002 (see lscm.h).
//
// Per triangle the Cauchy-Riemann residuals of the linear map are u_x - v_y and u_y + v_x;
// LSCM minimizes their area-weighted squares. The normal equations are assembled directly
// (the 6x6 blocks M_T^T M_T) and solved by sparse LDL^T. Measured alternative: conjugate
// gradients preconditioned by the factorized cotangent Laplacian (the LSCM matrix is
// blockdiag(L, L) minus a boundary-only area term) needed ~250-320 iterations for 1e-8 on
// 10K-100K vertex charts and was 5-8x slower than the direct solve: every discrete
// holomorphic function is a near-null mode, so the spectrum does not cluster.
#include "stream/lscm.h"

#include "core/check.h"

#include <Eigen/Sparse>
#include <cmath>

namespace mebake::stream {

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
        for (uint32_t v : f)
            used[v] = 1;
    uint32_t free_count = 0;
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (used[v] && v != pin0 && v != pin1)
            index[v] = free_count++;
    if (free_count == 0)
        return true;

    const Eigen::Index n = Eigen::Index(2) * free_count;
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(triangles.size() * 36);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
    for (size_t t = 0; t < triangles.size(); ++t) {
        const FlatTriangle& ft = flat[t];
        if (ft.area == 0)
            continue;
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
            if (var[a] == kFixed)
                continue;
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
    if (solver.info() != Eigen::Success)
        return false;
    const Eigen::VectorXd x = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !x.allFinite())
        return false;
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (index[v] != kFixed)
            (*uv)[v] = Vec2d(x[2 * index[v]], x[2 * index[v] + 1]);
    return true;
}

}  // namespace mebake::stream
