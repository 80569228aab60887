// GeometryCache: views hold the pyramids' bytes, sampling matches stream::SampleBilinear
// bit for bit, pins keep pyramids resident, the least recently used unpinned ones are
// evicted under the budget (and really leave resident memory), and a solve over cached
// pyramids evicted at every unpin gives the same bits as one over in-memory pyramids.
#include "solve/geometry_cache.h"

#include "core/units.h"
#include "patch_fixture.h"
#include "solve/polygon_light.h"
#include "solve/solver.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <unistd.h>

namespace mebake::solve {
namespace {

namespace fs = std::filesystem;

using testing::FreshDir;

// A wavy patch's geometry image at res x res.
stream::GeometryImage Wavy(int res, double phase) {
    auto patch = testing::MakePatch(
        [phase](double u, double v) {
            return Vec3d(u, 0.1 * std::sin(6 * u + phase) * std::cos(5 * v), v);
        },
        res, 7, 1);
    // MakePatch hands out a view; rebuild the image from it (same bytes).
    stream::GeometryImage img;
    img.resolution = patch.chart.geometry.resolution;
    for (const auto& level : patch.chart.geometry.levels)
        img.levels.emplace_back(level.begin(), level.end());
    return img;
}

bool SameBytes(std::span<const stream::GeometryTexel> a,
               const std::vector<stream::GeometryTexel>& b) {
    return a.size() == b.size() &&
           std::memcmp(a.data(), b.data(), b.size() * sizeof(stream::GeometryTexel)) == 0;
}

TEST(GeometryCache, ViewsHoldTheBytesAndSampleLikeTheImage) {
    const std::string dir = FreshDir("geocache-views", false);
    GeometryCache cache(dir, 0);
    std::vector<stream::GeometryImage> images = {Wavy(32, 0), Wavy(8, 1), Wavy(64, 2)};
    for (const auto& img : images)
        cache.Add(img);
    EXPECT_TRUE(fs::is_empty(dir)) << "the cache file must be unlinked";
    for (uint32_t c = 0; c < images.size(); ++c) {
        const GeometryPyramid view = cache.View(c);
        const GeometryPin pin = view.Pin();
        ASSERT_EQ(view.levels.size(), images[c].levels.size());
        EXPECT_EQ(view.resolution, images[c].resolution);
        for (size_t l = 0; l < view.levels.size(); ++l)
            EXPECT_TRUE(SameBytes(view.levels[l], images[c].levels[l])) << c << " level " << l;
        uint64_t state = 99 + c;
        for (int k = 0; k < 2000; ++k) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            const float u = float(state >> 40) / float(1 << 24) * 1.2f - 0.1f;
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            const float v = float(state >> 40) / float(1 << 24) * 1.2f - 0.1f;
            const int level = k % (view.finest_level() + 2);
            const auto a = SampleBilinear(view, level, u, v);
            const auto b = stream::SampleBilinear(images[c], level, u, v);
            ASSERT_EQ(std::memcmp(&a, &b, sizeof(a)), 0) << "u " << u << " v " << v;
        }
    }
    fs::remove_all(dir);
}

TEST(GeometryCache, PinsAndLeastRecentlyUsedEviction) {
    const std::string dir = FreshDir("geocache-lru", false);
    const stream::GeometryImage img = Wavy(32, 0);  // 1365 texels: 87,360 bytes
    const uint64_t bytes = 1365 * sizeof(stream::GeometryTexel);
    GeometryCache cache(dir, 2 * bytes);  // two unpinned pyramids may stay
    for (int c = 0; c < 4; ++c)
        cache.Add(img);
    std::vector<GeometryPyramid> views;
    for (uint32_t c = 0; c < 4; ++c)
        views.push_back(cache.View(c));
    for (uint32_t c = 0; c < 4; ++c)
        EXPECT_FALSE(cache.resident(c)) << "Add drops the written pages";

    { const GeometryPin p0 = views[0].Pin(); }
    { const GeometryPin p1 = views[1].Pin(); }
    EXPECT_TRUE(cache.resident(0));
    EXPECT_TRUE(cache.resident(1));
    EXPECT_EQ(cache.stats().evictions, 0u);
    {
        const GeometryPin p2 = views[2].Pin();
        // Pinned: three resident, over budget until the pin goes.
        EXPECT_EQ(cache.stats().resident_bytes, 3 * bytes);
    }
    // Unpinning chart 2 evicted the least recently used: chart 0.
    EXPECT_FALSE(cache.resident(0));
    EXPECT_TRUE(cache.resident(1));
    EXPECT_TRUE(cache.resident(2));
    EXPECT_EQ(cache.stats().evictions, 1u);
    {
        // Pinned pyramids are never evicted, even far over budget.
        GeometryPin a = views[3].Pin(), b = views[0].Pin();
        GeometryPin moved = std::move(a);
        { const GeometryPin c1 = views[1].Pin(); }
        EXPECT_TRUE(cache.resident(3));
        EXPECT_TRUE(cache.resident(0));
        // An evicted pyramid reads back the same bytes.
        for (size_t l = 0; l < img.levels.size(); ++l)
            EXPECT_TRUE(SameBytes(views[0].levels[l], img.levels[l]));
    }
    EXPECT_LE(cache.stats().resident_bytes, 2 * bytes);
    EXPECT_EQ(cache.stats().peak_resident_bytes, 4 * bytes);  // charts 0-3 while pinned
    fs::remove_all(dir);
}

TEST(GeometryCache, EvictionLeavesResidentMemory) {
    const std::string dir = FreshDir("geocache-rss", false);
    GeometryCache cache(dir, 0);
    const stream::GeometryImage img = Wavy(512, 0);  // 22 MB
    cache.Add(img);
    const GeometryPyramid view = cache.View(0);
    const uint64_t before = CurrentRssBytes();
    double sum = 0;
    uint64_t touched = 0;
    {
        const GeometryPin pin = view.Pin();
        for (const auto& level : view.levels)
            for (size_t k = 0; k < level.size(); k += 32) {
                sum += level[k].area;
                ++touched;
            }
        EXPECT_GT(CurrentRssBytes(), before + 16 * 1000 * 1000) << "pages read are resident";
    }
    EXPECT_GT(sum, 0);
    EXPECT_LT(CurrentRssBytes(), before + 4 * 1000 * 1000) << "eviction dropped them";
    EXPECT_GT(touched, 0u);
    fs::remove_all(dir);
}

// Two facing walls and a floor under a square light: direct light and a few bounces.
// Three faces of patch_fixture.h's lit box, with a stream::GeometryImage copy of each
// chart's pyramid to add to a cache.
struct Room : testing::LitBox {
    std::vector<stream::GeometryImage> images;
    Room() : LitBox(3, 32) {
        for (const SolveChart& c : charts) {
            stream::GeometryImage img;
            img.resolution = c.geometry.resolution;
            for (const auto& level : c.geometry.levels)
                img.levels.emplace_back(level.begin(), level.end());
            images.push_back(std::move(img));
        }
    }
};

std::vector<float> Solve(const Room& room, const std::vector<SolveChart>& charts) {
    SolveOptions opt;
    opt.settings.order = 1;
    opt.settings.max_bounces = 3;
    opt.settings.stop_fraction = 1e-6;
    Solver solver(room.scene, charts, room.vis, opt);
    solver.Run();
    return testing::FieldBits(solver);
}

TEST(GeometryCache, SolveOverEvictedPyramidsGivesTheSameBits) {
    const Room room;
    const std::vector<float> in_memory = Solve(room, room.charts);
    const std::string dir = FreshDir("geocache-solve", false);
    GeometryCache cache(dir, 0);  // every unpin evicts
    std::vector<SolveChart> charts = room.charts;
    for (const auto& img : room.images)
        cache.Add(img);
    for (uint32_t c = 0; c < charts.size(); ++c)
        charts[c].geometry = cache.View(c);
    const std::vector<float> cached = Solve(room, charts);
    ASSERT_EQ(in_memory.size(), cached.size());
    EXPECT_EQ(std::memcmp(in_memory.data(), cached.data(), cached.size() * sizeof(float)), 0);
    EXPECT_GT(cache.stats().evictions, 3u);
    EXPECT_EQ(cache.stats().resident_bytes, 0u);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake::solve
