// The seam metric on the two-chart fixture: zero for lighting continuous across the shared
// edge, the analytic jump for a discontinuous one, and the edge counts.
#include "output/seams.h"

#include "support/bake_fixture.h"

#include <gtest/gtest.h>

#include <filesystem>

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
}

TEST_F(SeamTest, DiscontinuousFieldJumps) {
    solve::testing::TinyBakeOptions o;
    o.light[0] = {Vec3f(2, 2, 2), Vec3f(0, 0, 0)};
    o.light[1] = {Vec3f(4, 4, 4), Vec3f(0, 0, 0)};
    solve::testing::WriteTinyBake(dir_, o);
    SeamOptions so;
    so.samples = 5;
    const SeamStats s = MeasureSeams(OpenBakeView(dir_), so);
    EXPECT_EQ(s.seam_edges, 1u);
    EXPECT_EQ(s.samples, 5u);
    // |1 - 2| / 1.5 with B = 0.5 E.
    EXPECT_NEAR(s.mean_relative, 2.0 / 3.0, 1e-5);
    EXPECT_NEAR(s.max_relative, 2.0 / 3.0, 1e-5);
    EXPECT_NEAR(s.p95_relative, 2.0 / 3.0, 1e-5);
    EXPECT_EQ(s.worst_v0, 1u);
    EXPECT_EQ(s.worst_v1, 4u);
    so.samples = 0;
    EXPECT_THROW(MeasureSeams(OpenBakeView(dir_), so), Error);
}

}  // namespace
}  // namespace mebake::output
