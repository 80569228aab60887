// Rendering the two-square fixture head-on: pixels on the squares show B / pi (each
// chart its own), missed pixels the background or the sky, glossy off equals diffuse,
// and the image is the same for any thread count.
#include "output/render.h"

#include "support/bake_fixture.h"
#include "core/parallel.h"
#include "io/exr_writer.h"
#include "io/png_writer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <numbers>

namespace mebake::output {
namespace {

constexpr float kPi = float(std::numbers::pi);

class RenderTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = solve::testing::FreshDir("render");
        opt_.light[0] = {Vec3f(2, 4, 6), Vec3f(0, 0, 0)};
        opt_.light[1] = {Vec3f(1, 1, 1), Vec3f(0, 0, 0)};
        solve::testing::WriteTinyBake(dir_, opt_);
        // Each chart's own field: the charts disagree at x = 1 on purpose (stitching is
        // stitch_test's).
        view_ = OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off);
        ro_.camera.eye = Vec3d(1, 0.5, 3);
        ro_.camera.target = Vec3d(1, 0.5, 0);
        ro_.camera.up = Vec3d(0, 1, 0);
        ro_.camera.fov = 40;
        ro_.camera.width = 64;
        ro_.camera.height = 32;
        ro_.background = Vec3f(0.25f, 0.5f, 0.75f);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    // The world point a pixel centre looks at on the plane z = 0.
    Vec3d Ground(int px, int py) const {
        const auto& c = ro_.camera;
        const double t = std::tan(c.fov * 0.5 * std::numbers::pi / 180);
        const double x = ((px + 0.5) / c.width * 2 - 1) * t * c.width / c.height;
        const double y = (1 - (py + 0.5) / c.height * 2) * t;
        return Vec3d(c.eye.x + x * c.eye.z, c.eye.y + y * c.eye.z, 0);
    }

    std::string dir_;
    solve::testing::TinyBakeOptions opt_;
    BakeView view_;
    RenderOptions ro_;
};

TEST_F(RenderTest, HeadOnQuadShowsRadianceAndBackground) {
    const RenderedImage img = Render(view_, ro_);
    ASSERT_EQ(img.width, 64);
    ASSERT_EQ(img.rgb.size(), 64u * 32 * 3);
    int on[2] = {0, 0}, off = 0;
    for (int py = 0; py < img.height; ++py)
        for (int px = 0; px < img.width; ++px) {
            const Vec3d g = Ground(px, py);
            const Vec3f v = img.At(px, py);
            const bool inside = g.x > 0.01 && g.x < 1.99 && g.y > 0.01 && g.y < 0.99;
            const bool outside = g.x < -0.01 || g.x > 2.01 || g.y < -0.01 || g.y > 1.01;
            if (inside && std::abs(g.x - 1) > 0.01) {
                const int c = g.x < 1 ? 0 : 1;
                const Vec3f want = solve::testing::ExpectedB(opt_, c, 0) / kPi;
                for (int k = 0; k < 3; ++k)
                    EXPECT_NEAR(v[k], want[k], 1e-5) << px << "," << py;
                ++on[c];
            } else if (outside) {
                EXPECT_EQ(v, *ro_.background) << px << "," << py;
                ++off;
            }
        }
    EXPECT_GT(on[0], 100);
    EXPECT_GT(on[1], 100);
    EXPECT_GT(off, 100);
    EXPECT_EQ(img.rays, 64u * 32);
    EXPECT_GT(img.hits, uint64_t(on[0] + on[1]) - 1);
}

TEST_F(RenderTest, BackOfTheSquaresIsBlack) {
    ro_.camera.eye = Vec3d(1, 0.5, -3);  // below the squares, which face +z
    const RenderedImage img = Render(view_, ro_);
    int black = 0;
    for (int py = 0; py < img.height; ++py)
        for (int px = 0; px < img.width; ++px) {
            const Vec3f v = img.At(px, py);
            if (v == *ro_.background)
                continue;
            EXPECT_EQ(v, Vec3f(0, 0, 0)) << px << "," << py;
            ++black;
        }
    EXPECT_GT(black, 200);
    EXPECT_EQ(img.hits, uint64_t(black));
}

TEST_F(RenderTest, SkyBehindAndSupersampling) {
    ro_.background.reset();
    ro_.samples = 2;
    const RenderedImage img = Render(view_, ro_);
    // The scene file's uniform sky.
    const Vec3f sky = img.At(0, 0);
    EXPECT_NEAR(sky.x, 0.1f, 1e-6);
    EXPECT_NEAR(sky.y, 0.2f, 1e-6);
    EXPECT_NEAR(sky.z, 0.3f, 1e-6);
    EXPECT_EQ(img.rays, 64u * 32 * 4);
    // Glossy display without a glossy material is the diffuse radiance.
    RenderOptions g = ro_;
    g.glossy = true;
    const RenderedImage gi = Render(view_, g);
    EXPECT_EQ(gi.rgb, img.rgb);
}

TEST_F(RenderTest, SameImageForAnyThreadCount) {
    ro_.camera.eye = Vec3d(-0.5, -1, 2);  // oblique: every pixel's shading differs
    const RenderedImage all = Render(view_, ro_);
    RenderedImage one;
    {
        ThreadLimit limit(1);
        one = Render(view_, ro_);
    }
    ASSERT_EQ(all.rgb.size(), one.rgb.size());
    EXPECT_EQ(0, std::memcmp(all.rgb.data(), one.rgb.data(), all.rgb.size() * sizeof(float)));
}

TEST_F(RenderTest, SameImageWhenChartsAreTracedOneGroupAtATime) {
    // One Embree scene per chart (the out-of-core path of a large mesh) against one scene
    // of both: the same closest hits, the same shading, the same bytes.
    ro_.camera.eye = Vec3d(-0.5, -1, 2);
    ro_.samples = 3;
    const RenderedImage whole = Render(view_, ro_);
    RenderOptions grouped = ro_;
    grouped.group_triangles = 1;
    const RenderedImage parts = Render(view_, grouped);
    ASSERT_EQ(whole.rgb.size(), parts.rgb.size());
    EXPECT_GT(whole.hits, 0u);
    EXPECT_EQ(whole.hits, parts.hits);
    EXPECT_EQ(0, std::memcmp(whole.rgb.data(), parts.rgb.data(), whole.rgb.size() * sizeof(float)));
    // With the sky as background too (its radiance follows each missed ray).
    ro_.background.reset();
    grouped.background.reset();
    EXPECT_EQ(Render(view_, ro_).rgb, Render(view_, grouped).rgb);
}

TEST_F(RenderTest, WritesExrAndPng) {
    const RenderedImage img = Render(view_, ro_);
    WriteRenderedImage(img, dir_ + "/v.exr", {}, io::ExrPixelType::Float);
    const io::ExrImage e = io::ReadExr(dir_ + "/v.exr");
    ASSERT_EQ(e.width, 64);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            ASSERT_EQ(e.At(x, y, e.Channel("G")), img.At(x, y).y);
    ToneMap tm;
    tm.exposure = 1;
    WriteRenderedImage(img, dir_ + "/v.png", tm);
    const io::PngImage p = io::ReadPng(dir_ + "/v.png");
    ASSERT_EQ(p.width, 64);
    uint8_t want[3];
    ToneMapPixel(img.At(10, 20), tm, want);
    EXPECT_EQ(p.pixels[(20 * 64 + 10) * 3 + 1], want[1]);
    EXPECT_THROW(WriteRenderedImage(img, dir_ + "/v.bmp", tm), Error);
}

TEST_F(RenderTest, BadCamerasAreUsageErrors) {
    RenderOptions r = ro_;
    r.camera.target = r.camera.eye;
    EXPECT_THROW(Render(view_, r), Error);
    r = ro_;
    r.camera.up = Vec3d(0, 0, 1);  // parallel to the view
    EXPECT_THROW(Render(view_, r), Error);
    r = ro_;
    r.camera.fov = 180;
    EXPECT_THROW(Render(view_, r), Error);
    r = ro_;
    r.camera.width = 0;
    EXPECT_THROW(Render(view_, r), Error);
}

}  // namespace
}  // namespace mebake::output
