// Light maps against the analytic B of a hand-made bake directory (bake_fixture.h): texel
// values, gutters, unused texels, no NaN or negative values, the irradiance channels, the
// EXR and PNG files and their page names, and thread-count determinism.
#include "output/lightmap.h"

#include "support/bake_fixture.h"
#include "core/parallel.h"
#include "io/exr_writer.h"
#include "io/png_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>

namespace mebake::output {
namespace {

using solve::testing::ExpectedB;
using solve::testing::TinyBakeOptions;

struct Page {
    uint32_t width = 0, height = 0;
    int nc = 0;
    std::vector<float> px;
    float At(uint32_t x, uint32_t y, int k) const {
        return px[(size_t(y) * width + x) * size_t(nc) + size_t(k)];
    }
};

Page Compute(const BakeView& view, const Atlas& atlas, uint32_t page, MapContent content,
             uint32_t band = 5, size_t group = 0) {
    Page p;
    p.width = atlas.pages[page].width;
    p.height = atlas.pages[page].height;
    p.nc = MapChannels(content);
    uint32_t next = 0;
    ComputePage(
        view, atlas, page, content,
        [&](std::span<const float> px, uint32_t first, uint32_t rows) {
            EXPECT_EQ(first, next);
            EXPECT_EQ(px.size(), size_t(rows) * p.width * size_t(p.nc));
            p.px.insert(p.px.end(), px.begin(), px.end());
            next += rows;
        },
        band, group);
    EXPECT_EQ(next, p.height);
    return p;
}

class LightMapTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = solve::testing::FreshDir("lightmap");
        opt_.light[0] = {Vec3f(2, 4, 6), Vec3f(1, -2, 3)};  // linear in u
        opt_.light[1] = {Vec3f(3, 3, 3), Vec3f(0, 0, 0)};   // constant
        solve::testing::WriteTinyBake(dir_, opt_);
        // Each chart's own field: the charts disagree at x = 1 on purpose (stitching is
        // stitch_test's).
        view_ = OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off);
        atlas_ = PackAtlas(ChartResolutions(view_), {});
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    std::string dir_;
    TinyBakeOptions opt_;
    BakeView view_;
    Atlas atlas_;
};

TEST_F(LightMapTest, TexelsEqualAnalyticRadiosity) {
    ASSERT_EQ(atlas_.pages.size(), 1u);
    const Page p = Compute(view_, atlas_, 0, MapContent::Radiosity);
    const uint32_t g = atlas_.gutter, r = opt_.resolution;
    std::vector<bool> covered(size_t(p.width) * p.height, false);
    for (uint32_t c = 0; c < 2; ++c) {
        const auto& ac = atlas_.charts[c];
        for (uint32_t by = 0; by < r + 2 * g; ++by)
            for (uint32_t bx = 0; bx < r + 2 * g; ++bx) {
                const uint32_t x = ac.x + bx, y = ac.y + by;
                covered[size_t(y) * p.width + x] = true;
                // Gutter texels repeat the nearest border texel.
                const uint32_t i = std::clamp(bx, g, g + r - 1) - g;
                const double u = (i + 0.5) / r;
                const Vec3f want = ExpectedB(opt_, int(c), u);
                for (int k = 0; k < 3; ++k)
                    EXPECT_NEAR(p.At(x, y, k), want[k], 1e-5 * (1 + want[k]))
                        << "chart " << c << " block texel " << bx << "," << by;
                EXPECT_EQ(p.At(x, y, 3), 1.f);
            }
    }
    for (uint32_t y = 0; y < p.height; ++y)
        for (uint32_t x = 0; x < p.width; ++x) {
            for (int k = 0; k < 4; ++k) {
                const float v = p.At(x, y, k);
                EXPECT_TRUE(std::isfinite(v) && v >= 0) << x << "," << y << " " << v;
                if (!covered[size_t(y) * p.width + x]) {
                    EXPECT_EQ(v, 0.f);
                }
            }
        }
}

TEST_F(LightMapTest, NegativeIrradianceClampsToZero) {
    TinyBakeOptions o;
    o.light[0] = {Vec3f(-1, 1, -5), Vec3f(0, 0, 10)};  // n . E < 0 on part of the square
    solve::testing::WriteTinyBake(dir_, o);
    const BakeView v = OpenBakeView(dir_);
    const Page p = Compute(v, atlas_, 0, MapContent::Radiosity);
    bool saw_zero = false;
    for (float x : p.px) {
        EXPECT_TRUE(std::isfinite(x) && x >= 0);
        saw_zero |= x == 0;
    }
    EXPECT_TRUE(saw_zero);
}

TEST_F(LightMapTest, IrradianceChannels) {
    const Page p = Compute(view_, atlas_, 0, MapContent::Irradiance);
    const auto names = MapChannelNames(MapContent::Irradiance);
    ASSERT_EQ(names.size(), 9u);
    EXPECT_EQ(names[0], "E.x.R");
    EXPECT_EQ(names[8], "E.z.B");
    const auto& ac = atlas_.charts[0];
    const uint32_t g = atlas_.gutter, r = opt_.resolution;
    for (uint32_t i = 0; i < r; ++i) {
        const double u = (i + 0.5) / r;
        const uint32_t x = ac.x + g + i, y = ac.y + g + 3;
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(p.At(x, y, c), 0, 1e-6);      // E.x
            EXPECT_NEAR(p.At(x, y, 3 + c), 0, 1e-6);  // E.y
            const double ez = opt_.light[0].a[c] + opt_.light[0].b[c] * u;
            EXPECT_NEAR(p.At(x, y, 6 + c), ez, 1e-5 * (1 + std::abs(ez)));
        }
    }
}

TEST_F(LightMapTest, SameBytesForAnyThreadCount) {
    const Page all = Compute(view_, atlas_, 0, MapContent::Radiosity, 64);
    Page one;
    {
        ThreadLimit limit(1);
        one = Compute(view_, atlas_, 0, MapContent::Radiosity, 3);
    }
    ASSERT_EQ(all.px.size(), one.px.size());
    EXPECT_EQ(0, std::memcmp(all.px.data(), one.px.data(), all.px.size() * sizeof(float)));
}

// One chart's tiles at a time, and fields read per chart from solution.bin (export's
// FieldLoading::OnDemand), give the same bytes as everything held at once.
TEST_F(LightMapTest, SameBytesChartByChartAndWithFieldsOnDemand) {
    // Both charts side by side on one shelf (PackAtlas stacks them for this tiny bake).
    Atlas atlas = atlas_;
    const uint32_t block = atlas.block(0);
    ASSERT_EQ(atlas.block(1), block);
    atlas.pages.assign(1, AtlasPage{});
    atlas.pages[0].width = 2 * block + 3;
    atlas.pages[0].height = block + 5;
    atlas.pages[0].shelves = {AtlasShelf{2, block, {0, 1}}};
    atlas.charts[0] = {0, 0, 2, atlas.charts[0].resolution};
    atlas.charts[1] = {0, block + 1, 2, atlas.charts[1].resolution};
    for (MapContent content : {MapContent::Radiosity, MapContent::Irradiance}) {
        const Page all = Compute(view_, atlas, 0, content, 64);
        const Page one = Compute(view_, atlas, 0, content, 4, 1);
        const BakeView lazy = OpenBakeView(dir_, FieldLoading::OnDemand, SeamStitching::Off);
        EXPECT_TRUE(lazy.solution.fields.empty());
        const Page on_demand = Compute(lazy, atlas, 0, content, 7, 1);
        if (content == MapContent::Radiosity) {  // chart 1's texels are there (A = 1)
            EXPECT_EQ(all.At(block + 1 + atlas.gutter + 1, 2 + atlas.gutter + 1, 3), 1.f);
        }
        for (const Page* p : {&one, &on_demand}) {
            ASSERT_EQ(all.px.size(), p->px.size());
            EXPECT_EQ(0, std::memcmp(all.px.data(), p->px.data(), all.px.size() * sizeof(float)));
        }
    }
}

TEST_F(LightMapTest, ExrAndPngFiles) {
    const Page p = Compute(view_, atlas_, 0, MapContent::Radiosity);
    MapWriteOptions mo;
    mo.exr_type = io::ExrPixelType::Float;
    const std::string exr = dir_ + "/lm.exr";
    ASSERT_EQ(WriteMapPages(view_, atlas_, exr, MapContent::Radiosity, mo),
              std::vector<std::string>{exr});
    const io::ExrImage img = io::ReadExr(exr);
    ASSERT_EQ(uint32_t(img.width), p.width);
    ASSERT_EQ(uint32_t(img.height), p.height);
    const char* names[4] = {"R", "G", "B", "A"};
    for (int k = 0; k < 4; ++k) {
        const int ch = img.Channel(names[k]);
        ASSERT_GE(ch, 0) << names[k];
        for (uint32_t y = 0; y < p.height; ++y)
            for (uint32_t x = 0; x < p.width; ++x)
                ASSERT_EQ(img.At(int(x), int(y), ch), p.At(x, y, k));
    }

    // Half: within half precision.
    mo.exr_type = io::ExrPixelType::Half;
    const std::string half = dir_ + "/irr.exr";
    WriteMapPages(view_, atlas_, half, MapContent::Irradiance, mo);
    const Page e = Compute(view_, atlas_, 0, MapContent::Irradiance);
    const io::ExrImage hi = io::ReadExr(half);
    const auto irr_names = MapChannelNames(MapContent::Irradiance);
    for (int k = 0; k < 9; ++k) {
        const int ch = hi.Channel(irr_names[size_t(k)]);
        ASSERT_GE(ch, 0);
        EXPECT_TRUE(hi.half[size_t(ch)]);
        for (uint32_t y = 0; y < p.height; ++y)
            for (uint32_t x = 0; x < p.width; ++x)
                ASSERT_NEAR(hi.At(int(x), int(y), ch), e.At(x, y, k),
                            1e-3 * (1 + std::abs(e.At(x, y, k))));
    }

    // PNG: the tone-mapped radiance B / pi.
    const std::string png = dir_ + "/lm.png";
    mo.tone.exposure = -1;
    WriteMapPages(view_, atlas_, png, MapContent::Radiosity, mo);
    const io::PngImage pi = io::ReadPng(png);
    ASSERT_EQ(uint32_t(pi.width), p.width);
    ASSERT_EQ(pi.channels, 3);
    EXPECT_TRUE(pi.srgb);
    for (uint32_t y = 0; y < p.height; ++y)
        for (uint32_t x = 0; x < p.width; ++x) {
            uint8_t want[3];
            ToneMapPixel(
                Vec3f(p.At(x, y, 0), p.At(x, y, 1), p.At(x, y, 2)) / float(std::numbers::pi),
                mo.tone, want);
            for (int k = 0; k < 3; ++k)
                ASSERT_EQ(pi.pixels[(size_t(y) * p.width + x) * 3 + size_t(k)], want[k]);
        }
    EXPECT_THROW(WriteMapPages(view_, atlas_, dir_ + "/lm.tif", MapContent::Radiosity, mo), Error);
    EXPECT_THROW(WriteMapPages(view_, atlas_, dir_ + "/e.png", MapContent::Irradiance, mo), Error);
}

TEST_F(LightMapTest, PagesGetUdimNames) {
    AtlasOptions ao;
    ao.max_size = 16;  // one 12-texel block per page
    const Atlas a = PackAtlas(ChartResolutions(view_), ao);
    ASSERT_EQ(a.pages.size(), 2u);
    const auto files = WriteMapPages(view_, a, dir_ + "/lm.exr", MapContent::Radiosity, {});
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files[0], dir_ + "/lm.1001.exr");
    EXPECT_EQ(files[1], dir_ + "/lm.1002.exr");
    for (const auto& f : files)
        EXPECT_TRUE(std::filesystem::exists(f));
    EXPECT_FALSE(std::filesystem::exists(dir_ + "/lm.exr"));
    EXPECT_THROW(WriteMapPages(view_, a, "-", MapContent::Radiosity, {}), Error);
}

TEST_F(LightMapTest, UnsolvedDirectoryIsAUsageError) {
    std::filesystem::remove(solve::SolutionPath(dir_));
    try {
        OpenBakeView(dir_);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Usage);
    }
}

}  // namespace
}  // namespace mebake::output
