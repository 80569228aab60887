// Error-driven link refinement (solve/link_refine.h): the irradiance bound holds for
// emitter squares near and far, and in a lit box (five charts touching at its edges,
// several bounces) the solve with the rule stays within its tolerance of the purely
// geometric refinement while tracing fewer link rays.
#include "solve/link_refine.h"

#include "core/parallel.h"
#include "patch_fixture.h"
#include "solve/rays.h"
#include "solve/solver.h"
#include "solve/transfer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace mebake::solve {
namespace {

// |E| at x (normal n) from a square of side `side` centred at c with normal m, radiosity 1,
// integrated over 64 x 64 sub-squares with the solver's kernel.
double SquareIrradiance(const Vec3d& x, const Vec3d& n, const Vec3d& c, const Vec3d& m,
                        double side) {
    const Vec3d ref = std::abs(m.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d tu = Normalize(Cross(ref, m)), tv = Cross(m, tu);
    constexpr int kN = 64;
    const double h = side / kN;
    Vec3d sum{};
    for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) {
            const Vec3d p = c + tu * ((i + 0.5) * h - side / 2) + tv * ((j + 0.5) * h - side / 2);
            Vec3d e;
            if (TexelTransfer(Vec3f(x), Vec3f(n), {Vec3f(p), Vec3f(m), float(h * h)}, h, &e))
                sum += e;
        }
    return Length(sum);
}

TEST(LinkRefine, IrradianceBoundHoldsNearAndFar) {
    uint64_t state = 7;
    auto rnd = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) / double(1ull << 53);
    };
    auto dir = [&] {
        for (;;) {
            const Vec3d d(2 * rnd() - 1, 2 * rnd() - 1, 2 * rnd() - 1);
            if (Length(d) > 0.1 && Length(d) < 1)
                return Normalize(d);
        }
    };
    int near = 0;
    for (int k = 0; k < 400; ++k) {
        const double side = 0.5 + rnd();
        const Vec3d c = dir() * (4 * rnd() * side), m = dir(), n(0, 0, 1);
        const double gap = Length(c) - side * std::sqrt(0.5);  // the square's sphere
        near += gap <= 0 ? 1 : 0;
        const double e = SquareIrradiance(Vec3d(0, 0, 0), n, c, m, side);
        EXPECT_LE(e, LinkIrradianceBound(1, side * side, gap)) << "k " << k << " gap " << gap;
    }
    EXPECT_GT(near, 50);  // touching pairs are tested too
}

struct BoxRun {
    std::vector<double> e;  // n . E (colour 0) at 16 x 16 points of every chart
    SolveStats stats;
};

BoxRun SolveBox(double link_tolerance) {
    testing::LitBox box(5, 32);
    SolveOptions opt;
    opt.settings.max_bounces = 8;
    opt.link_tolerance = link_tolerance;
    Solver solver(box.scene, box.charts, box.vis, opt);
    solver.Run();
    BoxRun r;
    r.stats = solver.stats();
    for (size_t c = 0; c < box.charts.size(); ++c) {
        const Vec3f n = box.charts[c].geometry.At(0, 0, 0).normal;
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                float v[9];
                solver.fields()[c].EvalValue((i + 0.5) / 16, (j + 0.5) / 16, v);
                r.e.push_back(n.x * v[0] + n.y * v[1] + n.z * v[2]);
            }
    }
    return r;
}

uint64_t LinkRays(const SolveStats& s) {
    return s.rays_by_kind.size() > size_t(RayKind::kLink) ? s.rays_by_kind[size_t(RayKind::kLink)]
                                                          : 0;
}

TEST(LinkRefine, LitBoxWithinToleranceWithFewerLinkRays) {
    const BoxRun ref = SolveBox(0), got = SolveBox(SolveOptions{}.link_tolerance);  // the default
    ASSERT_EQ(ref.e.size(), got.e.size());
    double worst = 0, sum = 0;
    size_t lit = 0;
    for (size_t k = 0; k < ref.e.size(); ++k) {
        if (ref.e[k] <= 0)
            continue;  // the ceiling's strip behind the light's plane
        ++lit;
        const double d = std::abs(got.e[k] - ref.e[k]) / ref.e[k];
        worst = std::max(worst, d);
        sum += d;
    }
    const double mean = sum / double(lit);
    std::printf("link rays %llu -> %llu, relative difference max %.4f mean %.5f\n",
                (unsigned long long)LinkRays(ref.stats), (unsigned long long)LinkRays(got.stats),
                worst, mean);
    EXPECT_GT(lit, ref.e.size() * 3 / 4);
    EXPECT_LT(worst, 0.005);
    EXPECT_LT(mean, 0.001);
    EXPECT_LT(LinkRays(got.stats), LinkRays(ref.stats) * 4 / 5);  // measured: 0.69
}

TEST(LinkRefine, BitIdenticalForAnyThreadCount) {
    auto run = [](int threads) {
        ThreadLimit limit(threads);
        return SolveBox(SolveOptions{}.link_tolerance).e;
    };
    const auto a = run(1), b = run(2);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

}  // namespace
}  // namespace mebake::solve
