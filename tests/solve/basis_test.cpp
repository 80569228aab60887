#include "solve/basis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

TEST(Basis, GaussRulesIntegrateMonomialsExactly) {
    for (int n = 1; n <= kMaxGauss; ++n) {
        const GaussRule& g = Gauss(n);
        EXPECT_EQ(g.n, n);
        for (int a = 1; a < n; ++a)
            EXPECT_LT(g.x[a - 1], g.x[a]);
        for (int d = 0; d <= 2 * n - 1; ++d) {
            double sum = 0;
            for (int a = 0; a < n; ++a)
                sum += g.w[a] * std::pow(g.x[a], d);
            EXPECT_NEAR(sum, 1.0 / (d + 1), 1e-14) << "n=" << n << " degree=" << d;
        }
        // Degree 2n is not integrated exactly: the rule has the expected order, not more.
        double sum = 0;
        for (int a = 0; a < n; ++a)
            sum += g.w[a] * std::pow(g.x[a] - 0.5, 2 * n);
        EXPECT_GT(std::abs(sum - std::pow(0.5, 2 * n) / (2 * n + 1)), 1e-12) << "n=" << n;
    }
    EXPECT_NEAR(Gauss(2).x[0], 0.5 - 0.5 / std::sqrt(3.0), 1e-15);
    EXPECT_NEAR(Gauss(3).w[1], 4.0 / 9.0, 1e-15);
}

TEST(Basis, GaussPoint2DIsTensorProduct) {
    double s, t, w, wsum = 0;
    for (int p = 0; p < 9; ++p) {
        GaussPoint2D(3, p, &s, &t, &w);
        EXPECT_EQ(s, Gauss(3).x[p % 3]);
        EXPECT_EQ(t, Gauss(3).x[p / 3]);
        wsum += w;
    }
    EXPECT_NEAR(wsum, 1.0, 1e-15);
}

TEST(Basis, LegendreIsOrthonormalOnTheNode) {
    double p[4];
    Legendre(3, 0.8, p);
    EXPECT_DOUBLE_EQ(p[0], 1.0);
    EXPECT_NEAR(p[1], std::sqrt(3.0) * (2 * 0.8 - 1), 1e-15);
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        std::vector<double> gram(nn * nn, 0.0);
        double phi[kMaxCoeffs];
        for (int q = 0; q < 64; ++q) {
            double s, t, w;
            GaussPoint2D(8, q, &s, &t, &w);
            EvalBasis(order, s, t, phi);
            for (int a = 0; a < nn; ++a) {
                for (int b = 0; b < nn; ++b)
                    gram[a * nn + b] += w * phi[a] * phi[b];
            }
        }
        for (int a = 0; a < nn; ++a) {
            for (int b = 0; b < nn; ++b)
                EXPECT_NEAR(gram[a * nn + b], a == b ? 1 : 0, 1e-13);
        }
    }
}

// Random coefficients, and the same function sampled on a tensor grid of points.
std::vector<float> RandomCoeffs(int order, int count, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> c(NumCoeffs(order) * count);
    for (float& v : c)
        v = u(rng);
    return c;
}

TEST(Basis, ProjectionRecoversPolynomialsForEveryRuleSize) {
    std::mt19937 rng(1);
    const int count = 9;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        auto c = RandomCoeffs(order, count, rng);
        for (int n = order + 1; n <= kMaxGauss; ++n) {
            std::vector<float> values(n * n * count), back(nn * count);
            EvalGauss(order, n, c.data(), count, values.data());
            ProjectGauss(order, n, values.data(), count, back.data());
            for (int i = 0; i < nn * count; ++i)
                EXPECT_NEAR(back[i], c[i], 2e-6);
        }
    }
}

TEST(Basis, ProjectionDropsHigherDegreesWhenTheRuleIsLargeEnough) {
    // f(s,t) = P~_{M+1}(s) P~_1(t) is orthogonal to the order-M space; a rule with
    // 2n-1 >= 2M+1 sees that exactly.
    for (int order = 0; order < kMaxOrder; ++order) {
        const int n = order + 1;
        std::vector<float> values(n * n);
        const GaussRule& g = Gauss(n);
        double ps[4], pt[4];
        for (int c = 0; c < n; ++c) {
            for (int a = 0; a < n; ++a) {
                Legendre(order + 1, g.x[a], ps);
                Legendre(1, g.x[c], pt);
                values[a + n * c] = float(ps[order + 1] * pt[order >= 1 ? 1 : 0]);
            }
        }
        std::vector<float> coeffs(NumCoeffs(order));
        ProjectGauss(order, n, values.data(), 1, coeffs.data());
        for (float v : coeffs)
            EXPECT_NEAR(v, 0.0f, 1e-6) << "order " << order;
    }
}

TEST(Basis, CollocationInterpolatesAtTheGaussPoints) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0, 10);
    const int count = 3;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int n = order + 1, nn = NumCoeffs(order);
        std::vector<float> values(n * n * count), coeffs(nn * count), back(n * n * count);
        for (float& v : values)
            v = u(rng);
        ProjectGauss(order, n, values.data(), count, coeffs.data());
        EvalGauss(order, n, coeffs.data(), count, back.data());
        for (size_t i = 0; i < values.size(); ++i)
            EXPECT_NEAR(back[i], values[i], 1e-4);
        // The control grid avoids the Gauss points, so random data shows a fit error there
        // (order 0 has one Gauss point and 2x2 corners: still nonzero for random data).
        const int g = DefaultControlGrid(order);
        for (int a = 0; a < g; ++a) {
            for (int k = 0; k < n; ++k)
                EXPECT_NE(ControlPoint(g, a), Gauss(n).x[k]);
        }
    }
}

TEST(Basis, EvalCoeffsMatchesTensorGridAndBasis) {
    std::mt19937 rng(3);
    const int order = 3, count = 2, nn = NumCoeffs(order);
    auto c = RandomCoeffs(order, count, rng);
    const double xs[3] = {0.0, 0.3, 1.0}, ts[2] = {0.25, 0.9};
    float grid[6 * count];
    EvalTensorGrid(order, c.data(), count, xs, 3, ts, 2, grid);
    for (int ci = 0; ci < 2; ++ci) {
        for (int a = 0; a < 3; ++a) {
            float out[count];
            EvalCoeffs(order, c.data(), count, xs[a], ts[ci], out);
            double phi[kMaxCoeffs];
            EvalBasis(order, xs[a], ts[ci], phi);
            for (int b = 0; b < count; ++b) {
                double ref = 0;
                for (int k = 0; k < nn; ++k)
                    ref += c[b * nn + k] * phi[k];
                EXPECT_NEAR(out[b], ref, 1e-5);
                EXPECT_NEAR(grid[(a + 3 * ci) * count + b], ref, 1e-5);
            }
        }
    }
}

// EvalCoeffs' unrolled sums are the plain loop's, to the bit, for every order and block
// count (the light map's bytes depend on it).
TEST(Basis, EvalCoeffsIsThePlainSumToTheBit) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> at(0, 1);
    for (int order = 0; order <= kMaxOrder; ++order)
        for (int count : {1, 3, 9}) {
            const int nn = NumCoeffs(order);
            const auto c = RandomCoeffs(order, count, rng);
            for (int p = 0; p < 50; ++p) {
                const double s = at(rng), t = at(rng);
                float out[9];
                EvalCoeffs(order, c.data(), count, s, t, out);
                double phi[kMaxCoeffs];
                EvalBasis(order, s, t, phi);
                for (int b = 0; b < count; ++b) {
                    double v = 0;
                    for (int k = 0; k < nn; ++k)
                        v += c[size_t(b * nn + k)] * phi[k];
                    EXPECT_EQ(out[b], float(v)) << order << " " << count << " " << b;
                }
            }
        }
}

TEST(Basis, ControlGridErrorIsZeroForRepresentableFunctions) {
    std::mt19937 rng(4);
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int g = DefaultControlGrid(order), count = 9;
        auto c = RandomCoeffs(order, count, rng);
        std::vector<float> values(g * g * count);
        EvalControlGrid(order, g, c.data(), count, values.data());
        EXPECT_LT(ControlGridError(order, g, c.data(), count, values.data()), 1e-6);
        values[5] += 0.5f;
        EXPECT_NEAR(ControlGridError(order, g, c.data(), count, values.data()), 0.5f, 1e-5);
    }
}

TEST(Basis, FitErrorOfASmoothFunctionDropsWithOrder) {
    // exp(s + 2t) fitted by collocation: the control-grid error must shrink with the order.
    float prev = 1e9f;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int n = order + 1, g = DefaultControlGrid(order);
        std::vector<float> values(n * n), coeffs(NumCoeffs(order)), control(g * g);
        for (int p = 0; p < n * n; ++p) {
            double s, t, w;
            GaussPoint2D(n, p, &s, &t, &w);
            values[p] = float(std::exp(s + 2 * t));
        }
        ProjectGauss(order, n, values.data(), 1, coeffs.data());
        for (int c = 0; c < g; ++c) {
            for (int a = 0; a < g; ++a)
                control[a + g * c] = float(std::exp(ControlPoint(g, a) + 2 * ControlPoint(g, c)));
        }
        float err = ControlGridError(order, g, coeffs.data(), 1, control.data());
        EXPECT_LT(err, prev * 0.5f) << "order " << order;
        std::printf("order %d control-grid error %g\n", order, err);
        prev = err;
    }
    EXPECT_LT(prev, 0.15f);  // of a range of e^3 ~ 20
}

TEST(Basis, PushIsTheExactRestrictionToEachQuadrant) {
    std::mt19937 rng(5);
    const int count = 9;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        auto parent = RandomCoeffs(order, count, rng);
        for (int child = 0; child < 4; ++child) {
            std::vector<float> cc(nn * count);
            Push(order, child, parent.data(), count, cc.data());
            const int qs = child & 1, qt = child >> 1;
            for (double u : {0.0, 0.2, 0.7, 1.0}) {
                for (double v : {0.0, 0.4, 0.95}) {
                    float a[count], b[count];
                    EvalCoeffs(order, cc.data(), count, u, v, a);
                    EvalCoeffs(order, parent.data(), count, (u + qs) / 2, (v + qt) / 2, b);
                    for (int k = 0; k < count; ++k)
                        EXPECT_NEAR(a[k], b[k], 2e-5);
                }
            }
            // PushAdd accumulates.
            std::vector<float> acc(cc);
            PushAdd(order, child, parent.data(), count, acc.data());
            for (int i = 0; i < nn * count; ++i)
                EXPECT_NEAR(acc[i], 2 * cc[i], 1e-6);
        }
    }
}

TEST(Basis, TwoScaleMatricesSatisfyThePartitionIdentity) {
    // (1/4) sum_c P_c^T P_c = I: the children together represent the parent exactly.
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        for (int a = 0; a < nn; ++a) {
            for (int b = 0; b < nn; ++b) {
                double sum = 0;
                for (int c = 0; c < 4; ++c) {
                    const double* p = TwoScaleMatrix(order, c);
                    for (int m = 0; m < nn; ++m)
                        sum += p[m * nn + a] * p[m * nn + b];
                }
                EXPECT_NEAR(sum / 4, a == b ? 1.0 : 0.0, 1e-14);
            }
        }
        // The constant maps to the constant in every child.
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(TwoScaleMatrix(order, c)[0], 1.0, 1e-15);
    }
}

TEST(Basis, PullOfPushIsIdentity) {
    std::mt19937 rng(6);
    const int count = 9;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        auto parent = RandomCoeffs(order, count, rng);
        std::vector<float> kids[4], back(nn * count);
        const float* ptr[4];
        for (int c = 0; c < 4; ++c) {
            kids[c].resize(nn * count);
            Push(order, c, parent.data(), count, kids[c].data());
            ptr[c] = kids[c].data();
        }
        Pull(order, ptr, count, back.data());
        for (int i = 0; i < nn * count; ++i)
            EXPECT_NEAR(back[i], parent[i], 2e-6);
    }
}

// Push and Pull run with compile-time sizes and Push's loops turned (basis.cpp): the bits
// must be those of the plain products, each output summed in the same order, for
// coefficients of both signs and zeros.
TEST(Basis, PushAndPullGiveTheDenseProductsBits) {
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-3.f, 3.f);
    const int count = 9;
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        for (int trial = 0; trial < 50; ++trial) {
            std::vector<float> parent(size_t(nn * count)), kids[4];
            for (float& x : parent)
                x = trial % 5 == 0 && u(rng) < 0 ? 0.f : u(rng);
            const float* ptr[4];
            for (int c = 0; c < 4; ++c) {
                const double* p = TwoScaleMatrix(order, c);
                std::vector<float> want(size_t(nn * count)), got(size_t(nn * count), 1.f);
                for (int b = 0; b < count; ++b)
                    for (int m = 0; m < nn; ++m) {
                        float v = 0;
                        for (int k = 0; k < nn; ++k)
                            v += float(p[m * nn + k]) * parent[size_t(b * nn + k)];
                        want[size_t(b * nn + m)] = v;
                    }
                Push(order, c, parent.data(), count, got.data());
                ASSERT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(float)), 0)
                    << "order " << order << " child " << c;
                kids[c] = got;
                ptr[c] = kids[c].data();
            }
            std::vector<float> want(size_t(nn * count)), got(size_t(nn * count));
            for (int b = 0; b < count; ++b) {
                float acc[kMaxCoeffs] = {};
                for (int c = 0; c < 4; ++c) {
                    const double* p = TwoScaleMatrix(order, c);
                    for (int m = 0; m < nn; ++m)
                        for (int k = 0; k < nn; ++k)
                            acc[k] += float(p[m * nn + k]) * ptr[c][b * nn + m];
                }
                for (int k = 0; k < nn; ++k)
                    want[size_t(b * nn + k)] = 0.25f * acc[k];
            }
            Pull(order, ptr, count, got.data());
            ASSERT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(float)), 0)
                << "order " << order;
        }
    }
}

TEST(Basis, PullIsTheL2ProjectionOfThePiecewiseChildren) {
    std::mt19937 rng(7);
    for (int order = 0; order <= kMaxOrder; ++order) {
        const int nn = NumCoeffs(order);
        std::vector<float> kids[4];
        const float* ptr[4];
        for (int c = 0; c < 4; ++c) {
            kids[c] = RandomCoeffs(order, 1, rng);
            ptr[c] = kids[c].data();
        }
        std::vector<float> parent(nn);
        Pull(order, ptr, 1, parent.data());
        // Reference: integrate child(x) * phi_k(x) over each quadrant with an exact rule.
        std::vector<double> ref(nn, 0.0);
        for (int c = 0; c < 4; ++c) {
            const int qs = c & 1, qt = c >> 1;
            for (int p = 0; p < 16; ++p) {
                double u, v, w;
                GaussPoint2D(4, p, &u, &v, &w);
                float val;
                EvalCoeffs(order, kids[c].data(), 1, u, v, &val);
                double phi[kMaxCoeffs];
                EvalBasis(order, (u + qs) / 2, (v + qt) / 2, phi);
                for (int k = 0; k < nn; ++k)
                    ref[k] += 0.25 * w * val * phi[k];
            }
        }
        for (int k = 0; k < nn; ++k)
            EXPECT_NEAR(parent[k], ref[k], 2e-6) << order << " " << k;
    }
}

}  // namespace
}  // namespace mebake::solve
