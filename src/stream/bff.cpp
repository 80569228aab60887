// Boundary First Flattening, Sawhney and Crane 2017 (see bff.h).
//
// With A the (positive) cotangent Laplacian, Omega_i = 2 pi - (angle sum) the angle defect
// of an interior vertex and k_b = pi - (angle sum) the turning angle of a boundary vertex:
//  1. the log scale factor u that flattens the interior, with u = 0 on the boundary:
//     A_II u_I = -Omega_I;
//  2. the flattened boundary's turning angles k~_b = k_b + (A u)_b (the discrete
//     transformation law of geodesic curvature; they sum to 2 pi by Gauss-Bonnet);
//  3. the boundary polygon from k~ and the 3D edge lengths, closed by the least change
//     of lengths sum (l* - l)^2 / l subject to sum l* T = 0 (paper, section 4.2);
//  4. the interior as the harmonic extension of the polygon: A_II x_I = -A_IB x_B.
// The harmonic extension is not exactly conformal (the paper extends x and takes y as its
// conjugate); the refinement that follows makes the difference moot.
#include "stream/bff.h"

#include "core/check.h"

#include <cmath>
#include <numbers>

namespace mebake::stream {

bool FlattenBff(std::span<const Vec3f> position, std::span<const FlatTriangle> flat,
                std::span<const std::array<uint32_t, 3>> triangles,
                std::span<const uint32_t> boundary, std::vector<Vec2d>* uv) {
    CHECK_EQ(flat.size(), triangles.size());
    constexpr double kPi = std::numbers::pi;
    const size_t vertex_count = position.size();
    const size_t nb = boundary.size();
    if (nb < 3)
        return false;
    std::vector<char> on_boundary(vertex_count, 0);
    for (uint32_t b : boundary)
        on_boundary[b] = 1;

    std::vector<double> angle_sum(vertex_count, 0.0);
    for (const auto& f : triangles) {
        for (int k = 0; k < 3; ++k) {
            const Vec3d p(position[f[k]]);
            const Vec3d a = Vec3d(position[f[(k + 1) % 3]]) - p;
            const Vec3d b = Vec3d(position[f[(k + 2) % 3]]) - p;
            angle_sum[f[k]] += std::atan2(Length(Cross(a, b)), Dot(a, b));
        }
    }

    CotanLaplacian interior;
    if (!interior.Factorize(flat, triangles, on_boundary))
        return false;
    const std::vector<uint32_t>& row = interior.row();
    const size_t n = interior.size();
    constexpr uint32_t kFixed = CotanLaplacian::kFixed;

    // 1. Scale factors: A_II u_I = -Omega_I.
    std::vector<double> u(vertex_count, 0.0);
    {
        std::vector<double> rhs(n);
        for (size_t v = 0; v < vertex_count; ++v)
            if (row[v] != kFixed)
                rhs[row[v]] = angle_sum[v] - 2 * kPi;
        if (!interior.Solve(&rhs, 1))
            return false;
        for (size_t v = 0; v < vertex_count; ++v)
            if (row[v] != kFixed)
                u[v] = rhs[row[v]];
    }
    // 2. Target turning angles k~_b = k_b + (A u)_b (u_B = 0, so only interior columns).
    std::vector<double> turning(vertex_count, 0.0);
    for (uint32_t b : boundary)
        turning[b] = kPi - angle_sum[b];
    for (size_t t = 0; t < triangles.size(); ++t) {
        if (flat[t].area == 0)
            continue;
        for (int i = 0; i < 3; ++i) {
            const uint32_t vi = triangles[t][i];
            if (!on_boundary[vi])
                continue;
            for (int j = 0; j < 3; ++j) {
                const uint32_t vj = triangles[t][j];
                if (!on_boundary[vj])
                    turning[vi] += CotanWeight(flat[t], i, j) * u[vj];
            }
        }
    }
    // 3. Boundary polygon: edge j runs from boundary[j] to boundary[j + 1].
    std::vector<double> length(nb);
    std::vector<Vec2d> tangent(nb);
    double phi = 0;
    double m00 = 0, m01 = 0, m11 = 0;
    Vec2d sum(0, 0);
    for (size_t j = 0; j < nb; ++j) {
        if (j > 0)
            phi += turning[boundary[j]];
        tangent[j] = Vec2d(std::cos(phi), std::sin(phi));
        length[j] = Length(Vec3d(position[boundary[(j + 1) % nb]]) - Vec3d(position[boundary[j]]));
        m00 += length[j] * tangent[j].x * tangent[j].x;
        m01 += length[j] * tangent[j].x * tangent[j].y;
        m11 += length[j] * tangent[j].y * tangent[j].y;
        sum += tangent[j] * length[j];
    }
    // l*_j = l_j (1 - T_j . lambda), M lambda = sum_j l_j T_j, M = sum_j l_j T_j T_j^T.
    const double det = m00 * m11 - m01 * m01;
    if (!(std::abs(det) > 1e-300))
        return false;
    const Vec2d lambda((m11 * sum.x - m01 * sum.y) / det, (m00 * sum.y - m01 * sum.x) / det);
    uv->assign(vertex_count, Vec2d(0, 0));
    Vec2d at(0, 0);
    for (size_t j = 0; j < nb; ++j) {
        (*uv)[boundary[j]] = at;
        const double l = length[j] * (1 - Dot(tangent[j], lambda));
        if (!(l > 0))
            return false;
        at += tangent[j] * l;
    }
    // 4. Harmonic extension: A_II x_I = -A_IB x_B.
    if (n == 0)
        return true;
    std::vector<double> rhs(2 * n, 0.0);
    for (size_t t = 0; t < triangles.size(); ++t) {
        if (flat[t].area == 0)
            continue;
        for (int i = 0; i < 3; ++i) {
            const uint32_t ri = row[triangles[t][i]];
            if (ri == kFixed)
                continue;
            for (int j = 0; j < 3; ++j) {
                const uint32_t vj = triangles[t][j];
                if (!on_boundary[vj])
                    continue;
                const double w = CotanWeight(flat[t], i, j);
                rhs[ri] -= w * (*uv)[vj].x;
                rhs[ri + n] -= w * (*uv)[vj].y;
            }
        }
    }
    if (!interior.Solve(&rhs, 2))
        return false;
    for (size_t v = 0; v < vertex_count; ++v)
        if (row[v] != kFixed)
            (*uv)[v] = Vec2d(rhs[row[v]], rhs[row[v] + n]);
    return true;
}

}  // namespace mebake::stream
