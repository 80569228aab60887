// Triangle flattening and the factorized cotangent Laplacian (see cotan_laplacian.h).
#include "stream/cotan_laplacian.h"

#include "core/check.h"

#include <Eigen/Sparse>
#include <cmath>

namespace mebake::stream {

FlatTriangle FlattenTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    FlatTriangle t;
    const Vec3d e1 = p1 - p0, e2 = p2 - p0;
    const Vec3d n = Cross(e1, e2);
    const double twice_area = Length(n);
    const double l1 = Length(e1);
    const double scale = Dot(e1, e1) + Dot(e2, e2) + Dot(p2 - p1, p2 - p1);
    // Angles below ~1e-12 rad: the gradients would be ~1e12 and swamp the solves.
    if (!(twice_area > 1e-12 * scale) || !(l1 > 0))
        return t;
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
        flat[t] =
            FlattenTriangle(Vec3d(position[f[0]]), Vec3d(position[f[1]]), Vec3d(position[f[2]]));
    }
    return flat;
}

struct CotanLaplacian::Impl {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
};

CotanLaplacian::CotanLaplacian() : impl_(std::make_unique<Impl>()) {}
CotanLaplacian::~CotanLaplacian() = default;

bool CotanLaplacian::Factorize(std::span<const FlatTriangle> flat,
                               std::span<const std::array<uint32_t, 3>> triangles,
                               std::span<const char> fixed) {
    CHECK_EQ(flat.size(), triangles.size());
    const size_t vertex_count = fixed.size();
    row_.assign(vertex_count, kFixed);
    std::vector<char> used(vertex_count, 0);
    for (const auto& f : triangles)
        for (uint32_t v : f)
            used[v] = 1;
    size_ = 0;
    for (size_t v = 0; v < vertex_count; ++v)
        if (used[v] && !fixed[v])
            row_[v] = size_++;
    if (size_ == 0)
        return true;

    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(triangles.size() * 6);
    for (size_t t = 0; t < triangles.size(); ++t) {
        if (flat[t].area == 0)
            continue;
        for (int i = 0; i < 3; ++i) {
            const uint32_t ri = row_[triangles[t][i]];
            if (ri == kFixed)
                continue;
            for (int j = 0; j < 3; ++j) {
                const uint32_t rj = row_[triangles[t][j]];
                if (rj == kFixed || rj > ri)
                    continue;  // lower triangle is all LDL^T reads
                triplets.emplace_back(ri, rj, CotanWeight(flat[t], i, j));
            }
        }
    }
    Eigen::SparseMatrix<double> matrix(size_, size_);
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    impl_->ldlt.compute(matrix);
    return impl_->ldlt.info() == Eigen::Success;
}

bool CotanLaplacian::Solve(std::vector<double>* b, int columns) const {
    CHECK_EQ(b->size(), size_t(columns) * size_);
    if (size_ == 0)
        return true;
    Eigen::Map<Eigen::MatrixXd> m(b->data(), size_, columns);
    m = impl_->ldlt.solve(m).eval();
    return m.allFinite();
}

}  // namespace mebake::stream
