#include "solve/quadrature.h"

#include "solve/basis.h"
#include "solve/polygon_light.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

// Owning SoA sample set.
struct Samples {
    std::vector<float> px, py, pz, nx, ny, nz, w, r, g, b;
    void Add(Vec3f p, Vec3f n, float area, Vec3f rgb) {
        px.push_back(p.x);
        py.push_back(p.y);
        pz.push_back(p.z);
        nx.push_back(n.x);
        ny.push_back(n.y);
        nz.push_back(n.z);
        w.push_back(area);
        r.push_back(rgb.x);
        g.push_back(rgb.y);
        b.push_back(rgb.z);
    }
    EmitterSamples View() const { return {px, py, pz, nx, ny, nz, w, r, g, b}; }
};

// Gauss samples of the square [x0,x0+side]^2 at height z facing down.
Samples CeilingSamples(float x0, float side, float z, int cells, int n, Vec3f rgb) {
    Samples s;
    const GaussRule& g = Gauss(n);
    const float cell = side / cells;
    for (int ci = 0; ci < cells; ++ci) {
        for (int cj = 0; cj < cells; ++cj) {
            for (int a = 0; a < n; ++a) {
                for (int c = 0; c < n; ++c) {
                    Vec3f p{x0 + cell * (ci + float(g.x[a])), x0 + cell * (cj + float(g.x[c])), z};
                    s.Add(p, {0, 0, -1}, float(g.w[a] * g.w[c]) * cell * cell, rgb);
                }
            }
        }
    }
    return s;
}

Vec3d Colour(const RgbVector& e, int c) {
    return {e.e[3 * c], e.e[3 * c + 1], e.e[3 * c + 2]};
}

TEST(Quadrature, SingleSampleIsTheTransportFormula) {
    Samples s;
    const Vec3f y{0.3f, -0.2f, 2.0f}, n = Normalize(Vec3f{0.1f, 0.2f, -1.0f});
    s.Add(y, n, 0.01f, {1.0f, 2.0f, 0.5f});
    const Vec3f x{0.1f, 0.4f, 0.2f};
    RgbVector e;
    AccumulateTransfer(s.View(), {}, x, &e, Kernel::kPoint);
    const Vec3d d = Vec3d(y) - Vec3d(x);
    const double r2 = Dot(d, d);
    const double f = Dot(Vec3d(x) - Vec3d(y), Vec3d(n)) * 0.01 / (M_PI * r2 * r2);
    for (int c = 0; c < 3; ++c) {
        const double b = c == 0 ? 1.0 : (c == 1 ? 2.0 : 0.5);
        const Vec3d ref = d * (b * f);
        EXPECT_NEAR(Length(Colour(e, c) - ref) / Length(ref), 0.0, 1e-6);
    }
    // The disc kernel differs by the factor pi r^2 / (pi r^2 + w).
    RgbVector ed;
    AccumulateTransfer(s.View(), {}, x, &ed, Kernel::kDisk);
    EXPECT_NEAR(ed.e[2] / e.e[2], M_PI * r2 / (M_PI * r2 + 0.01), 1e-6);
}

TEST(Quadrature, GaussSampledSquareMatchesLambertsFormula) {
    // Unit square at z = 1 facing down with B = pi L; receivers below it.
    const float L = 1.5f;
    Samples s = CeilingSamples(0, 1, 1, 4, 8, {float(M_PI) * L, 0, float(M_PI) * 2 * L});
    std::vector<Vec3d> poly = {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}};
    const Vec3f xs[] = {{0.5f, 0.5f, 0.0f}, {-0.3f, 0.2f, 0.4f}, {1.4f, 1.2f, -0.5f}};
    for (const Vec3f& x : xs) {
        const Vec3d ref = VectorIrradiance(poly, L, Vec3d(x));
        RgbVector ep, ed;
        AccumulateTransfer(s.View(), {}, x, &ep, Kernel::kPoint);
        AccumulateTransfer(s.View(), {}, x, &ed, Kernel::kDisk);
        EXPECT_LT(Length(Colour(ep, 0) - ref) / Length(ref), 2e-6);
        EXPECT_LT(Length(Colour(ep, 2) - ref * 2.0) / Length(ref * 2.0), 2e-6);
        EXPECT_EQ(Length(Colour(ep, 1)), 0.0);
        // Disc regularization: bias below max w / (pi r^2) (cells of 1/4, Gauss weights).
        EXPECT_LT(Length(Colour(ed, 0) - ref) / Length(ref), 2e-3);
    }
}

TEST(Quadrature, BackFacingAndInvisibleSamplesDoNotContribute) {
    Samples s = CeilingSamples(0, 1, 1, 1, 4, {1, 1, 1});
    RgbVector above;
    AccumulateTransfer(s.View(), {}, {0.5f, 0.5f, 2.0f}, &above);
    for (double v : above.e)
        EXPECT_EQ(v, 0.0);

    const Vec3f x{0.2f, 0.7f, 0.0f};
    std::vector<uint8_t> mask(s.px.size());
    for (size_t k = 0; k < mask.size(); ++k)
        mask[k] = k % 3 == 0;
    RgbVector masked, manual;
    AccumulateTransfer(s.View(), mask, x, &masked);
    for (size_t k = 0; k < mask.size(); ++k) {
        if (!mask[k])
            continue;
        Samples one;
        one.Add({s.px[k], s.py[k], s.pz[k]}, {0, 0, -1}, s.w[k], {1, 1, 1});
        AccumulateTransfer(one.View(), {}, x, &manual);
    }
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(masked.e[i], manual.e[i], 1e-6 * std::abs(manual.e[i]));
    std::vector<uint8_t> none(s.px.size(), 0);
    RgbVector zero;
    AccumulateTransfer(s.View(), none, x, &zero);
    for (double v : zero.e)
        EXPECT_EQ(v, 0.0);
}

TEST(Quadrature, NearSingularSamplesStayFinite) {
    Samples s;
    s.Add({0, 0, 1}, {0, 0, -1}, 0.04f, {3, 3, 3});
    s.Add({0, 0, 1e-20f}, {0, 0, -1}, 0.04f, {3, 3, 3});
    const Vec3f probes[] = {{0, 0, 1}, {0, 0, 1 - 1e-7f}, {0, 0, 0}, {1e-30f, 0, 0.999f}};
    for (const Vec3f& x : probes) {
        for (Kernel k : {Kernel::kDisk, Kernel::kPoint}) {
            RgbVector e;
            AccumulateTransfer(s.View(), {}, x, &e, k);
            for (double v : e.e)
                ASSERT_TRUE(std::isfinite(v));
            // The disc kernel is bounded by B per sample.
            if (k == Kernel::kDisk) {
                EXPECT_LE(Length(Colour(e, 0)), 2 * 3.0 + 1e-6);
            }
        }
    }
}

TEST(Quadrature, TailAndLanesGiveTheSameSumAsSingleCalls) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    Samples s;
    for (int i = 0; i < 13; ++i)
        s.Add({u(rng), u(rng), 2 + u(rng)}, Normalize(Vec3f{u(rng), u(rng), -2}), 0.01f,
              {1 + u(rng), 1, 1});
    const Vec3f x{0.1f, 0.1f, 0};
    RgbVector all, one_by_one;
    AccumulateTransfer(s.View(), {}, x, &all);
    for (size_t k = 0; k < s.px.size(); ++k) {
        Samples one;
        one.Add({s.px[k], s.py[k], s.pz[k]}, {s.nx[k], s.ny[k], s.nz[k]}, s.w[k],
                {s.r[k], s.g[k], s.b[k]});
        AccumulateTransfer(one.View(), {}, x, &one_by_one);
    }
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(all.e[i], one_by_one.e[i], 1e-6);
    // Same input, same bits.
    RgbVector again;
    AccumulateTransfer(s.View(), {}, x, &again);
    for (int i = 0; i < 9; ++i)
        EXPECT_EQ(all.e[i], again.e[i]);
}

TEST(Quadrature, BoundingSphereContainsThePoints) {
    std::mt19937 rng(4);
    std::normal_distribution<float> nd(0, 3);
    std::vector<float> x(500), y(500), z(500);
    for (int i = 0; i < 500; ++i) {
        x[i] = 100 + nd(rng);
        y[i] = nd(rng);
        z[i] = -50 + 0.1f * nd(rng);
    }
    BoundingSphere s = ComputeBoundingSphere(x, y, z);
    for (int i = 0; i < 500; ++i) {
        const Vec3f d = Vec3f{x[i], y[i], z[i]} - s.center;
        EXPECT_LE(Length(d), s.radius);
    }
    EXPECT_LT(s.radius, 30.0f);
}

TEST(Quadrature, TransferBoundIsConservative) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 1);
    for (float height : {1.2f, 2.0f, 5.0f, 20.0f}) {
        // Emitter: 0.5 x 0.5 patch at z = height facing down, B up to 2 in green.
        Samples s = CeilingSamples(0, 0.5f, height, 2, 4, {1, 2, 0.5f});
        BoundingSphere es = ComputeBoundingSphere(s.px, s.py, s.pz);
        // Receiver: points of a 0.3 cube at the origin.
        BoundingSphere rs{{0.15f, 0.15f, 0.15f}, 0.3f * std::sqrt(3.0f) / 2 * 1.001f};
        TransferBound tb = BoundTransfer(es, 0.25, 2.0, rs);
        ASSERT_GT(tb.gap, 0);
        double worst = 0;
        for (int i = 0; i < 200; ++i) {
            const Vec3f x{0.3f * u(rng), 0.3f * u(rng), 0.3f * u(rng)};
            RgbVector e;
            AccumulateTransfer(s.View(), {}, x, &e, Kernel::kPoint);
            worst = std::max(worst, Length(Colour(e, 1)));
        }
        EXPECT_LE(worst, tb.e_max);
        // Not absurdly loose for distant pairs.
        if (height > 10) {
            EXPECT_GT(worst, 0.5 * tb.e_max);
        }
        EXPECT_GT(tb.spread, 0.0);
    }
    TransferBound overlap = BoundTransfer({{0, 0, 0}, 1}, 1.0, 3.0, {{0.5f, 0, 0}, 1});
    EXPECT_LE(overlap.gap, 0);
    EXPECT_TRUE(std::isinf(overlap.form_factor));
    EXPECT_EQ(overlap.e_max, 12.0);
}

TEST(Quadrature, Throughput) {
    Samples s = CeilingSamples(0, 1, 1, 16, 4, {1, 2, 3});  // 4096 samples
    RgbVector e;
    const int reps = 2000;
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < reps; ++i)
        AccumulateTransfer(s.View(), {}, {0.01f * (i % 50), 0.3f, 0}, &e);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("AccumulateTransfer: %.1f M sample-transfers/s (one thread)\n",
                reps * double(s.px.size()) / sec * 1e-6);
    EXPECT_TRUE(std::isfinite(e.e[0]));
}

}  // namespace
}  // namespace mebake::solve
