#include "stream/chart_merge.h"

#include "core/parallel.h"
#include "stream/segment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;

// An n x n grid over [0,1]^2 lifted by height(u, v).
template <typename Fn>
TriMesh Grid(int n, Fn height) {
    TriMesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double u = double(i) / n, v = double(j) / n;
            m.position.push_back(Vec3f(float(u), float(v), float(height(u, v))));
        }
    auto id = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

// Chart ids of a grid cut into k x k blocks of cells.
std::vector<uint32_t> Blocks(int n, int k) {
    std::vector<uint32_t> chart;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            for (int t = 0; t < 2; ++t)
                chart.push_back(uint32_t((j * k / n) * k + i * k / n));
    return chart;
}

size_t Count(const std::vector<uint32_t>& chart) {
    return chart.empty() ? 0 : *std::max_element(chart.begin(), chart.end()) + 1;
}

// Every chart a disc whose parameterization passes the merge test.
void ExpectCharts(const TriMesh& m, const std::vector<uint32_t>& chart, const MergeOptions& o) {
    for (const TriMesh& c : ExtractCharts(m, chart)) {
        EXPECT_TRUE(CheckDisc(c).IsDisc());
        const ChartParam p = ParameterizeChart(c, o.param);
        EXPECT_EQ(p.status, ParamStatus::kOk) << p.message;
        EXPECT_EQ(p.metrics.flipped, 0u);
    }
}

TEST(ChartMerge, FlatBlocksBecomeOneChart) {
    const TriMesh m = Grid(32, [](double, double) { return 0.0; });
    std::vector<uint32_t> chart = Blocks(32, 4);
    ASSERT_EQ(Count(chart), 16u);
    // Two square blocks make a 2:1 rectangle, whose square is twice theirs together: by
    // default that union is refused (the light map would grow) ...
    std::vector<uint32_t> kept = chart;
    const MergeReport none = MergeCharts(m, MergeOptions{}, &kept);
    EXPECT_EQ(none.charts_after, 16u);
    EXPECT_GT(none.tried, 0u);
    EXPECT_EQ(kept, chart);
    // ... and allowed when the square may double; then rectangles pair up into squares.
    MergeOptions o;
    o.max_square_growth = 1;
    const MergeReport r = MergeCharts(m, o, &chart);
    EXPECT_EQ(r.charts_before, 16u);
    EXPECT_EQ(r.charts_after, 1u);
    EXPECT_EQ(r.accepted, 15u);
    EXPECT_EQ(Count(chart), 1u);
    // Pairs are matched per round: 16 -> 8 -> 4 -> 2 -> 1 at best, never one per round.
    EXPECT_LE(r.rounds, 8u);
}

TEST(ChartMerge, TheRuleStopsMerging) {
    // A steep bump cannot be flattened within 1 % area deviation as one chart.
    const TriMesh m = Grid(48, [](double u, double v) {
        const double x = u - 0.5, y = v - 0.5;
        return 0.6 * std::exp(-(x * x + y * y) / 0.02);
    });
    std::vector<uint32_t> chart = Blocks(48, 6);
    MergeOptions o;
    const MergeReport r = MergeCharts(m, o, &chart);
    EXPECT_LT(r.charts_after, r.charts_before);
    EXPECT_GT(r.charts_after, 1u);
    EXPECT_GT(r.tried, r.accepted);  // some unions failed the test
    for (const TriMesh& c : ExtractCharts(m, chart)) {
        const ChartParam p = ParameterizeChart(c, o.param);
        // Every block of 8 x 8 cells starts within the bound here, so every chart ends so.
        EXPECT_LE(p.metrics.jacobian_deviation_mean, o.max_mean_deviation);
    }
    ExpectCharts(m, chart, o);
}

TEST(ChartMerge, SquareSizeBoundsUnions) {
    const TriMesh m = Grid(32, [](double, double) { return 0.0; });
    std::vector<uint32_t> chart = Blocks(32, 4);
    MergeOptions o;
    o.max_square_growth = 1;
    // A block's square is about 0.25 / (1 - 2 margin) on a side; two blocks need more.
    o.max_scale = 0.3;
    EXPECT_EQ(MergeCharts(m, o, &chart).charts_after, 16u);
}

TEST(ChartMerge, FoldsStayApart) {
    // A box's sides, two triangles each, one chart per side: every border is a 90-degree
    // fold, so nothing merges although each pair of sides flattens without distortion.
    TriMesh box;
    box.position = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    box.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                     {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
    std::vector<uint32_t> chart = {0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5};
    const MergeReport r = MergeCharts(box, MergeOptions{}, &chart);
    EXPECT_EQ(r.charts_after, 6u);
    EXPECT_EQ(r.tried, 0u);
    EXPECT_EQ(r.rejected_fold, 12u);
    // Without the fold rule two sides do merge (into an L whose square is twice theirs).
    MergeOptions any;
    any.fold_deg = 180;
    any.max_square_growth = 1;
    EXPECT_LT(MergeCharts(box, any, &chart).charts_after, 6u);
}

TEST(ChartMerge, SphereChartsStayDiscsAndAreDeterministic) {
    // A closed sphere: at least two charts remain (a disc cannot be closed).
    TriMesh m;
    const int stacks = 30, slices = 60;
    m.position.push_back({0, 0, 1});
    for (int s = 1; s < stacks; ++s)
        for (int k = 0; k < slices; ++k) {
            const double th = M_PI * s / stacks, ph = 2 * M_PI * k / slices;
            m.position.push_back({float(std::sin(th) * std::cos(ph)),
                                  float(std::sin(th) * std::sin(ph)), float(std::cos(th))});
        }
    m.position.push_back({0, 0, -1});
    const uint32_t south = uint32_t(m.position.size() - 1);
    auto id = [&](int s, int k) { return uint32_t(1 + (s - 1) * slices + (k % slices)); };
    for (int k = 0; k < slices; ++k)
        m.triangles.push_back({0, id(1, k), id(1, k + 1)});
    for (int s = 1; s + 1 < stacks; ++s)
        for (int k = 0; k < slices; ++k) {
            m.triangles.push_back({id(s, k), id(s + 1, k), id(s + 1, k + 1)});
            m.triangles.push_back({id(s, k), id(s + 1, k + 1), id(s, k + 1)});
        }
    for (int k = 0; k < slices; ++k)
        m.triangles.push_back({id(stacks - 1, k), south, id(stacks - 1, k + 1)});
    SegmentOptions so;
    so.target_chart_faces = 100;
    so.max_normal_deviation_deg = 20;
    const std::vector<uint32_t> segmented = SegmentCharts(m, so);
    ASSERT_GE(Count(segmented), 20u);
    std::vector<uint32_t> one = segmented, two = segmented;
    MergeReport r;
    {
        ThreadLimit limit(1);
        r = MergeCharts(m, MergeOptions{}, &one);
    }
    {
        ThreadLimit limit(2);
        MergeCharts(m, MergeOptions{}, &two);
    }
    EXPECT_EQ(one, two);
    EXPECT_GE(r.charts_after, 2u);
    EXPECT_LT(r.charts_after, Count(segmented) / 2);
    ExpectCharts(m, one, MergeOptions{});
}

TEST(ChartMerge, TurningInsideHorizonCellsBoundsUnions) {
    // A half cylinder of radius 1 and length 2 in 8 strips along its axis (22.5 degrees
    // each). Unions are developable; what grows is how far the surface turns inside one
    // of the 8 x 8 cells of the union's square: about 3 degrees for one strip, 14 for two,
    // 22 for all eight.
    const int n = 64;
    TriMesh m = Grid(n, [](double, double) { return 0.0; });
    for (Vec3f& p : m.position) {
        const double a = M_PI * p.x;
        p = Vec3f(float(std::cos(a)), float(2 * p.y), float(std::sin(a)));
    }
    std::vector<uint32_t> strips;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            for (int t = 0; t < 2; ++t)
                strips.push_back(uint32_t(i * 8 / n));
    MergeOptions o;
    o.max_square_growth = 1;
    std::vector<uint32_t> loose = strips, tight = strips;
    EXPECT_LT(MergeCharts(m, o, &loose).charts_after, 3u);
    o.max_cell_spread_deg = 5;
    const MergeReport r = MergeCharts(m, o, &tight);
    EXPECT_EQ(r.charts_after, 8u);
    EXPECT_GT(r.tried, 0u);
}

TEST(ChartMerge, OneChartOrNone) {
    const TriMesh m = Grid(4, [](double, double) { return 0.0; });
    std::vector<uint32_t> chart(m.triangle_count(), 0);
    EXPECT_EQ(MergeCharts(m, MergeOptions{}, &chart).charts_after, 1u);
    TriMesh empty;
    std::vector<uint32_t> none;
    EXPECT_EQ(MergeCharts(empty, MergeOptions{}, &none).charts_after, 0u);
}

}  // namespace
}  // namespace mebake::stream
