// Triangle flattening and the factorized cotangent Laplacian (see cotan_laplacian.h).
#include "stream/cotan_laplacian.h"

#include "core/check.h"

#include <Eigen/Sparse>
#include <cmath>
#include <type_traits>

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

namespace {

// Eigen's AMDOrdering (OrderingMethods/Ordering.h) for the matrix SimplicialLDLT hands its
// ordering, the full selfadjoint matrix: AMDOrdering first builds A^T + A, whose pattern is
// then A's own, in the same sorted order, so the AMD routine gets a plain copy of A here
// (the same permutation, without the transpose and the sparse sum; test
// CotanLaplacian.SolveGivesEigensBits factorizes with Eigen's default and compares bits).
struct SymmetricAmdOrdering {
    using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
    template <typename MatrixType>
    void operator()(const MatrixType& a, PermutationType& perm) {
        Eigen::SparseMatrix<typename MatrixType::Scalar, Eigen::ColMajor, int> pattern = a;
        Eigen::internal::minimum_degree_ordering(pattern, perm);
    }
};

}  // namespace

struct CotanLaplacian::Impl {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, SymmetricAmdOrdering> ldlt;
    std::vector<double> inverse_d;  // 1 / D, as Eigen's solve computes it
    // Solve's scratch, kept for the next solve (one thread solves with one Laplacian) and
    // freed with the Laplacian.
    std::vector<double> x;
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
    if (impl_->ldlt.info() != Eigen::Success)
        return false;
    const Eigen::VectorXd d = impl_->ldlt.vectorD();
    impl_->inverse_d.resize(size_);
    for (uint32_t i = 0; i < size_; ++i)
        impl_->inverse_d[i] = 1.0 / d[i];
    return true;
}

// Eigen's SimplicialLDLT::solve (Eigen 3.4, SimplicialCholesky.h and SparseCore/
// TriangularSolver.h) with its columns done together: x = P b, the unit lower solve by
// columns of L, x_i = (1 / d_i) x_i, the unit upper solve by rows of L^T, b = P^-1 x. Each
// column sees Eigen's operations in Eigen's order (the same bits, test
// CotanLaplacian.SolveGivesEigensBits); L's indices and values are read once for all
// columns, and a row's columns sit side by side.
bool CotanLaplacian::Solve(std::vector<double>* b, int columns) const {
    CHECK_EQ(b->size(), size_t(columns) * size_);
    if (size_ == 0)
        return true;
    const auto& ldlt = impl_->ldlt;
    if (ldlt.info() != Eigen::Success)
        return false;
    const size_t n = size_, k = size_t(columns);
    const auto& L = ldlt.matrixL().nestedExpression();
    const int* p = nullptr;
    const int* pinv = nullptr;
    if (ldlt.permutationP().size() > 0) {
        p = ldlt.permutationP().indices().data();
        pinv = ldlt.permutationPinv().indices().data();
    }
    // x[r * k + c]: row r of column c, after the permutation.
    std::vector<double>& x = impl_->x;
    x.resize(n * k);
    for (size_t c = 0; c < k; ++c)
        for (size_t r = 0; r < n; ++r)
            x[(p ? size_t(p[r]) : r) * k + c] = (*b)[c * n + r];
    using Iter = std::decay_t<decltype(L)>::InnerIterator;
    const bool triangular = L.nonZeros() > 0;  // otherwise L = I
    if (triangular) {
        for (size_t i = 0; i < n; ++i) {
            Iter start(L, Eigen::Index(i));
            while (start && size_t(start.index()) < i)
                ++start;
            if (start && size_t(start.index()) == i)
                ++start;
            if (k == 2 && x[2 * i] != 0 && x[2 * i + 1] != 0) {  // the usual case
                const double t0 = x[2 * i], t1 = x[2 * i + 1];
                for (Iter it = start; it; ++it) {
                    const size_t j = 2 * size_t(it.index());
                    x[j] -= t0 * it.value();
                    x[j + 1] -= t1 * it.value();
                }
                continue;
            }
            for (size_t c = 0; c < k; ++c) {
                const double t = x[i * k + c];
                if (t == 0)  // Eigen skips a zero (its sparse right-hand side shortcut)
                    continue;
                for (Iter it = start; it; ++it)
                    x[size_t(it.index()) * k + c] -= t * it.value();
            }
        }
    }
    for (size_t i = 0; i < n; ++i) {
        const double inv = impl_->inverse_d[i];
        for (size_t c = 0; c < k; ++c)
            x[i * k + c] = inv * x[i * k + c];
    }
    if (triangular) {
        double tmp[2];
        for (size_t i = n; i-- > 0;) {
            Iter it(L, Eigen::Index(i));
            while (it && size_t(it.index()) < i)
                ++it;
            if (it && size_t(it.index()) == i)
                ++it;
            if (k == 2) {  // the usual case (u and v), both in one pass
                tmp[0] = x[2 * i];
                tmp[1] = x[2 * i + 1];
                for (; it; ++it) {
                    const size_t j = 2 * size_t(it.index());
                    tmp[0] -= it.value() * x[j];
                    tmp[1] -= it.value() * x[j + 1];
                }
                x[2 * i] = tmp[0];
                x[2 * i + 1] = tmp[1];
                continue;
            }
            for (size_t c = 0; c < k; ++c) {
                double t = x[i * k + c];
                for (Iter jt = it; jt; ++jt)
                    t -= jt.value() * x[size_t(jt.index()) * k + c];
                x[i * k + c] = t;
            }
        }
    }
    bool finite = true;
    for (size_t c = 0; c < k; ++c)
        for (size_t r = 0; r < n; ++r) {
            const double v = x[r * k + c];
            (*b)[c * n + (pinv ? size_t(pinv[r]) : r)] = v;
            finite &= std::isfinite(v);
        }
    return finite;
}

}  // namespace mebake::stream
