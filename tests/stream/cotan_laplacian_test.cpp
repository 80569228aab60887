#include "stream/cotan_laplacian.h"

#include <Eigen/Sparse>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace mebake::stream {
namespace {

// An n x n grid over a bumpy height field, interior vertices jittered, random diagonals.
void BumpyGrid(int n, uint32_t seed, std::vector<Vec3f>* position,
               std::vector<std::array<uint32_t, 3>>* triangles) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jit(-0.3, 0.3);
    std::bernoulli_distribution coin(0.5);
    const double h = 1.0 / (n - 1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const bool inside = i > 0 && i < n - 1 && j > 0 && j < n - 1;
            const double x = i * h + (inside ? jit(rng) * h : 0);
            const double y = j * h + (inside ? jit(rng) * h : 0);
            position->push_back(Vec3f(Vec3d(x, y, 0.2 * std::sin(7 * x) * std::cos(5 * y))));
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const uint32_t a = uint32_t(j * n + i), b = a + 1, c = a + uint32_t(n), d = c + 1;
            if (coin(rng)) {
                triangles->push_back({a, b, d});
                triangles->push_back({a, d, c});
            } else {
                triangles->push_back({a, b, c});
                triangles->push_back({b, d, c});
            }
        }
}

// Solve's columns done together give, bit for bit, what Eigen's SimplicialLDLT::solve
// gives on the same matrix (built here as Factorize builds it), for one and two columns,
// with the boundary fixed (BFF's interior) and with one pin (the refinement's), and with
// zeros in the right-hand side (Eigen skips those in its lower solve).
TEST(CotanLaplacian, SolveGivesEigensBits) {
    for (uint32_t seed = 1; seed <= 6; ++seed) {
        std::vector<Vec3f> position;
        std::vector<std::array<uint32_t, 3>> triangles;
        const int n = 8 + int(seed) * 5;
        BumpyGrid(n, seed, &position, &triangles);
        const std::vector<FlatTriangle> flat = FlattenTriangles(position, triangles);
        for (int pinned = 0; pinned < 2; ++pinned) {
            std::vector<char> fixed(position.size(), 0);
            if (pinned) {
                fixed[seed % position.size()] = 1;
            } else {
                for (int i = 0; i < n; ++i) {
                    fixed[size_t(i)] = fixed[size_t((n - 1) * n + i)] = 1;
                    fixed[size_t(i * n)] = fixed[size_t(i * n + n - 1)] = 1;
                }
            }
            CotanLaplacian lap;
            ASSERT_TRUE(lap.Factorize(flat, triangles, fixed));
            const uint32_t size = lap.size();
            ASSERT_GT(size, 10u);
            // The reference: Eigen on the same lower triangle, in the same triplet order.
            std::vector<Eigen::Triplet<double>> triplets;
            for (size_t t = 0; t < triangles.size(); ++t) {
                if (flat[t].area == 0)
                    continue;
                for (int i = 0; i < 3; ++i) {
                    const uint32_t ri = lap.row()[triangles[t][i]];
                    if (ri == CotanLaplacian::kFixed)
                        continue;
                    for (int j = 0; j < 3; ++j) {
                        const uint32_t rj = lap.row()[triangles[t][j]];
                        if (rj == CotanLaplacian::kFixed || rj > ri)
                            continue;
                        triplets.emplace_back(ri, rj, CotanWeight(flat[t], i, j));
                    }
                }
            }
            Eigen::SparseMatrix<double> matrix(size, size);
            matrix.setFromTriplets(triplets.begin(), triplets.end());
            Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(matrix);
            ASSERT_EQ(ldlt.info(), Eigen::Success);
            std::mt19937 rng(seed * 7 + uint32_t(pinned));
            std::uniform_real_distribution<double> value(-1, 1);
            for (int columns = 1; columns <= 2; ++columns) {
                std::vector<double> b(size_t(columns) * size);
                for (size_t r = 0; r < b.size(); ++r)
                    b[r] = r % 5 == 0 ? 0.0 : value(rng);
                Eigen::Map<Eigen::MatrixXd> m(b.data(), size, columns);
                const Eigen::MatrixXd want = ldlt.solve(m);
                ASSERT_TRUE(lap.Solve(&b, columns));
                ASSERT_EQ(size_t(want.size()), b.size());
                EXPECT_EQ(std::memcmp(want.data(), b.data(), b.size() * sizeof(double)), 0)
                    << "seed " << seed << " pinned " << pinned << " columns " << columns;
            }
        }
    }
}

}  // namespace
}  // namespace mebake::stream
