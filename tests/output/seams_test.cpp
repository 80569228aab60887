// The seam metric on the two-chart fixture: zero for lighting continuous across the shared
// edge, the analytic jump for a discontinuous one, and the edge counts.
#include "output/seams.h"

#include "output/continuous_field.h"
#include "output/node_seams.h"
#include "output/tonemap.h"
#include "support/bake_fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

namespace mebake::output {
namespace {

class SeamTest : public ::testing::Test {
protected:
    void SetUp() override { dir_ = solve::testing::FreshDir("seams"); }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::string dir_;
};

TEST_F(SeamTest, ContinuousFieldHasNoSeam) {
    solve::testing::TinyBakeOptions o;
    // E_z = 1 + 2x over both squares: chart 0 a + b u with u = x, chart 1 with u = x - 1.
    o.light[0] = {Vec3f(1, 1, 1), Vec3f(2, 2, 2)};
    o.light[1] = {Vec3f(3, 3, 3), Vec3f(2, 2, 2)};
    solve::testing::WriteTinyBake(dir_, o);
    const SeamStats s = MeasureSeams(OpenBakeView(dir_));
    EXPECT_EQ(s.seam_edges, 1u);  // the edge x = 1 (vertices 1 and 4)
    EXPECT_EQ(s.open_edges, 6u);  // the rest of the two squares' outlines
    EXPECT_EQ(s.samples, 3u);
    EXPECT_NEAR(s.mean_relative, 0, 1e-6);
    EXPECT_NEAR(s.max_relative, 0, 1e-6);
    EXPECT_NEAR(s.mean_level, solve::testing::kAlbedo * 3, 1e-5);
    EXPECT_NEAR(s.display.max, 0, 1e-6);
}

// What a viewer sees of a luminance y of B: the default tone map of y / pi, sRGB-encoded.
double Shown(double y) {
    return EncodeSrgb(ApplyToneCurve(float(y / M_PI), ToneMap{}));
}

TEST_F(SeamTest, DiscontinuousFieldJumps) {
    solve::testing::TinyBakeOptions o;
    o.light[0] = {Vec3f(2, 2, 2), Vec3f(0, 0, 0)};
    o.light[1] = {Vec3f(4, 4, 4), Vec3f(0, 0, 0)};
    solve::testing::WriteTinyBake(dir_, o);
    SeamOptions so;
    so.samples = 5;
    // The fields as fitted; stitched (the default) the same edge shows no jump.
    EXPECT_LT(MeasureSeams(OpenBakeView(dir_), so).display.max, 1e-6);
    const SeamStats s =
        MeasureSeams(OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off), so);
    EXPECT_EQ(s.seam_edges, 1u);
    EXPECT_EQ(s.samples, 5u);
    // |1 - 2| / 1.5 with B = 0.5 E.
    EXPECT_NEAR(s.mean_relative, 2.0 / 3.0, 1e-5);
    EXPECT_NEAR(s.max_relative, 2.0 / 3.0, 1e-5);
    EXPECT_NEAR(s.p95_relative, 2.0 / 3.0, 1e-5);
    const double shown = Shown(2.0) - Shown(1.0);
    EXPECT_GT(shown, 0.05);
    EXPECT_NEAR(s.display.mean, shown, 1e-6);
    EXPECT_NEAR(s.display.p95, shown, 1e-4);  // a histogram of 1e-4 bins
    EXPECT_EQ(s.worst_v0, 1u);
    EXPECT_EQ(s.worst_v1, 4u);
    so.samples = 0;
    EXPECT_THROW(MeasureSeams(OpenBakeView(dir_), so), Error);
}

TEST_F(SeamTest, NodeBordersOfAContinuousFieldDoNotJump) {
    solve::testing::TinyBakeOptions o;
    o.light[0] = {Vec3f(1, 1, 1), Vec3f(2, 2, 2)};
    o.light[1] = {Vec3f(3, 3, 3), Vec3f(2, 2, 2)};
    o.subdivide = 2;  // 16 leaves per chart, each the restriction of the linear field
    solve::testing::WriteTinyBake(dir_, o);
    const NodeSeamStats s = MeasureNodeSeams(OpenBakeView(dir_));
    EXPECT_EQ(s.edges, 2u * 24u);  // per chart: 3 inner lines x 4 leaves x 2 directions
    EXPECT_EQ(s.display.samples, 2u * 24u * 3u);
    EXPECT_LT(s.display.max, 1e-4);
}

TEST_F(SeamTest, ABrighterLeafIsShownContinuously) {
    solve::testing::TinyBakeOptions o;
    o.light[0] = o.light[1] = {Vec3f(2, 2, 2), Vec3f(0, 0, 0)};
    o.subdivide = 1;
    o.leaf_step = 2;  // chart 0's first leaf [0, 0.5]^2: E_z 4 instead of 2, B 2 instead of 1
    solve::testing::WriteTinyBake(dir_, o);
    const BakeView view = OpenBakeView(dir_);
    // The raw field steps at the leaf's border; what is shown (and measured) does not.
    const NodeSeamStats s = MeasureNodeSeams(view);
    ASSERT_EQ(s.display.samples, 24u);  // per chart 4 inner edges x 3 samples
    EXPECT_LT(s.display.max, 1e-3);
    // Across the border u = 0.5 at v = 0.25: the bright leaf's B (2) well inside it, the
    // mean of the two (1.5) on the border, the neighbour's (1) past the blend width, and a
    // ramp in between.
    const auto field = view.Field(0);
    const ContinuousField shown(*field, 1.0 / 8);  // the fixture's texel
    const double d = shown.delta();
    EXPECT_NEAR(d, 1.0 / 8, 1e-12);
    auto b_at = [&](double u) {
        float val[9];
        shown.Eval(u, 0.25, val);
        return solve::testing::kAlbedo * val[2];  // E_z of red
    };
    EXPECT_NEAR(b_at(0.5 - 1.5 * d), 2.0, 1e-5);
    EXPECT_NEAR(b_at(0.5), 1.5, 1e-5);
    EXPECT_NEAR(b_at(0.5 + 1.5 * d), 1.0, 1e-5);
    EXPECT_NEAR(b_at(0.5 - 0.5 * d), 1.75, 1e-5);
    EXPECT_NEAR(b_at(0.5 + 0.5 * d), 1.25, 1e-5);
}

// The 95th percentile's selection on spilled samples: the value std::nth_element puts at q,
// for values with repeats, zeros, tiny and huge magnitudes, at every rank of a small set
// and at chosen ranks of a large one.
TEST(NthSmallestTest, SameValueAsNthElement) {
    std::mt19937_64 rng(7);
    std::vector<double> v;
    for (int i = 0; i < 20000; ++i) {
        const double u = std::uniform_real_distribution<double>(0, 1)(rng);
        const int kind = int(rng() % 4);
        if (kind == 0)
            v.push_back(0.0);
        else if (kind == 1)
            v.push_back(std::ldexp(u, int(rng() % 200) - 100));
        else if (kind == 2)
            v.push_back(double(int(u * 5)));  // repeats
        else
            v.push_back(u);
    }
    auto over = [](const std::vector<double>& vals) {
        return [&vals](auto&& f) {
            for (double x : vals)
                f(x);
        };
    };
    auto expect = [&](const std::vector<double>& vals, uint64_t q) {
        std::vector<double> sorted = vals;
        std::nth_element(sorted.begin(), sorted.begin() + ptrdiff_t(q), sorted.end());
        EXPECT_EQ(NthSmallest(q, over(vals)), sorted[q]) << "rank " << q;
    };
    const std::vector<double> small(v.begin(), v.begin() + 40);
    for (uint64_t q = 0; q < small.size(); ++q)
        expect(small, q);
    for (uint64_t q : {uint64_t(0), uint64_t(1), uint64_t(4999), uint64_t(10000),
                       uint64_t(18999), uint64_t(19999)})
        expect(v, q);
}

}  // namespace
}  // namespace mebake::output
