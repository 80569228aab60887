#include "stream/segment.h"

#include "core/error.h"
#include "core/parallel.h"
#include "stream/repair.h"

#include "scan_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <ctime>
#include <optional>
#include <string>

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;

TriMesh Make(std::vector<Vec3f> positions, std::vector<Tri> triangles) {
    TriMesh m;
    m.position = std::move(positions);
    m.triangles = std::move(triangles);
    for (size_t v = 0; v < m.position.size(); ++v)
        m.vertex_id.push_back(7 * v + 1);
    for (size_t f = 0; f < m.triangles.size(); ++f) {
        m.face_id.push_back(3 * f + 2);
        m.material.push_back(uint32_t(f % 2));
    }
    return m;
}

// A (u, v) -> position surface on an n x m grid, optionally periodic in u and/or v.
template <typename Fn>
TriMesh Param(int n, int m, bool wrap_u, bool wrap_v, Fn fn) {
    const int nu = wrap_u ? n : n + 1, nv = wrap_v ? m : m + 1;
    std::vector<Vec3f> p;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i)
            p.push_back(fn(double(i) / n, double(j) / m));
    auto id = [&](int i, int j) {
        return uint32_t((j % nv) * nu + (i % nu));
    };
    std::vector<Tri> t;
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < n; ++i) {
            t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return Make(p, t);
}

TriMesh Plane(int n) {
    return Param(n, n, false, false,
                 [](double u, double v) { return Vec3f(float(u), float(v), 0); });
}

TriMesh Annulus(int n, int m) {  // flat ring, 2 boundary loops
    return Param(n, m, true, false, [](double u, double v) {
        const double r = 1 + v;
        return Vec3f(float(r * std::cos(2 * M_PI * u)), float(r * std::sin(2 * M_PI * u)), 0);
    });
}

TriMesh Torus(int n, int m) {
    return Param(n, m, true, true, [](double u, double v) {
        const double a = 2 * M_PI * u, b = 2 * M_PI * v, r = 1 + 0.4 * std::cos(b);
        return Vec3f(float(r * std::cos(a)), float(r * std::sin(a)), float(0.4 * std::sin(b)));
    });
}

TriMesh Sphere(int stacks, int slices) {
    std::vector<Vec3f> p{{0, 0, 1}};
    for (int s = 1; s < stacks; ++s) {
        const double th = M_PI * s / stacks;
        for (int k = 0; k < slices; ++k) {
            const double ph = 2 * M_PI * k / slices;
            p.push_back({float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                         float(std::cos(th))});
        }
    }
    p.push_back({0, 0, -1});
    const uint32_t south = uint32_t(p.size() - 1);
    auto id = [&](int s, int k) {
        return uint32_t(1 + (s - 1) * slices + (k % slices));
    };
    std::vector<Tri> t;
    for (int k = 0; k < slices; ++k)
        t.push_back({0, id(1, k), id(1, k + 1)});
    for (int s = 1; s + 1 < stacks; ++s)
        for (int k = 0; k < slices; ++k) {
            t.push_back({id(s, k), id(s + 1, k), id(s + 1, k + 1)});
            t.push_back({id(s, k), id(s + 1, k + 1), id(s, k + 1)});
        }
    for (int k = 0; k < slices; ++k)
        t.push_back({id(stacks - 1, k), south, id(stacks - 1, k + 1)});
    return Make(p, t);
}

size_t CountCharts(const std::vector<uint32_t>& ids) {
    uint32_t n = 0;
    for (uint32_t c : ids)
        n = std::max(n, c + 1);
    return n;
}

// Every face in exactly one chart, ids dense and numbered by first face, every chart a disc.
void ExpectValidCharts(const TriMesh& m, const std::vector<uint32_t>& ids,
                       uint32_t max_vertices = ~0u) {
    ASSERT_EQ(ids.size(), m.triangle_count());
    const size_t n = CountCharts(ids);
    uint32_t next = 0;
    for (uint32_t c : ids) {
        ASSERT_LE(c, next) << "ids not numbered by first face";
        if (c == next)
            ++next;
    }
    size_t faces = 0;
    const std::vector<TriMesh> all = ExtractCharts(m, ids);
    ASSERT_EQ(all.size(), n);
    for (uint32_t c = 0; c < n; ++c) {
        const TriMesh& chart = all[c];
        faces += chart.triangle_count();
        const TopologyReport t = CheckDisc(chart);
        EXPECT_TRUE(t.IsDisc()) << "chart " << c << ": faces " << t.faces << " loops "
                                << t.boundary_loops << " euler " << t.euler << " components "
                                << t.components;
        EXPECT_LE(chart.vertex_count(), max_vertices) << "chart " << c;
    }
    EXPECT_EQ(faces, m.triangle_count());
}

TEST(CheckDisc, RecognisesDiscsAndOthers) {
    EXPECT_TRUE(CheckDisc(Plane(4)).IsDisc());
    const TopologyReport s = CheckDisc(Sphere(6, 8));
    EXPECT_FALSE(s.IsDisc());
    EXPECT_EQ(s.boundary_loops, 0u);
    EXPECT_EQ(s.euler, 2);
    const TopologyReport a = CheckDisc(Annulus(12, 3));
    EXPECT_FALSE(a.IsDisc());
    EXPECT_EQ(a.boundary_loops, 2u);
    EXPECT_EQ(a.euler, 0);
    const TopologyReport t = CheckDisc(Torus(12, 8));
    EXPECT_EQ(t.euler, 0);
    EXPECT_EQ(t.boundary_loops, 0u);
    const TopologyReport bow = CheckDisc(
        Make({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}}));
    EXPECT_EQ(bow.nonmanifold_vertices, 1u);
    EXPECT_FALSE(bow.IsDisc());
}

TEST(ExtractChart, ReindexesLocallyAndKeepsGlobalIds) {
    const TriMesh m = Plane(3);  // 18 faces, 16 vertices
    std::vector<uint32_t> ids(m.triangle_count(), 0);
    for (size_t f = 9; f < ids.size(); ++f)
        ids[f] = 1;
    const TriMesh c = ExtractChart(m, ids, 1);
    ASSERT_EQ(c.triangle_count(), 9u);
    const std::vector<TriMesh> all = ExtractCharts(m, ids);
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[1].triangles, c.triangles);
    EXPECT_EQ(all[1].vertex_id, c.vertex_id);
    EXPECT_EQ(all[0].triangle_count(), 9u);
    for (size_t v = 1; v < c.vertex_count(); ++v)
        EXPECT_LT(c.vertex_id[v - 1], c.vertex_id[v]);
    for (size_t f = 0; f < c.triangle_count(); ++f) {
        EXPECT_EQ(c.face_id[f], m.face_id[9 + f]);
        EXPECT_EQ(c.material[f], m.material[9 + f]);
        for (int k = 0; k < 3; ++k) {
            const uint32_t global = m.triangles[9 + f][k];
            EXPECT_EQ(c.position[c.triangles[f][k]], m.position[global]);
            EXPECT_EQ(c.vertex_id[c.triangles[f][k]], m.vertex_id[global]);
        }
    }
}

TEST(Segment, FlatPlaneIsOneChart) {
    const TriMesh m = Plane(20);
    SegmentReport r;
    const auto ids = SegmentCharts(m, {}, &r);
    EXPECT_EQ(CountCharts(ids), 1u);
    ExpectValidCharts(m, ids);
    EXPECT_LE(r.max_normal_deviation_deg, 1.0);
}

TEST(Segment, SizeTargetGivesCompactCharts) {
    const TriMesh m = Plane(40);  // 3200 faces
    SegmentOptions o;
    o.target_chart_faces = 400;
    o.min_chart_faces = 16;
    SegmentReport r;
    const auto ids = SegmentCharts(m, o, &r);
    const size_t n = CountCharts(ids);
    EXPECT_GE(n, 6u);
    EXPECT_LE(n, 12u);
    ExpectValidCharts(m, ids);
    // Compact: perimeter^2 / area stays far from a strip's (a 400-face square of the grid
    // has 80 boundary edges for 200 cells: ratio 32; a 1-cell-wide strip would be ~800).
    for (uint32_t c = 0; c < n; ++c) {
        const TriMesh chart = ExtractChart(m, ids, c);
        const TopologyReport t = CheckDisc(chart);
        const double cells = chart.triangle_count() / 2.0;
        EXPECT_LT(double(t.boundary_edges * t.boundary_edges) / cells, 64.0) << "chart " << c;
    }
}

TEST(Segment, ClosedSphereIsSplitIntoDiscs) {
    const TriMesh m = Sphere(30, 40);
    SegmentOptions o;
    o.max_normal_deviation_deg = 180;  // only topology forces the split
    const auto ids = SegmentCharts(m, o);
    EXPECT_GE(CountCharts(ids), 2u);
    ExpectValidCharts(m, ids);
}

TEST(Segment, AnnulusAndTorusAreCutIntoDiscs) {
    SegmentOptions o;
    o.max_normal_deviation_deg = 180;
    const TriMesh ring = Annulus(60, 6);
    const auto ring_ids = SegmentCharts(ring, o);
    EXPECT_GE(CountCharts(ring_ids), 2u);
    ExpectValidCharts(ring, ring_ids);

    const TriMesh torus = Torus(60, 24);
    const auto torus_ids = SegmentCharts(torus, o);
    EXPECT_GE(CountCharts(torus_ids), 2u);
    ExpectValidCharts(torus, torus_ids);
}

TEST(Segment, NormalDeviationBoundDrivesChartCount) {
    const TriMesh m = Sphere(40, 60);
    SegmentOptions loose, tight;
    loose.max_normal_deviation_deg = 90;
    tight.max_normal_deviation_deg = 35;
    SegmentReport rl, rt;
    const auto a = SegmentCharts(m, loose, &rl);
    const auto b = SegmentCharts(m, tight, &rt);
    ExpectValidCharts(m, a);
    ExpectValidCharts(m, b);
    EXPECT_GT(CountCharts(b), CountCharts(a));
    EXPECT_LE(rt.max_normal_deviation_deg, 35.0 + 1.0);
    EXPECT_LE(rl.max_normal_deviation_deg, 90.0 + 1.0);
}

TEST(Segment, VertexBoundIsHard) {
    const TriMesh m = Plane(60);  // 3721 vertices
    SegmentOptions o;
    o.target_chart_faces = 1000000;
    o.max_chart_vertices = 500;
    const auto ids = SegmentCharts(m, o);
    EXPECT_GE(CountCharts(ids), 8u);
    ExpectValidCharts(m, ids, 500);
}

TEST(Segment, SeparateComponentsGetSeparateCharts) {
    TriMesh a = Plane(5), b = Plane(5);
    const uint32_t off = uint32_t(a.vertex_count());
    for (auto& p : b.position)
        p.z += 2;
    for (auto& t : b.triangles)
        for (auto& v : t)
            v += off;
    a.position.insert(a.position.end(), b.position.begin(), b.position.end());
    a.vertex_id.insert(a.vertex_id.end(), b.vertex_id.begin(), b.vertex_id.end());
    a.triangles.insert(a.triangles.end(), b.triangles.begin(), b.triangles.end());
    a.face_id.insert(a.face_id.end(), b.face_id.begin(), b.face_id.end());
    a.material.insert(a.material.end(), b.material.begin(), b.material.end());
    SegmentReport r;
    const auto ids = SegmentCharts(a, {}, &r);
    EXPECT_EQ(r.components, 2u);
    EXPECT_EQ(CountCharts(ids), 2u);
    ExpectValidCharts(a, ids);
}

TEST(SplitChart, BisectsADiscIntoTwoBalancedDiscs) {
    const TriMesh m = Param(40, 20, false, false, [](double u, double v) {
        return Vec3f(float(2 * u), float(v), float(0.2 * std::sin(3 * u)));
    });
    const auto ids = SplitChart(m, 2);
    ASSERT_EQ(CountCharts(ids), 2u);
    ExpectValidCharts(m, ids);
    size_t first = 0;
    for (uint32_t c : ids)
        first += c == 0;
    EXPECT_GT(first, m.triangle_count() / 4);
    EXPECT_LT(first, 3 * m.triangle_count() / 4);

    const auto four = SplitChart(m, 4);
    EXPECT_EQ(CountCharts(four), 4u);
    ExpectValidCharts(m, four);
    const TriMesh one = Make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
    EXPECT_EQ(SplitChart(one, 2), std::vector<uint32_t>{0});
}

TEST(Segment, RejectsBadOptions) {
    SegmentOptions o;
    o.max_normal_deviation_deg = 0;
    EXPECT_THROW(SegmentCharts(Plane(2), o), Error);
    o = {};
    o.lloyd_iterations = 0;
    EXPECT_THROW(SegmentCharts(Plane(2), o), Error);
}

TEST(Segment, IsDeterministicAcrossThreadCounts) {
    const TriMesh m = Torus(80, 30);
    SegmentOptions o;
    o.target_chart_faces = 800;
    std::vector<uint32_t> one, two, again;
    {
        ThreadLimit limit(1);
        one = SegmentCharts(m, o);
    }
    {
        ThreadLimit limit(2);
        two = SegmentCharts(m, o);
        again = SegmentCharts(m, o);
    }
    EXPECT_EQ(one, two);
    EXPECT_EQ(two, again);
    ExpectValidCharts(m, one);
}

TEST(Segment, RepairedRandomSoupsGiveDiscs) {
    uint64_t state = 777;
    auto next = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(state >> 33);
    };
    for (int trial = 0; trial < 150; ++trial) {
        const uint32_t nv = 4 + next() % 60, nf = 1 + next() % 400;
        std::vector<Vec3f> p;
        for (uint32_t v = 0; v < nv; ++v)
            p.push_back({float(next() % 9), float(next() % 9), float(next() % 4)});
        std::vector<Tri> t;
        for (uint32_t f = 0; f < nf; ++f)
            t.push_back({next() % nv, next() % nv, next() % nv});
        TriMesh m = Make(p, t);
        Repair(m, {}, {});
        SegmentOptions o;
        o.min_chart_faces = 4;
        o.target_chart_faces = 20;
        const auto ids = SegmentCharts(m, o);
        ExpectValidCharts(m, ids);
        ASSERT_FALSE(::testing::Test::HasFailure()) << "trial " << trial;
    }
}

TEST(Segment, EmptyMesh) {
    EXPECT_TRUE(SegmentCharts(TriMesh{}, {}).empty());
    EXPECT_TRUE(SplitChart(TriMesh{}, 2).empty());
}

// Real data ------------------------------------------------------------------------------

using testing::LoadScan;

std::string Scan(const char* name) {
    return std::string(MEBAKE_SHARED_DATA) + "/scans/" + name;
}

double Ms(std::clock_t t0) {
    return 1000.0 * double(std::clock() - t0) / CLOCKS_PER_SEC;  // CPU time
}

TEST(SegmentData, BunnyChartsAreDiscs) {
    auto loaded = LoadScan(Scan("bun_zipper.ply"));
    if (!loaded)
        GTEST_SKIP() << "no " << Scan("bun_zipper.ply");
    TriMesh m = *loaded;
    auto t0 = std::clock();
    Repair(m, {}, {});
    const double repair_ms = Ms(t0);
    SegmentOptions o;
    SegmentReport r;
    t0 = std::clock();
    const auto ids = SegmentCharts(m, o, &r);
    const double segment_ms = Ms(t0);
    std::printf("bun_zipper: repair %.0f ms, segment %.0f ms: %zu charts (seeds %zu + %zu, "
                "%zu Lloyd passes, %zu leftover, %zu merged, %zu split), max %zu faces %zu "
                "vertices, max deviation %.0f deg\n",
                repair_ms, segment_ms, r.charts, r.initial_seeds, r.inserted_seeds,
                r.lloyd_iterations, r.leftover_charts, r.merged_charts, r.split_charts,
                r.max_chart_faces, r.max_chart_vertices, r.max_normal_deviation_deg);
    ExpectValidCharts(m, ids, o.max_chart_vertices);
    EXPECT_EQ(r.charts, CountCharts(ids));
    EXPECT_GE(r.charts, 3u);  // 69K faces and a 60 degree bound
    EXPECT_LE(r.max_chart_faces, 2 * size_t(o.target_chart_faces));
    EXPECT_LE(r.max_normal_deviation_deg, o.max_normal_deviation_deg + 1.0);

    std::vector<uint32_t> single;
    {
        ThreadLimit limit(1);
        single = SegmentCharts(m, o);
    }
    EXPECT_EQ(single, ids);

    // Smaller charts: many of them, all discs.
    o.target_chart_faces = 2000;
    const auto small = SegmentCharts(m, o, &r);
    std::printf("bun_zipper, 2000-face target: %zu charts, max %zu faces\n", r.charts,
                r.max_chart_faces);
    EXPECT_GE(r.charts, 30u);
    ExpectValidCharts(m, small, o.max_chart_vertices);
}

TEST(SegmentData, LowResolutionBunnyAfterRepair) {
    auto loaded = LoadScan(Scan("bun_zipper_res2.ply"));
    if (!loaded)
        GTEST_SKIP() << "no " << Scan("bun_zipper_res2.ply");
    TriMesh m = *loaded;
    Repair(m, {}, {});
    SegmentOptions o;
    o.target_chart_faces = 1500;
    SegmentReport r;
    const auto ids = SegmentCharts(m, o, &r);
    ExpectValidCharts(m, ids, o.max_chart_vertices);
    EXPECT_EQ(SegmentCharts(m, o), ids);
}

// A coarse box (two triangles per side, as in the Cornell boxes' OBJ files): every side
// must be a chart of its own, since one polynomial across a 90-degree edge rings.
TEST(Segment, CoarseBoxGetsOneChartPerSide) {
    const std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const std::vector<Tri> t = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
    const TriMesh box = Make(p, t);
    const std::vector<uint32_t> chart = SegmentCharts(box, SegmentOptions{});
    ASSERT_EQ(chart.size(), 12u);
    for (size_t f = 0; f < 12; f += 2)
        EXPECT_EQ(chart[f], chart[f + 1]) << "side " << f / 2 << " is split";
    std::vector<uint32_t> ids(chart.begin(), chart.end());
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(std::unique(ids.begin(), ids.end()) - ids.begin(), 6);
}

}  // namespace
}  // namespace mebake::stream
