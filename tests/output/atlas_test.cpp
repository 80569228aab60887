// Atlas packing: blocks (square + gutters) never overlap and stay inside their page, pages
// are powers of two no larger than the limit, the result is deterministic, and the uv
// mapping and its texel inverse agree.
#include "output/atlas.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mebake::output {
namespace {

std::vector<uint32_t> RandomResolutions(size_t n, uint32_t seed) {
    std::vector<uint32_t> r(n);
    uint64_t s = seed;
    for (auto& x : r) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        x = 1u << ((s >> 33) % 9);  // 1 .. 256
    }
    return r;
}

bool IsPow2(uint32_t x) {
    return x && !(x & (x - 1));
}

void ExpectValid(const Atlas& a, std::span<const uint32_t> res, const AtlasOptions& opt) {
    ASSERT_EQ(a.charts.size(), res.size());
    for (const auto& p : a.pages) {
        if (opt.power_of_two) {
            EXPECT_TRUE(IsPow2(p.width) && IsPow2(p.height)) << p.width << "x" << p.height;
        } else {
            EXPECT_TRUE(p.width % 4 == 0 && p.height % 4 == 0) << p.width << "x" << p.height;
        }
        EXPECT_LE(p.width, opt.max_size);
        EXPECT_LE(p.height, opt.max_size);
    }
    // Every chart inside its page; no two blocks of a page overlap (gutters included).
    for (size_t c = 0; c < res.size(); ++c) {
        const auto& ac = a.charts[c];
        EXPECT_EQ(ac.resolution, res[c]);
        ASSERT_LT(ac.page, a.pages.size());
        const uint32_t b = a.block(uint32_t(c));
        EXPECT_LE(ac.x + b, a.pages[ac.page].width);
        EXPECT_LE(ac.y + b, a.pages[ac.page].height);
    }
    for (size_t c = 0; c < res.size(); ++c)
        for (size_t d = c + 1; d < res.size(); ++d) {
            const auto &p = a.charts[c], &q = a.charts[d];
            if (p.page != q.page)
                continue;
            const uint32_t bp = a.block(uint32_t(c)), bq = a.block(uint32_t(d));
            const bool apart =
                p.x + bp <= q.x || q.x + bq <= p.x || p.y + bp <= q.y || q.y + bq <= p.y;
            EXPECT_TRUE(apart) << "charts " << c << " and " << d << " overlap";
        }
    // Shelves list each chart once.
    size_t listed = 0;
    for (const auto& p : a.pages)
        for (const auto& s : p.shelves) {
            listed += s.charts.size();
            for (uint32_t c : s.charts)
                EXPECT_EQ(a.charts[c].y, s.y);
        }
    EXPECT_EQ(listed, res.size());
}

TEST(Atlas, RandomChartsPackWithoutOverlap) {
    AtlasOptions opt;
    opt.max_size = 1024;
    opt.gutter = 3;
    const auto res = RandomResolutions(300, 7);
    const Atlas a = PackAtlas(res, opt);
    ExpectValid(a, res, opt);
    EXPECT_GT(a.fill(), 0.3) << "a packing this loose wastes most of the atlas";
    // Deterministic.
    const Atlas b = PackAtlas(res, opt);
    for (size_t c = 0; c < res.size(); ++c) {
        EXPECT_EQ(a.charts[c].page, b.charts[c].page);
        EXPECT_EQ(a.charts[c].x, b.charts[c].x);
        EXPECT_EQ(a.charts[c].y, b.charts[c].y);
    }
}

TEST(Atlas, SplitsIntoPagesOverTheLimit) {
    AtlasOptions opt;
    opt.max_size = 256;
    opt.gutter = 2;
    // 20 charts of 128 (+4) texels: 1 per row and column of a 256 page -> 20 pages.
    std::vector<uint32_t> res(20, 128);
    const Atlas a = PackAtlas(res, opt);
    ExpectValid(a, res, opt);
    EXPECT_EQ(a.pages.size(), 20u);
    // Small charts fill a page before the next one starts, in chart-id order for ties.
    std::vector<uint32_t> small(100, 16);
    const Atlas s = PackAtlas(small, opt);
    ExpectValid(s, small, opt);
    ASSERT_EQ(s.pages.size(), 1u);  // 12 x 12 blocks of 20 texels fit a 256 page
    EXPECT_EQ(s.pages[0].width, 256u);
}

TEST(Atlas, SmallestPowerOfTwoPage) {
    AtlasOptions opt;
    opt.gutter = 2;
    const std::vector<uint32_t> one{64};
    const Atlas a = PackAtlas(one, opt);
    ASSERT_EQ(a.pages.size(), 1u);
    EXPECT_EQ(a.pages[0].width, 128u);  // 68 texels need 128
    EXPECT_EQ(a.pages[0].height, 128u);
    const std::vector<uint32_t> four{60, 60, 60, 60};
    const Atlas b = PackAtlas(four, opt);
    ASSERT_EQ(b.pages.size(), 1u);
    EXPECT_EQ(uint64_t(b.pages[0].width) * b.pages[0].height, 128u * 128u);
}

TEST(Atlas, MultipleOfFourPagesFillBetter) {
    AtlasOptions opt;
    opt.gutter = 2;
    const std::vector<uint32_t> res(8, 512);  // 516-texel blocks
    const Atlas pow2 = PackAtlas(res, opt);
    opt.power_of_two = false;
    const Atlas npot = PackAtlas(res, opt);
    ExpectValid(npot, res, opt);
    ASSERT_EQ(npot.pages.size(), 1u);
    EXPECT_EQ(npot.pages[0].width % 4, 0u);
    EXPECT_EQ(npot.pages[0].height % 4, 0u);
    EXPECT_LT(npot.texels(), pow2.texels());
    EXPECT_GT(npot.fill(), 0.8);
    const auto rnd = RandomResolutions(500, 3);
    opt.max_size = 2048;
    ExpectValid(PackAtlas(rnd, opt), rnd, opt);
}

TEST(Atlas, LargerChartsFirstTiesById) {
    const std::vector<uint32_t> res{8, 32, 8, 32};
    const Atlas a = PackAtlas(res, {});
    // Placement order = reading order of the page (shelf, then left to right).
    auto rank = [&](uint32_t c) {
        return uint64_t(a.charts[c].y) << 32 | a.charts[c].x;
    };
    EXPECT_EQ(rank(1), 0u);
    EXPECT_LT(rank(1), rank(3));
    EXPECT_LT(rank(3), rank(0));
    EXPECT_LT(rank(0), rank(2));
}

TEST(Atlas, UvAndTexelInverse) {
    const std::vector<uint32_t> res{16, 8, 4};
    AtlasOptions opt;
    opt.gutter = 2;
    const Atlas a = PackAtlas(res, opt);
    for (uint32_t c = 0; c < 3; ++c) {
        const auto& ac = a.charts[c];
        const auto& pg = a.pages[ac.page];
        const uint32_t b = a.block(c);
        for (uint32_t by = 0; by < b; ++by)
            for (uint32_t bx = 0; bx < b; ++bx) {
                const Vec2f uv = a.TexelUv(c, bx, by);
                EXPECT_GT(uv.x, 0.f);
                EXPECT_LT(uv.x, 1.f);
                const Vec2f at = a.AtlasUv(c, uv);
                // Inside the square the texel centre maps back to itself; a gutter texel to the
                // nearest border texel.
                const double ex = std::clamp<double>(bx, 2, 2 + res[c] - 1) + ac.x + 0.5;
                const double ey = std::clamp<double>(by, 2, 2 + res[c] - 1) + ac.y + 0.5;
                EXPECT_NEAR(at.x * pg.width, ex, 1e-3);
                EXPECT_NEAR(at.y * pg.height, ey, 1e-3);
            }
        // The square's corners land on the inner edge of the gutter.
        const Vec2f o = a.AtlasUv(c, Vec2f(0, 0));
        EXPECT_FLOAT_EQ(o.x * pg.width, float(ac.x + 2));
        EXPECT_FLOAT_EQ(o.y * pg.height, float(ac.y + 2));
    }
}

TEST(Atlas, RejectsWhatCannotFit) {
    AtlasOptions opt;
    opt.max_size = 64;
    const std::vector<uint32_t> big{64};  // + gutters > 64
    EXPECT_THROW(PackAtlas(big, opt), Error);
    opt.max_size = 1000;
    EXPECT_THROW(PackAtlas(std::vector<uint32_t>{4}, opt), Error);
    EXPECT_TRUE(PackAtlas(std::vector<uint32_t>{}, {}).pages.empty());
}

}  // namespace
}  // namespace mebake::output
