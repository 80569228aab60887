// MappedCache: regions read back their bytes, pins keep them resident, eviction drops the
// least recently used unpinned ones, and nothing is left in the directory. (The typed
// layer over it, solve/geometry_cache.h, has its own tests, including resident memory.)
#include "core/mapped_cache.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <filesystem>
#include <unistd.h>
#include <vector>

namespace mebake {
namespace {

namespace fs = std::filesystem;

std::string FreshDir(const char* name) {
    const fs::path dir =
        fs::temp_directory_path() / (std::string(name) + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir.string();
}

std::vector<std::byte> Pattern(size_t n, int seed) {
    std::vector<std::byte> v(n);
    for (size_t i = 0; i < n; ++i)
        v[i] = std::byte((i * 131 + size_t(seed) * 17) & 0xff);
    return v;
}

TEST(MappedCache, RegionsOfAnySizeReadBackTheirPieces) {
    const std::string dir = FreshDir("mapped-roundtrip");
    {
        MappedCache cache(dir, "test regions", 0);
        const std::vector<size_t> sizes = {1, 4095, 4096, 4097, 100000, 0, 12};
        std::vector<std::vector<std::byte>> data;
        for (size_t k = 0; k < sizes.size(); ++k) {
            data.push_back(Pattern(sizes[k], int(k)));
            // Two pieces per region: the region is their concatenation.
            const size_t half = sizes[k] / 2;
            const std::span<const std::byte> all(data.back());
            const std::span<const std::byte> pieces[] = {all.first(half), all.subspan(half)};
            EXPECT_EQ(cache.Add(pieces), k);
        }
        EXPECT_EQ(cache.region_count(), sizes.size());
        for (uint32_t k = 0; k < sizes.size(); ++k) {
            EXPECT_EQ(cache.region_bytes(k), sizes[k]);
            const RegionPin pin = cache.Pin(k);
            if (sizes[k] > 0) {  // an empty vector's data() may be null
                EXPECT_EQ(std::memcmp(cache.Data(k), data[k].data(), sizes[k]), 0)
                    << "region " << k;
            }
        }
        // The file has no name: the directory stays empty.
        EXPECT_TRUE(fs::is_empty(dir));
    }
    fs::remove_all(dir);
}

TEST(MappedCache, LeastRecentlyUsedUnpinnedRegionsAreDroppedBeyondTheBudget) {
    const std::string dir = FreshDir("mapped-lru");
    const std::vector<std::byte> d = Pattern(3 * 4096, 1);
    MappedCache cache(dir, "test regions", 2 * d.size());
    for (int r = 0; r < 3; ++r) {
        const std::span<const std::byte> piece[] = {d};
        cache.Add(piece);
    }
    { const RegionPin a = cache.Pin(0); }
    { const RegionPin b = cache.Pin(1); }
    {
        const RegionPin c = cache.Pin(2);
        EXPECT_EQ(cache.stats().resident_bytes, 3 * d.size());  // over budget while pinned
    }
    EXPECT_FALSE(cache.resident(0));
    EXPECT_TRUE(cache.resident(1));
    EXPECT_TRUE(cache.resident(2));
    EXPECT_EQ(cache.stats().evictions, 1u);
    const RegionPin again = cache.Pin(0);
    EXPECT_EQ(std::memcmp(cache.Data(0), d.data(), d.size()), 0) << "dropped pages read back";
    fs::remove_all(dir);
}

// Resident kB of the mapping that holds `p` (/proc/self/smaps), -1 when not found.
long MappingRssKb(const void* p) {
    std::ifstream in("/proc/self/smaps");
    std::string line;
    bool inside = false;
    const auto at = reinterpret_cast<uintptr_t>(p);
    while (std::getline(in, line)) {
        unsigned long lo = 0, hi = 0;
        if (std::sscanf(line.c_str(), "%lx-%lx ", &lo, &hi) == 2 && line.find(' ') < 30) {
            inside = at >= lo && at < hi;
            continue;
        }
        long kb = 0;
        if (inside && std::sscanf(line.c_str(), "Rss: %ld kB", &kb) == 1)
            return kb;
    }
    return -1;
}

// A read maps the pages around it too (the kernel's fault-around, 64 KiB windows), pages of
// regions already evicted: with one-page regions and no budget, reading region 1 again
// mapped its 15 neighbours, and evicting region 1 alone left them mapped, uncounted (the
// 100M solve held 220 MB so). Eviction drops the window: nothing stays mapped.
TEST(MappedCache, EvictionDropsThePagesMappedAroundARead) {
    const std::string dir = FreshDir("mapped-faultaround");
    {
        MappedCache cache(dir, "test regions", 0);
        const size_t page = size_t(::sysconf(_SC_PAGESIZE));
        const std::vector<std::byte> data = Pattern(page, 3);
        for (int r = 0; r < 64; ++r) {
            const std::span<const std::byte> piece(data);
            cache.Add(std::span(&piece, 1));
        }
        auto read = [&](uint32_t r) {
            const RegionPin pin = cache.Pin(r);
            volatile std::byte b = cache.Data(r)[0];
            (void)b;
        };
        for (uint32_t r = 0; r < 64; ++r)
            read(r);
        read(1);
        read(40);
        EXPECT_EQ(MappingRssKb(cache.Data(0)), 0);
    }
    fs::remove_all(dir);
}

TEST(MappedCache, AMissingDirectoryIsAnIoErrorNamingIt) {
    try {
        MappedCache cache("/nonexistent-mebake-dir/x", "test regions", 0);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent-mebake-dir/x"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace mebake
