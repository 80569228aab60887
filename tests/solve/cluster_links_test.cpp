// Cluster links (solve/cluster_links.cpp) against the chart-by-chart gather they replace: a
// far square emitter over a floor of 64 small charts, without and with an occluder whose
// shadow has an umbra, a penumbra and a lit part; and thread-count identity.
#include "core/parallel.h"
#include "patch_fixture.h"
#include "solve/rays.h"
#include "solve/solver.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace mebake::solve {
namespace {

using testing::MakePatch;
using testing::Patch;

constexpr int kTilesX = 16, kTilesZ = 4;
constexpr double kTile = 0.25, kX0 = -1.5;

struct FloorScene {
    Scene scene;
    std::vector<SolveChart> charts;
    VisibilityScene vis;

    // Chart 0: a unit square at height 4 facing down, radiosity 1; charts 1..64: black
    // floor tiles x in [-1.5, 2.5], z in [0, 1]. The occluder (visibility only): a plate at
    // height 2 over x < 0.5, so the floor is in umbra for x < 0, lit for x > 1.
    explicit FloorScene(bool occluder) {
        Material emit, black;
        emit.albedo = black.albedo = Vec3f(0, 0, 0);
        emit.emission = Vec3f(1, 1, 1) * float(1 / std::numbers::pi);
        emit.use_vertex_colors = black.use_vertex_colors = false;
        scene.per_input = {{emit}, {black}};
        Add(MakePatch([](double u, double v) { return Vec3d(u, 4, v); }, 32, 0, 1));
        for (int tz = 0; tz < kTilesZ; ++tz)
            for (int tx = 0; tx < kTilesX; ++tx) {
                const double x0 = kX0 + tx * kTile, z0 = tz * kTile;
                Add(MakePatch(
                    [=](double u, double v) {
                        return Vec3d(x0 + kTile * u, 0, z0 + kTile * (1 - v));
                    },
                    8, 1 << 16, kTile));
            }
        if (occluder) {
            const std::vector<float> xyz = {-5, 2, -3, 0.5f, 2, -3, 0.5f, 2, 4, -5, 2, 4};
            const std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
            vis.AddTriangles(xyz, tris, "occluder");
        }
        vis.Commit();
    }
    void Add(const Patch& p) {
        charts.push_back(p.chart);
        vis.AddTriangles(p.xyz, p.tris, "patch");
    }
};

struct Result {
    std::vector<double> e;  // n . E at 8 x 8 points of every floor tile
    SolveStats stats;
};

Result Solve(bool occluder, bool clusters) {
    FloorScene fs(occluder);
    SolveOptions opt;
    opt.settings.order = 2;
    opt.settings.max_bounces = 1;
    opt.cluster_links = clusters;
    opt.link_probes = clusters ? 8 : 0;  // the reference: one ray per pair, as before
    Solver solver(fs.scene, fs.charts, fs.vis, opt);
    solver.Run();
    Result r;
    r.stats = solver.stats();
    for (size_t c = 1; c < fs.charts.size(); ++c)
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i) {
                float val[9];
                solver.fields()[c].EvalValue((i + 0.5) / 8, (j + 0.5) / 8, val);
                r.e.push_back(val[1]);  // n = +y
            }
    return r;
}

uint64_t Rays(const SolveStats& s, RayKind k) {
    return size_t(k) < s.rays_by_kind.size() ? s.rays_by_kind[size_t(k)] : 0;
}

// Largest and mean difference, relative to the brightest reference value.
void Compare(const Result& got, const Result& ref, double* worst, double* mean) {
    ASSERT_EQ(got.e.size(), ref.e.size());
    double top = 0, sum = 0;
    *worst = 0;
    for (double v : ref.e)
        top = std::max(top, v);
    ASSERT_GT(top, 0);
    for (size_t k = 0; k < ref.e.size(); ++k) {
        const double d = std::abs(got.e[k] - ref.e[k]) / top;
        *worst = std::max(*worst, d);
        sum += d;
    }
    *mean = sum / double(ref.e.size());
}

TEST(ClusterLinks, UnoccludedFarEmitterMatchesChartByChart) {
    const Result ref = Solve(false, false), got = Solve(false, true);
    double worst, mean;
    Compare(got, ref, &worst, &mean);
    // All visibility samples agree (1): the same kernel at the same points and texels.
    EXPECT_LT(worst, 1e-5);
    EXPECT_GT(got.stats.cluster_links, 0u);
    EXPECT_EQ(ref.stats.cluster_links, 0u);
    EXPECT_LT(Rays(got.stats, RayKind::kLink) + Rays(got.stats, RayKind::kCluster),
              Rays(ref.stats, RayKind::kLink) / 4);
}

TEST(ClusterLinks, OccludedFarEmitterWithinBoundOfChartByChart) {
    const Result ref = Solve(true, false), got = Solve(true, true);
    double worst, mean;
    Compare(got, ref, &worst, &mean);
    // Umbra and lit clusters are accepted with visibility 0 and 1; the penumbra's charts,
    // whose samples disagree, are opened and gathered chart by chart.
    EXPECT_LT(worst, 0.02) << "mean " << mean;
    EXPECT_LT(mean, 0.002);
    EXPECT_GT(got.stats.cluster_links, 0u);
    EXPECT_GT(got.stats.opened_links, 0u);
    EXPECT_LT(Rays(got.stats, RayKind::kLink) + Rays(got.stats, RayKind::kCluster),
              Rays(ref.stats, RayKind::kLink));
    // The umbra really is dark and the lit side lit (the scene is what it claims).
    EXPECT_EQ(ref.e.front(), 0.0);
    EXPECT_GT(ref.e[size_t(kTilesX - 1) * 64], 0.0);
}

TEST(ClusterLinks, BitIdenticalForAnyThreadCount) {
    auto run = [](int threads) {
        ThreadLimit limit(threads);
        return Solve(true, true).e;
    };
    const auto one = run(1), two = run(2);
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(double)));
}

}  // namespace
}  // namespace mebake::solve
