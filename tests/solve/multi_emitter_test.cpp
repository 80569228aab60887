// Multi-emitter simplification (seed 002) on the paper's Fig. 7 setting: a floor lit by two
// rectangles with one square occluder between them. Checks lit regions against Lambert's
// formula (the extremal boundaries against the exact shadow: extremal_boundary_exact_test),
// simplify against full in L2, leaves and direct rays, and thread determinism.
#include "solve/multi_emitter.h"

#include "core/parallel.h"
#include "patch_fixture.h"
#include "solve/basis.h"
#include "solve/direct.h"
#include "solve/extremal_boundary.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/solver.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mebake::solve {
namespace {

using testing::MakePatch;

// Light k: 1 x 1 at height 2 facing down, centred at x = cx; the occluder is 0.8 x 0.8 at
// height 1 centred at the origin; the floor is 6 x 6 at height 0 (chart u along x, v along -z).
std::vector<Vec3d> Rect(double cx, double y, double h) {
    return {{cx - h, y, -h}, {cx + h, y, -h}, {cx + h, y, h}, {cx - h, y, h}};
}

struct Fig7 {
    Scene scene;
    std::vector<SolveChart> charts;
    VisibilityScene vis;
    explicit Fig7(double second_radiance) {
        Material m;
        m.albedo = Vec3f(0, 0, 0);
        m.use_vertex_colors = false;
        scene.per_input = {{m}};
        const double radiance[2] = {1.0, second_radiance};
        const double centre[2] = {-0.6, 0.9};
        for (int k = 0; k < 2; ++k) {
            PolygonLight l;
            l.vertices = Rect(centre[k], 2, 0.5);
            l.radiance = {radiance[k], radiance[k], radiance[k]};
            scene.lights.push_back(l);
        }
        auto p =
            MakePatch([](double u, double v) { return Vec3d(6 * u - 3, 0, 3 - 6 * v); }, 128, 0, 6);
        charts.push_back(p.chart);
        vis.AddTriangles(p.xyz, p.tris, "floor");
        std::vector<float> occ = {-0.4f, 1, -0.4f, 0.4f, 1, -0.4f, 0.4f, 1, 0.4f, -0.4f, 1, 0.4f};
        std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
        vis.AddTriangles(occ, tris, "occluder");
        vis.Commit();
    }
};

SolveOptions Options(bool simplify, double tolerance) {
    SolveOptions opt;
    opt.settings.max_bounces = 0;
    opt.settings.tolerance = tolerance;
    opt.settings.light_samples = 256;
    opt.settings.multi_emitter_simplify = simplify;
    opt.max_nodes_per_chart = 1u << 20;
    return opt;
}

double Irradiance(const Solver& s, double x, double z) {
    float val[9];
    s.fields()[0].EvalValue((x + 3) / 6, (3 - z) / 6, val);
    return val[1];  // n = +y, colour 0
}

// Whether the leaf of s holding floor point (x, z) lies wholly in the light centred at cx
// (a lit region: the closed form there, no simplification). The shadow of the occluder
// (penumbra and umbra) is the open rectangle -0.8 - (cx + 0.5) < x < 0.8 - (cx - 0.5),
// |z| < 1.3 (the occluder projected from the light's corners).
bool InLitLeaf(const Solver& s, double x, double z, double cx) {
    double ls, lt;
    const QuadNode& leaf =
        s.fields()[0].node(s.fields()[0].LeafAt((x + 3) / 6, (3 - z) / 6, &ls, &lt));
    const double x0 = 6 * leaf.U(0) - 3, x1 = 6 * leaf.U(1) - 3;
    const double z0 = 3 - 6 * leaf.V(1), z1 = 3 - 6 * leaf.V(0);
    const bool x_clear = x1 <= -0.8 - (cx + 0.5) || x0 >= 0.8 - (cx - 0.5);
    const bool z_clear = z1 <= -1.3 || z0 >= 1.3;
    return x_clear || z_clear;
}

// Whether the leaf of s holding floor point (x, z) touches a leaf of another size (its border
// nodes may be tied to a neighbour's polynomial, slave_nodes.h).
bool BordersOtherSize(const Solver& s, double x, double z) {
    const ChartField& f = s.fields()[0];
    double ls, lt;
    const QuadNode& leaf = f.node(f.LeafAt((x + 3) / 6, (3 - z) / 6, &ls, &lt));
    const double eps = 1e-9;
    // Just outside the leaf: 9 points along each side, corners diagonally.
    for (int k = 0; k <= 8; ++k) {
        const double e = std::clamp(k / 8.0, 1e-6, 1 - 1e-6);
        const double around[4][2] = {{leaf.U(0) - eps, leaf.V(e)}, {leaf.U(1) + eps, leaf.V(e)},
                                     {leaf.U(e), leaf.V(0) - eps}, {leaf.U(e), leaf.V(1) + eps}};
        for (const auto& p : around) {
            double a, b;
            if (p[0] > 0 && p[0] < 1 && p[1] > 0 && p[1] < 1 &&
                f.node(f.LeafAt(p[0], p[1], &a, &b)).level != leaf.level)
                return true;
        }
    }
    for (int c = 0; c < 4; ++c) {
        const double u = c & 1 ? leaf.U(1) + eps : leaf.U(0) - eps;
        const double v = c & 2 ? leaf.V(1) + eps : leaf.V(0) - eps;
        double a, b;
        if (u > 0 && u < 1 && v > 0 && v < 1 && f.node(f.LeafAt(u, v, &a, &b)).level != leaf.level)
            return true;
    }
    return false;
}

uint64_t DirectRays(const Solver& s) {
    const auto& k = s.stats().rays_by_kind;
    return k[size_t(RayKind::kClassify)] + k[size_t(RayKind::kPenumbra)];
}

TEST(MultiEmitter, L2MeasuresByGaussLegendre) {
    // A biquadratic fitted at 3 x 3 Gauss points is exact for a biquadratic.
    const int order = 2, n = 5;
    float coeffs[9] = {1, 0.5f, 0.25f, 0, 0.1f, 0, 0, 0, 0.2f};
    float values[25];
    EvalGauss(order, n, coeffs, 1, values);
    EXPECT_LT(GaussL2Error(order, n, coeffs, 1, values), 1e-6f);
    // The L2 norm of the constant 1 is 1, of the fit minus 1 + the fit is 1 too.
    for (float& v : values)
        v -= 1;
    EXPECT_NEAR(GaussL2Error(order, n, coeffs, 1, values), 1.0f, 1e-5f);
    EXPECT_NEAR(GaussResidualMax(order, n, coeffs, 1, values), 1.0f, 1e-5f);
    // One point off by 1: the largest residual is 1, the L2 norm the square root of that
    // point's weight (the weights sum to 1), which the largest residual bounds.
    values[7] += 1;
    double s, t, w;
    GaussPoint2D(n, 7, &s, &t, &w);
    for (float& v : values)
        v += 1;
    EXPECT_NEAR(GaussResidualMax(order, n, coeffs, 1, values), 1.0f, 1e-5f);
    EXPECT_NEAR(GaussL2Error(order, n, coeffs, 1, values), std::sqrt(w), 1e-5f);
    EXPECT_NE(KnownCode(std::vector<uint8_t>{2, 0}), KnownCode(std::vector<uint8_t>{0, 2}));
    EXPECT_EQ(KnownCode(std::vector<uint8_t>{0, 0, 0}), 0u);
}

// Both modes on the Fig. 7 scene; the second light `second` times the first.
void CompareModes(double second, double tolerance) {
    Fig7 f(second);
    Solver full(f.scene, f.charts, f.vis, Options(false, tolerance));
    full.Run();
    Solver simple(f.scene, f.charts, f.vis, Options(true, tolerance));
    simple.Run();
    double diff2 = 0, peak = 0, lit_worst = 0, tied_worst = 0;
    int lit_points = 0;
    const int n = 120;
    for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
            const double x = -3 + 6 * (a + 0.5) / n, z = -3 + 6 * (b + 0.5) / n;
            const double hs = Irradiance(simple, x, z), hf = Irradiance(full, x, z);
            diff2 += (hs - hf) * (hs - hf) / (n * n);
            peak = std::max(peak, hf);
            if (InLitLeaf(simple, x, z, -0.6) && InLitLeaf(simple, x, z, 0.9)) {
                const Vec3d p(x, 0, z), up(0, 1, 0);
                const double exact = IrradianceClipped(f.scene.lights[0].vertices, 1.0, p, up) +
                                     IrradianceClipped(f.scene.lights[1].vertices, second, p, up);
                // A lit leaf next to a leaf of another size shares its values along the
                // border (C0, slave_nodes.h): it moves by the neighbour's error there (up to
                // the tolerance at its tested points) spread by the Lagrange functions of the
                // border nodes (at most 1.25 per axis at M2).
                double& worst = BordersOtherSize(simple, x, z) ? tied_worst : lit_worst;
                worst = std::max(worst, std::abs(hs - exact));
                ++lit_points;
            }
        }
    const double l2 = std::sqrt(diff2) / peak;
    std::printf("second light x%g, tolerance %g: L2(simplify - full) / peak %.5f, lit worst %.5f "
                "of peak (%.5f in lit leaves tied to another size); leaves %llu -> %llu; direct "
                "rays %llu -> %llu\n",
                second, tolerance, l2, lit_worst / peak, tied_worst / peak, (unsigned long long)full.stats().leaves,
                (unsigned long long)simple.stats().leaves, (unsigned long long)DirectRays(full),
                (unsigned long long)DirectRays(simple));
    std::printf("classify %llu -> %llu, penumbra %llu -> %llu\n",
                (unsigned long long)full.stats().rays_by_kind[0],
                (unsigned long long)simple.stats().rays_by_kind[0],
                (unsigned long long)full.stats().rays_by_kind[1],
                (unsigned long long)simple.stats().rays_by_kind[1]);
    EXPECT_LT(l2, tolerance);
    EXPECT_LT(lit_worst, 1e-3 * peak);
    EXPECT_LT(tied_worst, 2 * tolerance * peak);
    EXPECT_GT(lit_points, n * n / 4);
    EXPECT_LT(simple.stats().leaves, full.stats().leaves);
    EXPECT_LT(DirectRays(simple), DirectRays(full));
}

TEST(MultiEmitter, TwoEqualLightsSimplifyWithinToleranceOfFull) {
    CompareModes(1.0, 2e-3);
}

TEST(MultiEmitter, BrightSecondLightWashesOutTheFirstsPenumbra) {
    CompareModes(8.0, 2e-3);
}

// The largest jump of the direct light (colour 0, n = +y) across the sides where a leaf of
// `s` borders a coarser leaf, over `peak`, at 8 points inside each side. With `simplified`
// (full's solve of the same scene), only borders whose coarser leaf `full` refined further
// count (seed 002's simplified/unsimplified borders); *borders gets their number.
double CoarseFineJump(const Solver& s, double peak, const Solver* full, int* borders,
                      int* continuous = nullptr) {
    const ChartField& f = s.fields()[0];
    double worst = 0;
    *borders = 0;
    if (continuous)
        *continuous = 0;
    for (size_t n = 0; n < f.node_count(); ++n) {
        const QuadNode& leaf = f.node(n);
        if (!leaf.leaf() || leaf.level == 0)
            continue;
        for (int side = 0; side < 4; ++side) {
            const bool along_t = side < 2;  // a side of constant s
            const double end = side % 2, out = end == 0 ? -1e-9 : 1e-9;
            bool counted = false;
            double side_jump = 0;
            for (int k = 0; k < 8; ++k) {
                const double e = (k + 0.5) / 8;
                const double ls = along_t ? end : e, lt = along_t ? e : end;
                const double u = leaf.U(ls) + (along_t ? out : 0), v = leaf.V(lt) + (along_t ? 0 : out);
                if (u <= 0 || u >= 1 || v <= 0 || v >= 1)
                    break;
                double ms, mt;
                const size_t across = f.LeafAt(u, v, &ms, &mt);
                const QuadNode& m = f.node(across);
                if (m.level >= leaf.level)
                    break;
                if (full) {
                    double fs, ft;
                    const QuadNode& fl = full->fields()[0].node(
                        full->fields()[0].LeafAt(m.U(0.5), m.V(0.5), &fs, &ft));
                    if (fl.level <= m.level)
                        break;
                }
                float a[9], b[9];
                EvalCoeffs(f.order(), f.value(n), 9, ls, lt, a);
                EvalCoeffs(f.order(), f.value(across), 9, ms, mt, b);
                side_jump = std::max(side_jump, std::abs(double(a[1]) - double(b[1])) / peak);
                counted = true;
            }
            worst = std::max(worst, side_jump);
            *borders += counted ? 1 : 0;
            if (continuous && counted && side_jump < 2e-6)
                ++*continuous;
        }
    }
    return worst;
}

// Seed 002's slave nodes: where simplify keeps a coarse leaf and finer leaves border it, the
// finer leaves take its values along the common side (slave_nodes.h), unless that would move
// them by more than the tolerance in L2. Most coarse-fine sides are then continuous (a side
// counts as continuous when it jumps by less than 2e-6 of the peak at 8 points); full's field
// (not tied) is continuous on none of them, which shows the measure sees jumps. The L2 bound
// to full holds with the ties (CompareModes).
TEST(MultiEmitter, ContinuousAtTVerticesBetweenSimplifiedAndUnsimplifiedLeaves) {
    Fig7 f(1.0);
    Solver full(f.scene, f.charts, f.vis, Options(false, 2e-3));
    full.Run();
    Solver simple(f.scene, f.charts, f.vis, Options(true, 2e-3));
    simple.Run();
    double peak = 0;
    for (int b = 0; b < 60; ++b)
        for (int a = 0; a < 60; ++a)
            peak = std::max(peak, Irradiance(full, -3 + 6 * (a + 0.5) / 60, -3 + 6 * (b + 0.5) / 60));
    int borders = 0, simplified = 0, full_borders = 0, cont = 0, cont_simplified = 0, full_cont = 0;
    const double all = CoarseFineJump(simple, peak, nullptr, &borders, &cont);
    const double at_simplified = CoarseFineJump(simple, peak, &full, &simplified, &cont_simplified);
    const double untied = CoarseFineJump(full, peak, nullptr, &full_borders, &full_cont);
    std::printf("coarse-fine sides: simplify %d, %d continuous (%d / %d on a simplified leaf), "
                "largest jump %.2e (%.2e on a simplified leaf) of the peak; full (no ties) %d "
                "sides, %d continuous, largest jump %.2e\n",
                borders, cont, cont_simplified, simplified, all, at_simplified, full_borders,
                full_cont, untied);
    EXPECT_GT(simplified, 20);
    EXPECT_GT(cont_simplified, simplified / 2);
    EXPECT_GT(cont, borders / 2);
    EXPECT_LT(full_cont, full_borders / 10);
    EXPECT_GT(untied, 1e-4);
}

// One polygon light: nothing to merge, simplify is full (same bytes, no boundary pass).
TEST(MultiEmitter, OneLightIsFull) {
    Fig7 f(1.0);
    f.scene.lights.pop_back();
    Solver full(f.scene, f.charts, f.vis, Options(false, 1e-2));
    full.Run();
    Solver simple(f.scene, f.charts, f.vis, Options(true, 1e-2));
    simple.Run();
    const auto a = full.fields()[0].values(), b = simple.fields()[0].values();
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
    EXPECT_EQ(DirectRays(full), DirectRays(simple));
}

TEST(MultiEmitter, BitIdenticalForAnyThreadCount) {
    auto run = [](int threads) {
        ThreadLimit limit(threads);
        Fig7 f(2.0);
        Solver s(f.scene, f.charts, f.vis, Options(true, 1e-2));
        s.Run();
        const auto v = s.fields()[0].values();
        return std::vector<float>(v.begin(), v.end());
    };
    const auto one = run(1), two = run(2);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
}

}  // namespace
}  // namespace mebake::solve
